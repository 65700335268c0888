"""Where the steps of a deployment go (docs/deployment.md 8b): counts, independent of the load.

The bench's deployment (tetherlab/benchmarks/deployment.py, 500 m rods, 39 births) measured three
ways, every count summed over the phases:

1. the cost of a restart: every phase restarted once and three more times inside (breakpoints:
   a fresh initial step and RADAU5's workspace rebuilt, as at a birth);
2. where the steps fall inside a phase: each phase integrated as four quarters, steps per quarter;
3. ``error_scale = "tether"`` against "rod": steps, and how far the end mass moves relative to the
   station, at the end and over every output row;
4. ``reel.birth = "quasi-static"`` against "straight" (docs/deployment.md 6.4), with either error
   scale: steps, the largest energy jump at a birth, and the end mass's move at the end;
5. which components hold the error test (docs/deployment.md 6.5): one phase re-integrated with
   the absolute tolerance of one block of the state loosened 1e4 times, and the whole run with
   RADAU5's Newton-rate cap off;
6. other placements of the new joint (docs/deployment.md 6.5): the quasi-static offset with its
   rate scaled by 0 and 2, and the joint (or the joint and B) moved across the line until its
   acceleration is the old rod's material acceleration there (an experiment, not a birth option);
7. what the cost comes with: phases re-integrated with the reel stopped, or with the line's
   transverse shape and rates smoothed by a polynomial in s; the same deployment started at 5 km;
   a 20-rod line at equilibrium with one joint kicked sideways (the error test's sensitivity);
8. the retirement's centre of mass on an orbit (docs/deployment.md 6.5): the bench's line hauled in
   from 5 km at 2 m/s (five merges), with the translation from the masses and with the former one
   from the momentum columns: energy jumps at the merges and the line's angle at the end.

Run: ``python -m studies.deployment_steps`` (~3 min on a loaded 2-core machine; not in make verify).
"""

from __future__ import annotations

import dataclasses

import numpy as np


def _run(rod_m: float, error_scale: str, phase_hook):
    """The deployment with each phase integrated by ``phase_hook(prep, p, update) -> res``."""
    import tetherlab.deployment as dep
    from tetherlab.benchmarks.deployment import _scene
    from tetherlab.pipeline import simulate

    orig = dep.MemoryPhases.run_phase
    dep.MemoryPhases.run_phase = lambda self, loop, prep, p, update: (phase_hook(loop, prep, p, update), p)
    try:
        return simulate(_scene(rod_m, True, error_scale), progress=False)
    finally:
        dep.MemoryPhases.run_phase = orig


def restarts(rod_m: float = 500.0, extra=(0, 1, 3)) -> dict:
    """Accepted steps with ``k`` extra restarts per phase, for each k of ``extra``."""
    from tetherlab.pipeline import run_segments, segment_plan

    out = {}
    for k in extra:
        tot = {"n_accepted": 0, "n_rejected": 0, "phases": 0}

        def hook(loop, prep, p, update, k=k, tot=tot):
            t_a, t_b = float(prep.t_out[0]), float(prep.t_out[-1])
            mids = tuple(t_a + (t_b - t_a) * j / (k + 1) for j in range(1, k + 1))
            prep = dataclasses.replace(prep, breaks_s=tuple(sorted(set(prep.breaks_s) | set(mids))))
            res = run_segments(prep, segment_plan(prep, p), update)
            tot["n_accepted"] += res.stats["n_accepted"]
            tot["n_rejected"] += res.stats["n_rejected"]
            tot["phases"] += 1
            return res

        _run(rod_m, "rod", hook)
        out[k] = tot
    return out


def quarters(rod_m: float = 500.0) -> list:
    """Per phase (index, rods, [steps in each quarter]), each quarter its own integration."""
    from tetherlab.pipeline import run_segments, segment_plan

    rows = []

    def hook(loop, prep, p, update):
        t_a, t_b = float(prep.t_out[0]), float(prep.t_out[-1])
        edges = np.linspace(t_a, t_b, 5)
        y, q = prep.y0, []
        for a, b in zip(edges[:-1], edges[1:]):
            pr = dataclasses.replace(prep, y0=y, t0_s=a, t_out=np.array([a, b]))
            res = run_segments(pr, segment_plan(pr, p), update)
            y = res.y_end
            q.append(int(res.stats["n_accepted"]))
        rows.append((loop["phase"], sum(loop["rods"].values()), q))
        return run_segments(prep, segment_plan(prep, p), update)

    _run(rod_m, "rod", hook)
    return rows


