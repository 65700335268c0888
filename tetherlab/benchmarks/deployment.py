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

import time

import numpy as np

ROD_LENGTHS_M = (1000.0, 500.0, 250.0)
#: (error scale, birth) of each block of rows: the default, then the options that cut the steps
OPTIONS = (("rod", "straight"), ("tether", "straight"), ("rod", "quasi-static"), ("tether", "quasi-static"))
L0_M, L1_M = 500.0, 20000.0


def _scene(rod_m: float, reel: bool, error_scale: str = "rod", birth: str = "straight"):
    from ..scene import Scene

    import math

    period = 2 * math.pi * math.sqrt((7000e3) ** 3 / 3.986004418e14)
    tether = {"from": "m0", "to": "mf", "EA": "1e4 N", "linear_density": "2e-4 kg/m", "damping": "2e4 N s",
              "model": "paper", "initial": {"shape": "straight", "theta": "0 deg"}}
    if reel:
        tether.update(length=f"{L0_M} m", reel={"law": "constant", "speed": f"{(L1_M - L0_M) / period} m/s",
                                                "rod_length": f"{rod_m} m", "stored_length": f"{L1_M} m", "birth": birth})
    else:
        tether.update(length=f"{L1_M} m", rods=int(round(L1_M / rod_m)))
    return Scene.from_dict({
        "name": "deployment-bench", "duration": f"{period} s", "effects": {"central_gravity": {}},
        "bodies": {"m0": {"mass": "1000 kg"}, "mf": {"mass": "25 kg"}},
        "orbit": {"reference": "center_of_mass", "motion": "corotating",
                  "elements": {"a": "7000 km", "e": 0.0, "i": "0 deg", "raan": "0 deg", "argp": "0 deg", "nu": "0 deg"}},
        "tethers": {"main": tether},
        "integrator": {"method": "radau5", "rtol": 1e-8, "atol": 1e-8, "error_scale": error_scale},
        "output": {"count": 101},
    })  # fmt: skip


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
    fixed_runs = {}
    rows = []
    for scale, birth in options:
        walls, rods, setups = [], [], []
        for rod_m in rod_lengths:
            w_reel, dep = _wall(_scene(rod_m, True, scale, birth))
            # the fixed run, once per error scale and rod length, right after the first deployment
            if (scale, rod_m) not in fixed_runs:
                fixed_runs[(scale, rod_m)] = _wall(_scene(rod_m, False, scale))
            w_fixed, fixed = fixed_runs[(scale, rod_m)]
            births = sum(1 for c in dep.changes if c["change"] == "birth")
            n_final = int(dep.reel["rods"].iloc[-1])
            (s_dep, r_dep), (s_fix, r_fix) = _counts(dep), _counts(fixed)
            setup = w_reel - _integration_s(dep)
            rows.append({"error_scale": scale, "birth": birth, "rod_m": rod_m, "births": births, "final_rods": n_final,
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
        rows.append({"error_scale": scale, "birth": birth, "rod_m": "fitted exponent (wall; steps; set-up)",
                     "births": "", "final_rods": "", "deploy_s": fit, "fixed_s": "", "ratio": "", "per_birth_ms": "",
                     "deploy_steps": fit_steps, "deploy_rejected": "", "fixed_steps": "", "fixed_rejected": "",
                     "step_ratio": "", "integration_s": "", "setup_s": fit_setup, "setup_per_birth_ms": "",
                     "setup_over_fixed": "", "fixed_setup_s": "", "tables_s": ""})  # fmt: skip
    return rows
