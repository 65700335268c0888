"""Run a scene: build the model, lay out the initial state, integrate, compute diagnostics.

``simulate(scene)`` is the whole pipeline behind ``tetherlab run``.  Everything here runs once per
run; the only per-step work happens inside the compiled integrator and right-hand side.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from . import diagnostics as diag
from .errors import SceneError
from .forces import effect as effect_spec
from .formulations.cowell import cowell_rhs

from .kernel.events import event_components, system_events
from .kernel.layout import (
    FAIL_TEXT,
    H_EV_STOP_R,
    H_FAIL_CODE,
    H_FAIL_EFFECT,
    H_FAIL_EFFECT_T,
    H_FAIL_ROD,
    H_FAIL_T,
    H_FAIL_VAL,
)
from .orbits.kepler import elements_to_cartesian
from .result import Result
from .system import (
    BodySpec,
    ControlSpec,
    Model,
    RigidSpec,
    TetherSpec,
    WheelSpec,
    build_model,
    center_of_mass,
    chain_state,
    tolerance_scales,
)


class SimulationError(RuntimeError):
    """A run that stopped before its end.  ``.result`` holds every output computed before it."""

    def __init__(self, message: str, result: Result):
        super().__init__(message)
        self.result = result


@dataclass
class Prepared:
    """Everything the integrator needs, built from a scene (exposed for studies and benchmarks)."""

    model: Model
    y0: np.ndarray
    t_out: np.ndarray
    atol: np.ndarray
    rtol: float
    method: str
    h_max: float
    max_steps: int
    ref_radius_m: float
    ref_period_s: float
    sides: list[float]
    event_names: tuple = ()  # components of kernel/events.py::system_events for this scene
    event_terminal: tuple = ()
    # shape 'equilibrium': the external force R_f on the end mass that holds the starting shape
    # (tetherlab.statics); the run itself applies it only if the scene names it (applied_force)
    holding_force_N: np.ndarray | None = None
    formulation: str = "cowell"  # "cowell", "cowell-orbit", "dromo-sigma" (point mass) or "dromo-time"
    mu_m3_s2: float = 0.0
    time_element: str = "none"  # DROMO sigma form: "none" (tau) or "linear" (scene.IntegratorSpec)


def _state_of(entity, mu: float):
    """(r, v) of a body or orbit block with position/velocity or elements, else None."""
    if getattr(entity, "elements", None) is not None:
        el = entity.elements
        r, v = elements_to_cartesian(mu, el.a_m, el.e, el.i_rad, el.raan_rad, el.argp_rad, el.nu_rad)
        return np.asarray(r, float), np.asarray(v, float)
    if getattr(entity, "position_m", None) is not None:
        v = entity.velocity_m_s if entity.velocity_m_s is not None else (0.0, 0.0, 0.0)
        return np.asarray(entity.position_m, float), np.asarray(v, float)
    return None


@dataclass
class Topology:
    """The scene's graph as the kernel runs it (docs/scenes.md, "Body order in the kernel").

    ``bodies``: BodySpec in kernel order (0 the first root, 1 + k the child end of tether k, then
    the other roots); ``parents[k]``/``children[k]``: the body names at tether k's root side and
    far end; ``reversed[k]``: the scene writes tether k child -> parent.  ``simple``: a star of
    point masses around body 0 written from it (the original layout code applies, bit for bit).
    """

    bodies: list
    tethers: list
    parents: list
    children: list
    reversed: list
    roots: list
    simple: bool


def _topology(scene) -> Topology:
    """The forest of the scene (validated at load: no loops, attachments on rigid bodies only).

    The root of each connected component is its fixed body, else the `from` body of its first
    tether in file order, else (no tether) the body itself.  Tethers keep file order; each is
    oriented from its root side (reversed when the scene writes it the other way)."""
    names = [b.name for b in scene.bodies]
    tethers = list(scene.tethers)
    adj: dict[str, list] = {n: [] for n in names}
    for k, t in enumerate(tethers):
        adj[t.from_body].append((k, t.to_body))
        adj[t.to_body].append((k, t.from_body))
    comp: dict[str, int] = {}
    members: list[list[str]] = []
    for n in names:
        if n in comp:
            continue
        stack = [n]
        comp[n] = len(members)
        group = []
        while stack:
            x = stack.pop()
            group.append(x)
            for _, y in adj[x]:
                if y not in comp:
                    comp[y] = comp[n]
                    stack.append(y)
        members.append(group)
    roots = []
    for c, group in enumerate(members):
        fixed = [b.name for b in scene.bodies if b.name in group and b.fixed]
        if len(fixed) > 1:
            raise SceneError(
                f"bodies.{fixed[1]}.fixed", "at most one fixed body in a group of bodies joined by tethers "
                "(the kernel holds only the root of a tree at rest)", f"true on {fixed}",
            )
        first = next((t for t in tethers if t.from_body in group), None)
        root = fixed[0] if fixed else (first.from_body if first is not None else next(n for n in names if n in group))
        roots.append(root)
    # orient every tether away from its component's root
    parents = [None] * len(tethers)
    children = [None] * len(tethers)
    for root in roots:
        stack = [root]
        seen = {root}
        while stack:
            x = stack.pop()
            for k, y in adj[x]:
                if y in seen:
                    continue
                seen.add(y)
                parents[k] = x
                children[k] = y
                stack.append(y)
    rev = [parents[k] != t.from_body for k, t in enumerate(tethers)]
    by_name = {b.name: b for b in scene.bodies}
    root0 = roots[comp[names[0]]] if tethers or len(names) == 1 else roots[comp[names[0]]]
    other_roots = [r for r in roots if r != root0]
    order = [root0] + list(children) + other_roots
    bodies = [_body_spec(by_name[n]) for n in order]
    simple = (
        not other_roots
        and not any(rev)
        and all(parents[k] == root0 for k in range(len(tethers)))
        and all(b.rigid is None for b in scene.bodies)
    )
    return Topology(bodies, tethers, parents, children, rev, [root0] + other_roots, simple)


def _body_spec(body) -> BodySpec:
    r = body.rigid
    if r is None:
        return BodySpec(body.name, body.mass_kg, bool(body.fixed))
    wheels = []
    for w in r.wheels:
        if isinstance(w.torque, str):
            mode, tau, times, values = "control", 0.0, (), ()
        elif isinstance(w.torque, tuple):
            mode, tau, (times, values) = "table", 0.0, w.torque
        else:
            mode, tau, times, values = "constant", float(w.torque), (), ()
        wheels.append(WheelSpec(
            name=w.name, axis=tuple(w.axis), inertia_kg_m2=w.inertia_kg_m2, speed_rad_s=w.speed_rad_s,
            max_speed_rad_s=w.max_speed_rad_s or 0.0, max_torque_N_m=w.max_torque_N_m or 0.0, mode=mode,
            torque_N_m=tau, times_s=tuple(times), values_N_m=tuple(values),
        ))  # fmt: skip
    control = None
    if r.control is not None:
        c = r.control
        control = ControlSpec(c.target, c.kp_N_m, c.kd_N_m_s, tuple(c.quaternion) if c.quaternion else (1.0, 0.0, 0.0, 0.0))
    return BodySpec(body.name, body.mass_kg, bool(body.fixed), RigidSpec(r.inertia_kg_m2, tuple(wheels), control))


def prepare(scene, *, outputs_in_memory: bool = True, out_dir=None) -> Prepared:
    """Build the model and initial state.  First checks that the run fits the machine
    (tetherlab/resources.py): all outputs in memory (``simulate``), or streamed to ``out_dir``."""
    from .resources import check_scene

    check_scene(scene, outputs_in_memory=outputs_in_memory, out_dir=out_dir)
    mu = scene.central_body.mu_m3_s2
    central = {"mu_m3_s2": mu, "radius_m": scene.central_body.radius_m}
    effects = [(effect_spec(e.name), e.params_si) for e in scene.effects]
    topo = _topology(scene)
    root_name = topo.roots[0]
    tethers = topo.tethers
    root = scene.body(root_name)
    zero = (0.0, 0.0, 0.0)
    specs = []
    for k, t in enumerate(tethers):
        a_pt = t.from_point_m or zero
        b_pt = t.to_point_m or zero
        specs.append(TetherSpec(
            name=t.name,
            rods=t.rods,
            length_m=t.length_m,
            ea_n=t.EA_N,
            mass_kg=t.mass_kg,
            damping_n_s=t.damping_N_s,
            model=t.model,
            tip_mass_kg=scene.body(topo.children[k]).mass_kg,
            tip_name=topo.children[k],
            tension_only=t.tension_only,
            diameter_m=t.diameter_m,
            parent=topo.parents[k],
            from_point_m=tuple(b_pt if topo.reversed[k] else a_pt),
            to_point_m=tuple(a_pt if topo.reversed[k] else b_pt),
            reversed=topo.reversed[k],
        ))  # fmt: skip
    nq = tethers[0].quadrature if tethers else 2
    if any(t.quadrature != nq for t in tethers):
        raise SceneError(
            "tethers.*.quadrature", "the same quadrature for every tether", str([t.quadrature for t in tethers])
        )
    model = build_model(
        root_mass_kg=root.mass_kg,
        tethers=specs,
        effects=effects,
        central=central,
        quadrature=nq,
        root_fixed=bool(getattr(root, "fixed", False)),
        root_name=root_name,
        epoch=scene.epoch,
        duration_s=_duration_hint(scene),
        bodies=topo.bodies,
    )
    # The relative equilibrium is a rigid rotation under the conservative effects; a velocity-
    # dependent or time-dependent force (electrodynamic, drag, third bodies) has none, so the
    # equilibrium is solved without them and they act from t = 0 (docs/scenes.md, orbit.motion).
    eq_model = model
    if any(not spec.conservative for spec, _ in effects):
        eq_model = build_model(
            root_mass_kg=root.mass_kg,
            tethers=specs,
            effects=[(spec, prm) for spec, prm in effects if spec.conservative],
            central=central,
            quadrature=nq,
            root_fixed=bool(getattr(root, "fixed", False)),
            root_name=root_name,
            bodies=topo.bodies,
        )
    if topo.simple:
        y0, r_ref, v_ref, sides = _initial_state(scene, model, root_name, tethers, mu, eq_model)
    else:
        from .layout_forest import forest_state

        y0, r_ref, v_ref, sides = forest_state(scene, model, topo, mu)
    holding = None
    if any(t.initial is not None and t.initial.shape == "equilibrium" for t in tethers):
        y0, holding = _static_start(scene, root, tethers, specs, effects, central, nq, y0)
    stop_radius = 0.0
    if scene.stop is not None and scene.stop.altitude_m is not None:
        stop_radius = scene.central_body.radius_m + scene.stop.altitude_m
        if not float(np.linalg.norm(y0[:3])) > stop_radius:
            raise SceneError(
                "stop.altitude", f"an altitude below the root body's initial altitude "
                f"({float(np.linalg.norm(y0[:3])) - scene.central_body.radius_m:.6g} m)",
                f"{scene.stop.altitude_m:.6g} m",
            )
    model.p[H_EV_STOP_R] = stop_radius
    event_names, event_terminal = event_components(model, stop_radius)
    if event_names and scene.integrator.method.startswith("scipy:"):
        raise SceneError(
            "integrator.method", "a native method (dop853 or radau5): this scene has events "
            f"({', '.join(sorted({n.split('.')[0] for n in event_names}))}) that only they locate",
            repr(scene.integrator.method),
        )

    # reference orbit: radius and Keplerian period (for "N orbits" and the tolerance scales)
    rr = float(np.linalg.norm(r_ref))
    # A scene with an [orbit] or the central body's gravity has an orbit (and "N orbits"); a
    # surface-frame scene (uniform_gravity, a nail possibly at the origin) has no period and a
    # time unit of 1 s for the velocity tolerances.
    orbital = (scene.orbit is not None or any(e.name == "central_gravity" for e in scene.effects)) and rr > 0 and mu > 0
    energy = 0.5 * float(v_ref @ v_ref) - mu / rr if orbital else 0.0
    if orbital and energy < 0:
        a = -mu / (2 * energy)
        period = 2 * math.pi * math.sqrt(a**3 / mu)
    else:
        period = float("nan")
    t_unit = math.sqrt(rr**3 / mu) if orbital else 1.0
    ref_len = rr if orbital else max(rr, max((t.length_m for t in tethers), default=1.0))
    atol = scene.integrator.atol * tolerance_scales(model, ref_len, t_unit)

    duration = scene.duration_s
    if duration is None:  # given in orbits
        if not math.isfinite(period):
            raise SceneError(
                "duration", "a time (e.g. '10 d') for a reference that is not on a closed orbit",
                f"{scene.duration_orbits} orbits",
            )
        duration = scene.duration_orbits * period
    t_out = _output_times(scene.output, duration)
    h_max = scene.integrator.max_step_s or 0.0
    # events are located in time: with DROMO they run the time form (docs/dromo.md section 10)
    formulation = _formulation(scene, model, tethers, y0, bool(event_names))
    if scene.integrator.method == "abm" and formulation != "dromo-sigma":
        raise SceneError(
            "integrator.method", "'abm' only with formulation 'dromo' on a single body without events (the DROMO "
            "sigma form; docs/integrators.md section 8)", f"'abm' with the {formulation} formulation",
        )
    if scene.integrator.time_element != "none":
        if formulation != "dromo-sigma":
            raise SceneError(
                "integrator.time_element", "'none' unless the formulation is 'dromo' on a single body without events "
                "(the time element is a variable of DROMO's sigma form; docs/dromo.md section 11)",
                f"{scene.integrator.time_element!r} with the {formulation} formulation",
            )  # fmt: skip
    return Prepared(
        model=model,
        y0=y0,
        t_out=t_out,
        atol=atol,
        rtol=scene.integrator.rtol,
        method=scene.integrator.method,
        h_max=h_max,
        max_steps=scene.integrator.max_steps or 10**9,
        ref_radius_m=rr,
        ref_period_s=period,
        sides=sides,
        event_names=tuple(event_names),
        event_terminal=tuple(event_terminal),
        holding_force_N=holding,
        formulation=formulation,
        mu_m3_s2=mu,
        time_element=scene.integrator.time_element,
    )


def _event_args(prep) -> dict:
    """The event function and its flags, only when the scene has events (scipy methods cannot
    take them, so a scene with events names a native method; the driver says so otherwise)."""
    if not prep.event_names:
        return {}
    return {"event": system_events, "n_events": len(prep.event_names), "terminal": prep.event_terminal}


def _static_start(scene, root, tethers, specs, effects, central, nq, y0):
    """Initial state of a tether that starts in static equilibrium between its placed ends.

    The root must be fixed and the end mass placed at rest; tetherlab.statics solves for the
    rods and for the holding force R_f (docs/catenary.md).  Returns (y0, R_f).
    """
    from .statics import held_model, solve

    t = tethers[0]
    path = f"tethers.{t.name}.initial.shape"
    if not root.fixed:
        raise SceneError(
            f"bodies.{root.name}.fixed", "true: shape 'equilibrium' holds the tether between a fixed root and its end mass",
            "false",
        )
    if len(tethers) != 1:
        raise SceneError(path, "'equilibrium' only in a scene with a single tether", f"{len(tethers)} tethers")
    tip_r, tip_v = _state_of(scene.body(t.to_body), scene.central_body.mu_m3_s2)
    if np.any(tip_v != 0.0):
        raise SceneError(
            f"bodies.{t.to_body}.velocity", "[0, 0, 0] m/s: a static equilibrium starts at rest", str(tip_v.tolist())
        )
    r0 = y0[:3]
    orbital = any(e.name == "central_gravity" for e in scene.effects) and np.linalg.norm(r0) > 0
    down = -r0 / np.linalg.norm(r0) if orbital else np.array([0.0, 0.0, -1.0])  # for the first guess
    held = held_model(specs[0], effects, central, quadrature=nq, root_name=root.name)
    try:
        eq = solve(held, r0, tip_r, down=down)
    except ValueError as exc:
        raise SceneError(path, "a tether with a static equilibrium between its placed ends", str(exc)) from None
    return eq.y, eq.holding_force_N


def _formulation(scene, model: Model, tethers, y0: np.ndarray, events: bool = False) -> str:
    """The formulation the integrator runs, checked against the scene (docs/dromo.md section 7)."""
    name = scene.integrator.formulation
    if name == "cowell":
        return "cowell"
    key = "integrator.formulation"
    if name == "cowell-orbit":
        if model.root_fixed:
            raise SceneError(key, "'cowell' for a scene whose root body is fixed (it has no orbit to turn with)", repr(name))
        if model.has_attitude:
            raise SceneError(key, "'cowell' for a scene with rigid bodies (the attitude and wheel states are not "
                             "carried into the turning frame)", repr(name))  # fmt: skip
        h = y0.size // 2
        if not float(np.linalg.norm(np.cross(y0[:3], y0[h : h + 3]))) > 0.0:
            raise SceneError(key, "'cowell' for a root body with no orbital motion about the centre (r x v = 0: "
                             "no frame to turn with)", repr(name))  # fmt: skip
        return "cowell-orbit"
    if "central_gravity" not in model.effect_names:
        # DROMO integrates the Kepler motion about the central body analytically: without
        # central_gravity in [effects] it would add a force the scene did not name
        raise SceneError(key, "'cowell' when [effects] does not name central_gravity (DROMO builds it in)", repr(name))
    if model.root_fixed:
        raise SceneError(key, "'cowell' for a scene whose root body is fixed (it has no orbit)", repr(name))
    if model.has_attitude:
        # DROMO's time form integrates the root's orbit in elements; the attitude and wheel blocks
        # are not carried through its state conversion yet
        raise SceneError(key, "'cowell' for a scene with rigid bodies (attitude and wheel states)", repr(name))
    if name == "dromo" and not tethers and not events and len(model.bodies) == 1:
        if scene.integrator.max_step_s is not None:
            raise SceneError(
                "integrator.max_step", "no max_step with formulation 'dromo' on a point mass (the independent "
                "variable is the ideal anomaly; use 'dromo-time' to bound the time step)", f"{scene.integrator.max_step_s} s",
            )
        h = y0.size // 2
        r, v = y0[:3], y0[h : h + 3]
        energy = 0.5 * float(v @ v) - scene.central_body.mu_m3_s2 / float(np.linalg.norm(r))
        if not energy < 0:
            raise SceneError(key, "'dromo-time' for an orbit that is not elliptic (the sigma form schedules its "
                             "outputs on the osculating ellipse)", repr(name))  # fmt: skip
        return "dromo-sigma"
    return "dromo-time"


def _duration_hint(scene) -> float | None:
    """The run length for effects fitted over the run (before the initial state is laid out)."""
    try:
        return scene.duration_seconds()
    except ValueError:  # "N orbits" without an orbit: refused below with a SceneError
        return None


def _output_times(output, duration: float) -> np.ndarray:
    if output.times_s is not None:
        t = np.asarray(output.times_s, float)
        if t[0] > 0:
            t = np.concatenate([[0.0], t])
        return t
    if output.count is not None:
        return np.linspace(0.0, duration, int(output.count))
    n = int(math.floor(duration / output.step_s + 1e-9))
    t = output.step_s * np.arange(n + 1)
    if duration - t[-1] > 1e-9 * max(duration, 1.0):
        t = np.concatenate([t, [duration]])
    return t


def _initial_state(scene, model: Model, root_name: str, tethers, mu: float, eq_model: Model | None = None):
    from .diagnostics import direction_from_angles

    root = scene.body(root_name)
    root_state = _state_of(root, mu)
    orbit = scene.orbit
    sides = []
    # 1. every tether whose both ends carry explicit states: a straight line between them
    explicit_tips = [_state_of(scene.body(t.to_body), mu) for t in tethers]
    if tethers and root_state is not None and all(s is not None for s in explicit_tips):
        r0, v0 = root_state
        dirs, strains = [], []
        rod_vel = []
        for t, (rt, vt) in zip(tethers, explicit_tips):
            span = rt - r0
            dist = float(np.linalg.norm(span))
            dirs.append(np.tile(span / dist, (t.rods, 1)))
            strains.append(dist / t.length_m - 1.0)
            rod_vel.append((vt - v0) / (2 * math.sqrt(3) * t.rods))
            sides.append(1.0)
        y0 = chain_state(model, r0, v0, dirs, strains, None)
        h = y0.size // 2
        for k, sl in enumerate(model.rod_slices):
            for g in range(sl.start, sl.stop):
                y0[h + 3 + 3 * g : h + 6 + 3 * g] = rod_vel[k]
        return y0, r0, v0, sides

    # 2. the reference point's orbit: [orbit] block, or the root's own state
    if orbit is not None:
        ref = _state_of(orbit, mu)
        reference = orbit.reference
        motion = orbit.motion
    elif root_state is not None:
        ref = root_state
        reference = root_name
        motion = "corotating"
    else:
        raise SceneError("orbit", "an [orbit] block or an initial state on the root body", "neither")
    r_ref, v_ref = ref
    # (a reference point at the centre has no orbit to corotate with: no rotation)
    rr2 = float(r_ref @ r_ref)
    omega = np.cross(r_ref, v_ref) / rr2 if motion in ("corotating", "equilibrium", "quasi-static") and rr2 > 0 else None
    dirs, strains = [], []
    for t in tethers:
        ini = t.initial
        if ini is None:
            raise SceneError(
                f"tethers.{t.name}.initial", "an initial shape (only one end has an explicit state)", "none"
            )
        side = 1.0 if ini.side == "up" else -1.0
        sides.append(side)
        thetas, phis = ini.rod_angles_rad(t.rods)
        dirs.append(np.array([direction_from_angles(r_ref, v_ref, th, ph, side) for th, ph in zip(thetas, phis)]))
        strains.append(ini.strain)
    # lay out with the root at the origin, then move the reference point onto its orbit
    y0 = chain_state(model, np.zeros(3), np.zeros(3), dirs, strains, omega)
    if reference == "center_of_mass":
        c, _ = center_of_mass(model, y0)
    elif reference == root_name:
        c = np.zeros(3)
    else:
        k = [t.to_body for t in tethers].index(reference)
        from .system import point_positions

        c = point_positions(model, y0)["joints"][k][-1]
    r0 = r_ref - c
    v0 = v_ref + (np.cross(omega, r0 - r_ref) if omega is not None else 0.0)
    h = y0.size // 2
    y0[:3] = r0
    y0[h : h + 3] = v0
    if motion in ("equilibrium", "quasi-static"):
        y0 = _relative_equilibrium(eq_model or model, y0, r_ref, v_ref, omega, reference, root_name, tethers)
    if motion == "quasi-static":
        y0 = _quasi_static(model, y0, r_ref, reference, root_name, tethers)
    return y0, r_ref, v_ref, sides


def _rigidly_rotating(model, y0, d, W, r_ref, reference, root_name, tethers):
    """y0 with the rod vectors ``d`` (nrods x 3), the reference point at ``r_ref`` and every point
    rotating rigidly with ``W`` about the centre of the central body."""
    h = y0.size // 2
    y = y0.copy()
    y[3:h] = d.ravel()
    if reference == "center_of_mass":
        y[:3] = 0.0
        c, _ = center_of_mass(model, y)
    elif reference == root_name:
        c = np.zeros(3)
    else:
        from .system import point_positions

        y[:3] = 0.0
        k = [t.to_body for t in tethers].index(reference)
        c = point_positions(model, y)["joints"][k][-1]
    y[:3] = r_ref - c if reference != root_name else r_ref
    y[h : h + 3] = np.cross(W, y[:3])
    y[h + 3 :] = np.cross(W, d).ravel()
    return y


def _quasi_static(model, y0, r_ref, reference, root_name, tethers):
    """The rigidly rotating configuration under every effect of the scene at t = 0 (docs/model.md,
    section 8.1; ``orbit.motion = "quasi-static"``).

    Starts from the relative equilibrium ``y0`` of the conservative effects (spin rate W kept) and
    solves all three components of every rod vector d_g so that, in the frame rotating with W, every
    rod's relative acceleration d''_g - W x (W x d_g) vanishes: the tether takes the bowed and tilted
    shape the non-conservative forces (electrodynamic, drag) hold it in at t = 0.  Those forces
    vary along the orbit at the orbital frequency, far below the tether's lateral modes, so from
    this start the lateral modes are hardly excited; from the straight start they ring undamped for
    the whole run (the de-orbit: docs/integrators.md, section 11).  The centre of mass still
    decelerates: only the relative motion is in equilibrium.  Newton with a finite-difference
    Jacobian (3 n unknowns; set-up cost only).
    """
    from .formulations.cowell import cowell_rhs_py

    nrods = model.n_rods
    h = y0.size // 2
    r0 = y0[:3]
    W = np.cross(r0, y0[h : h + 3]) / float(r0 @ r0)  # the rigid rotation of the equilibrium
    w2 = float(W @ W)
    d0 = y0[3:h].reshape(nrods, 3)
    size = 2 * math.sqrt(3) * float(np.linalg.norm(d0, axis=1).sum())
    dscale = float(np.max(np.linalg.norm(d0, axis=1)))

    def residual(x):
        d = x.reshape(nrods, 3)
        y = _rigidly_rotating(model, y0, d, W, r_ref, reference, root_name, tethers)
        acc = cowell_rhs_py(model, y)[h + 3 :].reshape(nrods, 3)
        return (acc - np.cross(W, np.cross(W, d))).ravel() / (w2 * size)

    x = d0.ravel().copy()
    f = residual(x)
    step_max = np.inf
    for _ in range(30):
        J = np.empty((x.size, x.size))
        for j in range(x.size):
            dx = 1e-7 * max(1.0, abs(x[j]))
            xp = x.copy()
            xp[j] += dx
            J[:, j] = (residual(xp) - f) / dx
        step = np.linalg.lstsq(J, f, rcond=None)[0]
        x = x - step
        f = residual(x)
        step_max = float(np.max(np.abs(step)))
        # The rod vectors to 1e-10 of their length: the residual has a round-off floor (orbital
        # accelerations of ~8 m/s^2 against tidal ones of ~1e-3 m/s^2), the step does not.
        if step_max < 1e-10 * dscale:
            break
    if not step_max < 1e-10 * dscale:
        raise SceneError(
            "orbit.motion", "a configuration with a quasi-static equilibrium under every effect (Newton converging)",
            f"last Newton step {step_max:.3g} m on rod vectors of {dscale:.3g} m after 30 iterations",
        )
    return _rigidly_rotating(model, y0, x.reshape(nrods, 3), W, r_ref, reference, root_name, tethers)


def _relative_equilibrium(model, y0, r_ref, v_ref, omega, reference, root_name, tethers):
    """Rod lengths and spin rate that make the laid-out system rotate rigidly (docs/model.md 8).

    Unknowns: one length factor per rod and the spin rate Omega (about the orbit normal).
    Equations: in the frame rotating with Omega, the axial component of every rod's relative
    acceleration d'' - Omega x (Omega x d) and the radial component of the root's vanish.  For a
    tether along the local vertical this is the exact relative equilibrium of paper section 4.3
    (the tether stays vertical and the rods do not breathe); for a tilted tether it removes the
    axial transient and leaves the libration.  The reference point is kept on its orbit.
    """
    from .formulations.cowell import cowell_rhs_py

    nrods = model.n_rods
    h = y0.size // 2
    zhat = omega / np.linalg.norm(omega)
    w0 = float(np.linalg.norm(omega))
    d0 = y0[3:h].reshape(nrods, 3).copy()
    size = 2 * math.sqrt(3) * float(np.linalg.norm(d0, axis=1).sum())  # whole tether length

    def build(x):
        W = x[-1] * w0 * zhat
        return _rigidly_rotating(model, y0, d0 * x[:-1, None], W, r_ref, reference, root_name, tethers), W

    def residual(x):
        y, W = build(x)
        dy = cowell_rhs_py(model, y)
        acc = dy[h:]
        r0 = y[:3]
        d = y[3:h].reshape(nrods, 3)
        res = np.empty(nrods + 1)
        a_rel0 = acc[:3] - np.cross(W, np.cross(W, r0))
        res[0] = a_rel0 @ r0 / np.linalg.norm(r0) / (w0 * w0 * np.linalg.norm(r0))
        # every rod at once (a Python loop of per-rod cross products made this solve O(n^2) in
        # interpreter calls: 12 s at n = 256)
        u = d / np.linalg.norm(d, axis=1)[:, None]
        a_rel = acc[3:].reshape(nrods, 3) - np.cross(W, np.cross(W, d))
        res[1:] = (a_rel * u).sum(axis=1) / (w0 * w0 * size)
        return res

    # Newton with a finite-difference Jacobian; the residuals are relative accelerations in units
    # of Omega^2 * size, whose round-off floor is ~1e-12 (8 m/s^2 gravity against ~1e-3 m/s^2
    # tidal terms), so convergence is judged on the step, not on the residual alone.
    x = np.ones(nrods + 1)
    f = residual(x)
    for _ in range(40):
        J = np.empty((nrods + 1, nrods + 1))
        for j in range(nrods + 1):
            dx = 1e-6 * max(1.0, abs(x[j]))
            xp = x.copy()
            xp[j] += dx
            J[:, j] = (residual(xp) - f) / dx
        step = np.linalg.solve(J, f)
        x = x - step
        f = residual(x)
        if np.max(np.abs(step)) < 1e-14 or np.max(np.abs(f)) < 1e-12:
            break
    # Converged when the solution is known to 1e-11 in the unknowns (rod length factors ~ strain,
    # spin rate relative): the residual alone has a scene-dependent round-off floor (1.4e-9
    # measured on the de-orbit tether, i.e. a strain error of ~4e-12).
    x_err = float(np.max(np.abs(np.linalg.solve(J, f))))
    if not x_err < 1e-11:
        raise SceneError(
            "orbit.motion", "a configuration with a relative equilibrium (Newton converging)",
            f"residual {np.max(np.abs(f)):.3g} (error in the unknowns ~{x_err:.2g}) after 40 iterations",
        )
    return build(x)[0]


def _failing_effect(p: np.ndarray, code: int) -> str:
    """' (from effect NAME)' when a named effect's force was non-finite in the failing
    evaluation (kernel/effects.py records it), else ''."""
    from .forces import EFFECTS

    ecode = int(p[H_FAIL_EFFECT])
    if ecode <= 0 or (code != 0 and p[H_FAIL_EFFECT_T] != p[H_FAIL_T]):
        return ""
    names = [name for name, spec in EFFECTS.items() if spec.code == ecode]
    name = names[0] if names else f"code {ecode}"
    return f" (the effect {name!r} returned a non-finite force at t = {p[H_FAIL_EFFECT_T]:.9g} s)"


def failure_message(p: np.ndarray, model: Model, status: int, t_end: float, base: str) -> str:
    code = int(p[H_FAIL_CODE])
    if code == 0:
        return base + _failing_effect(p, 0)
    rod = int(p[H_FAIL_ROD])
    where = ""
    if rod >= 0:
        for k, sl in enumerate(model.rod_slices):
            if sl.start <= rod < sl.stop:
                where = f" in tether {model.tethers[k].name!r}, rod {rod - sl.start + 1} of {sl.stop - sl.start}"
    why = FAIL_TEXT.get(code, f"failure code {code}") + _failing_effect(p, code)
    detail = f" (strain {p[H_FAIL_VAL]:.6g})" if code == 11 else ""
    return (
        f"run stopped at t = {t_end:.9g} s: {why}{where}{detail}; "
        f"last failing evaluation at t = {p[H_FAIL_T]:.9g} s. Outputs up to t = {t_end:.9g} s are kept."
    )


def simulate(scene, *, progress: bool | None = None, raise_on_failure: bool = True) -> Result:
    """Integrate a scene and return a :class:`~tetherlab.result.Result`.

    A run that fails raises :class:`SimulationError` whose ``.result`` keeps every output
    computed before the failure (or, with ``raise_on_failure=False``, returns that result with
    ``result.ok`` false and ``result.message`` saying when, where and why).
    """
    prep = prepare(scene)
    p = prep.model.fresh_params()
    bar = _ProgressBar(prep.t_out[-1], enabled=progress)
    t_wall = time.perf_counter()
    res, p = integrate_prepared(prep, p, bar.update)
    bar.close()
    stats, message = run_outcome(prep, res, p, time.perf_counter() - t_wall)
    d = diag.compute(prep.model, res.t, res.y)
    result = Result.from_run(scene, prep, res.t, res.y, d, stats, res.status, message, p)
    if res.status != 0 and raise_on_failure:
        raise SimulationError(message, result)
    return result


def run_outcome(prep: Prepared, res, p: np.ndarray, total_wall_s: float) -> tuple[dict, str]:
    """The run statistics and the message (when, where and why a failed run stopped)."""
    stats = dict(res.stats)
    stats["total_wall_s"] = total_wall_s
    stats["formulation"] = prep.formulation
    if prep.formulation == "dromo-sigma":
        stats["time_element"] = prep.time_element  # what the sigma form carried as its time
    stats["events"] = [
        {"t_s": float(te), "event": prep.event_names[k], "side": "taut" if side > 0 else "slack"}
        if prep.event_names[k].startswith("slack.") else
        {"t_s": float(te), "event": prep.event_names[k]}
        for te, k, side in res.events
    ]  # fmt: skip
    stopped = res.stopped_by
    stats["stopped_by"] = None if stopped is None else prep.event_names[stopped]
    message = res.message if res.status == 0 else failure_message(p, prep.model, res.status, res.t_end, res.message)
    return stats, message


def integrate_prepared(prep: Prepared, p: np.ndarray, progress=None):
    """Integrate a prepared scene with its formulation; returns (result, the parameter block used).

    The result's states are Cowell states [q, q', attitude, wheels] whatever the formulation."""
    if prep.formulation == "cowell":
        return _integrate_cowell(prep, p, progress), p
    if prep.formulation == "cowell-orbit":
        return _integrate_cowell_orbit(prep, p, progress)
    return _integrate_dromo(prep, p, progress)


#: The frame of formulation "cowell-orbit" is re-anchored (its rate reset to the root body's) every
#: this many reference orbital periods (docs/integrators.md section 11: measured 1, 5, 20, never).
ANCHOR_ORBITS = 5.0


def _integrate_cowell_orbit(prep: Prepared, p: np.ndarray, progress):
    """Cowell in the frame turning with the orbit, outputs turned back to inertial Cowell states
    (formulations/cowell_orbit.py).  The event functions are frame invariant (|r0|, rod tensions).

    The run is a sequence of segments of ANCHOR_ORBITS reference periods; each starts from the
    inertial state reached by the last with a frame anchored there (its rate the root body's r x v
    / |r|^2 then), so the frame keeps up with a decaying orbit.  A failure or a terminal event ends
    the sequence with every output computed so far."""
    import dataclasses

    from .formulations import cowell_orbit as co
    from .integrators.driver import integrate
    from .tether.newton_solver import choose as choose_newton

    nqt = prep.model.n_qt
    t_out = prep.t_out
    t_last = float(t_out[-1])
    seg_s = ANCHOR_ORBITS * prep.ref_period_s if math.isfinite(prep.ref_period_s) else t_last
    t_a, y_in = 0.0, prep.y0.copy()
    ts, ys, events, anchors = [], [], [], []
    sums: dict = {}
    budget = prep.max_steps
    k_out = 0  # first output not yet produced
    # one parameter block for the whole run (the model's counters and failure records carry on);
    # each segment sets its frame in it
    pe = co.attach(p, co.frame_rate(y_in, nqt), t_a)
    while True:
        t_b = min(t_a + seg_s, t_last)
        if t_last - t_b < 1e-6 * seg_s:  # no sliver of a segment at the end
            t_b = t_last
        k_end = int(np.searchsorted(t_out, t_b, side="right"))
        seg_t = t_out[k_out:k_end]
        extra = seg_t.size == 0 or seg_t[-1] < t_b
        if extra:
            seg_t = np.concatenate([seg_t, [t_b]])
        omega = co.frame_rate(y_in, nqt)
        anchors.append([t_a, *omega.tolist()])
        co.set_frame(pe, omega, t_a)
        res = integrate(prep.method, co.cowell_orbit_rhs, t_a, co.to_frame(0.0, y_in, omega, nqt), seg_t, pe,
                        prep.rtol, prep.atol, h_max=prep.h_max, max_steps=budget, progress=progress,
                        second_order=True, newton=choose_newton(pe, y_in.size, True),
                        **_event_args(prep))  # fmt: skip
        for key, v in res.stats.items():
            if isinstance(v, (int, float)) and not isinstance(v, bool):
                sums[key] = sums.get(key, 0) + v
            else:
                sums.setdefault(key, v)
        budget -= int(res.stats["n_accepted"])
        events.extend(res.events)
        y_rows = co.to_inertial(res.t - t_a, res.y, omega, nqt) if len(res.t) else res.y
        y_in = co.to_inertial([res.t_end - t_a], res.y_end, omega, nqt)[0]
        ended = res.status != 0 or res.stopped_by is not None or t_b >= t_last
        keep = len(res.t) - (1 if (extra and res.stopped_by is None and len(res.t) == seg_t.size) else 0)
        ts.append(res.t[:keep])
        ys.append(y_rows[:keep])
        k_out += min(keep, k_end - k_out)
        if ended or budget <= 0:
            break
        t_a = float(res.t_end)
    sums["frame_anchors"] = anchors  # [t_a, omega_x, omega_y, omega_z] of every segment
    sums["n_events"] = len(events)
    res = dataclasses.replace(res, t=np.concatenate(ts), y=np.concatenate(ys), y_end=y_in, stats=sums,
                              events=tuple(events))  # fmt: skip
    return res, pe


def _integrate_dromo(prep: Prepared, p: np.ndarray, progress):
    """DROMO run with outputs converted back to Cowell states [r0, d, v0, d'] (docs/dromo.md 7)."""
    from .formulations import dromo
    from .kernel.layout import FORM_DROMO_SIGMA, FORM_DROMO_TIME
    from .propagation import dromo as drive

    h = prep.y0.size // 2
    length_m = float(np.linalg.norm(prep.y0[:3]))  # L = |r0| (docs/dromo.md section 2)
    if prep.formulation == "dromo-sigma":
        pe = dromo.attach(p, FORM_DROMO_SIGMA, prep.mu_m3_s2, length_m, prep.y0.size,
                          dromo.TIME_ELEMENTS[prep.time_element])  # fmt: skip
        res = drive.integrate_sigma(
            prep.method, pe, prep.y0[:3], prep.y0[h : h + 3], prep.t_out, prep.rtol,
            prep.atol[0] / prep.ref_radius_m, prep.mu_m3_s2, length_m, max_steps=prep.max_steps,
            progress=progress,
        )  # fmt: skip
    else:
        pe = dromo.attach(p, FORM_DROMO_TIME, prep.mu_m3_s2, length_m, prep.y0.size)
        res = drive.integrate_time(
            prep.method, pe, prep.y0, prep.t_out, prep.rtol, prep.atol, prep.mu_m3_s2, length_m,
            h_max=prep.h_max, max_steps=prep.max_steps, progress=progress,
            n_events=len(prep.event_names), terminal=prep.event_terminal,
        )  # fmt: skip
    return res, pe


def _integrate_cowell(prep: Prepared, p: np.ndarray, progress, **store):
    """``store``: y_out, checkpoint, restart for runs written as they go (tetherlab/runstore.py)."""
    from .integrators.driver import integrate
    from .tether.newton_solver import choose as choose_newton

    # Cowell: y = [q, q', attitude, wheels] with q' exact for the first NQT components (the
    # state-layout descriptor): RADAU5 reduces its Newton systems to n - NQT unknowns
    second_order = True if not prep.model.has_attitude else prep.model.n_qt
    return integrate(
        prep.method,
        cowell_rhs,
        0.0,
        prep.y0,
        prep.t_out,
        p,
        prep.rtol,
        prep.atol,
        h_max=prep.h_max,
        max_steps=prep.max_steps,
        progress=progress,
        second_order=second_order,
        newton=choose_newton(p, prep.y0.size, second_order),  # the model's Newton matrix for RADAU5
        **_event_args(prep),
        **store,
    )


class _ProgressBar:
    """A tqdm bar that appears only on runs longer than a couple of seconds."""

    def __init__(self, t_end: float, enabled: bool | None):
        self.t_end = t_end
        self.enabled = enabled
        self.start = time.perf_counter()
        self.bar = None
        self.last = 0.0

    def update(self, t: float) -> None:
        if self.enabled is False:
            return
        if self.bar is None:
            if self.enabled is None and time.perf_counter() - self.start < 2.0:
                return
            from tqdm import tqdm

            self.bar = tqdm(total=float(self.t_end), unit="s(sim)", unit_scale=True, leave=False)
        self.bar.update(float(t) - self.last)
        self.last = float(t)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