def error_scales(rod_m: float = 500.0) -> dict:
    """Steps with each error scale and the end mass's move relative to the station (m)."""
    from tetherlab.pipeline import run_segments, segment_plan

    rel, steps = {}, {}
    for scale in ("rod", "tether"):
        n = [0]

        def hook(loop, prep, p, update, n=n):
            res = run_segments(prep, segment_plan(prep, p), update)
            n[0] += int(res.stats["n_accepted"])
            return res

        r = _run(rod_m, scale, hook)
        steps[scale] = n[0]
        rel[scale] = np.concatenate([ph.timeseries[["mf.x_m", "mf.y_m", "mf.z_m"]].to_numpy()
                                     - ph.timeseries[["m0.x_m", "m0.y_m", "m0.z_m"]].to_numpy() for ph in r.phases])  # fmt: skip
    d = rel["tether"] - rel["rod"]
    return {"steps": steps, "end_move_m": float(np.linalg.norm(d[-1])),
            "max_move_m": float(np.linalg.norm(d, axis=1).max())}  # fmt: skip


def births(rod_m: float = 500.0) -> dict:
    """Per (error scale, birth): accepted steps, the largest |energy jump| at a birth (J), and the
    end mass's position relative to the station at the end (m)."""
    from tetherlab.benchmarks.deployment import _scene
    from tetherlab.pipeline import simulate

    out = {}
    for scale in ("rod", "tether"):
        for birth in ("straight", "quasi-static"):
            r = simulate(_scene(rod_m, True, scale, birth), progress=False)
            inv = r.invariants
            e, ph = inv["energy_J"].to_numpy(), inv["phase"].to_numpy()
            jumps = np.abs(np.diff(e))[np.diff(ph) != 0]
            ts = r.phases[-1].timeseries
            rel = ts[["mf.x_m", "mf.y_m", "mf.z_m"]].to_numpy()[-1] - ts[["m0.x_m", "m0.y_m", "m0.z_m"]].to_numpy()[-1]
            out[(scale, birth)] = {"steps": sum(int(p.stats["n_accepted"]) for p in r.phases),
                                   "max_energy_jump_J": float(jumps.max()) if jumps.size else 0.0, "end_rel_m": rel}  # fmt: skip
    for scale in ("rod", "tether"):
        d = out[(scale, "quasi-static")]["end_rel_m"] - out[(scale, "straight")]["end_rel_m"]
        out[(scale, "quasi-static")]["end_move_m"] = float(np.linalg.norm(d))
    return out


def error_components(rod_m: float = 500.0, phases=(5, 20, 35), factor: float = 1e4) -> list:
    """Per phase of ``phases`` (quasi-static births, "tether" error scale): its accepted steps,
    then the same phase from the same state with the absolute tolerance of one block multiplied
    by ``factor``: the rods' half-separations d, their rates d', the root's position and velocity,
    the two rods at the reel (d and d'), the rates of every rod beyond them.  The block whose
    loosening cuts the steps is the one the error test follows."""
    from tetherlab.pipeline import run_segments, segment_plan

    rows = []

    def hook(loop, prep, p, update):
        res = run_segments(prep, segment_plan(prep, p), update)
        if loop["phase"] in phases:
            lay, g0 = prep.model.state, prep.model.rod_slices[0].start
            idx = np.arange(lay.size)
            blocks = {"rods d": idx[lay.rods_d], "rods d'": idx[lay.rods_dd],
                      "root r, v": np.r_[idx[lay.root_r], idx[lay.root_v]],
                      "two rods at the reel, d and d'": np.r_[idx[lay.rod(g0)], idx[lay.rod(g0 + 1)],
                                                              idx[lay.rod_rate(g0)], idx[lay.rod_rate(g0 + 1)]],
                      "rods beyond, d'": idx[lay.rods_dd][6:]}  # fmt: skip
            row = {"phase": loop["phase"], "rods": sum(loop["rods"].values()), "steps": int(res.stats["n_accepted"])}
            for name, ix in blocks.items():
                atol = prep.atol.copy()
                atol[ix] *= factor
                pr = dataclasses.replace(prep, atol=atol)
                row[name] = int(run_segments(pr, segment_plan(pr, prep.model.fresh_params()), None).stats["n_accepted"])
            rows.append(row)
        return res

    _run_birth(rod_m, "tether", "quasi-static", hook)
    return rows


