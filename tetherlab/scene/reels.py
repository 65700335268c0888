"""[tethers.NAME.reel]: a reel at the tether's `from` end and its law (docs/deployment.md,
docs/scenes.md).  Checked here: every bound positive, the birth and retirement bounds apart by
more than a rod (the hysteresis that keeps a birth from being undone at once), the law's
parameter present and the initial length within one rod's bounds."""

from __future__ import annotations

import math
from typing import Any

from ..errors import SceneError
from ..units import LENGTH, RATE, SPEED, TIME, shown
from .data import REEL_EXITS, REEL_LAWS, Reel
from .keys import _choice, _quantity, _required, _table

_REEL_KEYS = ("at", "exit", "law", "speed", "rate", "times", "lengths", "rod_length", "birth_length", "retire_length",
              "stored_length")

#: Default bounds in rod lengths: a birth at 1.5 leaves a first rod of 0.5, a retirement at 0.25
#: leaves one of 1.25, both a quarter of a rod from the other bound.
BIRTH_DEFAULT = 1.5
RETIRE_DEFAULT = 0.25


def rods_for(length_m: float, reel: Reel) -> int:
    """Rods of a reel tether of deployed length ``length_m``: full rods of ``rod_length_m`` and the
    first, between the retirement and the birth bounds."""
    n = 1
    first = length_m
    while first > reel.birth_length_m:
        first -= reel.rod_length_m
        n += 1
    return n


def parse_reel(value: Any, path: str, length_m: float) -> Reel:
    table = _table(value, path, _REEL_KEYS)
    at = _choice(table.get("at", "from"), f"{path}.at", ("from",))
    del at  # one end today: the tether's `from` end, its attachment on the parent body
    exit_ = _choice(table.get("exit", "canister"), f"{path}.exit", REEL_EXITS)
    law = _choice(_required(table, "law", path, f"one of {REEL_LAWS}"), f"{path}.law", REEL_LAWS)
    speed = rate = 0.0
    times: tuple = ()
    lengths: tuple = ()
    others = {"constant": ("rate", "times", "lengths"), "exponential": ("speed", "times", "lengths"),
              "table": ("speed", "rate")}[law]  # fmt: skip
    for key in others:
        if key in table:
            raise SceneError(f"{path}.{key}", f"no {key!r} with law {law!r}", shown(table[key]))
    if law == "table":
        times, lengths = _table_law(table, path, length_m)
    elif law == "constant":
        speed = _quantity(_required(table, "speed", path, SPEED.describe()), f"{path}.speed", SPEED)
    else:
        rate = _quantity(_required(table, "rate", path, RATE.describe()), f"{path}.rate", RATE)
    rod = _quantity(_required(table, "rod_length", path, LENGTH.describe()), f"{path}.rod_length", LENGTH, positive=True)
    birth = (_quantity(table["birth_length"], f"{path}.birth_length", LENGTH, positive=True)
             if "birth_length" in table else BIRTH_DEFAULT * rod)  # fmt: skip
    retire = (_quantity(table["retire_length"], f"{path}.retire_length", LENGTH, positive=True)
              if "retire_length" in table else RETIRE_DEFAULT * rod)  # fmt: skip
    if not retire + rod < birth:
        raise SceneError(
            f"{path}.birth_length",
            f"more than retire_length + rod_length = {retire + rod:.6g} m (a rod born at the birth bound must leave a "
            "first rod longer than the retirement bound, and a merge one shorter than the birth bound)",
            f"{birth:.6g} m with retire_length {retire:.6g} m and rod_length {rod:.6g} m",
        )
    stored = _quantity(table.get("stored_length", "0 m"), f"{path}.stored_length", LENGTH, nonnegative=True)
    if length_m < retire:
        raise SceneError(
            f"{path}.retire_length", f"at most the deployed length ({length_m:.6g} m): at least one rod must be out",
            f"{retire:.6g} m",
        )
    return Reel(law, exit_, speed, rate, rod, birth, retire, stored, times, lengths)


def _table_law(table, path: str, length_m: float) -> tuple[tuple, tuple]:
    """times (from 0, increasing) and lengths (> 0, the first the tether's length) of a table law."""
    raw_t = _required(table, "times", path, "a list of times from 0, increasing (e.g. ['0 s', '600 s'])")
    raw_l = _required(table, "lengths", path, "a list of deployed lengths, one per time")
    if not isinstance(raw_t, (list, tuple)) or len(raw_t) < 2:
        raise SceneError(f"{path}.times", "a list of at least 2 times from 0, increasing", shown(raw_t))
    times = tuple(_quantity(x, f"{path}.times[{j}]", TIME) for j, x in enumerate(raw_t))
    if times[0] != 0.0 or any(not b > a for a, b in zip(times, times[1:])):
        raise SceneError(f"{path}.times", "times from 0, strictly increasing", shown(raw_t))
    if not isinstance(raw_l, (list, tuple)) or len(raw_l) != len(times):
        raise SceneError(f"{path}.lengths", f"a list of {len(times)} lengths, one per time", shown(raw_l))
    lengths = tuple(_quantity(x, f"{path}.lengths[{j}]", LENGTH, positive=True) for j, x in enumerate(raw_l))
    if abs(lengths[0] - length_m) > 1e-12 * length_m:
        raise SceneError(f"{path}.lengths", f"a first length equal to the tether's length ({length_m:.6g} m): the "
                         "deployed length at t = 0", f"{lengths[0]:.6g} m")  # fmt: skip
    return times, lengths


def table_spline(reel: Reel):
    """The natural cubic spline of a table law (C2: the rod's apparent load, which has L'', stays
    continuous); beyond the table the last interval's cubic continues."""
    from scipy.interpolate import CubicSpline

    return CubicSpline(reel.times_s, reel.lengths_m, bc_type="natural", extrapolate=True)


def length_at(reel: Reel, length0_m: float, t_s: float) -> float:
    """The deployed unstretched length L(t) of the law."""
    if reel.law == "constant":
        return length0_m + reel.speed_m_s * t_s
    if reel.law == "table":
        return float(table_spline(reel)(t_s))
    return length0_m * math.exp(reel.rate_1_s * t_s)


def speed_at(reel: Reel, length0_m: float, t_s: float) -> float:
    """dL/dt of the law."""
    if reel.law == "constant":
        return reel.speed_m_s
    if reel.law == "table":
        return float(table_spline(reel)(t_s, 1))
    return reel.rate_1_s * length0_m * math.exp(reel.rate_1_s * t_s)
