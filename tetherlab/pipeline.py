"""Run a scene: build the model, lay out the initial state, integrate, compute diagnostics.

``simulate(scene)`` is the whole pipeline behind ``tetherlab run``.  Everything here runs once per
run; the only per-step work happens inside the compiled integrator and right-hand side.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import diagnostics as diag
from . import initial
from .initial import inextensible
from .errors import SceneError
from .forces import effect as effect_spec
from .formulations.cowell import cowell_rhs

from .kernel.events import event_components, system_events
from .model.params import FAIL_TEXT, ParamView
from .result import Result
from .system import (
    BodySpec,
    ControlSpec,
    Model,
    ReelSpec,
    RigidSpec,
    TetherSpec,
    WheelSpec,
    build_model,
    tether_error_floor,
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
    # every corner and jump of the time tables: the steps land on them (docs/integrators.md 14)
    breaks_s: tuple = ()
    # the start time: 0, the end of the run the scene continues (continue_from), or the start of a
    # phase of a deployment (tetherlab/deployment.py)
    t0_s: float = 0.0
    ref_r_m: np.ndarray | None = None  # the reference state the orbit scales came from
    ref_v_m_s: np.ndarray | None = None


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


def prepare(scene, *, outputs_in_memory: bool = True, out_dir=None, reel_phase: dict | None = None) -> Prepared:
    """Build the model and initial state.  First checks that the run fits the machine
    (tetherlab/resources.py): all outputs in memory (``simulate``), or streamed to ``out_dir``.

    ``reel_phase``: a later phase of a deployment after births or retirements
    (tetherlab/deployment.py): {"rods": {tether name: (rods, deployed length in m)}, "first": the
    Prepared of the run's first phase (its reference orbit)}; the state is left to the caller."""
    from .resources import check_scene

    if reel_phase is None:  # a later phase's outputs are part of the run the first phase checked
        check_scene(scene, outputs_in_memory=outputs_in_memory, out_dir=out_dir)
    # a scene continuing a finished run starts from its final state and time (continuation.py)
    start = None
    if scene.continue_from is not None:
        from .continuation import final_state

        start = final_state(scene.continue_from)
    t0 = start.t_s if start is not None else 0.0
    mu = scene.central_body.mu_m3_s2
    central = {"mu_m3_s2": mu, "radius_m": scene.central_body.radius_m}
    effects = [(effect_spec(e.name), e.params_si) for e in scene.effects]
    # the scene's graph, built and checked at load (tetherlab/model/topology.py)
    graph = scene.graph_of()
    root_name = graph.roots[0]
    tethers = list(scene.tethers)
    root = scene.body(root_name)
    by_name = {b.name: b for b in scene.bodies}
    kernel_bodies = [_body_spec(by_name[n]) for n in graph.kernel_bodies]
    zero = (0.0, 0.0, 0.0)
    specs = []
    for k, t in enumerate(tethers):
        a_pt = t.from_point_m or zero
        b_pt = t.to_point_m or zero
        rods, length_m = (reel_phase or {"rods": {}})["rods"].get(t.name, (t.rods, t.length_m))
        specs.append(TetherSpec(
            name=t.name,
            rods=rods,
            length_m=length_m,
            ea_n=t.EA_N,
            mass_kg=t.mass_kg,
            damping_n_s=t.damping_N_s,
            model=t.model,
            tip_mass_kg=scene.body(graph.tethers[k].child).mass_kg,
            tip_name=graph.tethers[k].child,
            tension_only=t.tension_only,
            diameter_m=t.diameter_m,
            parent=graph.tethers[k].parent,
            from_point_m=tuple(b_pt if graph.tethers[k].reversed else a_pt),
            to_point_m=tuple(a_pt if graph.tethers[k].reversed else b_pt),
            reversed=graph.tethers[k].reversed,
            part="inextensible" if t.model == "inextensible" else "",
            reel=None if t.reel is None else ReelSpec(
                t.reel.law, t.reel.exit, t.length_m, t.reel.speed_m_s, t.reel.rate_1_s, t.reel.rod_length_m,
                t.mass_kg / t.length_m, t.length_m + t.reel.stored_length_m, _reel_table(t.reel),
                spool_radius_m=t.reel.spool_radius_m,
                spool_axis=t.reel.spool_axis or t.reel.exit_direction or (0.0, 0.0, 0.0),
                **_spool_spec(t.reel),
            ),
        ))  # fmt: skip
    nq = tethers[0].quadrature if tethers else 2  # one for every tether (checked at load)
    model = build_model(
        root_mass_kg=root.mass_kg,
        tethers=specs,
        effects=effects,
        central=central,
        quadrature=nq,
        root_fixed=bool(getattr(root, "fixed", False)),
        root_name=root_name,
        epoch=scene.epoch,
        duration_s=None if _duration_hint(scene) is None else t0 + _duration_hint(scene),
        bodies=kernel_bodies,
        graph=graph,
    )
    # The relative equilibrium is a rigid rotation under the conservative effects; a velocity-
    # dependent or time-dependent force (electrodynamic, drag, third bodies) has none, so the
    # equilibrium is solved without them and they act from t = 0 (docs/scenes.md, orbit.motion).
    # An inextensible tether's relative equilibrium is solved as the elastic one of its EA (the
    # rods' strains are the unknowns there); its start then restores the lengths
    # (tetherlab/initial/inextensible.py).
    eq_model = model
    inext = any(s.model == "inextensible" for s in specs)
    # (a later phase of a deployment takes its state from the last: no equilibrium to solve)
    if reel_phase is None and (any(not spec.conservative for spec, _ in effects) or inext):
        eq_model = build_model(
            root_mass_kg=root.mass_kg,
            tethers=[inextensible.elastic_stand_in(s) for s in specs],
            effects=[(spec, prm) for spec, prm in effects if spec.conservative],
            central=central,
            quadrature=nq,
            root_fixed=bool(getattr(root, "fixed", False)),
            root_name=root_name,
            bodies=kernel_bodies,
            graph=graph,
        )
    if reel_phase is None:
        y0, r_ref, v_ref, sides = initial.initial_state(scene, graph, model, mu, eq_model)
        if any(t.reel is not None for t in specs):
            from .deployment import reel_start

            y0 = reel_start(model, y0)
    else:  # a later phase of a deployment: its state is remapped from the last (tetherlab/deployment.py)
        first = reel_phase["first"]
        y0 = np.zeros(model.state.size)
        r_ref, v_ref, sides = first.ref_r_m, first.ref_v_m_s, first.sides
    holding = None
    if any(t.initial is not None and t.initial.shape == "equilibrium" for t in tethers):
        y0, holding = initial.static_start(scene, root, tethers, specs, effects, central, nq, y0)
    if start is not None:
        from .continuation import check_layout

        check_layout(start, model.state)
        y0 = start.y.copy()
    stop_radius = 0.0
    if scene.stop is not None and scene.stop.altitude_m is not None:
        stop_radius = scene.central_body.radius_m + scene.stop.altitude_m
        if reel_phase is None and not float(np.linalg.norm(y0[:3])) > stop_radius:
            raise SceneError(
                "stop.altitude", f"an altitude below the root body's initial altitude "
                f"({float(np.linalg.norm(y0[:3])) - scene.central_body.radius_m:.6g} m)",
                f"{scene.stop.altitude_m:.6g} m",
            )
    ParamView(model.p).stop_radius_m = stop_radius
    # (a scipy method with events is refused at load: tetherlab/scene/checks.py)
    event_names, event_terminal = event_components(model, stop_radius)

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
    if inextensible.has_inextensible(model):
        inextensible.set_rates(model, tethers, t_unit)
        if start is None and reel_phase is None:  # a continued run starts where the last one ended
            y0 = inextensible.project(model, y0)
        inextensible.check_taut(model, t0, y0, lambda name: f"tethers.{name}.initial")
    ref_len = rr if orbital else max(rr, max((t.length_m for t in tethers), default=1.0))
    atol = scene.integrator.atol * tolerance_scales(model, ref_len, t_unit)
    if scene.integrator.error_scale == "tether":
        # err_i/(atol_i + rtol |y_i|) with |d_i| ~ L_rod/(2 sqrt 3): this floor makes the rods'
        # test rtol relative to the tether's length instead (docs/integrators.md section 15)
        atol = atol + scene.integrator.rtol * tether_error_floor(model, t_unit)

    duration = scene.duration_s
    if duration is None:  # given in orbits
        if not math.isfinite(period):
            raise SceneError(
                "duration", "a time (e.g. '10 d') for a reference that is not on a closed orbit",
                f"{scene.duration_orbits} orbits",
            )
        duration = scene.duration_orbits * period
    t_out = _output_times(scene.output, duration)
    if t0 != 0.0:
        t_out = t0 + t_out  # duration and output times count from the continued run's end
    h_max = scene.integrator.max_step_s or 0.0
    # events are located in time: with DROMO they run the time form (docs/dromo.md section 10)
    formulation = _formulation(scene, model, tethers, y0, bool(event_names))
    # The wheels' limits are located events with Cowell and a native method (the other
    # formulations and scipy apply them unlocated: docs/integrators.md section 14)
    if formulation == "cowell" and not scene.integrator.method.startswith("scipy:") and any(
        w.max_torque_N_m > 0.0 or w.max_speed_rad_s > 0.0
        for b in model.bodies if getattr(b, "rigid", None) is not None for w in b.rigid.wheels
    ):  # fmt: skip
        ParamView(model.p).wheel_limit_events = 1
        event_names, event_terminal = event_components(model, stop_radius, wheel_limits=True)
    if start is not None and formulation == "dromo-sigma":
        raise SceneError(
            "continue_from", "a formulation integrated in time: DROMO's sigma form (a single body without events) "
            "keeps its own clock from t = 0 (set integrator.formulation = 'cowell')", "formulation 'dromo'",
        )  # fmt: skip
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
        breaks_s=tuple(model.breakpoints_s().tolist()),
        t0_s=t0,
        ref_r_m=np.asarray(r_ref, float),
        ref_v_m_s=np.asarray(v_ref, float),
    )


