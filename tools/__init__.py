"""Generators of committed files: the reference pages and the shipped schemas
(``python -m tools.NAME`` from the repository's root; not installed)."""
