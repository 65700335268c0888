"""A run of a scene with reels: phases of a fixed rod count between births and retirements.

A reel's first rod varies in length (tether/reel.py).  When it grows past the reel's birth bound
a new rod is born at the reel; when it shrinks below the retirement bound it is merged into the
next.  Either ends a phase: the run's segment loop (pipeline.run_segments) stops at that time,
the state is remapped through the model's StateLayout into the layout of the next rod count
(:func:`birth_state`, or :func:`quasi_static_birth_state` with ``reel.birth = "quasi-static"``;
:func:`retire_state`; docs/deployment.md 6) and the next phase starts
from it.  The laws are prescribed, so the times of births and retirements are known before a
phase starts (:func:`next_change`).

What a phase keeps: its own :class:`~tetherlab.result.Result` (its own columns: the rod count
differs), and the reel table (:data:`tetherlab.tether.reel_diagnostics.REEL_COLUMNS`) with the
material invariants that are continuous across phases: momentum, angular momentum and energy of
bodies, stored tether and rods, and the energy taken out at the exit, integrated over the run.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd

from . import diagnostics as diag
from .errors import SceneError
from .scene.reels import length_at, speed_at, table_spline

SQ3 = math.sqrt(3.0)


@dataclass
class DeploymentResult:
    """``phases``: one Result per phase (its own rod count); ``reel``: per output row and reel,
    the reel's quantities (t_s, phase, reel, rods, stored_length_m, REEL_COLUMNS, exit_work_J,
    carnot_J); ``invariants``: per row the material momentum, angular momentum and energy of the
    whole system and energy + exit work; ``changes``: the births and retirements."""

    phases: list
    reel: pd.DataFrame
    invariants: pd.DataFrame
    changes: list = field(default_factory=list)
    status: int = 0
    message: str = ""
    stopped_by: str | None = None

    @property
    def ok(self) -> bool:
        return self.status == 0


def reel_tethers(scene) -> list:
    return [t for t in scene.tethers if t.reel is not None]


def check_law(scene, duration_s: float) -> None:
    """The law must keep 0 < L(t) <= deployed + stored over the run (a SceneError naming the key)."""
    for t in reel_tethers(scene):
        r = t.reel
        path = f"tethers.{t.name}.reel"
        line = t.length_m + r.stored_length_m
        if r.spool is not None:  # its length is state: the kernel stops a run that spends the line
            for j, start in enumerate(s.start_s for s in r.spool.stages):
                if start is not None and not start < duration_s:
                    raise SceneError(f"{path}.stages[{j}].start", f"a start within the run (before {duration_s:.6g} s)",
                                     f"{start:.6g} s")  # fmt: skip
            continue
        if r.law == "table":
            if r.times_s[-1] < duration_s:
                raise SceneError(f"{path}.times", f"a table reaching the end of the run ({duration_s:.6g} s)",
                                 f"a last time of {r.times_s[-1]:.6g} s")  # fmt: skip
            ts = np.linspace(0.0, duration_s, 20001)
            ls = table_spline(r)(ts)
            if not ls.min() > 0.0:
                raise SceneError(f"{path}.lengths", "lengths whose spline stays positive over the run",
                                 f"L = {ls.min():.6g} m at t = {ts[ls.argmin()]:.6g} s")  # fmt: skip
            end = float(ls.max())
        else:
            end = length_at(r, t.length_m, duration_s)
        if r.law == "constant" and not end > 0.0:
            when = t.length_m / -r.speed_m_s
            raise SceneError(f"{path}.speed", f"a speed that keeps the deployed length positive over the run "
                             f"({duration_s:.6g} s); at most {t.length_m / duration_s:.6g} m/s of retrieval",
                             f"{r.speed_m_s:.6g} m/s (L reaches 0 at t = {when:.6g} s)")  # fmt: skip
        if max(end, t.length_m) > line * (1.0 + 1e-12):
            raise SceneError(f"{path}.stored_length", f"at least {max(end, t.length_m) - t.length_m:.6g} m: the law "
                             f"deploys {end:.6g} m by the end of the run", f"{r.stored_length_m:.6g} m")  # fmt: skip


def next_change(reel, length0_m: float, rods: int, t_a: float, t_end: float):
    """The first time after t_a when the first rod reaches a bound: (t, kind) with kind 'birth',
    'retire' or 'retrieved' (the last rod below the retirement bound), or (inf, None)."""
    if reel.spool is not None:  # a spool law's births and retirements are located events of the run
        return (math.inf, None)
    fixed = (rods - 1) * reel.rod_length_m
    targets = [(fixed + reel.birth_length_m, "birth")]
    targets.append((fixed + reel.retire_length_m, "retire" if rods > 1 else "retrieved"))
    best = (math.inf, None)
    for target, kind in targets:
        if reel.law == "table":
            roots = [float(x) for x in table_spline(reel).solve(target, extrapolate=True)
                     if x > t_a * (1.0 + 1e-12) + 1e-9]  # fmt: skip
            if not roots:
                continue
            tc = min(roots)
        elif reel.law == "constant":
            if reel.speed_m_s == 0.0:
                continue
            tc = (target - length0_m) / reel.speed_m_s
        else:
            if reel.rate_1_s == 0.0:
                continue
            tc = math.log(target / length0_m) / reel.rate_1_s
        # a change at t_a itself is the one just made (its bound is now a rod away)
        if tc > t_a * (1.0 + 1e-12) + 1e-9 and tc <= t_end and tc < best[0]:
            best = (tc, kind)
    return best


def reel_start(model, y0: np.ndarray) -> np.ndarray:
    """The initial state of a scene whose tethers are paid out by reels: the straight start the
    initial layout made for equal rods, re-cut to the reel's rods (the first at the reel
    shorter; the ends and the strain kept), and the line moving out of the reel at the law's
    speed L'(0)(1 + eps) relative to the rigid motion (no velocity jump at the first instant)."""
    from .model.params import REEL_LAW_CONSTANT, REEL_LAW_TABLE, ParamView

    y = np.array(y0, float)
    lay = model.state
    v = ParamView(model.p)
    lengths = model.rod_lengths()
    for i in range(v.n_reels):
        rv = v.reel(i)
        k = int(rv.tether)
        sl = model.rod_slices[k]
        gs = range(sl.start, sl.stop)
        S = sum(y[lay.rod(g)] for g in gs) * 2 * SQ3
        Sd = sum(y[lay.rod_rate(g)] for g in gs) * 2 * SQ3
        L = sum(lengths[g] for g in gs)
        for g in gs:
            y[lay.rod(g)] = S * lengths[g] / L / (2 * SQ3)
            y[lay.rod_rate(g)] = Sd * lengths[g] / L / (2 * SQ3)
        eps = float(np.linalg.norm(S)) / L - 1.0
        u = S / np.linalg.norm(S)
        if int(rv.law) == REEL_LAW_CONSTANT or int(rv.state_offset) >= 0:  # a spool law: L'(0)
            speed = rv.speed_m_s
        elif int(rv.law) == REEL_LAW_TABLE:
            speed = float(model.p[int(rv.table_offset) + 2])  # a1 of the first interval: L'(0)
        else:
            speed = rv.rate_1_s * rv.length0_m
        y[lay.rod_rate(sl.start)] += speed * (1.0 + eps) * u / (2 * SQ3)
    return y


