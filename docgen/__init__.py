"""Generators of the documentation site's pages from their single sources (the argument parsers,
the typed settings, the results JSON)."""
