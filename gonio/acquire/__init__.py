"""Acquisition: the devices of one run (`devices`), the per-target measuring step written
against the `drivers.base` contract only (`measure`), and the calibration with the
reference standard (`calibration`). The engine (`gonio acquire`) builds on these."""