def _spool_spec(reel) -> dict:
    """The ReelSpec fields of a spool or tension law (tether/reel_spool.py), SI."""
    sp = reel.spool
    if sp is None:
        return {}
    return dict(
        spool_mass_kg=sp.spool_inertia_kg_m2 / sp.drum_radius_m**2 if sp.spool_inertia_kg_m2 > 0.0 else 0.0,
        radius_m=sp.drum_radius_m, torque_N_m=sp.torque_N_m, viscous_N_s_m=sp.viscous_N_s_m, coulomb_N=sp.coulomb_N,
        friction_speed_m_s=sp.friction_speed_m_s, mstar_kg=sp.reduced_mass_kg, omega_rad_s=sp.orbit_rate_rad_s,
        lc_m=sp.commanded_length_m, k1=sp.k1, k2=sp.k2, tmin_N=sp.min_tension_N, tmax_N=sp.max_tension_N,
        twidth_N=sp.limit_width_N, birth_length_m=reel.birth_length_m, retire_length_m=reel.retire_length_m,
        max_torque_N_m=sp.max_torque_N_m, torque_width_N_m=sp.torque_limit_width_N_m, max_speed_m_s=sp.max_speed_m_s,
        speed_gain_N_s_m=sp.speed_brake_gain_N_s_m, speed_width_m_s=sp.speed_limit_width_m_s,
    )


