"""Benchmark tables for ``make bench`` (each module returns rows; nothing here is asserted)."""
