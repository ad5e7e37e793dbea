"""ROBOTIS Dynamixel X-series motors over Protocol 2.0.

:mod:`drivers.dynamixel.control_table` is the control table as data,
:mod:`drivers.dynamixel.protocol` the packet format (our own codec, used by the
emulator and to check the SDK byte for byte), :mod:`drivers.dynamixel.bus` the
`MotorBus` on the unmodified ``dynamixel-sdk``.
"""
