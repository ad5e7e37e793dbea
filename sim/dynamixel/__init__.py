"""The Dynamixel bus emulator's command, ``python -m sim.dynamixel.emulator`` (the
emulator itself is `sim.peers.dynamixel`)."""

__all__: list[str] = []
