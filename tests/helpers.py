"""Shared helpers for the physics tests (not a test module)."""

from __future__ import annotations

from pathlib import Path


ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "studies" / "scenes"
MU_EARTH = 3.986004418e14  # m^3/s^2, the scene preset "earth" (tetherlab/scene.py)

from tetherlab.diagnostics import zero_crossing_frequency  # noqa: E402,F401  (re-export for the tests)
