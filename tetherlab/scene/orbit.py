"""[orbit]: the reference point (the centre of mass or a body), its initial orbit and the initial
motion of the system about it."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import SceneError
from .bodies import _parse_state
from ..units import ANGULAR_RATE, shown, to_si
from .data import CENTER_OF_MASS, MOTIONS, SPIN_FRAMES, Body, Orbit, Spin
from .keys import _NOTHING, _bounded, _choice, _number, _quoted, _string, _suggest, _table


def _parse_orbit(value: Any, bodies: tuple[Body, ...], mu: float, radius_m: float | None = None) -> Orbit:
    path = "orbit"
    table = _table(value, path, ("reference", "elements", "position", "velocity", "motion", "spin"))
    names = [b.name for b in bodies]
    reference = _string(table.get("reference", CENTER_OF_MASS), f"{path}.reference", f"{CENTER_OF_MASS!r} or a body name")
    if reference != CENTER_OF_MASS and reference not in names:
        raise SceneError(
            f"{path}.reference",
            f"{CENTER_OF_MASS!r} or the name of a body ({_quoted(names)})",
            f"{reference!r} (no such body)",
            hint=_suggest(reference, [CENTER_OF_MASS, *names]),
        )
    position, velocity, elements = _parse_state(table, path, radius_m=radius_m)
    motion = _choice(table.get("motion", "corotating"), f"{path}.motion", MOTIONS)
    spin = _parse_spin(table["spin"], f"{path}.spin", motion) if "spin" in table else None
    orbit = Orbit(reference, elements, position, velocity, motion, spin)
    has_state = position is not None or elements is not None
    if has_state:
        with np.errstate(all="ignore"):  # a size near 0 or 1e308 overflows: refused below, not warned
            r, v = orbit.state(mu)
        if not (np.all(np.isfinite(r)) and np.all(np.isfinite(v))):
            raise SceneError(f"{path}.{'elements' if elements is not None else 'position'}",
                             "an initial state with finite position and velocity", f"{r.tolist()} m, {v.tolist()} m/s")  # fmt: skip
        if not np.linalg.norm(r) > 0.0:
            raise SceneError(f"{path}.position", "a position away from the centre of the central body", "the origin")
        if spin is not None and spin.frame == "orbit" and not np.linalg.norm(np.cross(r, v)) > 0.0:
            raise SceneError(f"{path}.spin.frame", "'inertial': this orbit has no orbit frame (r x v = 0)", "'orbit'")

    explicit = [b for b in bodies if b.has_state]
    if reference == CENTER_OF_MASS:
        if explicit:
            raise SceneError(
                f"{path}.reference",
                "a body name when some bodies have explicit states (the centre of mass would depend on them)",
                f"{CENTER_OF_MASS!r} while body {explicit[0].name!r} has an explicit state",
            )
        if not has_state:
            raise SceneError(f"{path}.elements", "the initial orbit: elements, or position and velocity", _NOTHING)
    else:
        body = bodies[names.index(reference)]
        if body.fixed:
            raise SceneError(f"{path}.reference", "a moving body (a fixed body has no orbit)", f"{reference!r} (fixed)")
        if body.has_state and has_state:
            raise SceneError(
                f"{path}.{'elements' if elements is not None else 'position'}",
                f"no orbit state: the reference body {reference!r} already has its own (give it once)",
                "a second initial state",
            )
        if not body.has_state and not has_state:
            raise SceneError(
                f"{path}.elements",
                f"the initial orbit (elements, or position and velocity), or an explicit state on body {reference!r}",
                _NOTHING,
            )
    return orbit


def _parse_spin(value: Any, path: str, motion: str) -> Spin:
    """``spin = { rate = "2 deg/s", axis = [0, 0, 1], frame = "orbit" }``: rate signed, axis
    normalised (default the orbit normal), frame "orbit" (radial, along-track, normal) or
    "inertial"."""
    table = _table(value, path, ("rate", "axis", "frame"))
    if "rate" not in table:
        raise SceneError(f"{path}.rate", f"{ANGULAR_RATE.describe()} (signed: right-handed about axis)", _NOTHING)
    rate = _bounded(to_si(table["rate"], ANGULAR_RATE, key=f"{path}.rate"), f"{path}.rate", ANGULAR_RATE, table["rate"])
    if rate == 0.0:
        raise SceneError(f"{path}.rate", "a non-zero angular rate (leave spin out for none)", shown(table["rate"]))
    raw = table.get("axis", [0.0, 0.0, 1.0])
    if not isinstance(raw, (list, tuple)) or len(raw) != 3:
        raise SceneError(f"{path}.axis", "3 plain numbers (a direction)", shown(raw))
    axis = np.array([_number(x, f"{path}.axis[{j}]", "a plain number") for j, x in enumerate(raw)])
    norm = float(np.linalg.norm(axis))
    if not norm > 0.0:
        raise SceneError(f"{path}.axis", "a non-zero direction", shown(raw))
    frame = _choice(table.get("frame", "orbit"), f"{path}.frame", SPIN_FRAMES)
    if motion in ("equilibrium", "quasi-static"):
        raise SceneError(f"{path}", f"no spin with motion {motion!r} (a relative equilibrium turns with the orbit); "
                         "use motion 'corotating' or 'translating'", "a spin table")  # fmt: skip
    return Spin(rate, tuple(float(x) for x in axis / norm), frame)
