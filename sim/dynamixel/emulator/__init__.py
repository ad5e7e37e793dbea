"""``python -m sim.dynamixel.emulator``: serve an emulated bus
(`sim.peers.dynamixel.emulator.main`)."""

__all__: list[str] = []
