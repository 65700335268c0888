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
from .keys import _choice, _number, _quantity, _required, _table, _vector

_REEL_KEYS = ("at", "exit", "law", "speed", "rate", "times", "lengths", "rod_length", "birth_length", "retire_length",
              "stored_length", "point", "exit_direction", "spool_radius", "spool_axis")

#: a drum's axis must be perpendicular to its exit direction within this cosine (its rim moves along
#: the exit direction where the line leaves it)
DRUM_AXIS_COS = 1e-6

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
    hub = _parse_hub(table, path, exit_)
    return Reel(law, exit_, speed, rate, rod, birth, retire, stored, times, lengths, **hub)


def _unit_vector(raw, key: str) -> tuple:
    """A direction in body axes: 3 plain numbers, not all zero; returned normalised."""
    if not isinstance(raw, (list, tuple)) or len(raw) != 3:
        raise SceneError(key, "a list of 3 numbers (a direction in body axes, e.g. [0, 0, 1])", shown(raw))
    v = [_number(x, f"{key}[{j}]", "a number") for j, x in enumerate(raw)]
    n = math.sqrt(sum(x * x for x in v))
    if not n > 0.0:
        raise SceneError(key, "a direction of non-zero length (body axes)", shown(raw))
    return tuple(x / n for x in v)


def _parse_hub(table, path: str, exit_: str) -> dict:
    """The keys of a reel on a rigid body (docs/deployment.md 9): the exit point (body axes, from
    the centre of mass), the exit direction, the spool's radius and, for a drum, its axis.  Whether
    the body is rigid is checked with the scene (scene/checks.py)."""
    out: dict = {}
    if "point" in table:
        out["point_m"] = _vector(table["point"], f"{path}.point", LENGTH)
    if "exit_direction" in table:
        out["exit_direction"] = _unit_vector(table["exit_direction"], f"{path}.exit_direction")
    if "spool_radius" in table:
        out["spool_radius_m"] = _quantity(table["spool_radius"], f"{path}.spool_radius", LENGTH, positive=True)
    if "spool_axis" in table:
        if exit_ != "drum":
            raise SceneError(f"{path}.spool_axis", "no spool_axis with exit 'canister' (a canister's axis is its "
                             "exit_direction: the line is pulled off the end of the spool)", shown(table["spool_axis"]))  # fmt: skip
        axis = _unit_vector(table["spool_axis"], f"{path}.spool_axis")
        e = out.get("exit_direction")
        if e is not None and abs(sum(a * b for a, b in zip(axis, e))) > DRUM_AXIS_COS:
            raise SceneError(f"{path}.spool_axis", "an axis perpendicular to exit_direction (the drum's rim moves along "
                             "the exit direction where the line leaves it)", f"{shown(table['spool_axis'])}, "
                             f"cosine {sum(a * b for a, b in zip(axis, e)):.3g} with exit_direction")  # fmt: skip
        out["spool_axis"] = axis
    return out


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
