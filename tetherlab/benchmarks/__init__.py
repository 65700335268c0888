"""Benchmark tables for ``make bench``: one module a benchmark, each returning rows (nothing here is
asserted; heyoka, where compared, is imported inside functions only)."""


def print_markdown(rows: list[dict]) -> None:
    """Print rows (dicts with the same keys) as a Markdown table, floats to 4 significant digits."""
    keys = list(rows[0])
    print("| " + " | ".join(keys) + " |\n|" + "---|" * len(keys))
    for r in rows:
        print("| " + " | ".join(f"{v:.4g}" if isinstance(v, float) else str(v) for v in r.values()) + " |",
              flush=True)  # fmt: skip
