"""Measurements synthesized without the acquisition engine, for reconstruction studies."""
