"""Summary functions for sweeps: run one scene, reduce it to a few floats.

Each is a module-level function ``f(scene) -> dict[str, float]`` (picklable by name, so it can
run in a worker process or on a Dask worker; see :mod:`tetherlab.sweep`).  Every summary also
returns the run's cost (``wall_s`` integrator wall time, ``n_rhs``, ``n_steps``), so a study
can report what its accuracy cost.  A failed run raises (``SimulationError``): the sweep records
the message; summaries never turn a failure into numbers.

Quantities (the first tether of the scene is "the tether"; its ends are the root body and the
tip body):

* :func:`attachment_tension`: force of the tether on each end body at t = 0 (joint reactions,
  paper eq. 29-30), for static scenes (relative equilibrium along the local vertical).
* :func:`libration_frequency`: in-plane libration angular frequency from the zero crossings of
  theta(t) (:func:`tetherlab.diagnostics.zero_crossing_frequency`), and the period from those of
  theta smoothed over 1/12 of a period (the faster lateral modes removed).
* :func:`lateral_frequency`: first lateral (string) mode: zero crossings of the in-plane
  distance of the middle node from the root-tip chord, mean removed.
* :func:`deployment`: a scene with reels (the others refuse one, naming the key): per reel the
  deployed length, speed, rods and angle at the end, births, retirements, the largest exit tension.
* :func:`final_state`: every body's final position, for work-precision errors.
* :func:`invariants`: NaN check, angular momentum and energy drift in units of the tether's own
  angular momentum and rotational energy, final positions (hard cases).
* :func:`stiefel_heyoka_final_state`: the oracle's point on the work-precision axes: heyoka
  (double-precision Taylor) on the Stiefel-Scheifele scene at the scene's tolerance.  Needs
  heyoka installed (it is imported inside :func:`tetherlab.benchmarks.stiefel.heyoka_rows` only).
"""

from __future__ import annotations

import math

import numpy as np


def _run(scene):
    from .pipeline import simulate

    reels = [t.name for t in scene.tethers if t.reel is not None]
    if reels:  # its run is a DeploymentResult of phases, not one Result these summaries read
        raise ValueError(f"scene {scene.name!r} has a reel (tethers.{reels[0]}.reel): this summary reads a run of a "
                         f"fixed rod count; use summary = \"tetherlab.summaries:deployment\"")  # fmt: skip
    return simulate(scene, progress=False)


def deployment(scene) -> dict[str, float]:
    """A run with reels: per reel tether (``<name>.`` prefixed) the deployed length, speed, rods and
    in-plane angle at the end, the largest exit tension and |angle|, the births and retirements and
    the energy taken at the exit (brake and Carnot loss, J); for the run its end time, whether a
    reel's line ran out (``spent``: 1 or 0) and the cost summed over the phases.  The angle is the
    tether's ``theta_rad`` diagnostic (the libration angle; NaN for a scene without an orbit)."""
    import pandas as pd

    from .pipeline import simulate

    run = simulate(scene, progress=False)
    out: dict[str, float] = {"t_end_s": float(run.reel["t_s"].iloc[-1]),
                             "spent": float(bool(run.stopped_by) and run.stopped_by.endswith(".spent"))}
    for name, r in run.reel.groupby("reel", sort=False):
        kinds = [c["change"] for c in run.changes if c["reel"] == name]
        th = pd.concat([ph.diagnostics[f"{name}.theta_rad"] for ph in run.phases if f"{name}.theta_rad" in
                        ph.diagnostics], ignore_index=True) if scene.orbit is not None else pd.Series([math.nan])  # fmt: skip
        out.update({
            f"{name}.deployed_length_m": float(r["deployed_length_m"].iloc[-1]),
            f"{name}.speed_m_s": float(r["speed_m_s"].iloc[-1]),
            f"{name}.rods": float(r["rods"].iloc[-1]),
            f"{name}.births": float(kinds.count("birth")),
            f"{name}.retirements": float(kinds.count("retire")),
            f"{name}.max_exit_tension_N": float(r["exit_tension_N"].max()),
            f"{name}.carnot_J": float(r["carnot_J"].iloc[-1]),
            f"{name}.theta_end_rad": float(th.iloc[-1]) if len(th) else math.nan,
            f"{name}.max_abs_theta_rad": float(th.abs().max()) if len(th) else math.nan,
        })  # fmt: skip
    out["exit_work_J"] = float(run.invariants["exit_work_J"].iloc[-1])
    stats = [ph.stats for ph in run.phases]
    out.update(wall_s=float(sum(s.get("wall_s", 0.0) for s in stats)),
               n_rhs=float(sum(s.get("n_rhs", 0) for s in stats)),
               n_steps=float(sum(s.get("n_accepted", 0) for s in stats)))  # fmt: skip
    return out


