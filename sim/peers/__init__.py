"""The byte-level peers the real drivers talk to on pseudo-terminals: the Dynamixel bus
emulator (`dynamixel`), the serial photometer (`serial_photometer`), the VISA lab
instruments (`visa_instruments`) and the lamp relay (`serial_light`).

Imported by module: a peer started from the command line loads only its own."""

__all__: list[str] = []