def _reel_table(reel) -> tuple:
    """The intervals (t_k, a0, a1, a2, a3) of a table law's spline (tether/reel.py reads them)."""
    if reel.law != "table":
        return ()
    from .scene.reels import table_spline

    sp = table_spline(reel)
    return tuple((float(sp.x[k]), *(float(sp.c[3 - j, k]) for j in range(4))) for k in range(len(sp.x) - 1))


def _event_args(prep) -> dict:
    """The event function and its flags, only when the scene has events (scipy methods cannot
    take them, so a scene with events names a native method; the driver says so otherwise)."""
    if not prep.event_names:
        return {}
    return {"event": system_events, "n_events": len(prep.event_names), "terminal": prep.event_terminal}


def _formulation(scene, model: Model, tethers, y0: np.ndarray, events: bool = False) -> str:
    """The formulation the integrator runs: the first of the scene's choice that supports the scene
    (formulations/registry.py; docs/dromo.md section 7), else its reason as the SceneError."""
    from .formulations.registry import Refusal, SceneFacts, choose

    facts = SceneFacts(scene.integrator.formulation, y0, scene.central_body.mu_m3_s2, events,
                       scene.integrator.max_step_s)  # fmt: skip
    form = choose(model, facts)
    if isinstance(form, Refusal):
        raise SceneError(form.key, form.expected, form.got)
    return form.name


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


