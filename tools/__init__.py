"""Generators of committed files (run from the repository's root; not installed)."""
