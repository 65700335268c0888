"""The electrodynamic de-orbit of paper section 5 (studies/scenes/deorbit-ed.toml), whole mission.

:func:`run_until_altitude` integrates a scene until the root body's altitude falls to a
threshold, located as a terminal event by the integrator (the scene-level ``[stop] altitude``).

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
#: The scipy backends cannot locate the [stop] event (tetherlab's kernels do), and take minutes
#: here (scipy:Radau 101 s measured with day-by-day chunks): they are left out of the table.
DEFAULT_METHODS = {"radau5": 1e-8, "dop853": 1e-8, "vern9": 1e-8}


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


def run_until_altitude(scene, stop_altitude_m=STOP_ALTITUDE_M, max_days=200) -> Mission:
    """Integrate ``scene`` until the root body's altitude falls to ``stop_altitude_m``.

    The scene's duration is replaced by ``max_days`` and its ``[stop] altitude`` by the
    threshold: the crossing is a terminal event located by the integrator (the stop state is the
    last row).  The relative equilibrium of ``orbit.motion = "equilibrium"`` is solved under the
    conservative effects; the current (and drag) act from t = 0.
    """
    from ..formulations.cowell import cowell_rhs
    from ..integrators.driver import integrate
    from ..pipeline import _event_args, prepare

    sc = scene.replace(**{"duration": f"{max_days} d", "stop.altitude": f"{stop_altitude_m} m"})
    prep = prepare(sc)
    p = prep.model.fresh_params()
    if prep.formulation != "cowell":  # DROMO (the time form) or the frame turning with the orbit
        from ..pipeline import integrate_prepared

        res, _ = integrate_prepared(prep, p, None)
    else:
        from ..tether.newton_solver import choose

        res = integrate(prep.method, cowell_rhs, 0.0, prep.y0, prep.t_out, p, prep.rtol, prep.atol,
                        h_max=prep.h_max, max_steps=prep.max_steps, second_order=True,
                        newton=choose(p, prep.y0.size, True), **_event_args(prep))  # fmt: skip
    stats = {k: v for k, v in res.stats.items() if isinstance(v, (int, float))}
    crossing = float(res.t[-1]) if res.stopped_by is not None else float("nan")
    message = f"altitude {stop_altitude_m:g} m reached at t = {crossing:.9g} s" if res.stopped_by is not None else res.message
    return Mission(prep, np.asarray(res.t), np.asarray(res.y), stats, crossing, res.stats["wall_s"], res.status, message)


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


def bench_rows() -> list[dict]:
    """``make bench`` entry: the n = 1 mission with every native integrator."""
    return table()


#: The many-rod mission: RADAU5 in the frame turning with the orbit, from the
#: quasi-static start (docs/integrators.md section 11).
RODS_SETTINGS = {"integrator.method": "radau5", "integrator.formulation": "cowell-orbit",
                 "orbit.motion": "quasi-static", "integrator.rtol": 1e-8, "integrator.atol": 1e-8}  # fmt: skip


def rods_table(rods=(1, 4, 16, 64), scene_path=SCENE, settings=None) -> list[dict]:
    """The whole de-orbit against the rod count: de-orbit time, its change from n = 1, wall time
    (integration only, compilation excluded) and the fitted exponent of wall time against n."""
    from ..benchmarks.cost_vs_n import fit_exponent
    from ..scene import load_scene

    settings = RODS_SETTINGS if settings is None else settings
    base = load_scene(scene_path).replace(**settings)
    rows = []
    for n in rods:
        sc = base.replace(**{"tethers.main.rods": n})
        run_until_altitude(sc.replace(duration="0.01 d"), max_days=0.01)  # warm-up (set-up code)
        t_wall = time.perf_counter()
        m = run_until_altitude(sc)
        total = time.perf_counter() - t_wall
        rows.append({
            "rods": n, "deorbit_days": m.crossing_s / DAY_S, "deorbit_s": m.crossing_s,
            "change_from_n1_s": float("nan"), "integrate_s": m.wall_s, "total_s": total,
            "steps": int(m.stats.get("n_accepted", 0)), "rejected": int(m.stats.get("n_rejected", 0)),
            "newton_fail": int(m.stats.get("n_newton_fail", 0)), "rhs": int(m.stats.get("n_rhs", 0)),
            "status": m.status,
        })  # fmt: skip
    first = rows[0]["deorbit_s"] if rods and rods[0] == 1 else float("nan")
    for r in rows:
        r["change_from_n1_s"] = r["deorbit_s"] - first
    rows.append({"rods": f"{rods[0]}-{rods[-1]}", "deorbit_days": "", "deorbit_s": "", "change_from_n1_s": "",
                 "integrate_s": fit_exponent([r["rods"] for r in rows], [r["integrate_s"] for r in rows]),
                 "total_s": "<- exponent of integrate_s vs n", "steps": "", "rejected": "",
                 "newton_fail": "", "rhs": "", "status": ""})  # fmt: skip
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--methods", nargs="*", default=list(DEFAULT_METHODS), help="integrators to time")
    ap.add_argument("--rtol", type=float, default=None, help="one rtol for every method")
    ap.add_argument("--rods", type=int, default=1)
    ap.add_argument("--rod-counts", type=int, nargs="*", default=None,
                    help="the many-rod table instead: cowell-orbit, quasi-static start, RADAU5 1e-8")
    args = ap.parse_args(argv)
    if args.rod_counts:
        rows = rods_table(tuple(args.rod_counts))
        keys = list(rows[0])
        print("| " + " | ".join(keys) + " |\n|" + "---|" * len(keys))
        for r in rows:
            print("| " + " | ".join(f"{v:.10g}" if isinstance(v, float) else str(v) for v in r.values()) + " |")
        return 0
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