def _failing_effect(p: np.ndarray, code: int) -> str:
    """' (from effect NAME)' when a named effect's force was non-finite in the failing
    evaluation (kernel/effects.py records it), else ''."""
    from .forces import EFFECTS

    rep = ParamView(p).report
    ecode = rep.fail_effect_code
    if ecode <= 0 or (code != 0 and rep.fail_effect_time_s != rep.fail_time_s):
        return ""
    names = [name for name, spec in EFFECTS.items() if spec.code == ecode]
    name = names[0] if names else f"code {ecode}"
    return f" (the effect {name!r} returned a non-finite force at t = {rep.fail_effect_time_s:.9g} s)"


def failure_message(p: np.ndarray, model: Model, status: int, t_end: float, base: str) -> str:
    rep = ParamView(p).report
    code = rep.fail_code
    if code == 0:
        return base + _failing_effect(p, 0)
    rod = rep.fail_rod
    where = ""
    if rod >= 0:
        for k, sl in enumerate(model.rod_slices):
            if sl.start <= rod < sl.stop:
                where = f" in tether {model.tethers[k].name!r}, rod {rod - sl.start + 1} of {sl.stop - sl.start}"
    why = FAIL_TEXT.get(code, f"failure code {code}") + _failing_effect(p, code)
    detail = f" (strain {rep.fail_value:.6g})" if code == 11 else ""
    return (
        f"run stopped at t = {t_end:.9g} s: {why}{where}{detail}; "
        f"last failing evaluation at t = {rep.fail_time_s:.9g} s. Outputs up to t = {t_end:.9g} s are kept."
    )


def simulate(scene, *, progress: bool | None = None, raise_on_failure: bool = True) -> Result:
    """Integrate a scene and return a :class:`~tetherlab.result.Result`.

    A run that fails raises :class:`SimulationError` whose ``.result`` keeps every output
    computed before the failure (or, with ``raise_on_failure=False``, returns that result with
    ``result.ok`` false and ``result.message`` saying when, where and why).

    A scene with a reel runs phase by phase between the births and retirements of its rods and
    returns a :class:`tetherlab.deployment.DeploymentResult` (one Result per phase, the reel's
    table and the invariants across phases; docs/deployment.md).
    """
    from .scene import Scene

    if not isinstance(scene, Scene):
        hint = (" (a file name: load it first with tetherlab.load_scene(path))" if isinstance(scene, (str, Path))
                else " (a dictionary: build it with tetherlab.Scene.from_dict(d))" if isinstance(scene, dict) else "")
        raise TypeError(f"simulate(scene): expected a tetherlab.Scene, from tetherlab.load_scene(path) or "
                        f"tetherlab.Scene.from_dict(d); got {type(scene).__name__} {scene!r:.60}{hint}")  # fmt: skip
    if any(t.reel is not None for t in scene.tethers):
        from .deployment import simulate_reel

        return simulate_reel(scene, progress=progress, raise_on_failure=raise_on_failure)
    prep = prepare(scene)
    p = prep.model.fresh_params()
    bar = _ProgressBar(prep.t_out[-1], enabled=progress)
    t_wall = time.perf_counter()
    res, p = integrate_prepared(prep, p, bar.update)
    bar.close()
    stats, message = run_outcome(prep, res, p, time.perf_counter() - t_wall)
    d = diag.compute(prep.model, res.t, res.y, branch_spans(prep, res.events))
    result = Result.from_run(scene, prep, res.t, res.y, d, stats, res.status, message, p)
    from .regime import check as regime_check

    result.stats["warnings"] = regime_check(scene, result.timeseries, result.diagnostics, bar.trace)
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
    stats["events"] = [event_record(prep.event_names[k], te, side) for te, k, side in res.events]
    stopped = res.stopped_by
    stats["stopped_by"] = None if stopped is None else prep.event_names[stopped]
    message = res.message if res.status == 0 else failure_message(p, prep.model, res.status, res.t_end, res.message)
    if res.status == 0 and stats["stopped_by"] and stats["stopped_by"].startswith("inextensible."):
        message = inextensible_stop_text(stats["stopped_by"], res.t_end)
    return stats, message


