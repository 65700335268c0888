"""Shared helpers for the physics tests (not a test module)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "studies" / "scenes"
MU_EARTH = 3.986004418e14  # m^3/s^2, the scene preset "earth" (tetherlab/scene.py)


def zero_crossing_frequency(t: np.ndarray, x: np.ndarray) -> float:
    """Angular frequency from the mean spacing of the zero crossings (linear interpolation)."""
    s = np.sign(x)
    idx = np.where(s[:-1] * s[1:] < 0)[0]
    if len(idx) < 3:
        raise ValueError(f"only {len(idx)} zero crossings: run longer")
    tz = t[idx] - x[idx] * (t[idx + 1] - t[idx]) / (x[idx + 1] - x[idx])
    half_period = (tz[-1] - tz[0]) / (len(tz) - 1)
    return np.pi / half_period