#: The deliberate defects of the Python remaps (negative controls only; None in every user run),
#: passed down as ``remap_defect`` from :func:`simulate_reel` / :func:`run_phases`:
#: "linear-only": a retirement restores the linear momentum only (the remap before section 6.3 of
#: docs/deployment.md); "cut-nominal": a birth's cut fraction la/l taken against the nominal rod
#: length l - la instead of the first rod's length l, so the new joint sits at la/(l - la) of the
#: chord (1/2 instead of 1/3 at a birth of 1.5 rods): the new rods are strained by a fixed fraction
#: whatever the rod length, an error per birth that does not shrink with the rods (docs 8c).
#: "transport-dropped": the new rods get the affine field alone, the material's transport velocity
#: (1 - s) w dropped (birth_state at speed 0): a wrong limit that part G's order and bounds gates
#: pass and the continuum gate catches (docs 8h).
REMAP_DEFECTS = ("linear-only", "cut-nominal", "transport-dropped")


def check_remap_defect(remap_defect) -> None:
    if remap_defect is not None and remap_defect not in REMAP_DEFECTS:
        raise ValueError(f"remap_defect: expected None or one of {', '.join(map(repr, REMAP_DEFECTS))}; "
                         f"got {remap_defect!r}")


def birth_state(lay_old, lay_new, y: np.ndarray, g0: int, l_m: float, la_m: float, speed_m_s: float,
                remap_defect: str | None = None) -> np.ndarray:
    """The state after a birth: rod g0 (length l, at the reel) cut at the material point la from
    the reel into a new first rod (la, varying) and a full rod (l - la).  Every point of the line
    keeps its position and its material velocity v_A + s D' + (1 - s) w (docs/deployment.md 6.1),
    so mass, momentum, angular momentum and kinetic energy are those of before, to round-off.
    ``remap_defect``: "cut-nominal" or "transport-dropped" for the negative controls
    (:data:`REMAP_DEFECTS`)."""
    d = y[lay_old.rod(g0)]
    dd = y[lay_old.rod_rate(g0)]
    f = la_m / l_m
    if remap_defect == "cut-nominal":  # negative control only (REMAP_DEFECTS)
        f = la_m / (l_m - la_m)
    if remap_defect == "transport-dropped":  # negative control only (REMAP_DEFECTS)
        speed_m_s = 0.0
    lam = speed_m_s / l_m
    d_a = f * d
    dd_a = f * dd + (1.0 - f) * lam * d
    return _with_rods(lay_old, lay_new, y, g0, 1, [(d_a, dd_a), (d - d_a, dd - dd_a)])


def quasi_static_offset(y, lay, g0: int, l_m: float, la_m: float, l2_m: float, speed_m_s: float):
    """(delta, delta') of the new joint of a birth from the straight cut (:func:`birth_state`) to
    the line's quasi-static shape: the quadratic through the exit, the reel rod's far end B and
    the next rod's far end C, in the unstretched coordinate s (A at 0, B at l, C at l + l2),
    evaluated at the cut s = la; the same for the material velocity (v_A + w at the exit), each
    taken perpendicular to the reel rod's chord (docs/deployment.md 6.4)."""
    k2 = 2 * SQ3
    D, Dd = k2 * y[lay.rod(g0)], k2 * y[lay.rod_rate(g0)]
    D2, D2d = k2 * y[lay.rod(g0 + 1)], k2 * y[lay.rod_rate(g0 + 1)]
    w = (speed_m_s / l_m) * D
    # r(s) = A + s (B - A)/l + s (s - l) K, K the second divided difference of (A, B, C)
    K = (D2 / l2_m - D / l_m) / (l_m + l2_m)
    Kv = (D2d / l2_m - (Dd - w) / l_m) / (l_m + l2_m)
    c = la_m * (la_m - l_m)
    u = D / np.linalg.norm(D)
    delta, ddelta = c * K, c * Kv
    return delta - (delta @ u) * u, ddelta - (ddelta @ u) * u