def inextensible_stop_text(event: str, t_s: float) -> str:
    """Why a run with an inextensible tether stopped at its terminal tension event."""
    _, tether, rod = event.split(".", 2)
    return (f"run stopped at t = {t_s:.9g} s: the tension of {rod.replace('rod', 'rod ')} of tether {tether!r} reached "
            "zero, where the inextensible model no longer holds (the rod would go slack); the outputs up to "
            "there are kept. A slack tether needs model = 'paper' with tension_only = true")


def event_record(name: str, t_s: float, side: int) -> dict:
    """One located event as the run's statistics list it: its time, component and what happened
    (a rod gone slack or taut; a wheel limit entered, when the limit starts to act, or left)."""
    rec = {"t_s": float(t_s), "event": name}
    if name.startswith("slack."):
        rec["side"] = "taut" if side > 0 else "slack"
    elif name.startswith("wheel."):
        rec["side"] = "left" if side > 0 else "entered"
    return rec


def _interval_setter(pe: np.ndarray):
    """The driver's ``at_interval``: the end of the smooth interval being integrated into the
    block, where the time tables take their left limit (bodies/wheels.py::table_value)."""
    view = ParamView(pe)

    def at_interval(t_b: float) -> None:
        view.interval_end_s = t_b

    return at_interval


def _wheel_targets(prep: Prepared) -> list:
    """(event component, wheel index, lock field) of every wheel-limit event component."""
    targets = []
    whl = ParamView(prep.model.p).wheel_state_index  # wheel j's state index is whl + j
    for k, name in enumerate(prep.event_names):
        if name.startswith("wheel."):
            _, body, wheel, limit = name.split(".")
            b = next(i for i, bs in enumerate(prep.model.bodies) if bs.name == body)
            j = prep.model.wheel_index[(b, wheel)] - whl
            targets.append((k, j, "torque_limit_lock" if limit == "max_torque" else "speed_limit_lock"))
    return targets


def _sides_setter(prep: Prepared, pe: np.ndarray):
    """The driver's ``at_sides``: each wheel limit's branch locked to its event component's side
    (bodies/wheels.py::motor_torque; negative side = the limit acts); None without wheel events."""
    targets = _wheel_targets(prep)
    if not targets:
        return None
    view = ParamView(pe)

    def at_sides(sides) -> None:
        for k, j, field in targets:
            setattr(view.wheel(j), field, 1.0 if sides[k] < 0.0 else 0.0)

    return at_sides


def branch_spans(prep: Prepared, events) -> list | None:
    """The wheel limits' branches the run held, span by span, for the diagnostics
    (diagnostics.compute): the sides at the start, as the driver finds them, then each located
    event (t, component, side) in order; None without wheel-limit events."""
    from .integrators.driver import event_values_at

    targets = _wheel_targets(prep)
    if not targets:
        return None
    g = event_values_at(system_events, prep.t0_s, prep.y0, prep.model.fresh_params(), len(prep.event_names))
    sides = np.where(g < 0.0, -1.0, 1.0)

    def locks():
        return [(j, field, 1.0 if sides[k] < 0.0 else 0.0) for k, j, field in targets]

    spans = [(-math.inf, locks())]
    for t, comp, side in events:
        sides[int(comp)] = float(side)
        spans.append((float(t), locks()))
    return spans


