"""Helpers shared by the tests of several packages (fixtures live in tests/conftest.py)."""
