"""The electrodynamic de-orbit of paper section 5 (studies/scenes/deorbit-ed.toml), whole mission.

:func:`run_until_altitude` integrates a scene day by day until the root body's altitude falls
below a threshold, and returns the crossing time interpolated in the output series.  It stands in
for the scene-level ``[stop] altitude = ...`` (event location in the integrator) until that lands:
each day is one call of the integrator (a restart costs one step-size ramp, negligible here).

:func:`table` times the whole n = 1 mission with every integrator; compilation excluded (a short
warm-up run first).  Command line: ``python -m tetherlab.benchmarks.deorbit [--methods ...]``.
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "studies" / "scenes" / "deorbit-ed.toml"
STOP_ALTITUDE_M = 200e3
DAY_S = 86400.0

#: method -> rtol used for it in the table: the implicit method at the tolerance recommended in
#: docs/effects-electrodynamic.md (section 6); explicit ones at the same value for comparison.
DEFAULT_METHODS = {"radau5": 1e-8, "dop853": 1e-8, "scipy:Radau": 1e-8, "scipy:DOP853": 1e-8}


@dataclass
class Mission:
    prep: object
    t: np.ndarray
    Y: np.ndarray
    stats: dict
    crossing_s: float  # nan when the threshold was not reached
    wall_s: float  # integration only (compilation excluded)
    status: int
    message: str


def _gravity_equilibrium_state(scene) -> np.ndarray:
    """Initial state of the relative equilibrium, or its one-rod approximation.

    pipeline.prepare's Newton solve stalls at a residual of ~1.4e-9 (its bound: 1e-9) for some
    rod counts of this scene (n = 4, 8: a round-off floor, reported to the lead); then every rod
    starts with the strain of the one-rod equilibrium in a corotating layout, which leaves only a
    small axial transient (the strain varies by ~1e-7 along the tether).
    """
    from ..errors import SceneError
    from ..pipeline import prepare

    try:
        return prepare(scene).y0
    except SceneError as exc:
        if exc.key != "orbit.motion":
            raise
    one = {f"tethers.{t.name}.rods": 1 for t in scene.tethers}
    y1 = prepare(scene.replace(**one)).y0
    changes = {"orbit.motion": "corotating"}
    for k, t in enumerate(scene.tethers):
        d = y1[3 + 3 * k : 6 + 3 * k]
        changes[f"tethers.{t.name}.initial.strain"] = float(2.0 * np.sqrt(3.0) * np.linalg.norm(d) / t.length_m - 1.0)
    return prepare(scene.replace(**changes)).y0


def run_until_altitude(scene, stop_altitude_m=STOP_ALTITUDE_M, max_days=200, chunk_s=DAY_S) -> Mission:
    """Integrate ``scene`` (its own duration ignored) until the root body's altitude < threshold."""
    from ..formulations.cowell import cowell_rhs
    from ..integrators.driver import integrate
    from ..pipeline import prepare

    # Start from the relative equilibrium under gravity alone, the current (and drag) switched on
    # at t = 0: the equilibrium solve of pipeline.prepare includes every named effect, and with a
    # non-conservative along-track force there is no rigid rotation to find (it fails for n = 4).
    others = {f"effects.{e.name}": None for e in scene.effects if e.name != "central_gravity"}
    if others and scene.orbit is not None and scene.orbit.motion == "equilibrium":
        prep = prepare(scene.replace(**{"orbit.motion": "corotating"}))
        prep.y0 = _gravity_equilibrium_state(scene.replace(**others))
    else:
        prep = prepare(scene)
    radius = scene.central_body.radius_m
    step = float(prep.t_out[1] - prep.t_out[0])
    p = prep.model.fresh_params()
    ts = [np.array([0.0])]
    ys = [prep.y0[None, :]]
    y = prep.y0.copy()
    t0 = 0.0
    stats: dict = {}
    wall = 0.0
    status, message = 0, "threshold not reached"
    crossing = float("nan")
    for _ in range(max_days):
        t_out = t0 + step * np.arange(1, int(round(chunk_s / step)) + 1)
        res = integrate(prep.method, cowell_rhs, t0, y, t_out, p, prep.rtol, prep.atol,
                        h_max=prep.h_max, max_steps=prep.max_steps, second_order=True)  # fmt: skip
        for k, v in res.stats.items():
            if isinstance(v, (int, float)) and k != "compile_s":
                stats[k] = stats.get(k, 0) + v
        wall += res.stats.get("wall_s", 0.0)
        ts.append(np.asarray(res.t))
        ys.append(np.asarray(res.y))
        if res.status != 0:
            status, message = res.status, res.message
            break
        alt = np.linalg.norm(res.y[:, :3], axis=1) - radius
        below = np.nonzero(alt < stop_altitude_m)[0]
        if below.size:
            j = below[0]
            t_prev = t0 if j == 0 else res.t[j - 1]
            a_prev = (np.linalg.norm(y[:3]) if j == 0 else np.linalg.norm(res.y[j - 1, :3])) - radius
            crossing = t_prev + (a_prev - stop_altitude_m) / (a_prev - alt[j]) * (res.t[j] - t_prev)
            status, message = 0, f"altitude below {stop_altitude_m:g} m at t = {crossing:.6g} s"
            break
        t0 = float(res.t[-1])
        y = res.y[-1].copy()
    t = np.concatenate(ts)
    Y = np.concatenate(ys)
    return Mission(prep, t, Y, stats, float(crossing), wall, status, message)


def table(methods: dict | None = None, rods: int = 1, scene_path=SCENE) -> list[dict]:
    """Wall time of the whole mission (to 200 km) per integrator; rows for a table."""
    from ..scene import load_scene

    methods = DEFAULT_METHODS if methods is None else methods
    base = load_scene(scene_path).replace(**{"tethers.main.rods": rods})
    rows = []
    for method, rtol in methods.items():
        sc = base.replace(**{"integrator.method": method, "integrator.rtol": rtol, "integrator.atol": rtol})
        run_until_altitude(sc.replace(duration="1 d"), max_days=1)  # warm-up: compile outside the timing
        t_wall = time.perf_counter()
        m = run_until_altitude(sc)
        total = time.perf_counter() - t_wall
        rows.append(
            {
                "method": method,
                "rtol": rtol,
                "rods": rods,
                "deorbit_days": m.crossing_s / DAY_S,
                "integrate_s": m.wall_s,
                "total_s": total,
                "steps": int(m.stats.get("n_accepted", 0)),
                "rejected": int(m.stats.get("n_rejected", 0)),
                "rhs": int(m.stats.get("n_rhs", 0)),
                "status": m.status,
            }
        )
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--methods", nargs="*", default=list(DEFAULT_METHODS), help="integrators to time")
    ap.add_argument("--rtol", type=float, default=None, help="one rtol for every method")
    ap.add_argument("--rods", type=int, default=1)
    args = ap.parse_args(argv)
    methods = {m: (args.rtol if args.rtol is not None else DEFAULT_METHODS.get(m, 1e-8)) for m in args.methods}
    rows = table(methods, rods=args.rods)
    keys = list(rows[0])
    print("| " + " | ".join(keys) + " |")
    print("|" + "---|" * len(keys))
    for r in rows:
        print("| " + " | ".join(f"{v:.4g}" if isinstance(v, float) else str(v) for v in r.values()) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
