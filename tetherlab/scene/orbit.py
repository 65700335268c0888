"""[orbit]: the reference point (the centre of mass or a body), its initial orbit and the initial
motion of the system about it."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import SceneError
from .bodies import _parse_state
from .data import CENTER_OF_MASS, MOTIONS, Body, Orbit
from .keys import _NOTHING, _choice, _quoted, _string, _suggest, _table


def _parse_orbit(value: Any, bodies: tuple[Body, ...], mu: float, radius_m: float | None = None) -> Orbit:
    path = "orbit"
    table = _table(value, path, ("reference", "elements", "position", "velocity", "motion"))
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
    orbit = Orbit(reference, elements, position, velocity, motion)
    has_state = position is not None or elements is not None
    if has_state:
        with np.errstate(all="ignore"):  # a size near 0 or 1e308 overflows: refused below, not warned
            r, v = orbit.state(mu)
        if not (np.all(np.isfinite(r)) and np.all(np.isfinite(v))):
            raise SceneError(f"{path}.{'elements' if elements is not None else 'position'}",
                             "an initial state with finite position and velocity", f"{r.tolist()} m, {v.tolist()} m/s")  # fmt: skip
        if not np.linalg.norm(r) > 0.0:
            raise SceneError(f"{path}.position", "a position away from the centre of the central body", "the origin")

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
