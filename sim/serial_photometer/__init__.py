"""The simulated photometer's command, ``python -m sim.serial_photometer`` (the
photometer itself is `sim.peers.serial_photometer`)."""

__all__: list[str] = []
