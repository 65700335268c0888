"""Where a report item came from: commit, library versions, machine, date (house style section 8).

Every figure a study writes ends with :func:`stamp_figure`'s line, and the report footer is
:func:`footer`, so a PNG copied out of ``reports/`` still says which code, which libraries and
which sources made it.
"""

from __future__ import annotations

import datetime as _dt
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def git_commit() -> tuple[str, bool]:
    """(commit hash or 'unknown', True if the working tree has uncommitted changes)."""
    try:
        commit = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True,
                                check=False).stdout.strip()  # fmt: skip
        dirty = subprocess.run(["git", "status", "--porcelain"], cwd=ROOT, capture_output=True, text=True,
                               check=False).stdout.strip()  # fmt: skip
    except OSError:
        return "unknown", False
    return commit or "unknown", bool(dirty)


def footer(short: bool = False) -> str:
    """One line: commit, library versions (machine included), UTC date.  ``short``: the commit's
    first 10 digits and the versions of numpy, scipy and numba only (for figures)."""
    from .result import library_versions

    commit, dirty = git_commit()
    v = library_versions()
    if short:
        commit = commit[:10]
        v = {k: v[k] for k in ("tetherlab", "numpy", "scipy", "numba", "machine") if k in v}
    date = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    return (f"commit {commit}{' (with uncommitted changes)' if dirty else ''} | "
            + ", ".join(f"{k} {val}" for k, val in v.items()) + f" | {date}")  # fmt: skip


def stamp_figure(fig, sources: str) -> None:
    """Lay the figure out above a strip at its bottom edge and write there the provenance line and
    the sources (e.g. 'studies/catenary.py; oracle: Irvine's elastic catenary').  Call it last,
    just before saving (it replaces a tight_layout call)."""
    import warnings

    strip = 0.3 / fig.get_size_inches()[1]  # two lines of 5-pt text, as a fraction of the height
    with warnings.catch_warnings():
        # tight_layout warns when some decoration cannot be fitted; the figure is still laid out
        warnings.simplefilter("ignore")
        fig.tight_layout(rect=(0.0, strip, 1.0, 1.0))
    fig.text(0.005, 0.005, f"{footer(short=True)}\nsources: {sources}", fontsize=5, va="bottom",
             ha="left", color="0.35")  # fmt: skip
