"""Reconstruction of a measured BRDF from a run's samples (docs/reconstruction.md)."""