def integrate_prepared(prep: Prepared, p: np.ndarray, progress=None):
    """Integrate a prepared scene with its formulation; returns (result, the parameter block used).

    The result's states are Cowell states [q, q', attitude, wheels] whatever the formulation."""
    if prep.formulation == "dromo-sigma":
        return _integrate_dromo(prep, p, progress)
    plan = segment_plan(prep, p)
    return run_segments(prep, plan, progress), plan.pe


#: The frame of formulation "cowell-orbit" is re-anchored (its rate reset to the root body's) every
#: this many reference orbital periods (docs/integrators.md section 11: measured 1, 5, 20, never).
ANCHOR_ORBITS = 5.0


@dataclass
class SegmentPlan:
    """How one formulation runs as a list of segments (the loop: :func:`run_segments`).

    ``pe``: the parameter block with the formulation's block appended (one for the whole run: the
    model's counters and failure records carry on); ``length_s``: a segment's length (inf: one
    segment); ``enter(t_a, y) -> (z, ctx)``: the formulation state at a segment's start from the
    Cowell state there (re-anchoring what the segment needs in ``pe``); ``leave(ctx, t, Z)``: Cowell
    rows from formulation rows ``Z`` at the times ``t``; ``anchor(ctx)``: what the run's stats keep
    of a segment (None: nothing); ``rowwise``: ``leave`` turns each row on its own, so a run store
    may turn a segment's rows into Cowell rows as the driver writes them (the same bits as at the
    segment's end) instead of when it ends."""

    pe: np.ndarray
    rhs: object
    events: object
    atol: np.ndarray
    second_order: object
    length_s: float
    enter: object
    leave: object
    anchor: object = None
    rowwise: bool = False


def segment_plan(prep: Prepared, p: np.ndarray) -> SegmentPlan:
    """The segment plan of the prepared scene's formulation (every one but the sigma form, whose
    independent variable is not the time)."""
    lay = prep.model.state
    events = _event_args(prep).get("event")
    if prep.formulation == "cowell":
        return SegmentPlan(p, cowell_rhs, events, prep.atol, _second_order(prep.model), math.inf,
                           lambda t_a, y: (y, None), lambda ctx, t, Z: Z)  # fmt: skip
    if prep.formulation == "cowell-orbit":
        from .formulations import cowell_orbit as co

        quats = [lay.quaternion_of(b).start for b, _ in lay.rigid]
        pe = co.attach(p, co.frame_rate(prep.y0, lay), 0.0)

        def enter(t_a, y):
            omega = co.frame_rate(y, lay)
            co.set_frame(pe, omega, t_a)
            return co.to_frame(0.0, y, omega, lay, quats), (t_a, omega)

        def leave(ctx, t, Z):
            t_a, omega = ctx
            return co.to_inertial(np.asarray(t) - t_a, Z, omega, lay, quats) if len(t) else Z

        seg = ANCHOR_ORBITS * prep.ref_period_s if math.isfinite(prep.ref_period_s) else math.inf
        return SegmentPlan(pe, co.cowell_orbit_rhs, events, prep.atol, _second_order(prep.model), seg, enter,
                           leave, lambda ctx: [ctx[0], *ctx[1].tolist()])  # fmt: skip
    if prep.formulation == "dromo-time":
        from .formulations import dromo
        from .model.params import FORM_DROMO_TIME

        mu = prep.mu_m3_s2
        length_m = float(np.linalg.norm(prep.y0[lay.root_r]))  # L = |r0| (docs/dromo.md section 2)
        pe = dromo.attach(p, FORM_DROMO_TIME, mu, length_m, lay.size)
        # elements and sigma are O(1) non-dimensional: atol in their own units = the scene's atol,
        # which is atol[0]/L (the root position scale is the reference radius)
        atol = np.concatenate([np.full(8, prep.atol[0] / length_m), lay.passthrough_atol(prep.atol)])

        def leave(ctx, t, Z):
            return np.array([dromo.cowell_state(z, lay, mu, length_m) for z in Z]).reshape(len(t), lay.size)

        return SegmentPlan(pe, dromo.dromo_time_rhs, dromo.dromo_time_events if events is not None else None,
                           atol, False, math.inf, lambda t_a, y: (dromo.time_state(y, lay, mu, length_m), None),
                           leave, rowwise=True)  # fmt: skip
    raise ValueError(f"formulation {prep.formulation!r}: expected one run by segments")


