"""``python -m sim.dynamixel.emulator --ids 1,2,3,4 [--baud 57600]``: serve an emulated bus
until Ctrl-C (`sim.peers.dynamixel.emulator.main`)."""

import signal
import sys

from sim.peers.dynamixel.emulator import main

if __name__ == "__main__":
    # Started with `&` from a non-interactive shell, the process inherits SIGINT ignored
    # and Python then installs no KeyboardInterrupt handler: restore it, so Ctrl-C (or
    # `kill -INT`) stops the emulator as its banner promises.
    signal.signal(signal.SIGINT, signal.default_int_handler)
    sys.exit(main())
