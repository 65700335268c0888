"""The checks of the whole scene made at load: its graph (a forest of bodies and tethers), the
initial layout every body needs, and what the kernel, the initial layout and the integrators can run
(``_check_run``, whose docstring lists the checks that stay where a run is prepared)."""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from ..errors import SceneError
from ..model import topology
from ..units import shown
from .keys import _NOTHING
from .data import (
    EQUILIBRIUM,
    MAX_SANE_STRAIN,
    Body,
    InitialShape,
    Orbit,
    Scene,
    Tether,
    _period_of_state,
    _reference_state,
)


def _check_forest(bodies: tuple[Body, ...], tethers: tuple["Tether", ...], graph: topology.Graph) -> None:
    """Bodies and tethers must form a forest: the graph's first cut tether (it joins two bodies
    already joined) closes a loop, refused naming it; attachment points only on rigid bodies."""
    if graph.cut:
        t = graph.cut[0]
        raise SceneError(
            f"tethers.{t.name}",
            "tethers forming a tree (no closed loop: the elimination runs towards one root)",
            f"tether {t.name!r} closes a loop between {t.from_body!r} and {t.to_body!r}",
        )
    by_name = {b.name: b for b in bodies}
    for t in tethers:
        for end, key in ((t.from_body, "from_point"), (t.to_body, "to_point")):
            point = t.from_point_m if key == "from_point" else t.to_point_m
            if point is not None and by_name[end].rigid is None:
                raise SceneError(
                    f"tethers.{t.name}.{key}", f"a rigid body at this end (give bodies.{end}.rigid), or no {key}",
                    f"an attachment point on the point mass {end!r}",
                )


def _check_layout(bodies, tethers, orbit, mu, graph: topology.Graph) -> tuple[Tether, ...]:
    """Check that every body can be placed; fill or forbid each tether's initial shape."""
    if orbit is None:
        if not any(b.has_state for b in bodies):
            raise SceneError(
                "orbit",
                "an [orbit] table giving the initial orbit, or explicit states for the bodies",
                "neither an [orbit] table nor any body with position/velocity, elements or fixed position",
            )
        for b in bodies:
            if not b.has_state:
                raise SceneError(
                    f"bodies.{b.name}",
                    "an initial state (position and velocity, elements, or fixed with position)",
                    "none",
                    hint="without an [orbit] table every body needs its own state; add [orbit] to "
                    "place it from the tether shapes",
                )
    steps, unplaced = graph.layout, graph.unplaced
    if unplaced:
        raise SceneError(
            f"bodies.{unplaced[0]}",
            "an explicit initial state, or a chain of tethers joining it to the orbit reference "
            f"{orbit.reference!r} or to a body with an explicit state",
            "neither",
        )
    by_name = {b.name: b for b in bodies}
    closing = {s.tether for s in steps if s.end is None}
    result = []
    for t in tethers:
        path = f"tethers.{t.name}"
        if t.initial is not None and t.initial.shape == EQUILIBRIUM and t.name not in closing:
            raise SceneError(
                f"{path}.initial.shape",
                "'straight' or 'rods' for a tether laid from one end ('equilibrium' needs both ends "
                "placed: the root fixed and the end mass with a position)",
                repr(EQUILIBRIUM),
            )
        if t.name in closing:
            if t.initial is not None and t.initial.shape != EQUILIBRIUM:
                raise SceneError(
                    f"{path}.initial",
                    "no initial shape: both ends are placed before this tether is laid, so it starts "
                    "straight between them",
                    "an [initial] table",
                )
            ends = (by_name[t.from_body].state(mu), by_name[t.to_body].state(mu))
            if ends[0] is not None and ends[1] is not None:
                _check_end_distance(t, float(np.linalg.norm(ends[1][0] - ends[0][0])), path)
        elif t.initial is None:
            t = dataclasses.replace(t, initial=InitialShape())
        result.append(t)
    return tuple(result)