def quasi_static_birth_state(model_old, model_new, y: np.ndarray, k: int, l_m: float, la_m: float, l2_m: float,
                             speed_m_s: float, t_s: float, rho_kg_m: float,
                             restore_momenta: bool = True, remap_defect: str | None = None) -> tuple[np.ndarray, dict]:
    """The birth of :func:`birth_state` with the new joint moved by :func:`quasi_static_offset`
    (placed on the line's quasi-static shape, so that it does not ring), then the centre of mass,
    momentum and angular momentum of before restored by the least change of kinetic energy
    (tetherlab/momentum_remap.py; docs/deployment.md 6.4).  Returns (state, info) with the
    offsets applied; a tether of one rod (no next joint) is cut straight.  ``restore_momenta=False``:
    the joint moved and nothing restored (the negative control of the momentum test)."""
    from .momentum_remap import _roots, centre_and_momenta, restore

    lay_old, lay_new = model_old.state, model_new.state
    g0 = model_old.rod_slices[k].start
    z = birth_state(lay_old, lay_new, y, g0, l_m, la_m, speed_m_s, remap_defect)
    if model_old.rod_slices[k].stop - g0 < 2:
        return z, {"delta_m": np.zeros(3), "delta_rate_m_s": np.zeros(3)}
    delta, ddelta = quasi_static_offset(y, lay_old, g0, l_m, la_m, l2_m, speed_m_s)
    k2 = 2 * SQ3
    z[lay_new.rod(g0)] += delta / k2
    z[lay_new.rod(g0 + 1)] -= delta / k2
    z[lay_new.rod_rate(g0)] += ddelta / k2
    z[lay_new.rod_rate(g0 + 1)] -= ddelta / k2
    if not restore_momenta:
        return z, {"delta_m": delta, "delta_rate_m_s": ddelta}
    # The two rods' material moved by the affine fields xi delta and (1 - xi) delta: their centre
    # of mass by delta/2 each, the system's by (m_a + m_b) delta / (2 M).  That shift is taken
    # back exactly, from the masses, not from the momentum columns: on an orbit those give the
    # centre of mass to ~1e-5 m only (H ~ r x P, differences of 1e13), which is ~0.1 J of
    # potential energy in the central field (docs/deployment.md 6.4)
    c_old, mass, before = centre_and_momenta(model_old, t_s, y)
    shift = -rho_kg_m * l_m * delta / (2.0 * mass)
    for b in _roots(model_new):
        z[lay_new.root_position(b)] += shift
    z, info = restore(model_new, t_s, z, before, c_old, translate=False)
    info["mass_kg"] = mass
    info["delta_m"], info["delta_rate_m_s"], info["shift_m"] = delta, ddelta, shift
    return z, info


def retire_state(model_old, model_new, y: np.ndarray, k: int, rho_kg_m: float, la_m: float, lb_m: float,
                 speed_m_s: float, t_s: float, angular: bool = True) -> np.ndarray:
    """The state after a retirement: the first rod of tether k (length la, at the reel) and the next
    (lb) merged into one rod of la + lb from the exit to the next's far end B.  Two rods become one
    straight rod whose material moves with the field (2.1) of docs/deployment.md, so the momentum
    and angular momentum of their material change (the transport speed, l' (1 + eps) at the exit,
    spread over la + lb instead of la; the kink straightened) and the centre of mass moves a little.
    The merged state is then translated back to the centre of mass of before (the shift from the
    masses, :func:`merge_com_shift`; docs/deployment.md 6.5) and given the rigid
    velocity increment a + omega x (r - c) that restores both momenta: of all velocity changes that
    do, the one that changes the kinetic energy least (docs/deployment.md 6.3;
    tetherlab/momentum_remap.py).  Momentum and angular momentum are kept to round-off; the energy
    changes (reported by the invariants).

    ``angular=False``: the correction of linear momentum alone (the velocity of B changed by
    delta so that the merged rod and what moves with B take -dP back; section 6.2): the negative
    control of the angular-momentum gate only."""
    from .momentum_remap import _roots, centre_of_mass, momenta, restore
    from .system import point_positions

    lay_old = model_old.state
    lay_new = model_new.state
    g0 = model_old.rod_slices[k].start
    n = model_old.rod_slices[k].stop - g0
    d_a, d_b = y[lay_old.rod(g0)], y[lay_old.rod(g0 + 1)]
    dd_a, dd_b = y[lay_old.rod_rate(g0)], y[lay_old.rod_rate(g0 + 1)]
    d, dd = d_a + d_b, dd_a + dd_b
    if angular:
        z = _with_rods(lay_old, lay_new, y, g0, 2, [(d, dd)])
        before = momenta(model_old, t_s, y[None, :])[0]
        c_old, mass = centre_of_mass(model_old, t_s, y)
        # The merge moves the centre of mass by merge_com_shift (from the masses); it is taken back
        # exactly, not from the momentum columns, whose centre of mass carries ~1e-5 m of round-off
        # on an orbit (~0.1 J of potential per translation; docs/deployment.md 6.4, 6.5)
        shift = -merge_com_shift(rho_kg_m, la_m, lb_m, 2 * SQ3 * d_a, 2 * SQ3 * d_b) / mass
        for b in _roots(model_new):
            z[lay_new.root_position(b)] += shift
        z, _ = restore(model_new, t_s, z, before, c_old, translate=False)
        return z
    v_a = point_positions(model_old, y)["jvel"][k][0]
    k2 = 2 * SQ3
    m_a, m_b, m = rho_kg_m * la_m, rho_kg_m * lb_m, rho_kg_m * (la_m + lb_m)
    p_old = m_a * (v_a + k2 * dd_a / 2) + m_a * (speed_m_s / la_m) * k2 * d_a / 2 + m_b * (v_a + k2 * dd_a + k2 * dd_b / 2)
    p_new = m * (v_a + k2 * dd / 2) + m * (speed_m_s / (la_m + lb_m)) * k2 * d / 2
    if n >= 3:  # the next rod's near end moves with B: half its mass
        beyond = rho_kg_m * lb_m / 2.0  # (every rod but the first is a full rod of lb)
    else:
        tip = model_old.tethers[k].tip_mass_kg
        beyond = tip if tip > 0 else 0.0
    delta = -(p_new - p_old) / (m / 2.0 + beyond)  # the change of v_B
    dd = dd + delta / k2
    z = _with_rods(lay_old, lay_new, y, g0, 2, [(d, dd)])
    if n >= 3:  # the next rod keeps its far end's velocity
        z[lay_new.rod_rate(g0 + 1)] -= delta / k2
    return z


