"""A byte-level Dynamixel Protocol 2.0 bus emulator on a real pseudo-terminal: the
packet codec (`protocol`), motors (`motor`, `motion`, `rules`), instructions, injectable
faults and the pty server (`emulator`). The real `drivers.dynamixel` talks to it through
the unmodified ROBOTIS SDK.

Run it with ``python -m sim.dynamixel.emulator``; the package re-exports nothing, so that
running the module does not import it twice.
"""

__all__: list[str] = []
