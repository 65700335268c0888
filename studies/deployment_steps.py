"""Where the steps of a deployment go (docs/deployment.md 8b): counts, independent of the load.

The bench's deployment (tetherlab/benchmarks/deployment.py, 500 m rods, 39 births) measured three
ways, every count summed over the phases:

1. the cost of a restart: every phase restarted once and three more times inside (breakpoints:
   a fresh initial step and RADAU5's workspace rebuilt, as at a birth);
2. where the steps fall inside a phase: each phase integrated as four quarters, steps per quarter;
3. ``error_scale = "tether"`` against "rod": steps, and how far the end mass moves relative to the
   station, at the end and over every output row;
4. ``reel.birth = "quasi-static"`` against "straight" (docs/deployment.md 6.4), with either error
   scale: steps, the largest energy jump at a birth, and the end mass's move at the end.

Run: ``python -m studies.deployment_steps`` (~2 min on a loaded 2-core machine; not in make verify).
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


if __name__ == "__main__":
    main()