def newton_cap_off(rod_m: float = 500.0) -> dict:
    """Accepted steps (rejections) of the deployment ("tether", quasi-static) and of the fixed run
    with RADAU5's Newton-rate cap (THETA_STEP, docs/integrators.md 7) and without it."""
    import tetherlab.integrators.radau5.workspace as ws
    from tetherlab.benchmarks.deployment import _scene
    from tetherlab.pipeline import simulate

    out = {}
    keep = ws.THETA_STEP
    try:
        for cap in (keep, 0.0):
            ws.THETA_STEP = cap
            dep = simulate(_scene(rod_m, True, "tether", "quasi-static"), progress=False)
            fixed = simulate(_scene(rod_m, False, "tether"), progress=False)
            out[cap] = {"deployment": (sum(int(p.stats["n_accepted"]) for p in dep.phases),
                                       sum(int(p.stats["n_rejected"]) for p in dep.phases)),
                        "fixed": (int(fixed.stats["n_accepted"]), int(fixed.stats["n_rejected"]))}  # fmt: skip
    finally:
        ws.THETA_STEP = keep
    return out


def _run_birth(rod_m: float, error_scale: str, birth: str, phase_hook=None):
    """The bench's deployment with ``birth``; each phase through ``phase_hook`` when given."""
    import tetherlab.deployment as dep
    from tetherlab.benchmarks.deployment import _scene
    from tetherlab.pipeline import simulate

    orig = dep.MemoryPhases.run_phase
    if phase_hook is not None:
        dep.MemoryPhases.run_phase = lambda self, loop, prep, p, update: (phase_hook(loop, prep, p, update), p)
    try:
        return simulate(_scene(rod_m, True, error_scale, birth), progress=False)
    finally:
        dep.MemoryPhases.run_phase = orig


def matched_birth_state(model_old, model_new, y, k, l_m, la_m, l2_m, speed_m_s, t_s, rho_kg_m, joints: int = 1):
    """The experiment of docs/deployment.md 6.5 (not a birth option): the straight cut of 6.1, then
    the new joint (``joints`` = 2: and B) moved across the line until its acceleration relative
    to the exit is the old rod's material acceleration there, xi D'' + (1 - xi) E (eq. 2.2; B: the
    old D''), by Newton's method on the model's right-hand side (the Jacobian by differences of
    1 mm); velocities those of the straight cut; then the centre of mass put back from the masses
    and P, H restored as in 6.4.  A constant-speed law (l'' = 0)."""
    import math

    from tetherlab.deployment import birth_state
    from tetherlab.formulations.cowell import cowell_rhs_py
    from tetherlab.momentum_remap import _roots, centre_of_mass, momenta, restore

    k2 = 2 * math.sqrt(3.0)
    lo, ln = model_old.state, model_new.state
    g0 = model_old.rod_slices[k].start
    z0 = birth_state(lo, ln, y, g0, l_m, la_m, speed_m_s)
    nj = min(joints, model_new.rod_slices[k].stop - g0 - 1)
    f = cowell_rhs_py(model_old, y, t_s)
    D, Dd, Ddd = k2 * y[lo.rod(g0)], k2 * y[lo.rod_rate(g0)], k2 * f[lo.rod_rate(g0)]
    lam, xi = speed_m_s / l_m, la_m / l_m
    target = [xi * Ddd + (1 - xi) * (2 * lam * Dd - 2 * lam * lam * D), Ddd][:nj]
    bases = []
    for j in range(nj):
        t = z0[ln.rod(g0 + j)] + z0[ln.rod(g0 + j + 1)]
        t = t / np.linalg.norm(t)
        e1 = np.cross(t, [0.0, 0.0, 1.0] if abs(t[2]) < 0.9 else [1.0, 0.0, 0.0])
        e1 /= np.linalg.norm(e1)
        bases.append(np.array([e1, np.cross(t, e1)]))

    def moved(x):
        z = z0.copy()
        for j in range(nj):
            m = bases[j].T @ x[2 * j : 2 * j + 2]
            z[ln.rod(g0 + j)] += m / k2
            z[ln.rod(g0 + j + 1)] -= m / k2
        return z

    def residual(x):
        fz = cowell_rhs_py(model_new, moved(x), t_s)
        acc = np.cumsum([k2 * fz[ln.rod_rate(g0 + j)] for j in range(nj)], axis=0)
        return np.concatenate([bases[j] @ (acc[j] - target[j]) for j in range(nj)])

    x = np.zeros(2 * nj)
    r0 = residual(x)
    J = np.column_stack([(residual(1e-3 * e) - r0) / 1e-3 for e in np.eye(2 * nj)])
    for _ in range(3):
        x = x - np.linalg.solve(J, residual(x))
    z = moved(x)
    lengths = model_new.rod_lengths()
    dc = sum(rho_kg_m * (lengths[g0 + j] + lengths[g0 + j + 1]) * (bases[j].T @ x[2 * j : 2 * j + 2]) / 2 for j in range(nj))
    c_old, mass = centre_of_mass(model_old, t_s, y)
    for b in _roots(model_new):
        z[ln.root_position(b)] -= dc / mass
    z, info = restore(model_new, t_s, z, momenta(model_old, t_s, y[None, :])[0], c_old, translate=False)
    info["delta_m"] = x
    return z, info