def _check_run(scene: Scene) -> None:
    """The checks that need the whole scene and its graph: what the kernel, the initial layout and
    the integrators can run (they were made when a run was prepared; they are scene content).

    Checks that stay where the run is prepared, and why:

    * the statics solve of shape 'equilibrium' (tetherlab/initial/statics.py) and the Newton
      solves of orbit.motion 'equilibrium' and 'quasi-static' (tetherlab/initial/equilibrium.py):
      whether they converge is known only by solving them on the built model;
    * a rigid body's attitude relative to an undefined orbit frame (r x v = 0) and a tether
      straight between two attachment points at the same place (tetherlab/initial/forest.py):
      they need the laid-out positions and attitudes;
    * stop.altitude above the root body's start, and "N orbits" of a reference that is not on a
      closed orbit (pipeline.prepare): they need the laid-out initial state (the [orbit] itself is
      checked at load, in _check_orbits_duration);
    * the formulation (pipeline._formulation) and what follows from it (integrator.method 'abm',
      integrator.time_element): the formulation layer resolves them from the built model;
    * a star of point masses with a tether between two placed ends whose far end is placed by the
      [orbit] rather than by its own state (tetherlab/initial/star.py): the star layout cannot lay
      it, yet such a scene is a valid scene (it loads, round-trips and may be edited into a
      runnable one), so it is refused when it is laid out;
    * the memory and disk a run needs (tetherlab/resources.py): a property of the machine;
    * per-effect checks made when an effect packs its parameters against the kernel bodies
      (tetherlab/forces/).
    """
    graph = scene.graph
    for c, fixed in enumerate(graph.fixed):
        if len(fixed) > 1:
            raise SceneError(
                f"bodies.{fixed[1]}.fixed", "at most one fixed body in a group of bodies joined by tethers "
                "(the kernel holds only the root of a tree at rest)", f"true on {list(fixed)}",
            )  # fmt: skip
    tethers = scene.tethers
    nq = tethers[0].quadrature if tethers else 2
    if any(t.quadrature != nq for t in tethers):
        raise SceneError(
            "tethers.*.quadrature", "the same quadrature for every tether", str([t.quadrature for t in tethers])
        )
    by_name = {b.name: b for b in scene.bodies}
    mu = scene.central_body.mu_m3_s2
    orbit = scene.orbit
    if not graph.simple:
        if orbit is not None and orbit.motion in ("equilibrium", "quasi-static"):
            raise SceneError("orbit.motion", "'corotating' or 'translating' for a scene with rigid bodies or a tree other "
                             "than a star (the relative-equilibrium solve handles stars of point masses)", repr(orbit.motion))  # fmt: skip
        for k in graph.placement_order:
            t = tethers[k]
            if t.initial is not None and t.initial.shape == EQUILIBRIUM:
                raise SceneError(f"tethers.{t.name}.initial.shape", "'straight' or 'rods' in a tree other than a star of "
                                 "point masses (the statics solve handles one tether on a fixed root)", "'equilibrium'")  # fmt: skip
    if any(t.initial is not None and t.initial.shape == EQUILIBRIUM for t in tethers):
        root = by_name[graph.roots[0]]
        t = tethers[0]
        if not root.fixed:
            raise SceneError(
                f"bodies.{root.name}.fixed", "true: shape 'equilibrium' holds the tether between a fixed root and its end mass",
                "false",
            )  # fmt: skip
        if len(tethers) != 1:
            raise SceneError(f"tethers.{t.name}.initial.shape", "'equilibrium' only in a scene with a single tether",
                             f"{len(tethers)} tethers")  # fmt: skip
        if t.initial is not None and t.initial.release is not None and not any(e.name == "uniform_gravity" for e in scene.effects):
            raise SceneError(
                f"tethers.{t.name}.initial.release", "a scene with uniform_gravity in [effects]: the release perturbs "
                "the tether hanging under it", "no uniform_gravity",
            )  # fmt: skip
        tip = by_name[t.to_body].state(mu)
        if tip is not None and np.any(tip[1] != 0.0):
            raise SceneError(
                f"bodies.{t.to_body}.velocity", "[0, 0, 0] m/s: a static equilibrium starts at rest", str(tip[1].tolist())
            )
    for k, t in enumerate(tethers):
        if t.reel is not None:
            _check_reel(scene, t, graph.tethers[k], by_name)
    # events (kernel/events.py::event_components): the stop altitude and every rod of a
    # tension-only tether
    events = (["stop"] if scene.stop is not None and scene.stop.altitude_m is not None else []) + (
        ["slack"] if any(t.tension_only for t in tethers) else []
    )
    if events and scene.integrator.method.startswith("scipy:"):
        raise SceneError(
            "integrator.method", "a native method (dop853 or radau5): this scene has events "
            f"({', '.join(sorted(events))}) that only they locate",
            repr(scene.integrator.method),
        )  # fmt: skip