def merge_com_shift(rho_kg_m: float, la_m: float, lb_m: float, D_a: np.ndarray, D_b: np.ndarray) -> np.ndarray:
    """The first moment of mass (kg m) that a retirement adds: rods of la and lb with chords D_a
    (from the exit) and D_b merged into one rod of la + lb with the chord D_a + D_b.  Each rod's
    material has its centre of mass at the middle of its chord, and the exit and the far end stay,
    so the change is (m_a + m_b)(D_a + D_b)/2 - m_a D_a/2 - m_b (D_a + D_b/2) = (m_a D_b - m_b D_a)/2:
    zero for a straight line of one strain, the kink's and the strain difference's otherwise
    (docs/deployment.md 6.5).  Divided by the total mass it is the move of the centre of mass."""
    return 0.5 * rho_kg_m * (la_m * np.asarray(D_b, float) - lb_m * np.asarray(D_a, float))


def _with_rods(lay_old, lay_new, y, g0, n_out, rods_in) -> np.ndarray:
    """y with rods g0 .. g0 + n_out - 1 replaced by ``rods_in`` [(d, d')] (the blocks of q and q'
    shift; the first-order blocks pass through)."""
    z = np.empty(lay_new.size)
    q_old, qd_old = y[lay_old.q], y[lay_old.qd]
    a, b = lay_old.rod(g0).start, lay_old.rod(g0 + n_out - 1).stop
    new_q = np.concatenate([q_old[:a]] + [r[0] for r in rods_in] + [q_old[b:]])
    new_qd = np.concatenate([qd_old[:a]] + [r[1] for r in rods_in] + [qd_old[b:]])
    z[lay_new.q] = new_q
    z[lay_new.qd] = new_qd
    z[lay_new.first_order] = y[lay_old.first_order]
    return z


def _kernel_index(prep, name: str) -> int:
    return [x.name for x in prep.model.tethers].index(name)


def stage_length(spool, t_s: float) -> float:
    """The commanded length of a tension law at t_s under its time stages: the last stage started at
    or before it (a stage that starts at t_s holds from there: a phase starting at a stage's start
    runs under it).  A stage started by a length is located in the run (:func:`active_stages`)."""
    return spool.commanded_length_m if (j := _time_stage(spool, -1, t_s)) < 0 else spool.stages[j].commanded_length_m


def _time_stage(spool, j: int, t_s: float) -> int:
    """Stage j (-1: the law's own) advanced over the time stages that follow it and have started at
    t_s (the window of :func:`next_change`: a start within 1e-12 t + 1e-9 s of t_s is at it)."""
    while j + 1 < len(spool.stages):
        start = spool.stages[j + 1].start_s
        if start is None or not start <= t_s * (1.0 + 1e-12) + 1e-9:
            break
        j += 1
    return j


def active_stages(tethers, changes: list, t_s: float) -> dict:
    """The stage each staged tension law runs under from t_s on: {tether: j}, -1 the law's own.
    A stage started by a length is a located event of the run, recorded in ``changes`` (change
    "stage"); those after it are started by lengths too (scene/reels.py), so the time stages are
    all before it and known from t_s."""
    out = {}
    for t in tethers:
        if t.reel.spool is None or not t.reel.spool.stages:
            continue
        j = max((c["stage"] for c in changes if c["change"] == "stage" and c["reel"] == t.name), default=-1)
        out[t.name] = _time_stage(t.reel.spool, j, t_s)
    return out


def located_length_tolerance(speed_m_s: float, t_s: float, phase_s: float, length_m: float, n_state: int,
                             rtol: float, atol: float) -> dict:
    """How far from its length a switch located by the event ``reel.<tether>.stage`` may stop
    (docs/deployment.md 10.7a), in metres, by term: ``bracket``, the event's time bracket
    (integrators/common.py event_time_tolerance, the step at most the phase) times |L'|;
    ``roundoff``, 4 eps L; ``integrator``, the integration to the bracket's end against the
    crossing step's polynomial the bracket was found on, both within one step's accepted error:
    an RMS of the n_state scaled errors at most 1 lets one component carry sqrt(n_state) of it,
    sqrt(n) (atol + rtol L); and ``total``."""
    from .integrators.common import EPS, event_time_tolerance

    out = {"bracket": abs(speed_m_s) * event_time_tolerance(t_s, phase_s), "roundoff": 4.0 * EPS * abs(length_m),
           "integrator": math.sqrt(n_state) * (atol + rtol * abs(length_m))}
    out["total"] = out["bracket"] + out["roundoff"] + out["integrator"]
    return out


