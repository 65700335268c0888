"""Deployment from a reel against the same system at its final length (docs/deployment.md).

A 1000 kg station on a 7000 km circular orbit pays out a line (EA 1e4 N, 0.2 g/m, damping
2e4 N s) to a 25 kg end mass at constant speed, from 500 m to 20 km in one orbit, with rods of
1000, 500 and 250 m (19, 39 and 79 births); the reference is the same system at its final
length, 20 km in rods of the same length, over the same time. Target (issue): the deployment with
rods of 500 m costs at most 2x the fixed run; the cost per birth (the phase's set-up: a model
built, the state remapped, the integrator restarted) is the difference divided by the births; the
last row fits the wall time's exponent in the final rod count (target ~1: linear in rods).
RADAU5 with the structured Newton matrix, rtol 1e-8; wall times, the kernels already compiled.
Next to each wall time the counts that do not depend on the machine's load: accepted steps and
rejections (summed over the phases). The rows with ``error_scale = "tether"``
(docs/integrators.md 15) measure the same runs with the rods' tolerances floored at the whole
line's (docs/deployment.md 8b says what that does to the answer); the rows with ``birth =
"quasi-static"`` place each new joint on the line's quasi-static shape (docs/deployment.md 6.4).
Rod lengths 1000, 500 and 250 m (20, 40, 80 rods at the end).

The last two blocks (``law = "exponential"``) deploy the same line by L = L0 exp(c Omega t),
c = 0.5, from 500 m to 20 km (1.17 orbits), started on the steady angle sin 2 theta = -4c/3 with
the steady strain: the constant speed's c = L'/(Omega L) is ~6 at 500 m, beyond the |c| <= 3/4
where a deploying line has a steady angle (docs/deployment.md 7).  Their fixed run is the same
system at 20 km over that duration (docs/deployment.md 8g).

The wall time is split into the integration (the driver's own clock, ``stats["wall_s"]``, summed
over the phases: the compiled steps and the chunk loop around them) and the set-up, everything
else: each phase's model, the remap of a birth, the phase's reel rows and invariants, the tables
at the end.  ``setup_per_birth_ms`` is the deployment's set-up divided by its births (target
~1.5 ms at 40 rods, so that the 39 set-ups stay below 0.4x the fixed run; docs/deployment.md
8d); ``setup_over_fixed`` is that set-up over the fixed run's whole wall time.  A phase's Result
is built when first read (tetherlab/result.py ``DeferredResult``): ``tables_s`` is the time to
read every phase's time series and diagnostics once after the run, which ``deploy_s`` does not
include.  The last row of each block fits the exponents of the wall time, the steps and the
set-up in the final rod count.
"""

from __future__ import annotations

import math
import time

import numpy as np

ROD_LENGTHS_M = (1000.0, 500.0, 250.0)
#: (law, error scale, birth) of each block of rows: the constant speed with the default, then with
#: the options that cut the steps; then the exponential law inside its steady range (docs/deployment.md 8g)
OPTIONS = (("constant", "rod", "straight"), ("constant", "tether", "straight"), ("constant", "rod", "quasi-static"),
           ("constant", "tether", "quasi-static"), ("exponential", "tether", "straight"),
           ("exponential", "tether", "quasi-static"))
L0_M, L1_M = 500.0, 20000.0
MU_M3_S2, A_M = 3.986004418e14, 7000e3
M0_KG, MF_KG, EA_N, RHO_KG_M = 1000.0, 25.0, 1e4, 2e-4
#: L'/(Omega L) of the exponential rows: inside |c| <= 3/4, where the line has a steady angle
EXP_C = 0.5


