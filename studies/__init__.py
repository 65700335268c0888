"""The studies of ``make verify``: scripts that write OUTDIR/<name>.md (+ CSV, PNG), each runnable on
its own (``python studies/<name>.py OUTDIR``).  A package of the source checkout (not installed
with tetherlab), so tetherlab.verify imports them by name (tetherlab/verify/checkout.py)."""