def placements(rod_m: float = 500.0, error_scale: str = "tether") -> dict:
    """Accepted steps of the deployment with other placements of the new joint (docs/deployment.md
    6.5): 6.4's quasi-static offset with its rate delta' scaled by 0, 1 and 2, and the joint (and
    B) placed by :func:`matched_birth_state`."""
    import tetherlab.deployment as dep

    out = {}
    offset, qs = dep.quasi_static_offset, dep.quasi_static_birth_state
    try:
        for scale in (0.0, 1.0, 2.0):
            dep.quasi_static_offset = lambda *a, s=scale: (lambda r: (r[0], s * r[1]))(offset(*a))
            run = _run_birth(rod_m, error_scale, "quasi-static")
            out[f"quasi-static, rate x {scale:g}"] = sum(int(p.stats["n_accepted"]) for p in run.phases)
        dep.quasi_static_offset = offset
        for joints in (1, 2):
            dep.quasi_static_birth_state = lambda *a, j=joints, **kw: matched_birth_state(*a, joints=j)
            run = _run_birth(rod_m, error_scale, "quasi-static")
            out[f"acceleration-matched, {joints} joint(s)"] = sum(int(p.stats["n_accepted"]) for p in run.phases)
    finally:
        dep.quasi_static_offset, dep.quasi_static_birth_state = offset, qs
    return out


def _smoothed(model, y, degree: int):
    """y with the transverse part (across the line's end-to-end chord) of every joint's position
    and rate relative to the exit replaced by its least-squares polynomial in s of ``degree``,
    the two ends held."""
    import math

    k2 = 2 * math.sqrt(3.0)
    lay, sl = model.state, model.rod_slices[0]
    s = np.concatenate([[0.0], np.cumsum(model.rod_lengths()[sl])])
    z = y.copy()
    for block in (lay.rod, lay.rod_rate):
        P = np.vstack([np.zeros(3), np.cumsum([k2 * y[block(g)] for g in range(sl.start, sl.stop)], axis=0)])
        R = np.vstack([np.zeros(3), np.cumsum([k2 * y[lay.rod(g)] for g in range(sl.start, sl.stop)], axis=0)])
        u = R[-1] / np.linalg.norm(R[-1])
        tr = P - np.outer(P @ u, u)
        V = np.vander(s / s[-1], degree + 1)
        w = np.ones(len(s))
        w[0] = w[-1] = 1e6
        coef, *_ = np.linalg.lstsq(V * w[:, None], tr * w[:, None], rcond=None)
        new = P - tr + V @ coef
        new[0], new[-1] = P[0], P[-1]
        for i, g in enumerate(range(sl.start, sl.stop)):
            z[block(g)] = (new[i + 1] - new[i]) / k2
    return z


