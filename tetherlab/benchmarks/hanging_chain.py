"""The hanging chain with a tip mass (docs/hanging-chain.md), side by side: the wall time of a whole
run (set-up, integration, diagnostics and result included) to reach 1e-4 and 1e-5 relative error
in the first lateral frequency against the continuum's, for every tether model, integrator and
error scale, from two starts, against the rod count.

The case: studies/scenes/hanging-chain.toml (10 m, 1 kg, EA = 1e7 N, 0.5 kg end mass, 35 s, 701
outputs).  The error is measured against the Bessel solution, omega_1 = 1.0761050 rad/s
(``oracles.hanging_chain.continuum_frequencies``, eq. H5), so it holds the rods' own error (order
2: 3.7e-5, 9.4e-6, 2.3e-6 at 16, 32, 64 bars, docs/hanging-chain.md 2) besides the integrator's:
1e-5 cannot be reached below 32 rods whatever the tolerance.

Starts (both the same swing, 1 % off the vertical, so they differ only in the axial energy):

* ``release``: the equilibrium start, the free hang turned by asin(0.01) with every rod at its
  release tension (``initial.release = { angle }``: no axial energy);
* ``placed``: studies/scenes/hanging-chain-placed.toml, the static shape with the end mass held at
  the unstretched length 1 % off the vertical, let go (2e-5 J in the axial modes);
* ``mode`` (not run by default): the free hang in its first lateral mode, end mass 1 cm aside.

For each combination the tolerance ladder rtol = atol = 1e-5 ... 1e-10 is run from the loosest;
the cost to reach an error is the wall time of the loosest rtol that reaches it.  The ladder stops
when both errors are reached, when the error has stopped changing above a target (the rods' error:
"not reached"), or when a run hits the step cap (``MAX_STEPS``): the explicit methods, whose step is
bounded by the stability of the axial modes (periods of 0.1-1 ms), are stopped there and their
cost is projected from the time they reached ("capped: projected").  Each row also gives the wall
time of the integration alone and the counts of the run that set its last target (steps, rhs calls,
Newton failures), which do not depend on the machine's load: where the whole run's cost grows
faster than they do, the rest is the set-up (the start) or the result.  A start the model refuses
is a row saying so.  Last rows: the fitted exponent of the cost (and of the counts) in n per
combination, and the placed start's cost over the release's.

``MODELS`` is the list of tether models compared; a model is one entry (its scene changes).

Command line: ``python -m tetherlab.benchmarks.hanging_chain [--rods 16 32 64 128] [--methods ...]
[--scales rod tether] [--starts release placed] [--models elastic ...]``.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

from ..errors import SceneError
from . import print_markdown
from .cost_vs_n import fit_exponent

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "studies" / "scenes"
LADDER = (1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)
TARGETS = (1e-4, 1e-5)
METHODS = ("radau5", "dop853", "vern9")
ERROR_SCALES = ("rod", "tether")
STARTS = ("release", "placed")
#: the tether models side by side: name -> the scene changes that select it.  A new model adds its
#: rows with one entry here.  The inextensible chain (docs/inextensible.md) has no axial modes:
#: its two starts differ only by the projection of the held shape onto the rods' lengths, and
#: RADAU5 takes its own structured Newton matrix (docs/inextensible.md 8).
MODELS: dict[str, dict] = {
    "elastic": {},
    "inextensible": {"tethers.main.model": "inextensible"},
}
#: a run stops after this many steps; the explicit methods reach it (stability-limited) and their
#: cost is projected from the simulated time reached
MAX_STEPS = 20_000
#: the error has stopped changing above a target when two tolerances differ by less than this
#: fraction of it: the rest is the rods' (or the start's) own error, not the integrator's
SETTLED = 0.02


def _scene(model, start, n, method, scale, rtol):
    from ..scene import load_scene

    if start == "placed":
        sc = load_scene(SCENES / "hanging-chain-placed.toml")
    else:
        sc = load_scene(SCENES / "hanging-chain.toml")
        release = {"mode": 1, "amplitude": "1 cm"} if start == "mode" else {"angle": f"{math.asin(0.01)} rad"}
        sc = sc.replace(**{"tethers.main.initial": {"shape": "equilibrium", "release": release}})
    return sc.replace(**{
        **MODELS[model], "tethers.main.rods": int(n), "integrator.method": method,
        "integrator.error_scale": scale, "integrator.rtol": rtol, "integrator.atol": rtol,
        "integrator.max_steps": MAX_STEPS,
    })  # fmt: skip


def omega_bessel() -> float:
    """omega_1 of the continuum with the tip mass (docs/hanging-chain.md eq. H5): 1.0761050 rad/s."""
    from ..oracles.hanging_chain import continuum_frequencies

    return float(continuum_frequencies(10.0, 1.0, 0.5, 9.80665, count=1)[0])


def run_one(model, start, n, method, scale, rtol) -> dict:
    """One whole run, timed around ``simulate`` (set-up to result): its omega_1, wall time, the
    integration's own wall time, steps, rhs calls, Newton failures (RADAU5), and whether it stopped
    at the step cap (then the simulated time it reached)."""
    from ..oracles.continuum import fit_frequencies
    from ..oracles.hanging_chain import continuum_frequencies
    from ..pipeline import simulate

    sc = _scene(model, start, n, method, scale, rtol)
    t0 = time.perf_counter()
    res = simulate(sc, progress=False, raise_on_failure=False)
    wall = time.perf_counter() - t0
    st = res.stats
    ts = res.timeseries
    t_end = float(ts["t_s"].iloc[-1]) if len(ts) else 0.0
    out = {"wall_s": wall, "integration_s": float(st["wall_s"]), "steps": int(st["n_accepted"]), "ok": res.ok,
           "rhs": int(st["n_rhs"]), "newton_fail": int(st["n_newton_fail"]), "t_end_s": t_end,
           "omega": float("nan")}  # fmt: skip
    if res.ok:
        guesses = continuum_frequencies(10.0, 1.0, 0.5, 9.80665, count=3)
        w, _, _ = fit_frequencies(ts["t_s"].to_numpy(), ts["tip.x_m"].to_numpy(), guesses)
        out["omega"] = float(w[0])
    return out


def ladder(model, start, n, method, scale, w_ref) -> dict:
    """The cost to reach each target along the tolerance ladder (see the module's docstring)."""
    best = {x: None for x in TARGETS}
    note = ""
    prev = None
    last = None
    for rtol in LADDER:
        try:
            r = run_one(model, start, n, method, scale, rtol)
        except SceneError as e:
            # a start the model refuses (the inextensible chain cannot be held at its full length:
            # its static shape would need the rods to stretch) is a row saying so, not a crash
            note = f"refused: {e}"
            break
        last = r
        if not r["ok"]:
            if r["t_end_s"] > 0:
                proj = r["wall_s"] * 35.0 / r["t_end_s"]
                note = f"capped at {MAX_STEPS} steps (t = {r['t_end_s']:.3g} s): projected {proj:.3g} s at rtol {rtol:g}"
            else:
                note = f"failed at rtol {rtol:g}"
            break
        err = abs(r["omega"] / w_ref - 1.0)
        r["err"] = err
        for x in TARGETS:
            if err <= x and best[x] is None:
                best[x] = dict(r, rtol=rtol)
        if all(best[x] is not None for x in TARGETS):
            break
        if prev is not None and abs(err - prev) < SETTLED * min(x for x in TARGETS if best[x] is None):
            note = f"error settled at {err:.3g} (rtol {rtol:g})"
            break
        prev = err
    row = {"model": model, "start": start, "method": method, "error_scale": scale, "rods": n}
    for x in TARGETS:
        b = best[x]
        row[f"wall_s@{x:g}"] = b["wall_s"] if b else float("nan")
        row[f"integration_s@{x:g}"] = b["integration_s"] if b else float("nan")
        row[f"rtol@{x:g}"] = b["rtol"] if b else "not reached"
    counted = best[TARGETS[-1]] or best[TARGETS[0]] or last or {}
    # the counts of the run that set the last target reached (else of the last run): they do not
    # depend on the machine's load, the wall times do
    for k in ("steps", "rhs", "newton_fail"):
        row[k] = counted.get(k, 0)
    row["note"] = note
    return row


def bench_rows(rods=(16, 32, 64, 128), methods=METHODS, scales=ERROR_SCALES, starts=STARTS,
               models=tuple(MODELS)) -> list[dict]:  # fmt: skip
    w_ref = omega_bessel()
    for model in models:  # warm-up: compile the kernels outside the timings
        for method in methods:
            run_one(model, "release", 4, method, "rod", 1e-4)
    rows = []
    for model in models:
        for start in starts:
            for method in methods:
                for scale in scales:
                    for n in rods:
                        rows.append(ladder(model, start, n, method, scale, w_ref))
    return rows + summary_rows(rows, starts)


def summary_rows(rows, starts) -> list[dict]:
    """The fitted exponent of the cost in n per combination, and the placed start's cost over the
    release's at each n (the target: within 5x)."""
    out = []
    keys = sorted({(r["model"], r["start"], r["method"], r["error_scale"]) for r in rows}, key=str)
    for key in keys:
        sel = [r for r in rows if (r["model"], r["start"], r["method"], r["error_scale"]) == key]
        if all(r["note"].startswith("refused") for r in sel):
            continue  # a start the model refuses has nothing to fit
        ns = [r["rods"] for r in sel]
        row = {"model": key[0], "start": key[1], "method": key[2], "error_scale": key[3],
               "rods": f"exponent in n, {ns[0]}-{ns[-1]}"}  # fmt: skip
        for x in TARGETS:
            row[f"wall_s@{x:g}"] = fit_exponent(ns, [r[f"wall_s@{x:g}"] for r in sel])
            row[f"integration_s@{x:g}"] = fit_exponent(ns, [r[f"integration_s@{x:g}"] for r in sel])
            row[f"rtol@{x:g}"] = ""
        for k in ("steps", "rhs"):
            row[k] = fit_exponent(ns, [r[k] for r in sel])
        row["newton_fail"] = ""
        row["note"] = "fitted over the rod counts that reached the target"
        out.append(row)
    if "placed" in starts and "release" in starts:
        for r in rows:
            if r["start"] != "placed":
                continue
            base = next((b for b in rows if b["start"] == "release" and all(
                b[k] == r[k] for k in ("model", "method", "error_scale", "rods"))), None)  # fmt: skip
            if base is None or r["note"].startswith("refused"):
                continue
            row = {"model": r["model"], "start": "placed / release", "method": r["method"],
                   "error_scale": r["error_scale"], "rods": r["rods"]}  # fmt: skip
            for x in TARGETS:
                row[f"wall_s@{x:g}"] = r[f"wall_s@{x:g}"] / base[f"wall_s@{x:g}"]
                row[f"integration_s@{x:g}"] = r[f"integration_s@{x:g}"] / base[f"integration_s@{x:g}"]
                row[f"rtol@{x:g}"] = ""
            for k in ("steps", "rhs", "newton_fail"):
                row[k] = ""
            row["note"] = "cost ratio (target: elastic <= 5)"
            out.append(row)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rods", nargs="*", type=int, default=[16, 32, 64, 128])
    ap.add_argument("--methods", nargs="*", default=list(METHODS))
    ap.add_argument("--scales", nargs="*", default=list(ERROR_SCALES))
    ap.add_argument("--starts", nargs="*", default=list(STARTS))
    ap.add_argument("--models", nargs="*", default=list(MODELS))
    args = ap.parse_args(argv)
    np.seterr(all="ignore")
    print_markdown(bench_rows(tuple(args.rods), tuple(args.methods), tuple(args.scales), tuple(args.starts),
                              tuple(args.models)))  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
