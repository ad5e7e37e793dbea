"""Studies of the BRDF models: example parameter sets, the lobe-anisotropy derivation
(a 2025 derivation) and the grid checks of the lobe study."""