def what_it_comes_with(rod_m: float = 500.0, phases=(5, 10, 20, 30), degrees=(3, 5, 8)) -> list:
    """Per phase of ``phases`` (quasi-static births, "tether"): its steps; the same state run with
    the reel stopped (speed 0 from the phase's start, the transport l'/l D taken out of the first
    rod's rate: a line of fixed length); and run with the transverse shape and rates smoothed
    (:func:`_smoothed`) for each degree."""
    from tetherlab.model.params import ParamView
    from tetherlab.pipeline import run_segments, segment_plan

    rows = []

    def hook(loop, prep, p, update):
        res = run_segments(prep, segment_plan(prep, p), update)
        if loop["phase"] in phases:
            lay, g0 = prep.model.state, prep.model.rod_slices[0].start
            t_a = float(prep.t_out[0])
            p2 = prep.model.p.copy()
            rv = ParamView(p2).reel(0)
            length = rv.length0_m + rv.speed_m_s * t_a
            first = length - (prep.model.rod_slices[0].stop - g0 - 1) * rod_m
            z = prep.y0.copy()
            z[lay.rod_rate(g0)] -= rv.speed_m_s / first * z[lay.rod(g0)]
            rv.length0_m, rv.speed_m_s = length, 0.0
            model = dataclasses.replace(prep.model, p=p2)
            pr = dataclasses.replace(prep, model=model, y0=z)
            row = {"phase": loop["phase"], "rods": sum(loop["rods"].values()), "steps": int(res.stats["n_accepted"]),
                   "reel stopped": int(run_segments(pr, segment_plan(pr, model.fresh_params()), None).stats["n_accepted"])}
            for deg in degrees:
                pr = dataclasses.replace(prep, y0=_smoothed(prep.model, prep.y0, deg))
                row[f"smoothed, degree {deg}"] = int(run_segments(pr, segment_plan(pr, prep.model.fresh_params()), None).stats["n_accepted"])
            rows.append(row)
        return res

    _run_birth(rod_m, "tether", "quasi-static", hook)
    return rows


def started_at(length0_m: float = 5000.0, rod_m: float = 500.0) -> list:
    """(rods, steps) per phase of the bench's deployment (quasi-static, "tether") started at
    ``length0_m`` (straight rods) instead of 500 m, at the same speed, to the same 20 km."""
    from tetherlab.benchmarks.deployment import _scene
    from tetherlab.pipeline import simulate
    from tetherlab.scene import Scene

    d = _scene(rod_m, True, "tether", "quasi-static").to_dict()
    speed = float(str(d["tethers"]["main"]["reel"]["speed"]).split()[0])
    d["tethers"]["main"]["length"] = f"{length0_m} m"
    d["duration"] = f"{(20000.0 - length0_m) / speed} s"
    run = simulate(Scene.from_dict(d), progress=False)
    rods = [int(x) for x in run.reel.groupby("phase")["rods"].first()]
    return [(n, int(ph.stats["n_accepted"])) for n, ph in zip(rods, run.phases)]


def kick_sensitivity(length_m: float = 10000.0, rods: int = 20, duration_s: float = 600.0,
                     amplitudes=(1e-4, 1e-3, 1e-2)) -> dict:
    """Steps of a line of ``rods`` rods at equilibrium on the bench's orbit (its straight radial
    start, no reel) over ``duration_s``, and with its middle joint moved sideways (in the orbit
    plane) by each amplitude (m), or given that sideways rate (m/s), per error scale."""
    import math

    from tetherlab.benchmarks.deployment import _scene
    from tetherlab.pipeline import prepare, run_segments, segment_plan
    from tetherlab.scene import Scene

    k2 = 2 * math.sqrt(3.0)
    out = {}
    for scale in ("tether", "rod"):
        d = _scene(length_m / rods, False, scale).to_dict()
        d["tethers"]["main"]["length"] = f"{length_m} m"
        d["tethers"]["main"]["rods"] = rods
        d["duration"] = f"{duration_s} s"
        d["output"] = {"count": 3}
        prep = prepare(Scene.from_dict(d))
        lay, g = prep.model.state, rods // 2
        along = prep.y0[lay.rod(g)] / np.linalg.norm(prep.y0[lay.rod(g)])
        side = np.cross([0.0, 0.0, 1.0], along)
        row = {"at rest": int(run_segments(prep, segment_plan(prep, prep.model.fresh_params()), None).stats["n_accepted"])}
        for kind, block in (("position", lay.rod), ("rate", lay.rod_rate)):
            for a in amplitudes:
                y = prep.y0.copy()
                y[block(g - 1)] += a * side / k2
                y[block(g)] -= a * side / k2
                pr = dataclasses.replace(prep, y0=y)
                row[f"{kind} {a:g}"] = int(run_segments(pr, segment_plan(pr, prep.model.fresh_params()), None).stats["n_accepted"])
        out[scale] = row
    return out