def set_stage(prep, tethers, active: dict) -> None:
    """Write every staged tension law's parameters of its stage (``active``, :func:`active_stages`)
    into the model's: the commanded length, gains and limits are constant over a phase, and a
    switch ends one (docs/deployment.md 10.6, 10.7); and the length whose reaching starts the next
    stage, the event ``reel.<tether>.stage`` (0: no such stage next)."""
    from .scene.reels import stage_parameters

    reels = p_view(prep.model.p).reels
    for t in tethers:
        if t.name not in active:
            continue
        sp, j = t.reel.spool, active[t.name]
        values = stage_parameters(sp, j)
        nxt = sp.stages[j + 1].at_length_m if j + 1 < len(sp.stages) else None
        k = _kernel_index(prep, t.name)
        for i in range(len(reels)):
            if int(reels[i].tether) == k:
                for name, v in values.items():
                    setattr(reels[i], name, v)
                reels[i].stage_m = nxt if nxt is not None else 0.0


def _deployed(tether, prep, y_end, t_s: float) -> float:
    """The deployed length of a reel tether at the end of a phase: its law's, or its state's."""
    if tether.reel.spool is not None:
        return float(y_end[prep.model.state.spool_of(_kernel_index(prep, tether.name))][0])
    return length_at(tether.reel, tether.length_m, t_s)


def _spool_change(stopped_by, tethers):
    """(tether, 'birth' | 'retire' | 'stage') when a spool law's located event ended the phase,
    else None."""
    if not stopped_by or not stopped_by.startswith("reel."):
        return None
    name, kind = stopped_by[len("reel."):].rsplit(".", 1)
    for t in tethers:
        if t.name == name and kind in ("birth", "retire", "stage"):
            return t, kind
    return None


def due_changes(tethers, state: dict, prep, y_end, t_a: float, t_b: float, t_end: float, first) -> list:
    """Every reel tether whose first rod is at or past a bound at t_b, the end of a phase that a
    change of ``first`` (its tether) ended: [(tether, kind), ...], ``first``'s change first, kinds
    as :func:`next_change`'s.  A change not taken here is never taken: the next phase would start
    with the rod already at its bound, and neither of the two ways a change is found sees that --
    :func:`next_change` skips a time within 1e-12 t + 1e-9 s of the phase's start (the change just
    made), and a spool law's event is a change of side of g = l - bound, so a rod starting at
    g >= 0 never crosses (docs/deployment.md 17.1).  Hence, per law:

    * prescribed (constant, exponential, table): due when its next change falls at or before
      t_b (1 + 1e-12) + 1e-9, exactly the window the next phase would skip;
    * spool: due when l >= l_birth - tol (l <= l_retire + tol), with tol the error of the located
      stop in length: |L'| times the event bracket's width (integrators/common.py
      event_time_tolerance: 64 eps max(|t_b|, |h|), h <= t_b - t_a) plus the round-off of
      l = L - (n - 1) l_rod (4 eps L).  A rod farther below than tol starts the next phase with
      g < 0 and its crossing is located there.

    A phase ended by a stage switch (``first`` (t, 'stage'), :func:`due_stages`) checks t's own
    bounds too: the switch leaves the layout as it is (docs/deployment.md 17.2)."""
    out = [first]
    for t in tethers:
        if t is first[0] and first[1] != "stage":
            continue
        reel, n = t.reel, state[t.name]
        if reel.spool is None:
            tc, kind = next_change(reel, t.length_m, n, t_a, t_end)
            if kind is not None and tc <= t_b * (1.0 + 1e-12) + 1e-9:
                out.append((t, kind))
            continue
        L, speed = (float(x) for x in y_end[prep.model.state.spool_of(_kernel_index(prep, t.name))])
        l_first = L - (n - 1) * reel.rod_length_m
        # the located stop's bracket and round-off terms; not the integration term a stage switch
        # adds (10.7a): with it, births 4.6e-12 m apart on a symmetric hub would share one stop
        # (docs/deployment.md 17.2)
        terms = located_length_tolerance(speed, t_b, t_b - t_a, L, len(y_end), prep.rtol, 0.0)
        tol = terms["bracket"] + terms["roundoff"]
        if l_first >= reel.birth_length_m - tol:
            out.append((t, "birth"))
        elif l_first <= reel.retire_length_m + tol:
            out.append((t, "retire" if n > 1 else "retrieved"))
    return out


def due_stages(tethers, active: dict, prep, y_a, y_end, t_a: float, t_b: float, located=None) -> list:
    """Every staged tension law whose next length stage is due at t_b, the end of a phase that a
    change ended: [(tether, 'stage'), ...], ``located`` (the tether whose switch ended the phase,
    if one did) left out.  Not taking it here would lose it: the event ``reel.<tether>.stage`` is a
    change of side of g = L - a, and a phase that starts with g on its new side never fires it
    (docs/deployment.md 17.2).  Due when g changed side over the phase (its crossing shared the
    located stop's bracket), or when |L - a| at t_b is within the located stop's tolerance in length
    (:func:`located_length_tolerance`, 10.7a): the switch is then as near its length as a located one."""
    out = []
    for t in tethers:
        if t.name not in active or t is located:
            continue
        sp, j = t.reel.spool, active[t.name]
        a = sp.stages[j + 1].at_length_m if j + 1 < len(sp.stages) else None
        if a is None:
            continue
        sl = prep.model.state.spool_of(_kernel_index(prep, t.name))
        L_a = float(y_a[sl][0])
        L_b, speed = (float(x) for x in y_end[sl])
        tol = located_length_tolerance(speed, t_b, t_b - t_a, a, len(y_end), prep.rtol,
                                       float(np.asarray(prep.atol)[sl][0]))["total"]  # fmt: skip
        if (L_a - a < 0.0) != (L_b - a < 0.0) or abs(L_b - a) <= tol:
            out.append((t, "stage"))
    return out


