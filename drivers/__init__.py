"""Hardware drivers: Dynamixel arm motors over serial and a serial detector.

This package imports nothing from :mod:`gonio` or :mod:`sim`; the interfaces every
backend implements live in ``drivers/base.py``.
"""
