"""Benchmarks run by ``make bench`` (one module a benchmark; heyoka imported inside functions only)."""
