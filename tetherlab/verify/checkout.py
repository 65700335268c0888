"""Where verify finds its inputs: the source checkout's studies/ (a package of study scripts),
studies/scenes/ and references/.  verify only runs inside a checkout (they are not installed with
the package): :func:`require_checkout` says so by name when they are missing."""

from __future__ import annotations

import importlib
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "studies" / "scenes"


def require_checkout() -> Path:
    """ROOT, or a RuntimeError naming what is missing (an installed tetherlab has no studies/)."""
    missing = [p for p in (ROOT / "studies" / "__init__.py", ROOT / "references" / "gates.toml") if not p.is_file()]
    if missing:
        raise RuntimeError(
            f"tetherlab.verify needs a source checkout (studies/ and references/ beside tetherlab/): "
            f"{', '.join(str(p) for p in missing)} not found; run it from a clone of the repository")  # fmt: skip
    return ROOT


def load_study(name: str):
    """The study module ``studies.<name>`` (studies/<name>.py), imported as a package module: one
    module object per study, found by name in worker processes (pickled dataclasses)."""
    require_checkout()
    if str(ROOT) not in sys.path:
        sys.path.insert(0, str(ROOT))  # the checkout root holds the studies package
    return importlib.import_module(f"studies.{name}")