def _cost(res) -> dict[str, float]:
    s = res.stats
    return {
        "wall_s": float(s.get("wall_s", math.nan)),
        "n_rhs": float(s.get("n_rhs", math.nan)),
        "n_steps": float(s.get("n_accepted", math.nan)),
    }


def _tether(scene):
    if not scene.tethers:
        raise ValueError(f"scene {scene.name!r} has no tether; this summary needs one")
    return scene.tethers[0]


def attachment_tension(scene) -> dict[str, float]:
    """Tether force on the root and on the tip body at t = 0, and its drift over the run (N)."""
    t = _tether(scene)
    res = _run(scene)
    ts = res.timeseries
    root = ts[f"{t.name}.joint0.reaction_N"].to_numpy()
    tip = ts[f"{t.name}.joint{t.rods}.reaction_N"].to_numpy()
    return {
        "root_tension_N": float(root[0]),
        "tip_tension_N": float(tip[0]),
        "root_tension_drift_N": float(np.max(np.abs(root - root[0]))),
        **_cost(res),
    }


def libration_frequency(scene) -> dict[str, float]:
    """In-plane libration angular frequency (rad/s) and period (s) from theta's zero crossings;
    ``libration_period_smoothed_s`` from those of theta smoothed by a Gaussian of standard
    deviation 1/12 of the period (it needs uniformly spaced outputs).

    The smoothing removes what rides on theta much faster than the libration (the lateral modes:
    1/8 of the period on the convergence scene, damped by the kernel to 1e-4), so the crossings
    move only with the libration itself; the kernel passes 0.87 of the libration's amplitude.
    """
    from .diagnostics import zero_crossing_frequency

    t = _tether(scene)
    res = _run(scene)
    d = res.diagnostics
    ts, theta = d["t_s"].to_numpy(), d[f"{t.name}.theta_rad"].to_numpy()
    w = zero_crossing_frequency(ts, theta)
    ws = zero_crossing_frequency(ts, theta, smooth_s=2 * math.pi / w / 12)
    return {"libration_rad_s": w, "libration_period_s": 2 * math.pi / w,
            "libration_period_smoothed_s": 2 * math.pi / ws, **_cost(res)}