def retrieval_merges(former: bool = False) -> dict:
    """The bench's line on its orbit hauled in from 5 km at 2 m/s for 1400 s (five retirements):
    the energy jump at each merge (J), the largest jump of H at a merge, and at the end the end
    mass's in-plane angle from the station's radial direction (rad) and its offset (m).
    ``former``: the merge translated by the centre of mass of the momentum columns
    (``restore(..., translate=True)``), as before docs/deployment.md 6.5."""
    import tetherlab.deployment as dep
    from tetherlab.benchmarks.deployment import _scene
    from tetherlab.momentum_remap import centre_of_mass, momenta, restore
    from tetherlab.pipeline import simulate
    from tetherlab.scene import Scene

    def columns(model_old, model_new, y, k, rho_kg_m, la_m, lb_m, speed_m_s, t_s, angular=True):
        lo, ln = model_old.state, model_new.state
        g0 = model_old.rod_slices[k].start
        z = dep._with_rods(lo, ln, y, g0, 2, [(y[lo.rod(g0)] + y[lo.rod(g0 + 1)], y[lo.rod_rate(g0)] + y[lo.rod_rate(g0 + 1)])])
        c_old, _ = centre_of_mass(model_old, t_s, y)
        return restore(model_new, t_s, z, momenta(model_old, t_s, y[None, :])[0], c_old)[0]

    d = _scene(500.0, True, "tether").to_dict()
    d["tethers"]["main"]["length"] = "5000 m"
    d["tethers"]["main"]["reel"]["speed"] = "-2 m/s"
    d["duration"] = "1400 s"
    d["output"] = {"count": 201}
    keep = dep.retire_state
    if former:
        dep.retire_state = columns
    try:
        run = simulate(Scene.from_dict(d), progress=False)
    finally:
        dep.retire_state = keep
    inv = run.invariants
    e, ph = inv["energy_J"].to_numpy(), inv["phase"].to_numpy()
    H = inv[[f"angmom_{a}_kg_m2_s" for a in "xyz"]].to_numpy()
    ts = run.phases[-1].timeseries
    r0 = ts[["m0.x_m", "m0.y_m"]].to_numpy()[-1]
    rel = ts[["mf.x_m", "mf.y_m"]].to_numpy()[-1] - r0
    return {"retirements": sum(c["change"] == "retire" for c in run.changes),
            "energy_jumps_J": np.diff(e)[np.diff(ph) != 0].tolist(),
            "max_H_jump": float(np.abs(np.diff(H, axis=0)[np.diff(ph) != 0]).max()),
            "end_angle_rad": float(np.arctan2(np.cross(r0, rel), r0 @ rel)), "end_offset_m": rel.tolist()}  # fmt: skip


def main() -> None:
    from tetherlab.benchmarks.deployment import _scene
    from tetherlab.pipeline import simulate

    simulate(_scene(2000.0, True), progress=False)  # compilation out of the way
    print("restarts: extra per phase -> steps (rejections)")
    for k, tot in restarts().items():
        print(f"  {k}: {tot['n_accepted']} ({tot['n_rejected']}) over {tot['phases']} phases")
    rows = quarters()
    print("steps per quarter of a phase (phase, rods, quarters):")
    for ph, rods, q in rows[::3]:
        print(f"  {ph:3d} {rods:3d} {q}")
    print("  summed over the phases but the first and last:", np.array([q for *_, q in rows[1:-1]]).sum(axis=0).tolist())
    print("error scale:", error_scales())
    print("births: (error scale, birth) -> steps, largest energy jump at a birth, end move against straight")
    for key, row in births().items():
        print(f"  {key}: {row['steps']} steps, {row['max_energy_jump_J']:.3g} J, {row.get('end_move_m', 0.0):.3g} m")
    print("error test: steps of a phase with one block's absolute tolerance x 1e4 (quasi-static, tether)")
    for row in error_components():
        print("  ", row)
    print("Newton-rate cap (THETA_STEP) -> steps (rejections):", newton_cap_off())
    for scale in ("tether", "rod"):
        print(f"placements ({scale}):", placements(error_scale=scale))
    print("what the cost comes with (steps of a phase: as run, reel stopped, smoothed):")
    for row in what_it_comes_with():
        print("  ", row)
    print("started at 5 km: (rods, steps) per phase:", started_at())
    print("a 10 km line of 20 rods over 600 s, its middle joint kicked:", kick_sensitivity())
    print("retirements on the orbit, centre of mass from the masses:", retrieval_merges())
    print("  the same from the momentum columns (before):", retrieval_merges(former=True))


if __name__ == "__main__":
    main()
