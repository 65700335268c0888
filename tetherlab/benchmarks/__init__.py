"""Benchmark tables for ``make bench``: one module a benchmark, each returning rows (nothing here is
asserted; heyoka, where compared, is imported inside functions only)."""
