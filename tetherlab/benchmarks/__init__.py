"""Benchmarks of whole missions, each returning rows (dicts) for a table (``make bench``)."""
