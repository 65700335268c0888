"""The start of an inextensible tether: rods at their lengths, no axial velocity, every rod taut.

Any initial shape (straight, per-rod angles, the static shape, a release) is built as for an
elastic tether; an inextensible rod then keeps its direction and takes its unstretched length,
and its rate loses the component along the rod (the constraint and its first derivative hold at
t0: docs/inextensible.md section 4).  The static shape of ``shape = "equilibrium"`` is solved with
the tether's EA, so its directions are those of the elastic hang; the lengths are not.

The model holds only while every rod pulls: a start where a rod's tension multiplier is not
positive is refused, naming the tether and the rod (the run would otherwise start in a regime the
model does not describe; the event that stops a run there is kernel/events.py's).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..errors import SceneError
from ..model.params import ParamView
from ..scene.data import INEXTENSIBLE

SQ3 = math.sqrt(3.0)


def default_rate_1_s(t_unit_s: float) -> float:
    """The Baumgarte rate when the scene gives none: the scene's reference rate, 1/t_unit (the
    mean motion on an orbit, 1/s on the surface).  docs/inextensible.md section 4: a violation
    decays over one such time, below any resolved frequency, so it adds no stiffness."""
    return 1.0 / t_unit_s


def elastic_stand_in(spec):
    """The elastic tether of the same EA in place of an inextensible TetherSpec: what the static
    and relative-equilibrium solves take (their unknowns include the rods' strains)."""
    if spec.model != INEXTENSIBLE:
        return spec
    return dataclasses.replace(spec, model="paper", part="")


def has_inextensible(model) -> bool:
    return any(t.model == INEXTENSIBLE for t in model.tethers)


def set_rates(model, scene_tethers, t_unit_s: float) -> None:
    """Write each inextensible tether's constraint rate into its rods' records: the scene's
    ``constraint_rate``, else :func:`default_rate_1_s`."""
    view = ParamView(model.p)
    given = {t.name: t.constraint_rate_1_s for t in scene_tethers}
    for t, sl in zip(model.tethers, model.rod_slices):
        if t.model != INEXTENSIBLE:
            continue
        rate = given.get(t.name)
        view.rods.constraint_rate_1_s[sl] = default_rate_1_s(t_unit_s) if rate is None else rate


def project(model, y: np.ndarray) -> np.ndarray:
    """y with every inextensible rod at its unstretched length (same direction) and without a
    rate along itself; other blocks unchanged."""
    lay = model.state
    lengths = ParamView(model.p).rods.length_m
    y = np.array(y, dtype=float)
    for t, sl in zip(model.tethers, model.rod_slices):
        if t.model != INEXTENSIBLE:
            continue
        for g in range(sl.start, sl.stop):
            d = y[lay.rod(g)]
            u = d / np.linalg.norm(d)
            y[lay.rod(g)] = u * (lengths[g] / (2.0 * SQ3))
            v = y[lay.rod_rate(g)]
            y[lay.rod_rate(g)] = v - (v @ u) * u
    return y


def check_taut(model, t0_s: float, y: np.ndarray, key_of) -> None:
    """Refuse a start where an inextensible rod's tension multiplier is not positive.
    ``key_of(tether_name)`` gives the scene key to name."""
    from ..diagnostics import compute

    rods = compute(model, np.array([t0_s]), np.asarray(y, float)[None, :])["rods"][0]
    for t, sl in zip(model.tethers, model.rod_slices):
        if t.model != INEXTENSIBLE:
            continue
        tension = rods[sl, 1]
        worst = int(np.argmin(tension))
        if not tension[worst] > 0.0:
            raise SceneError(
                key_of(t.name),
                "a start where every rod of an inextensible tether pulls (its tension at t0 > 0): the model holds "
                "only while taut; give a start that hangs or swings taut, or model = 'paper' with tension_only = true",
                f"rod {worst + 1} of {sl.stop - sl.start} at {tension[worst]:.6g} N",
            )