def _rows(model, t, Y):
    """The reel table and the material invariants of a phase's rows."""
    from .tether.reel_diagnostics import R_NCOL, reel_rows

    p = model.fresh_params()
    nreel = int(p_view(p).n_reels)
    out = np.full((len(t), nreel, R_NCOL), np.nan)
    lay = model.state
    acc = np.zeros(lay.n_qt)
    datt = np.zeros(lay.first_order.stop - lay.first_order.start)
    bad = reel_rows(np.ascontiguousarray(t, float), np.ascontiguousarray(Y, float), p, out, acc, datt)
    d = diag.compute(model, t, Y)
    return out, d, bad


def p_view(p):
    from .model.params import ParamView

    return ParamView(p)


def phase_rows(tethers, ph: int, rods: dict, t, out, d) -> tuple[list, dict]:
    """A phase's rows of the reel table (one dict of columns per reel) and of the invariants, as
    arrays (the phase, reel and rod count as scalars), from the kernel's reel rows ``out`` and the
    diagnostics ``d`` (:func:`_rows`).  No frame is built per phase: :func:`rows_frame` makes one
    table of all the phases' dicts at the end of the run (docs/deployment.md 8d)."""
    from .tether.reel_diagnostics import REEL_COLUMNS

    g = d["global"]
    reel_parts = []
    for i, tt in enumerate(tethers):
        cols = {"t_s": t, "phase": ph, "reel": tt.name, "rods": rods[tt.name]}
        for c, name in enumerate(REEL_COLUMNS):
            cols[name] = out[:, i, c]
        cols["stored_length_m"] = tt.length_m + tt.reel.stored_length_m - out[:, i, 0]
        reel_parts.append(cols)
    corr = out[:, :, 9:16].sum(axis=1)
    inv = {"t_s": t, "phase": ph}
    for j, ax in enumerate("xyz"):
        inv[f"momentum_{ax}_N_s"] = g[:, diag.G_PX + j] + corr[:, j]
    for j, ax in enumerate("xyz"):
        inv[f"angmom_{ax}_kg_m2_s"] = g[:, diag.G_HX + j] + corr[:, 3 + j]
    inv["kinetic_J"] = g[:, diag.G_KE] + corr[:, 6]
    inv["energy_J"] = g[:, diag.G_E] + corr[:, 6]
    inv["exit_power_W"] = out[:, :, 7].sum(axis=1)
    return reel_parts, inv


def rows_frame(parts: list) -> pd.DataFrame:
    """One table of :func:`phase_rows`' dicts in order (every dict has the same columns), as
    ``pd.concat([pd.DataFrame(p) for p in parts], ignore_index=True)`` gives it, the dtypes
    included, with one frame built instead of one a phase and reel."""
    if not parts:
        return pd.DataFrame()
    sizes = [len(np.asarray(p["t_s"])) for p in parts]
    cols = {}
    for name, first in parts[0].items():
        if isinstance(first, str):
            cols[name] = np.array([p[name] for p, n in zip(parts, sizes) for _ in range(n)], dtype=object)
        elif isinstance(first, (int, np.integer)):
            cols[name] = np.repeat(np.array([p[name] for p in parts], dtype=np.int64), sizes)
        else:
            cols[name] = np.concatenate([np.asarray(p[name], dtype=float) for p in parts])
    return pd.DataFrame(cols)


def phase_tables(tethers, ph: int, rods: dict, t, out, d) -> tuple[list, pd.DataFrame]:
    """A phase's rows of the reel table (one frame per reel) and of the invariants
    (:func:`phase_rows` as frames: the run store writes each phase's parts as it ends)."""
    reel_parts, inv = phase_rows(tethers, ph, rods, t, out, d)
    return [pd.DataFrame(c) for c in reel_parts], pd.DataFrame(inv)


def integrated_tables(reel_df: pd.DataFrame, inv_df: pd.DataFrame) -> None:
    """Add the energies taken out at the exit, integrated phase by phase over the whole run
    (trapezoid on the outputs; docs/deployment.md 8 says how fine the outputs must be for the
    energy gate): ``exit_work_J`` and ``energy_plus_exit_work_J`` to the invariants, ``carnot_J``
    to the reel table.  A phase's first row repeats its predecessor's last time (the same instant
    in the next layout), so no interval spans two phases."""
    # each interval's trapezoid, 0 across a phase change, summed in row order (np.cumsum adds
    # left to right: the same sums as a loop over the rows)
    work = _trapezoid_sums(inv_df["t_s"].to_numpy(), inv_df["exit_power_W"].to_numpy(), inv_df["phase"].to_numpy())
    inv_df["exit_work_J"] = work
    inv_df["energy_plus_exit_work_J"] = inv_df["energy_J"] + work
    carnot = np.zeros(len(reel_df))
    for _, part in reel_df.groupby("reel", sort=False):
        tt, cp, phs = (part[c].to_numpy() for c in ("t_s", "carnot_power_W", "phase"))
        carnot[part.index.to_numpy()] = _trapezoid_sums(tt, cp, phs)
    reel_df["carnot_J"] = carnot
    # a spool law's brake work and exit loss, integrated as the exit work (docs/deployment.md 10.3)
    for col, power in (("brake_work_J", "brake_power_W"), ("exit_loss_J", "exit_loss_power_W")):
        vals = np.zeros(len(reel_df))
        for _, part in reel_df.groupby("reel", sort=False):
            tt, pw, phs = (part[c].to_numpy() for c in ("t_s", power, "phase"))
            vals[part.index.to_numpy()] = _trapezoid_sums(tt, pw, phs)
        reel_df[col] = vals


def _trapezoid_sums(t, power, phase) -> np.ndarray:
    """The running trapezoid integral of ``power`` over the rows, each interval inside a phase
    (an interval across a phase change adds 0: its ends are the same instant)."""
    inc = np.where(phase[1:] == phase[:-1], 0.5 * (power[1:] + power[:-1]) * (t[1:] - t[:-1]), 0.0)
    return np.cumsum(np.concatenate([[0.0], inc])) if len(t) else np.zeros(0)


