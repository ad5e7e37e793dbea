"""Scripts that write the generated documentation pages (``python -m tools.NAME``)."""
