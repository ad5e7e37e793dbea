"""The simulated backend: virtual motors and detector, noise effects, a Dynamixel bus emulator."""