def _scene(rod_m: float, reel: bool, error_scale: str = "rod", birth: str = "straight", law: str = "constant",
           c: float = EXP_C):
    """The bench's deployment (``reel``) or the same system fixed at 20 km over the same time.
    ``law = "constant"``: L' = (L1 - L0)/T over one orbit T, from the local vertical at rest.
    ``law = "exponential"``: L = L0 exp(c Omega t) until L1, started on its steady angle
    sin 2 theta = -4c/3 with the steady strain (docs/deployment.md 7, 8g); the line moves out of
    the reel at L'(0) (``deployment.reel_start``)."""
    from ..scene import Scene

    period, om = _orbit()
    tether = {"from": "m0", "to": "mf", "EA": f"{EA_N} N", "linear_density": f"{RHO_KG_M} kg/m", "damping": "2e4 N s",
              "model": "paper", "initial": {"shape": "straight", "theta": "0 deg"}}
    duration = period if law == "constant" else _exp_duration_s(c)
    if reel:
        if law == "constant":
            rl = {"law": "constant", "speed": f"{(L1_M - L0_M) / period} m/s"}
        else:
            theta, strain = _steady_start(c, L0_M)
            tether["initial"] = {"shape": "straight", "theta": f"{math.degrees(theta)!r} deg", "strain": strain}
            rl = {"law": "exponential", "rate": f"{c * om!r} 1/s"}
        tether.update(length=f"{L0_M} m", reel={**rl, "rod_length": f"{rod_m} m", "stored_length": f"{L1_M} m",
                                                "birth": birth})
    else:
        tether.update(length=f"{L1_M} m", rods=int(round(L1_M / rod_m)))
    return Scene.from_dict({
        "name": "deployment-bench", "duration": f"{duration!r} s", "effects": {"central_gravity": {}},
        "bodies": {"m0": {"mass": f"{M0_KG} kg"}, "mf": {"mass": f"{MF_KG} kg"}},
        "orbit": {"reference": "center_of_mass", "motion": "corotating",
                  "elements": {"a": "7000 km", "e": 0.0, "i": "0 deg", "raan": "0 deg", "argp": "0 deg", "nu": "0 deg"}},
        "tethers": {"main": tether},
        "integrator": {"method": "radau5", "rtol": 1e-8, "atol": 1e-8, "error_scale": error_scale},
        "output": {"count": 101},
    })  # fmt: skip


def _orbit() -> tuple[float, float]:
    """(period s, rate rad/s) of the bench's 7000 km circular orbit."""
    return 2 * math.pi * math.sqrt(A_M**3 / MU_M3_S2), math.sqrt(MU_M3_S2 / A_M**3)


def _exp_duration_s(c: float) -> float:
    """The time L0 exp(c Omega t) takes to reach L1."""
    return math.log(L1_M / L0_M) / (c * _orbit()[1])


def _steady_start(c: float, length_m: float) -> tuple[float, float]:
    """(theta rad, strain) of the steady exponential deployment at ``length_m`` (docs/deployment.md
    7: sin 2 theta = -4c/3, T = m* Omega^2 l (3 cos^2 theta - c^2), m* the bodies' reduced mass)."""
    if not 0.0 < c <= 0.75:
        raise ValueError(f"_steady_start: c must be in (0, 3/4] for a steady angle; got {c!r}")
    om = _orbit()[1]
    theta = 0.5 * math.asin(-4.0 * c / 3.0)
    m_red = M0_KG * MF_KG / (M0_KG + MF_KG)
    return theta, m_red * om**2 * length_m * (3 * math.cos(theta) ** 2 - c**2) / EA_N


def _wall(scene) -> tuple[float, object]:
    from ..pipeline import simulate

    t0 = time.perf_counter()
    res = simulate(scene, progress=False)
    return time.perf_counter() - t0, res


def _integration_s(res) -> float:
    """The driver's own wall time (the compiled steps and the chunk loop), summed over the phases."""
    stats = [ph.stats for ph in res.phases] if hasattr(res, "phases") else [res.stats]
    return sum(float(s["wall_s"]) for s in stats)


