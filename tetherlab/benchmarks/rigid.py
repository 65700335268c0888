"""Right-hand-side cost with a rigid root, three wheels and four tethers against the point-mass hub
(docs/model.md 12), over rods per tether n = 4 ... 64, with the fitted exponent of cost against n.

Both scenes: a 200 kg hub carrying four identical tethers (100 m, n rods each, 5 kg tips) in a
circular orbit under central gravity; "rigid" makes the hub a rigid body (asymmetric inertia,
attitude from its orbit frame, a slow tumble) with three wheels spinning under constant motor
torques and its tethers at body-fixed points 1 m from its centre of mass.  The extra cost of the
rigid root is a constant per call (one 6x6 inverse, the G^T W G accumulations, the wheel and
gravity-gradient terms), so the exponent of both rows should be ~1 and their difference flat.
Measured by a compiled loop calling the Cowell cfunc (as ``tetherlab.bench.rhs_cost_table``);
best of 9 repeats, the two scenes measured alternately (the machine is shared).
"""

from __future__ import annotations

import time

import numpy as np

ROD_COUNTS = (4, 8, 16, 32, 64)


def _scene(n: int, rigid: bool):
    from ..scene import Scene

    hub = {"mass": "200 kg"}
    if rigid:
        hub["rigid"] = {
            "inertia": {"xx": "100 kg m2", "yy": "90 kg m2", "zz": "150 kg m2", "xy": "3 kg m2"},
            "attitude": "orbit",
            "angular_velocity": {"vector": ["0.01 rad/s", "-0.02 rad/s", "0.015 rad/s"], "frame": "orbit"},
        }
        hub["wheels"] = {
            w: {"axis": a, "inertia": "0.05 kg m2", "speed": "100 rad/s", "torque": "0.01 N m"}
            for w, a in (("wx", [1, 0, 0]), ("wy", [0, 1, 0]), ("wz", [0, 0, 1]))
        }
    bodies = {"hub": hub}
    tethers = {}
    points = ([1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, -1, 0])
    for k in range(4):
        bodies[f"tip{k}"] = {"mass": "5 kg"}
        t = {"from": "hub", "to": f"tip{k}", "rods": n, "length": "100 m", "EA": "1e4 N", "mass": "1 kg",
             "initial": {"theta": f"{20 + 90 * k} deg", "phi": "10 deg"}}
        if rigid:
            t["from_point"] = [f"{x} m" for x in points[k]]
        tethers[f"s{k}"] = t
    return Scene.from_dict({
        "duration": "10 s", "effects": {"central_gravity": {}}, "bodies": bodies, "tethers": tethers,
        "orbit": {"reference": "hub", "elements": {"a": "7000 km", "e": 0.0, "i": "40 deg"}}, "output": {"count": 2},
    })


def _costs_us(preps, repeats: int = 9) -> list[float]:
    """Best-of-``repeats`` cost per call of each prepared scene, measured alternately (so a load
    burst on the shared machine hits both rows alike)."""
    from ..bench import _time_rhs
    from ..formulations.cowell import cowell_rhs

    args = []
    for prep in preps:
        y = np.ascontiguousarray(prep.y0, float)
        dy = np.empty_like(y)
        p = prep.model.fresh_params()
        _time_rhs(cowell_rhs, y, dy, p, 10)
        args.append((y, dy, p, max(2000, int(4e5 / prep.model.n_rods))))
    best = [np.inf] * len(preps)
    for _ in range(repeats):
        for i, (y, dy, p, ncalls) in enumerate(args):
            t0 = time.perf_counter()
            _time_rhs(cowell_rhs, y, dy, p, ncalls)
            best[i] = min(best[i], (time.perf_counter() - t0) / ncalls)
    return [b * 1e6 for b in best]


def bench_rows(rod_counts=ROD_COUNTS) -> list[dict]:
    from ..pipeline import prepare

    rows = []
    cost = {"point": [], "rigid": []}
    for n in rod_counts:
        point, rigid = _costs_us([prepare(_scene(n, False)), prepare(_scene(n, True))])
        cost["point"].append(point)
        cost["rigid"].append(rigid)
        rows.append({"rods_per_tether": n, "total_rods": 4 * n, "point_hub_us": point, "rigid_root_us": rigid,
                     "difference_us": rigid - point})
    x = np.log(np.asarray(rod_counts, float))
    fit = {k: float(np.polyfit(x, np.log(v), 1)[0]) for k, v in cost.items()}
    rows.append({"rods_per_tether": "fitted exponent", "total_rods": "", "point_hub_us": fit["point"],
                 "rigid_root_us": fit["rigid"], "difference_us": ""})
    return rows
