"""``python -m sim.serial_photometer``: print the pty path and serve until Ctrl-C
(`sim.peers.serial_photometer.main`)."""

import sys

from sim.peers.serial_photometer.cli import main

if __name__ == "__main__":
    sys.exit(main())