class MemoryPhases:
    """The phases of :func:`run_phases` kept in memory (``simulate``): one Result per phase (built
    when first read: :class:`~tetherlab.result.DeferredResult`), the reel and invariant rows as
    arrays (one table each at the end: :func:`rows_frame`).  The run store's counterpart, written
    to a run directory as it goes, is tetherlab/reelstore.py; both answer the same four calls."""

    resume = None  # a loop state to continue from (the run store's checkpoint); None: from the start
    prepare_options: dict = {}

    def __init__(self, scene):
        self.scene = scene
        self.phases, self.reel_parts, self.inv_parts = [], [], []

    def start_phase(self, loop: dict) -> None:
        """Called with the loop's state before each phase (the run store checkpoints it)."""

    def run_phase(self, loop: dict, prep, p, update):
        from .pipeline import run_segments, segment_plan

        return run_segments(prep, segment_plan(prep, p), update), p

    def end_phase(self, loop: dict, prep, res, stats: dict, message: str, p, d, reel_parts, inv) -> None:
        from functools import partial

        from .result import DeferredResult, Result

        # the model's parameters are written again before the next phase when it goes on with the
        # same model (a table knot or a stage: set_stage), so the Result is built from a copy
        prep = replace(prep, model=replace(prep.model, p=prep.model.p.copy()))
        build = partial(Result.from_run, self.scene, prep, res.t, res.y, d, stats, res.status, message, p)
        self.phases.append(DeferredResult(build, stats, res.status, message))
        self.reel_parts.extend(reel_parts)
        self.inv_parts.append(inv)


def run_phases(scene, sink, *, progress=None, defect: int = 0, remap_defect: str | None = None):
    """The one phase loop of a scene with reels (module docstring), for ``simulate`` (``sink`` a
    :class:`MemoryPhases`) and for ``tetherlab run`` (tetherlab/reelstore.py).  Between phases
    the loop's whole state is ``loop`` (phase index, start time and state, rods per reel tether,
    the rods and lengths the current model was built with, the changes so far): the sink is
    handed it before each phase, and a sink with ``resume`` set continues from one.  Returns
    (status, message, stopped_by, changes).  ``remap_defect``: negative controls of the Python
    remaps only (:data:`REMAP_DEFECTS`)."""
    check_remap_defect(remap_defect)
    from .pipeline import _ProgressBar, prepare, run_outcome

    tethers = reel_tethers(scene)
    opts = sink.prepare_options
    prep0 = prepare(scene, **opts)
    t_out = prep0.t_out
    t_end = float(t_out[-1])
    check_law(scene, t_end)
    bar = _ProgressBar(t_end, enabled=progress) if not callable(progress) else None
    update = bar.update if bar is not None else progress
    knots = sorted({float(x) for t in tethers if t.reel.law == "table" for x in t.reel.times_s[1:-1]}
                   | {float(s.start_s) for t in tethers if t.reel.spool is not None for s in t.reel.spool.stages
                      if s.start_s is not None})  # fmt: skip
    loop = sink.resume or {"phase": 0, "t_a": 0.0, "y": prep0.y0, "rods": {t.name: t.rods for t in tethers},
                           "model_rods": None, "changes": []}  # fmt: skip
    # the model of the phase: the first one's, or rebuilt after the last birth or retirement
    prep = prep0
    if loop["model_rods"] is not None:
        prep = prepare(scene, reel_phase={"first": prep0, "rods": loop["model_rods"]}, **opts)
    status, message, stopped = 0, "", None
    try:
        while True:
            t_a, y, state, ph, changes = loop["t_a"], loop["y"], loop["rods"], loop["phase"], loop["changes"]
            # the next birth or retirement of any reel
            nxt = (math.inf, None, None)
            for t in tethers:
                tc, kind = next_change(t.reel, t.length_m, state[t.name], t_a, t_end)
                if tc < nxt[0]:
                    nxt = (tc, kind, t)
            # a table law's knots end a phase too, so that no step straddles the jump of L's third derivative;
            # so does a tension law's stage (its command jumps: docs/deployment.md 10.6)
            knot = min((k for k in knots if k > t_a * (1.0 + 1e-12) + 1e-9), default=math.inf)
            if knot < nxt[0] and knot < t_end:
                nxt = (knot, "knot", None)
            t_b = min(nxt[0], t_end)
            inside = t_out[(t_out > t_a) & (t_out < t_b)]
            times = np.concatenate([[t_a], inside, [t_b]])
            prep = replace(prep, y0=y, t_out=times, t0_s=t_a)
            p_view(prep.model.p).defect = defect  # 0 in every user run
            set_stage(prep, tethers, active_stages(tethers, changes, t_a))
            sink.start_phase(loop)
            res, p = sink.run_phase(loop, prep, prep.model.fresh_params(), update)
            stats, msg = run_outcome(prep, res, p, 0.0)
            out, d, _ = _rows(prep.model, res.t, res.y)
            reel_parts, inv = phase_rows(tethers, ph, state, res.t, out, d)
            sink.end_phase(loop, prep, res, stats, msg, p, d, reel_parts, inv)
            spool_change = _spool_change(stats.get("stopped_by"), tethers) if res.status == 0 else None
            if spool_change is not None:
                # a spool law's first rod reached a bound, or its deployed length the next stage's
                # (docs/deployment.md 10.7): located, the phase ends there
                t_b = float(res.t[-1])
                nxt = (t_b, spool_change[1], spool_change[0])
                if spool_change[1] == "retire" and state[spool_change[0].name] == 1:
                    nxt = (t_b, "retrieved", spool_change[0])
            elif res.status != 0 or res.stopped_by is not None:
                status, message = res.status, msg
                stopped = stats.get("stopped_by")
                break
            if nxt[1] is None or (t_b >= t_end and spool_change is None):
                break
            if nxt[1] == "knot":  # the same model goes on from the knot
                loop = dict(loop, phase=ph + 1, t_a=t_b, y=res.y_end)
                continue
            # a birth, a retirement, a stage switch or the last rod retrieved: the phase ends at t_b,
            # with every reel at its bound there (due_changes) and every stage at its length
            # (due_stages), taken at t_b in that order: a switch only rewrites the law's parameters
            # at the next phase's start, and a remap reads neither them nor changes them
            # (docs/deployment.md 17.2)
            active, prep_b = active_stages(tethers, changes, t_a), prep
            due = due_changes(tethers, state, prep, res.y_end, t_a, t_b, t_end, (nxt[2], nxt[1]))
            due += due_stages(tethers, active, prep, y, res.y_end, t_a, t_b,
                              nxt[2] if nxt[1] == "stage" else None)  # fmt: skip
            retrieved = [(t, kind) for t, kind in due if kind == "retrieved"]
            if retrieved:
                t = retrieved[0][0]
                stopped = f"reel.{t.name}.retrieved"
                message = (f"run stopped at t = {t_b:.9g} s: the tether {t.name!r} was retrieved to its last rod's "
                           f"retirement bound ({t.reel.retire_length_m:.6g} m deployed); outputs up to it are kept")  # fmt: skip
                changes.append({"t_s": t_b, "reel": t.name, "change": "retrieved", "rods": state[t.name]})
                break
            y_b, y, model_rods = res.y_end, res.y_end, loop["model_rods"]
            for t, kind in due:
                if kind == "stage":  # the same model goes on under the next stage (set_stage)
                    L = float(y_b[prep_b.model.state.spool_of(_kernel_index(prep_b, t.name))][0])
                    changes = changes + [{"t_s": t_b, "reel": t.name, "change": "stage", "stage": active[t.name] + 1,
                                          "length_m": L}]  # fmt: skip
                    continue
                prep, y, state, model_rods = _remap(scene, opts, prep0, prep, y, state, tethers, t, kind, t_b,
                                                    remap_defect)  # fmt: skip
                changes = changes + [{"t_s": t_b, "reel": t.name, "change": kind, "rods": state[t.name]}]
            loop = {"phase": ph + 1, "t_a": t_b, "y": y, "rods": state, "model_rods": model_rods, "changes": changes}
    finally:
        if bar is not None:
            bar.close()
    return status, message, stopped, loop["changes"]


