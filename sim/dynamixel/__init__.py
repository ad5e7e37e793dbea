"""A byte-level Dynamixel Protocol 2.0 bus emulator on a real pseudo-terminal: the
packet codec (`protocol`), motors (`motor`, `motion`, `rules`), instructions, injectable
faults and the pty server (`emulator`). The real `drivers.dynamixel` talks to it through
the unmodified ROBOTIS SDK."""