def _tables_s(res) -> float:
    """The time to read every phase's time series and diagnostics once (built at the first read)."""
    t0 = time.perf_counter()
    for ph in getattr(res, "phases", ()):
        _ = ph.timeseries, ph.diagnostics
    return time.perf_counter() - t0


def _counts(res) -> tuple[int, int]:
    """(accepted steps, rejections) of a run: a deployment's summed over its phases."""
    stats = [ph.stats for ph in res.phases] if hasattr(res, "phases") else [res.stats]
    return sum(int(s["n_accepted"]) for s in stats), sum(int(s["n_rejected"]) for s in stats)


def bench_rows(rod_lengths=ROD_LENGTHS_M, options=OPTIONS) -> list[dict]:
    _wall(_scene(rod_lengths[0], True))  # warm-up: compilation excluded
    _wall(_scene(rod_lengths[0], True, "rod", "quasi-static"))
    _wall(_scene(rod_lengths[0], False))  # the fixed run's first call imports what a reel run does not
    _wall(_scene(rod_lengths[0], True, "tether", "quasi-static", "exponential"))
    fixed_runs = {}
    rows = []
    for law, scale, birth in options:
        walls, rods, setups = [], [], []
        for rod_m in rod_lengths:
            w_reel, dep = _wall(_scene(rod_m, True, scale, birth, law))
            # the fixed run, once per law (its duration), error scale and rod length, right after
            # the first deployment that uses it
            if (law, scale, rod_m) not in fixed_runs:
                fixed_runs[(law, scale, rod_m)] = _wall(_scene(rod_m, False, scale, law=law))
            w_fixed, fixed = fixed_runs[(law, scale, rod_m)]
            births = sum(1 for c in dep.changes if c["change"] == "birth")
            n_final = int(dep.reel["rods"].iloc[-1])
            (s_dep, r_dep), (s_fix, r_fix) = _counts(dep), _counts(fixed)
            setup = w_reel - _integration_s(dep)
            rows.append({"law": law, "error_scale": scale, "birth": birth, "rod_m": rod_m, "births": births, "final_rods": n_final,
                         "deploy_s": w_reel, "fixed_s": w_fixed, "ratio": w_reel / w_fixed,
                         "per_birth_ms": 1e3 * (w_reel - w_fixed) / births if births else float("nan"),
                         "deploy_steps": s_dep, "deploy_rejected": r_dep, "fixed_steps": s_fix,
                         "fixed_rejected": r_fix, "step_ratio": s_dep / s_fix,
                         "integration_s": _integration_s(dep), "setup_s": setup,
                         "setup_per_birth_ms": 1e3 * setup / births if births else float("nan"),
                         "setup_over_fixed": setup / w_fixed, "fixed_setup_s": w_fixed - _integration_s(fixed),
                         "tables_s": _tables_s(dep)})  # fmt: skip
            walls.append(w_reel)
            setups.append(setup)
            rods.append(n_final)
        fit = float(np.polyfit(np.log(rods), np.log(walls), 1)[0])
        steps = [r["deploy_steps"] for r in rows[-len(rod_lengths):]]
        fit_steps = float(np.polyfit(np.log(rods), np.log(steps), 1)[0])
        fit_setup = float(np.polyfit(np.log(rods), np.log(setups), 1)[0])
        rows.append({"law": law, "error_scale": scale, "birth": birth, "rod_m": "fitted exponent (wall; steps; set-up)",
                     "births": "", "final_rods": "", "deploy_s": fit, "fixed_s": "", "ratio": "", "per_birth_ms": "",
                     "deploy_steps": fit_steps, "deploy_rejected": "", "fixed_steps": "", "fixed_rejected": "",
                     "step_ratio": "", "integration_s": "", "setup_s": fit_setup, "setup_per_birth_ms": "",
                     "setup_over_fixed": "", "fixed_setup_s": "", "tables_s": ""})  # fmt: skip
    return rows