def run_segments(prep: Prepared, plan: SegmentPlan, progress=None, store=None):
    """The one loop of a run: segments of ``plan.length_s``, each started from the Cowell state the
    last one reached (``plan.enter``), its outputs turned into Cowell rows (``plan.leave``) and
    kept as one table.  A failure, a terminal event or the end of the outputs ends the run, with
    every output computed so far.

    ``store`` (tetherlab/runstore.py): a run written as it goes; ``store.begin(k, seg_t, n)``
    returns the driver's ``y_out``, ``checkpoint`` and ``restart`` for segment k and
    ``store.resume`` the loop's state at a checkpoint (None: from the start)."""
    import dataclasses

    from .integrators.driver import integrate
    from .tether.newton_solver import choose as choose_newton

    t_out = prep.t_out
    t_last = float(t_out[-1])
    seg_s = plan.length_s if plan.length_s < t_last else t_last
    loop = store.resume if store is not None and store.resume is not None else {
        "k": 0, "t_a": prep.t0_s, "y_in": prep.y0, "k_out": 0, "budget": prep.max_steps, "sums": {}, "events": [],
        "anchors": [],
    }  # fmt: skip
    k, t_a, y_in, k_out, budget = loop["k"], loop["t_a"], loop["y_in"], loop["k_out"], loop["budget"]
    sums, events, anchors = loop["sums"], loop["events"], loop["anchors"]
    ts, ys = [t_out[:k_out]], []  # (a resumed run: the output times of the segments before it)
    ev = {}
    if plan.events is not None:
        ev = {"event": plan.events, "n_events": len(prep.event_names), "terminal": prep.event_terminal}
    while True:
        t_b = min(t_a + seg_s, t_last)
        if t_last - t_b < 1e-6 * seg_s:  # no sliver of a segment at the end
            t_b = t_last
        k_end = int(np.searchsorted(t_out, t_b, side="right"))
        seg_t = t_out[k_out:k_end]
        extra = seg_t.size == 0 or seg_t[-1] < t_b
        if extra:
            seg_t = np.concatenate([seg_t, [t_b]])
        z0, ctx = plan.enter(t_a, y_in)
        if plan.anchor is not None and len(anchors) <= k:
            anchors.append(plan.anchor(ctx))
        io = {} if store is None else store.begin(k, seg_t, z0.size, dict(loop, k=k, t_a=t_a, y_in=y_in, k_out=k_out,
                                                                            budget=budget), ctx)  # fmt: skip
        res = integrate(prep.method, plan.rhs, t_a, z0, seg_t, plan.pe, prep.rtol, plan.atol, h_max=prep.h_max,
                        max_steps=budget, progress=progress, second_order=plan.second_order,
                        newton=choose_newton(plan.pe, z0.size, plan.second_order), breaks=prep.breaks_s,
                        at_interval=_interval_setter(plan.pe), at_sides=_sides_setter(prep, plan.pe), **ev,
                        **io)  # fmt: skip
        if k == 0 and t_b >= t_last and not extra and store is None and plan.anchor is None:
            # one segment: the driver's result as it is, in Cowell rows
            y_rows = plan.leave(ctx, res.t, res.y)
            if y_rows is res.y:
                return res
            return dataclasses.replace(res, y=y_rows, y_end=plan.leave(ctx, [res.t_end], res.y_end[None, :])[0],
                                       stats=dict(res.stats))  # fmt: skip
        for key, v in res.stats.items():
            if isinstance(v, (int, float)) and not isinstance(v, bool):
                sums[key] = sums.get(key, 0) + v
            else:
                sums.setdefault(key, v)
        budget -= int(res.stats["n_accepted"])
        events.extend(res.events)
        y_rows = plan.leave(ctx, res.t, res.y)
        y_in = plan.leave(ctx, [res.t_end], res.y_end[None, :])[0]
        ended = res.status != 0 or res.stopped_by is not None or t_b >= t_last
        keep = len(res.t) - (1 if (extra and res.stopped_by is None and len(res.t) == seg_t.size) else 0)
        ts.append(res.t[:keep])
        ys.append(y_rows[:keep])
        if store is not None:
            store.end(k, k_out, res.t[:keep], y_rows[:keep])
        k_out += min(keep, k_end - k_out)
        if ended or budget <= 0:
            break
        t_a = float(res.t_end)
        k += 1
    if anchors:
        sums["frame_anchors"] = anchors  # [t_a, omega_x, omega_y, omega_z] of every segment
    sums["n_events"] = len(events)
    sums["n_segments"] = k + 1
    if store is not None:  # the rows are in the store's table
        return store.result(res, np.concatenate(ts), y_in, sums, tuple(events))
    return dataclasses.replace(res, t=np.concatenate(ts), y=np.concatenate(ys), y_end=y_in, stats=sums,
                               events=tuple(events))  # fmt: skip


