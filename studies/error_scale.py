"""What ``integrator.error_scale`` changes, in the answer and in the cost (docs/integrators.md section 15).

    PYTHONPATH=. python studies/error_scale.py [--cases chain,libration,deorbit] [--rods 4,8,16,32]

Three undamped cases, each run with ``error_scale = "rod"`` (the default) and ``"tether"`` at the
same rtol = atol, and once with a tight reference (``"rod"`` at ``--ref-rtol``) at the same rod
count, so that the difference is integration error only:

- chain: studies/scenes/hanging-chain-placed.toml (the placed start that rings the axial modes),
  35 s, RADAU5; the first lateral frequency fitted to the end mass's sideways motion, against the
  Bessel solution and against the reference run; the end mass's final position against the
  reference.
- libration: studies/scenes/libration-inplane.toml with RADAU5 (the many-rod method), ``--orbits``
  orbits; the libration frequency fitted to ``main.theta_rad`` (about sqrt(3) omega); the end
  mass's final position against the reference.
- deorbit: studies/scenes/deorbit-ed-rods.toml, a ``--deorbit`` stretch from its quasi-static
  start (or ``--deorbit-motion equilibrium``: the current then acts as a step load on the
  conservative equilibrium and rings the axial modes, docs/integrators.md section 10); the end
  mass's final position against the reference.

Per run: RADAU5 steps, rejections, integration wall time; per case and choice: the exponent of
the wall time and of the steps in the rod count (least squares on log-log).
"""

from __future__ import annotations

import argparse
import math
import pathlib

import numpy as np

import tetherlab
from tetherlab.oracles.continuum import fit_frequencies
from tetherlab.oracles.hanging_chain import continuum_frequencies

SCENES = pathlib.Path(__file__).resolve().parent / "scenes"
CHAIN = dict(length_m=10.0, mass_kg=1.0, tip_mass_kg=0.5, g_m_s2=9.80665)


def _case(name: str, args) -> tuple[object, str, float | None]:
    """(scene, the column whose frequency is fitted or None, the frequency guess in rad/s)."""
    if name == "chain":
        sc = tetherlab.load_scene(SCENES / "hanging-chain-placed.toml")
        return sc, "tip.x_m", continuum_frequencies(*CHAIN.values(), count=1)[0]
    if name == "libration":
        sc = tetherlab.load_scene(SCENES / "libration-inplane.toml")
        sc = sc.replace(**{"integrator.method": "radau5", "duration": f"{args.orbits} orbits",
                           "output.count": 401})  # fmt: skip
        a = 7400e3
        omega = math.sqrt(3.986004418e14 / a**3)
        return sc, "main.theta_rad", math.sqrt(3.0) * omega
    if name == "deorbit":
        sc = tetherlab.load_scene(SCENES / "deorbit-ed-rods.toml")
        sc = sc.replace(**{"duration": args.deorbit, "output.count": 11, "output.step": None,
                           "orbit.motion": args.deorbit_motion})  # fmt: skip
        return sc, None, None
    raise SystemExit(f"unknown case {name!r}")


def _run(scene, n: int, rtol: float, scale: str) -> dict:
    s = scene.replace(**{"tethers.main.rods": n, "integrator.rtol": rtol, "integrator.atol": rtol,
                         "integrator.error_scale": scale})  # fmt: skip
    res = tetherlab.simulate(s, progress=False)
    st = res.stats
    return {"res": res, "steps": st["n_accepted"], "rejected": st["n_rejected"], "wall_s": st["wall_s"]}


def _tip(res) -> np.ndarray:
    ts = res.timeseries
    cols = [c for c in ts.columns if c.endswith(".x_m") or c.endswith(".y_m") or c.endswith(".z_m")]
    # the tether's far end: the last body's position columns
    body = sorted({c.rsplit(".", 1)[0] for c in cols})
    name = "tip" if "tip" in body else ("mf" if "mf" in body else "end_mass")
    return ts[[f"{name}.x_m", f"{name}.y_m", f"{name}.z_m"]].to_numpy()[-1]


def _col(res, column: str) -> np.ndarray:
    ts = res.timeseries if column in res.timeseries.columns else res.diagnostics
    return ts[column].to_numpy()


def _freq(res, column: str, guess: float) -> float:
    w, _, _ = fit_frequencies(res.timeseries["t_s"].to_numpy(), _col(res, column), [guess])
    return float(w[0])


def _slope(n, y) -> float:
    return float(np.polyfit(np.log(n), np.log(y), 1)[0])


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", default="chain,libration,deorbit")
    ap.add_argument("--rods", default="4,8,16,32")
    ap.add_argument("--rtol", type=float, default=1e-8)
    ap.add_argument("--ref-rtol", type=float, default=1e-11)
    ap.add_argument("--ref-scale", default="tether", help="error_scale of the reference run")
    ap.add_argument("--orbits", type=float, default=1.0)
    ap.add_argument("--deorbit", default="0.02 d")
    ap.add_argument("--deorbit-motion", default="quasi-static",
                    help='orbit.motion of the de-orbit: "quasi-static" (the scene\'s) or "equilibrium" '
                         "(the conservative equilibrium: the current is a step load that rings the axial modes)")
    args = ap.parse_args(argv)
    rods = [int(x) for x in args.rods.split(",")]
    for case in args.cases.split(","):
        scene, column, guess = _case(case, args)
        print(f"\n== {case}: rtol = atol = {args.rtol:g}, reference {args.ref_scale} at {args.ref_rtol:g}")
        print(f"| n | choice | steps | rejected | wall s | frequency rad/s | vs reference | max over t of |d {column}| "
              "| end mass's final position vs reference, m |")
        print("|---|---|---|---|---|---|---|---|---|")
        cost = {"rod": [], "tether": []}
        steps = {"rod": [], "tether": []}
        for n in rods:
            ref = _run(scene, n, args.ref_rtol, args.ref_scale)
            ref_tip = _tip(ref["res"])
            ref_w = _freq(ref["res"], column, guess) if column else float("nan")
            print(f"| {n} | reference | {ref['steps']} | {ref['rejected']} | {ref['wall_s']:.3g} | "
                  f"{ref_w:.10g} | | | |", flush=True)  # fmt: skip
            for scale in ("rod", "tether"):
                r = _run(scene, n, args.rtol, scale)
                w = _freq(r["res"], column, guess) if column else float("nan")
                dx = float(np.linalg.norm(_tip(r["res"]) - ref_tip))
                dq = float(np.max(np.abs(_col(r["res"], column) - _col(ref["res"], column)))) if column else float("nan")
                cost[scale].append(r["wall_s"])
                steps[scale].append(r["steps"])
                print(f"| {n} | {scale} | {r['steps']} | {r['rejected']} | {r['wall_s']:.3g} | {w:.10g} | "
                      f"{(w - ref_w) / ref_w:.2e} | {dq:.2e} | {dx:.2e} |", flush=True)  # fmt: skip
        if len(rods) > 1:
            for scale in ("rod", "tether"):
                print(f"exponent in rods, {scale}: wall {_slope(rods, cost[scale]):.2f}, steps {_slope(rods, steps[scale]):.2f}")


if __name__ == "__main__":
    main()
