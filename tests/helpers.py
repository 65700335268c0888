"""Shared helpers for the physics tests (not a test module)."""

from __future__ import annotations

from pathlib import Path


ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "studies" / "scenes"
MU_EARTH = 3.986004418e14  # m^3/s^2, the scene preset "earth" (tetherlab/scene.py)

from tetherlab.diagnostics import zero_crossing_frequency  # noqa: E402,F401  (re-export for the tests)


def import_study(name: str):
    """Import studies/NAME.py as a module (the studies are scripts, not a package); the caller
    removes it from sys.modules when done (:func:`forget_study`)."""
    import importlib.util
    import sys

    spec = importlib.util.spec_from_file_location(f"tetherlab_study_{name}", ROOT / "studies" / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod
    spec.loader.exec_module(mod)
    return mod


def forget_study(name: str) -> None:
    import sys

    sys.modules.pop(f"tetherlab_study_{name}", None)