def _integrate_dromo(prep: Prepared, p: np.ndarray, progress, store=None):
    """The sigma form of DROMO (a point mass): its own driver schedules the outputs in physical
    time (propagation/dromo.py); rows [r, v] are Cowell states of the single body.  ``store``
    (tetherlab/runstore.py): rows streamed and the loop checkpointed between its compiled calls."""
    from .formulations import dromo
    from .model.params import FORM_DROMO_SIGMA
    from .propagation import dromo as drive

    lay = prep.model.state
    r0, v0 = prep.y0[lay.root_r], prep.y0[lay.root_v]
    length_m = float(np.linalg.norm(r0))  # L = |r0| (docs/dromo.md section 2)
    pe = dromo.attach(p, FORM_DROMO_SIGMA, prep.mu_m3_s2, length_m, prep.y0.size,
                      dromo.TIME_ELEMENTS[prep.time_element])  # fmt: skip
    res = drive.integrate_sigma(
        prep.method, pe, r0, v0, prep.t_out, prep.rtol,
        prep.atol[0] / prep.ref_radius_m, prep.mu_m3_s2, length_m, max_steps=prep.max_steps,
        progress=progress, store=store,
    )  # fmt: skip
    return res, pe


def _integrate_cowell(prep: Prepared, p: np.ndarray, progress, **store):
    """``store``: y_out, checkpoint, restart for runs written as they go (tetherlab/runstore.py)."""
    from .integrators.driver import integrate
    from .tether.newton_solver import choose as choose_newton

    return integrate(prep.method, cowell_rhs, prep.t0_s, prep.y0, prep.t_out, p, prep.rtol, prep.atol,
                     h_max=prep.h_max, max_steps=prep.max_steps, progress=progress,
                     second_order=_second_order(prep.model),
                     newton=choose_newton(p, prep.y0.size, _second_order(prep.model)), breaks=prep.breaks_s,
                     at_interval=_interval_setter(p), at_sides=_sides_setter(prep, p), **_event_args(prep),
                     **store)  # fmt: skip


def _second_order(model):
    """The driver's ``second_order`` for a state y = [q, q', attitude, wheels] with q' exact for the
    first n_qt components (the state layout): RADAU5 reduces its Newton systems to n - n_qt
    unknowns.  True (y = [q, q'] exactly) without first-order blocks."""
    return True if not model.state.has_attitude else model.state.n_qt


class _ProgressBar:
    """A tqdm bar that appears only on runs longer than a couple of seconds."""

    def __init__(self, t_end: float, enabled: bool | None):
        self.t_end = t_end
        self.enabled = enabled
        self.start = time.perf_counter()
        self.bar = None
        self.last = 0.0
        # (wall-clock s, simulated s) after every chunk: the run summary's slow-down check (regime.py)
        self.trace: list[tuple[float, float]] = []

    def update(self, t: float) -> None:
        self.trace.append((time.perf_counter(), float(t)))
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