def _check_reel(scene: Scene, t: Tether, oriented, by_name: dict) -> None:
    """What a reel can run today (docs/deployment.md 7): at its body's attachment of the tether, on
    a point mass, in the Cowell formulation, from a straight start."""
    path = f"tethers.{t.name}.reel"
    if oriented.reversed:
        raise SceneError(
            path, f"a reel at the end of the tether its body holds it by: {t.from_body!r} hangs from this tether, so "
            f"its attachment end is 'to' ({t.to_body!r}); write the tether from {t.to_body!r} to {t.from_body!r}",
            f"a reel at 'from' = {t.from_body!r}",
        )  # fmt: skip
    _check_reel_hub(t, by_name[t.from_body], path)
    if scene.integrator.formulation != "cowell":
        raise SceneError("integrator.formulation", "'cowell' for a scene with a reel (its rods are born and retired "
                         "between segments of the Cowell state)", repr(scene.integrator.formulation))  # fmt: skip
    if t.initial is not None and t.initial.shape != "straight":
        raise SceneError(f"tethers.{t.name}.initial.shape", "'straight' for a tether paid out by a reel",
                         repr(t.initial.shape))  # fmt: skip


#: the exit point and the spool radius of a reel on a rigid body, at most this many times the body's
#: size sqrt(tr J / m) (a solid sphere of radius r: 1.1 r): farther out the "rigid" body would be
#: mostly a boom the inertia tensor does not describe
REEL_SIZE_FACTOR = 10.0


def _check_reel_hub(t: Tether, body, path: str) -> None:
    """The keys of a reel on a rigid body: present there (exit point, direction, spool radius; a
    drum's axis), absent on a point mass; the point and the radius within the body's size."""
    r = t.reel
    hub_keys = {"point": r.point_m, "exit_direction": r.exit_direction, "spool_radius": r.spool_radius_m or None,
                "spool_axis": r.spool_axis}  # fmt: skip
    if body.rigid is None:
        for key, value in hub_keys.items():
            if value is not None:
                raise SceneError(f"{path}.{key}", f"no {key!r} for a reel on the point mass {body.name!r} (only a reel on "
                                 "a rigid body has an exit point, direction and spool)", shown(value))  # fmt: skip
        return
    need = ("point", "exit_direction", "spool_radius") + (("spool_axis",) if r.exit == "drum" else ())
    for key in need:
        if hub_keys[key] is None:
            what = {"point": "the exit point in body axes from the centre of mass (e.g. ['0 m', '0 m', '1 m'])",
                    "exit_direction": "the direction the line leaves the exit, body axes (e.g. [0, 0, 1])",
                    "spool_radius": "the radius of the spool the stored tether is wound on (e.g. '0.3 m')",
                    "spool_axis": "the drum's axis, body axes, perpendicular to exit_direction"}[key]  # fmt: skip
            raise SceneError(f"{path}.{key}", f"{what} for a reel on the rigid body {body.name!r}", _NOTHING)
    if r.exit == "drum" and r.spool is not None and not math.isclose(r.spool_radius_m, r.spool.drum_radius_m, rel_tol=1e-12):
        # under a spool law the drum turns at L'/R (R the torque's arm) and its turns, the ring of
        # radius R_s, move at the rim speed L' only if R_s = R (docs/deployment.md 9.7)
        raise SceneError(f"{path}.spool_radius", f"the drum_radius ({r.spool.drum_radius_m:.6g} m) for a drum under "
                         f"law {r.law!r} on the rigid body {body.name!r} (its turns are wound at the rim)",
                         f"{r.spool_radius_m:.6g} m")  # fmt: skip
    J = np.array(body.rigid.inertia_kg_m2, float)
    size = math.sqrt(float(np.trace(J)) / body.mass_kg)
    limit = REEL_SIZE_FACTOR * size
    dist = math.sqrt(sum(x * x for x in r.point_m))
    if dist > limit:
        raise SceneError(f"{path}.point", f"an exit point within {REEL_SIZE_FACTOR:g} times the body's size sqrt(tr J/m) "
                         f"= {size:.4g} m of its centre of mass: at most {limit:.4g} m", f"{dist:.6g} m from it")  # fmt: skip
    if r.spool_radius_m > limit:
        raise SceneError(f"{path}.spool_radius", f"a spool radius within {REEL_SIZE_FACTOR:g} times the body's size "
                         f"sqrt(tr J/m) = {size:.4g} m: at most {limit:.4g} m", f"{r.spool_radius_m:.6g} m")  # fmt: skip


