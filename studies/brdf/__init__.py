"""Studies of the BRDF models: example parameter sets, the lobe-anisotropy derivation
(seed 001) and the grid checks of the lobe study (seed 003)."""
