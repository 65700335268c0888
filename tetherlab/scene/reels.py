"""[tethers.NAME.reel]: a reel at the tether's `from` end and its law (docs/deployment.md,
docs/scenes.md).  Checked here: every bound positive, the birth and retirement bounds apart by
more than a rod (the hysteresis that keeps a birth from being undone at once), the law's
parameter present and the initial length within one rod's bounds."""

from __future__ import annotations

import math
from typing import Any

from ..errors import SceneError
from ..units import LENGTH, RATE, SPEED, shown
from .data import REEL_EXITS, REEL_LAWS, Reel
from .keys import _choice, _quantity, _required, _table

_REEL_KEYS = ("at", "exit", "law", "speed", "rate", "rod_length", "birth_length", "retire_length", "stored_length")

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
    if law == "constant":
        speed = _quantity(_required(table, "speed", path, SPEED.describe()), f"{path}.speed", SPEED)
        if "rate" in table:
            raise SceneError(f"{path}.rate", "no 'rate' with law 'constant' (it takes 'speed')", shown(table["rate"]))
    else:
        rate = _quantity(_required(table, "rate", path, RATE.describe()), f"{path}.rate", RATE)
        if "speed" in table:
            raise SceneError(f"{path}.speed", "no 'speed' with law 'exponential' (it takes 'rate')", shown(table["speed"]))
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
    return Reel(law, exit_, speed, rate, rod, birth, retire, stored)


def length_at(reel: Reel, length0_m: float, t_s: float) -> float:
    """The deployed unstretched length L(t) of the law."""
    if reel.law == "constant":
        return length0_m + reel.speed_m_s * t_s
    return length0_m * math.exp(reel.rate_1_s * t_s)