def lateral_offset_m(ts, tether_name: str, rods: int) -> np.ndarray:
    """Signed in-plane distance (m) of the middle node from the root-tip chord, per output row.

    The sign is that of (chord x offset) along the orbit normal, taken from the first row's
    positions and velocities of the nodes' centroid (planar runs: the normal does not turn).
    For an odd rod count the "middle" is the mean of the two central nodes.
    """
    def node(j):
        return np.stack([ts[f"{tether_name}.node{j}.{a}_m"].to_numpy() for a in "xyz"], axis=1)

    a, b = node(0), node(rods)
    mid = node(rods // 2) if rods % 2 == 0 else 0.5 * (node(rods // 2) + node(rods // 2 + 1))
    chord = b - a
    chord /= np.linalg.norm(chord, axis=1, keepdims=True)
    rel = mid - a
    off = rel - np.sum(rel * chord, axis=1, keepdims=True) * chord
    # orbit normal from the root's orbital motion over the first two rows
    normal = np.cross(a[0], a[1] - a[0])
    normal /= np.linalg.norm(normal)
    return np.einsum("ij,j->i", np.cross(chord, off), normal)


def lateral_frequency(scene) -> dict[str, float]:
    """First lateral mode angular frequency (rad/s) from the middle node's offset to the chord."""
    from .diagnostics import zero_crossing_frequency

    t = _tether(scene)
    if t.rods < 2:
        raise ValueError(f"tethers.{t.name}.rods: a lateral mode needs at least 2 rods, got {t.rods}")
    res = _run(scene)
    ts = res.timeseries
    off = lateral_offset_m(ts, t.name, t.rods)
    w = zero_crossing_frequency(ts["t_s"].to_numpy(), off - off.mean())
    return {"lateral_rad_s": w, "lateral_period_s": 2 * math.pi / w,
            "lateral_amplitude_m": float(np.max(np.abs(off - off.mean()))), **_cost(res)}


def _body_names(scene) -> list[str]:
    return [b.name for b in scene.bodies]


def final_state(scene) -> dict[str, float]:
    """Final position (m) of every body: ``<body>.x_m`` ... and the run's cost."""
    res = _run(scene)
    ts = res.timeseries
    out = {}
    for name in _body_names(scene):
        for a in "xyz":
            col = f"{name}.{a}_m"
            if col in ts:
                out[col] = float(ts[col].iloc[-1])
    out["t_end_s"] = float(ts["t_s"].iloc[-1])
    return {**out, **_cost(res)}


def own_angular_momentum_scale(scene) -> tuple[float, float]:
    """(I * n, I * n^2): angular momentum (kg m^2/s) and energy (J) scales of the tether's own
    rotation about the centre of mass at the orbit's mean motion n.

    I is the moment of inertia of the straight system about its centre of mass: root mass at
    s = 0, tip mass mf at s = L, tether mass mt uniform on [0, L]:
    I = mf L^2 + mt L^2 / 3 - (mf L + mt L / 2)^2 / M, M = m0 + mf + mt (parallel axis theorem).
    Errors of the total angular momentum about the Earth's centre are measured against this scale,
    not against the orbital angular momentum, which is 10^6-10^8 times larger and would hide them.
    """
    t = _tether(scene)
    m0 = scene.body(t.from_body).mass_kg
    mf = scene.body(t.to_body).mass_kg
    mt, L = t.mass_kg, t.length_m
    M = m0 + mf + mt
    inertia = mf * L**2 + mt * L**2 / 3 - (mf * L + mt * L / 2) ** 2 / M
    a = _semi_major_axis(scene)
    n = math.sqrt(scene.central_body.mu_m3_s2 / a**3)
    return inertia * n, inertia * n * n


def _semi_major_axis(scene) -> float:
    r, v = scene.reference_state()
    mu = scene.central_body.mu_m3_s2
    energy = 0.5 * float(v @ v) - mu / float(np.linalg.norm(r))
    return -mu / (2 * energy)


#: how many located events (slack/taut switches) :func:`invariants` reports, time and identity
N_EVENTS_REPORTED = 64


def event_code(event: dict) -> float:
    """A float naming a located event for a summary: 2 * rod + 1 for a rod going taut, 2 * rod for
    one going slack (names ``slack.<tether>.rod<k>``), -1 for any other event (a [stop])."""
    name = event.get("event", "")
    head, _, rod = name.rpartition(".rod")
    if not name.startswith("slack.") or not rod.isdigit():
        return -1.0
    return float(2 * int(rod) + (1 if event.get("side") == "taut" else 0))


def invariants(scene) -> dict[str, float]:
    """Hard-case checks: finite outputs, invariant drifts in the tether's own units, final state.

    ``angmom_error_own`` = max_t |H(t) - H(0)| / (I n); ``energy_error_own`` = max_t |E(t) -
    E(0)| / (I n^2) (meaningful for the "energy" model, which conserves E; docs/model.md);
    ``energy_rise_own`` = max_t (E(t) - E(0)) / (I n^2) (one-sided: what a damped tether may not
    gain); ``nonfinite`` = number of non-finite values in the outputs (must be 0).

    The scales that the round-off bounds of studies/hard_cases.py need, all maxima over the
    output rows: ``angmom_sum_scale`` S_H = sum of m |r| |v| over the system, taken as
    |r_cm| sqrt(2 M KE) (every mass moves with the centre of mass to 1e-3 here), in units of
    I n; ``energy_sum_scale`` S_E = 2 KE + |V_grav| = sum m (|v|^2 + mu/|r|), in units of
    I n^2; ``r_max_m`` = |r_cm|; ``v_max_m_s`` = sqrt(2 KE / M); ``t_end_s``.  Located events:
    ``n_events``, and for the first :data:`N_EVENTS_REPORTED` ``event<k>_t_s`` and
    ``event<k>_code`` (:func:`event_code`).
    """
    res = _run(scene)
    ts, d = res.timeseries, res.diagnostics
    h_scale, e_scale = own_angular_momentum_scale(scene)
    H = d[[f"angmom_{a}_kg_m2_s" for a in "xyz"]].to_numpy()
    E = d["energy_J"].to_numpy()
    t = _tether(scene)
    strain = np.stack([ts[f"{t.name}.rod{i + 1}.strain"].to_numpy() for i in range(t.rods)], axis=1)
    mass = sum(b.mass_kg for b in scene.bodies) + sum(th.mass_kg for th in scene.tethers)
    ke = d["kinetic_J"].to_numpy()
    r_cm = d["com_radius_m"].to_numpy()
    out = {
        "nonfinite": float(np.count_nonzero(~np.isfinite(ts.to_numpy())) + np.count_nonzero(~np.isfinite(d.to_numpy()))),
        "angmom_error_own": float(np.max(np.linalg.norm(H - H[0], axis=1)) / h_scale),
        "energy_error_own": float(np.max(np.abs(E - E[0])) / e_scale),
        # the largest rise of E above its start: a damped energy-model tether can only lose energy
        # (docs/model.md 6.2), so a rise beyond round-off is energy created (the n = 512 hard case)
        "energy_rise_own": float(np.max(E - E[0]) / e_scale),
        "strain_min": float(strain.min()),
        "strain_max": float(strain.max()),
        "angmom_sum_scale": float(np.max(r_cm * np.sqrt(2.0 * mass * ke)) / h_scale),
        "energy_sum_scale": float(np.max(2.0 * ke + np.abs(d["potential_J"].to_numpy())) / e_scale),
        "r_max_m": float(np.max(r_cm)),
        "v_max_m_s": float(np.sqrt(2.0 * np.max(ke) / mass)),
        "t_end_s": float(ts["t_s"].iloc[-1]),
    }
    events = res.stats.get("events", [])
    out["n_events"] = float(len(events))
    for k, ev in enumerate(events[:N_EVENTS_REPORTED]):
        out[f"event{k}_t_s"] = float(ev["t_s"])
        out[f"event{k}_code"] = event_code(ev)
    for name in _body_names(scene):
        for a in "xyz":
            col = f"{name}.{a}_m"
            if col in ts:
                out[col] = float(ts[col].iloc[-1])
    return {**out, **_cost(res)}


#: paper section 4.1: t_f = 50 revolutions; tetherlab.benchmarks.stiefel.heyoka_rows integrates to it
STIEFEL_DURATION_S = 288.12768941 * 86400.0


def stiefel_heyoka_final_state(scene) -> dict[str, float]:
    """heyoka's final position (m) of the Stiefel-Scheifele satellite at the scene's tolerance.

    The scene only selects the tolerance (``integrator.rtol``, which must equal ``atol``: heyoka
    has one); the equations are heyoka's own expression system in
    :func:`tetherlab.benchmarks.stiefel.heyoka_rows` (the reference builder's), so the scene must
    be the Stiefel-Scheifele one.  Cost keys as for tetherlab's runs, measured alike: ``wall_s``
    is one ``propagate_until`` after the integrator is built (its JIT compilation excluded, as
    tetherlab's kernel compilation is) and after one warm-up propagation; ``n_steps`` counts
    Taylor steps.  There is no ``n_rhs``: a Taylor method never evaluates the right-hand side
    (it builds each step's Taylor coefficients by automatic differentiation).
    """
    from .benchmarks.stiefel import heyoka_rows

    if scene.name != "stiefel-scheifele" or abs(scene.duration_seconds() - STIEFEL_DURATION_S) > 1e-3:
        raise ValueError(
            "stiefel_heyoka_final_state: expected the Stiefel-Scheifele scene (name 'stiefel-scheifele', "
            f"duration {STIEFEL_DURATION_S} s: heyoka_rows integrates that problem only); got "
            f"{scene.name!r} over {scene.duration_seconds()!r} s"
        )
    tol = float(scene.integrator.rtol)
    if float(scene.integrator.atol) != tol:
        raise ValueError(f"integrator: heyoka has one tolerance; expected atol == rtol, got rtol {tol!r}, "
                         f"atol {scene.integrator.atol!r}")
    row = heyoka_rows(tols=(tol,), repeats=1)[0]
    r_m, _ = row["run"]()  # deterministic: the timed run's final state again, for the caller's error measure
    return {"sat.x_m": float(r_m[0]), "sat.y_m": float(r_m[1]), "sat.z_m": float(r_m[2]),
            "t_end_s": STIEFEL_DURATION_S, "wall_s": float(row["wall_s"]), "n_steps": float(row["steps"])}
