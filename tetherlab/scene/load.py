"""Reading a scene: the TOML file (:func:`load_scene`) or the dictionary (``Scene.from_dict``), each
section validated in turn, then the graph and layout checks and the checks of what can run."""

from __future__ import annotations

import os

import dataclasses
import re
import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from ..errors import SceneError
from ..model import topology
from .bodies import _parse_bodies
from .checks import (
    _check_above_surface,
    _check_epoch,
    _check_forest,
    _check_layout,
    _check_orbits_duration,
    _check_run,
    _check_stop_altitude,
)
from .data import SINGULAR_AT_ORIGIN, OutputSpec, Scene
from .keys import _reject_non_finite, _required, _string, _table
from .orbit import _parse_orbit
from .sections import (
    _expand_per_body,
    _parse_central_body,
    _parse_duration,
    _parse_effects,
    _parse_epoch,
    _parse_integrator,
    _parse_output,
    _parse_stop,
)
from .tethers import _parse_tethers


def load_scene(path: str | Path) -> Scene:
    """Read and validate a TOML scene file."""
    path = Path(path)
    if not path.is_file():
        where = path.resolve()
        reason = "is a directory, not a scene file" if path.is_dir() else "does not exist"
        raise FileNotFoundError(f"scene file {str(path)!r} {reason} (resolved to {str(where)!r})")
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise SceneError("", "a UTF-8 text file", f"undecodable bytes ({exc.reason})", source=str(path)) from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        # Python 3.11 has no lineno attribute on the exception; the message ends "(at line L, column C)".
        match = re.search(r"at line (\d+)", str(exc))
        line = int(match.group(1)) if match else None
        raise SceneError("", "valid TOML", str(exc), source=str(path), line=line) from None
    return Scene.from_dict(data, source=str(path))


_TOP_KEYS = (
    "name",
    "continue_from",
    "description",
    "epoch",
    "duration",
    "central_body",
    "effects",
    "bodies",
    "tethers",
    "orbit",
    "integrator",
    "output",
    "stop",
)


def _parse_scene(data: Mapping[str, Any], source: str) -> Scene:
    _reject_non_finite(data, "")
    top = _table(data, "", _TOP_KEYS)

    if "name" in top:
        name = _string(top["name"], "name", "a non-empty string")
        if not name.strip():
            raise SceneError("name", "a non-empty string", repr(name))
    else:
        name = Path(source).stem if source != "<dict>" else "scene"
    description = _string(top["description"], "description") if "description" in top else None
    epoch = _parse_epoch(top["epoch"]) if "epoch" in top else None
    continue_from = None
    if "continue_from" in top:
        raw = _string(top["continue_from"], "continue_from", "the directory of a finished run (a path, e.g. 'runs/phase1')")
        if not raw.strip():
            raise SceneError("continue_from", "the directory of a finished run (a path, e.g. 'runs/phase1')", repr(raw))
        # relative to the working directory, as --out; kept absolute so a resumed run finds it
        continue_from = os.path.abspath(raw)

    central = _parse_central_body(top.get("central_body", {}))
    mu = central.mu_m3_s2
    effects = _parse_effects(_required(top, "effects", "", "a table of effects, e.g. central_gravity = {}; an empty table "
                                         "([effects] with nothing under it, or effects = {}) means no effect: free space"))
    origin_singular = [e.name for e in effects if e.name in SINGULAR_AT_ORIGIN]
    bodies = _parse_bodies(
        _required(top, "bodies", "", "a table of bodies, e.g. [bodies.m0] with mass = '1000 kg'"), mu, origin_singular,
        radius_m=central.radius_m,
    )
    effects = _expand_per_body(effects, bodies)
    tethers = _parse_tethers(top.get("tethers", {}), bodies)
    graph = topology.build(bodies, tethers)
    _check_forest(bodies, tethers, graph)
    orbit = _parse_orbit(top["orbit"], bodies, mu, central.radius_m) if "orbit" in top else None
    _check_above_surface(bodies, orbit, central, origin_singular)
    _check_epoch(effects, epoch)
    graph = graph.with_layout(bodies, tethers, orbit)
    tethers = _check_layout(bodies, tethers, orbit, mu, graph)

    duration_raw = _required(top, "duration", "", "a time (e.g. '6000 s'), 'N orbits' or 'N spins'")
    duration_s, duration_orbits = _parse_duration(_spins_to_seconds(duration_raw, orbit))
    if duration_orbits is not None:
        _check_orbits_duration(top["duration"], orbit, bodies, mu)
    integrator = _parse_integrator(top.get("integrator", {}))
    stop = _parse_stop(top["stop"], central) if "stop" in top else None
    if stop is not None:
        _check_stop_altitude(stop, orbit, bodies, central)
    scene = Scene(
        name=name,
        duration_s=duration_s,
        duration_orbits=duration_orbits,
        central_body=central,
        effects=effects,
        bodies=bodies,
        tethers=tethers,
        orbit=orbit,
        integrator=integrator,
        output=OutputSpec(),  # filled below: checking output times needs the resolved duration
        description=description,
        epoch=epoch,
        stop=stop,
        continue_from=continue_from,
        source=source,
        graph=graph,
    )
    output = _parse_output(_required(top, "output", "", "a table with one of step, count, times"), scene.duration_seconds())
    scene = dataclasses.replace(scene, output=output)
    _check_run(scene)
    return scene


_SPINS_RE = re.compile(r"^\s*([+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)\s*spins?\s*$")


def _spins_to_seconds(raw: Any, orbit) -> Any:
    """``duration = "N spins"``: N turns of ``[orbit] spin`` (2 pi / |rate| each), as seconds."""
    import math

    match = _SPINS_RE.match(raw) if isinstance(raw, str) else None
    if match is None:
        return raw
    spin = getattr(orbit, "spin", None)
    if spin is None:
        raise SceneError("duration", "a time or 'N orbits': 'N spins' needs [orbit] spin to say which spin", repr(raw))
    n = float(match.group(1))
    if not (math.isfinite(n) and n > 0.0):
        raise SceneError("duration", "a number of spins > 0", repr(raw))
    return f"{n * 2.0 * math.pi / abs(spin.rate_rad_s)!r} s"