def _remap(scene, opts, prep0, prep, y_end, state, tethers, t, kind: str, t_b: float, remap_defect):
    """One birth or retirement of tether t at t_b: (the next model's prep, its state, the rods per
    reel tether, the rods and lengths the model was built with)."""
    from .pipeline import prepare

    reel = t.reel
    n = state[t.name]
    lay_old = prep.model.state
    k = _kernel_index(prep, t.name)
    g0 = prep.model.rod_slices[k].start
    if reel.spool is not None:  # its length and rate are state
        L, speed = (float(x) for x in y_end[prep.model.state.spool_of(k)])
    else:
        L = length_at(reel, t.length_m, t_b)
        speed = speed_at(reel, t.length_m, t_b)
    l_first = L - (n - 1) * reel.rod_length_m
    n_new = n + 1 if kind == "birth" else n - 1
    state = dict(state, **{t.name: n_new})
    model_rods = {x.name: (state[x.name], _deployed(x, prep, y_end, t_b)) for x in tethers}
    nxt_prep = prepare(scene, reel_phase={"first": prep0, "rods": model_rods}, **opts)
    lay_new = nxt_prep.model.state
    if kind == "birth" and reel.birth == "quasi-static":
        y, _ = quasi_static_birth_state(prep.model, nxt_prep.model, y_end, k, l_first,
                                        l_first - reel.rod_length_m, reel.rod_length_m, speed, t_b,
                                        t.mass_kg / t.length_m, remap_defect=remap_defect)
    elif kind == "birth":
        y = birth_state(lay_old, lay_new, y_end, g0, l_first, l_first - reel.rod_length_m, speed, remap_defect)
    else:
        rho = t.mass_kg / t.length_m
        y = retire_state(prep.model, nxt_prep.model, y_end, k, rho, l_first, reel.rod_length_m, speed, t_b,
                         angular=remap_defect != "linear-only")
    return nxt_prep, y, state, model_rods


def simulate_reel(scene, *, progress=None, raise_on_failure: bool = True, defect: int = 0,
                  remap_defect: str | None = None) -> DeploymentResult:
    """Run a scene with reels phase by phase (module docstring), in memory.  A failed phase ends
    the run and keeps every output before it; a retrieval of the last rod stops it with the event
    'reel.<tether>.retrieved'.  ``defect``: negative controls only (kernel/layout.py DEFECT_*);
    ``remap_defect``: those of the Python remaps (:data:`REMAP_DEFECTS`)."""
    from .pipeline import SimulationError

    sink = MemoryPhases(scene)
    status, message, stopped, changes = run_phases(scene, sink, progress=progress, defect=defect,
                                                  remap_defect=remap_defect)
    reel_df = rows_frame(sink.reel_parts)
    inv_df = rows_frame(sink.inv_parts)
    integrated_tables(reel_df, inv_df)
    result = DeploymentResult(sink.phases, reel_df, inv_df, changes, status, message, stopped)
    if status != 0 and raise_on_failure:
        raise SimulationError(message, sink.phases[-1])
    return result