def _check_end_distance(t: Tether, distance: float, path: str) -> None:
    if distance == 0.0:
        raise SceneError(f"{path}.to", f"a body at another position than {t.from_body!r}", f"{t.to_body!r} at the same position")
    strain = distance / t.length_m - 1.0
    if strain > MAX_SANE_STRAIN:
        raise SceneError(
            f"{path}.length",
            f"at least {distance / (1.0 + MAX_SANE_STRAIN):.6g} m, since the ends are {distance:.6g} m apart "
            f"and MAX_SANE_STRAIN is {MAX_SANE_STRAIN:.0%}",
            f"{t.length_m:.6g} m: ends farther apart than the tether can stretch (strain {strain:.3%})",
        )


def _check_orbits_duration(raw: Any, orbit: Orbit | None, bodies, mu: float) -> None:
    state = _reference_state(orbit, bodies, mu)
    if state is None:
        raise SceneError("duration", "a time: 'N orbits' needs an [orbit] table to say which orbit", repr(raw))
    try:
        _period_of_state(mu, *state)
    except ValueError:
        raise SceneError("duration", "a time: the reference orbit is not closed (e >= 1), so it has no period", repr(raw)) from None


def _check_epoch(effects, epoch: str | None) -> None:
    """Effects (or effect options) that need the scene's epoch, refused at load without one: the
    registry says which (``EffectSpec.dated``, ``ParamSpec.dated``: forces/registry.py)."""
    if epoch is not None:
        return
    from ..forces import EFFECTS

    for use in effects:
        spec = EFFECTS[use.name]
        if spec.dated:
            raise SceneError("epoch", f"an ISO date (TDB), e.g. '2026-01-01T00:00:00', for effect {use.name!r} "
                             f"(its model is dated)", _NOTHING)  # fmt: skip
        for pname, pspec in spec.params.items():
            value = use.params_si.get(pname)
            if pspec.dated and value in pspec.dated:
                raise SceneError("epoch", f"an ISO date (TDB), e.g. '2026-01-01T00:00:00', for effects.{use.name}."
                                 f"{pname} = {value!r} (its model is dated)", _NOTHING)  # fmt: skip


def _check_above_surface(bodies, orbit: Orbit | None, central, singular: list[str]) -> None:
    """Every initial state given at load (the [orbit]'s, each body's own) above the central body's
    surface, when the scene has its gravity: an orbit inside the Earth is a mistake (typically a
    semi-major axis written for an altitude), never a scene to run."""
    if not singular:
        return
    mu, radius = central.mu_m3_s2, central.radius_m
    states = []
    with np.errstate(all="ignore"):  # a non-finite state is refused below (height NaN)
        if orbit is not None and (orbit.position_m is not None or orbit.elements is not None):
            states.append(("orbit", orbit.elements is not None, orbit.state(mu)[0]))
        for b in bodies:
            if b.has_state:
                states.append((f"bodies.{b.name}", b.elements is not None, b.state(mu)[0]))
    for path, by_elements, r in states:
        height = float(np.linalg.norm(r)) - radius
        if not height >= 0.0:
            key = f"{path}.elements.a" if by_elements else f"{path}.position"
            hint = ("for an altitude write elements.altitude (or perigee_altitude / apogee_altitude) instead of a"
                    if by_elements else None)
            raise SceneError(
                key, f"an initial position above the surface of the central body {central.name!r} "
                f"(radius {radius / 1e3:.6g} km)", f"a start {-height / 1e3:.6g} km below it", hint=hint,
            )  # fmt: skip


def _check_stop_altitude(stop, orbit: Orbit | None, bodies, central) -> None:
    """stop.altitude below the altitude the run starts from (the reference orbit's initial
    altitude; the run's own check on the laid-out root body stays in pipeline.prepare)."""
    if stop.altitude_m is None:
        return
    state = _reference_state(orbit, bodies, central.mu_m3_s2)
    if state is None:
        return
    start = float(np.linalg.norm(state[0])) - central.radius_m
    if not stop.altitude_m < start:
        raise SceneError("stop.altitude", f"an altitude below the start of the run ({start / 1e3:.6g} km above "
                         f"the central body's radius): the run would stop at once", f"{stop.altitude_m / 1e3:.6g} km")  # fmt: skip
