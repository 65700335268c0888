"""Hard cases that must stay numerically stable, each with a stated pass criterion.

    PYTHONPATH=. python studies/hard_cases.py OUTDIR [--skip-long] [--scheduler tcp://...] [--workers N]

Every case runs at two tolerances (rtol = atol = TOL_LOOSE and TOL_TIGHT) through tetherlab.sweep
(parallel, cached in OUTDIR/cache, resumable), with the summary tetherlab.summaries.invariants.
Pass means, for the tight run (and the loose one for the first check):
  * no NaN/inf anywhere in the outputs (``nonfinite == 0``);
  * |H(t) - H(0)| <= H_BOUND * I n: total angular momentum about the Earth's centre, measured in
    units of the tether's own angular momentum I n (tetherlab.summaries.own_angular_momentum_scale);
  * for the "energy" tether model (which conserves energy, docs/model.md):
    |E(t) - E(0)| <= E_BOUND * I n^2;
  * converging with the tolerance: the final positions of the loose and tight runs agree within
    the case's ``converge_m`` (metres);
  * a case outside the model's validity (``expect_error``) must stop with a SimulationError
    whose message names the failure and the rod, at both tolerances.
Writes OUTDIR/hard_cases.csv (every run) and OUTDIR/hard_cases.md; exits 1 when a case fails.
The slack-tether case (tension-only tether with event location; a tether starting slack and
snapping taut) is SLACK_SLOT below.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
SCENES = HERE / "scenes"
TOL_LOOSE, TOL_TIGHT = 1e-9, 1e-11
# 1e-4 of the tether's own angular momentum is ~4e-12 of the total (orbital) one for the
# bench-libration system (|H| / (I n) ~ 2.4e7), i.e. a few hundred ulps: a gross integration or
# model error shows up, round-off accumulated over ~1e5 steps does not.  Measured at rtol 1e-11
# (first run, this machine): worst 1.0e-5 (e = 0.95, whose scale uses the mean motion, ~100x
# below the perigee rate), 2.6e-6 over 35 days, <= 1.2e-6 elsewhere.
H_BOUND = 1e-4  # of I n
E_BOUND = 1e-4  # of I n^2; energy model measured <= 9.4e-7

# name, scene file, changes, criteria
CASES = [
    ("stiff EA x1000", "hard-stiff.toml", {}, {"converge_m": 1.0}),
    ("stiff EA x1000, energy model", "hard-stiff.toml", {"tethers.main.model": "energy"}, {"converge_m": 1.0}),
    ("e = 0.95", "hard-eccentric.toml", {}, {"converge_m": 1.0}),
    ("mf/m0 = 1e-4", "hard-massratio-small.toml", {}, {"converge_m": 1.0}),
    ("mf/m0 = 1", "hard-massratio-one.toml", {}, {"converge_m": 1.0}),
    ("mf/m0 = 1, energy model", "hard-massratio-one.toml", {"tethers.main.model": "energy"}, {"converge_m": 1.0}),
    ("n = 128", "hard-n128.toml", {}, {"converge_m": 1.0}),
    ("35 days", "hard-35day.toml", {}, {"converge_m": 100.0, "long": True}),
    ("rod collapse", "hard-collapse.toml", {}, {"expect_error": ["rod collapsed", "rod "]}),
]
# Tension-only tether (scene key tension_only): starts 1 % slack, snaps taut, chatters; every
# slack/taut switch of every rod is a located event.  Energy model: its potential is C^1, so the
# energy bound applies across the snaps.  Measured: 272/278 switches in 600 s at the two
# tolerances, final body positions 0.12 m apart (the rods' chatter is sensitive, the bodies not).
SLACK_SLOT: list = [
    ("slack start, snaps taut (tension-only)", "hard-slack-snap.toml",
     {"duration": "600 s", "tethers.main.model": "energy"}, {"converge_m": 1.0}),
]
CASES += SLACK_SLOT


def check(name, changes, crit, loose, tight, scene):
    """(passed, reasons) for one case from its two run records."""
    reasons = []
    if "expect_error" in crit:
        for rec in (loose, tight):
            if rec.ok:
                reasons.append(f"rtol {rec.params['tol']:g}: ran to the end, expected a SimulationError")
            elif not rec.error.startswith("SimulationError") or not all(s in rec.error for s in crit["expect_error"]):
                reasons.append(f"rtol {rec.params['tol']:g}: unexpected error: {rec.error}")
        return not reasons, reasons
    for rec in (loose, tight):
        if not rec.ok:
            reasons.append(f"rtol {rec.params['tol']:g} failed: {rec.error}")
    if reasons:
        return False, reasons
    for rec in (loose, tight):
        if rec.summary["nonfinite"] != 0:
            reasons.append(f"rtol {rec.params['tol']:g}: {rec.summary['nonfinite']:.0f} non-finite outputs")
    s = tight.summary
    if not s["angmom_error_own"] <= H_BOUND:
        reasons.append(f"|dH|/(I n) = {s['angmom_error_own']:.3g} > {H_BOUND:g}")
    if changes.get("tethers.main.model") == "energy" and not s["energy_error_own"] <= E_BOUND:
        reasons.append(f"|dE|/(I n^2) = {s['energy_error_own']:.3g} > {E_BOUND:g}")
    dist = max(
        math.dist([loose.summary[f"{b.name}.{a}_m"] for a in "xyz"], [s[f"{b.name}.{a}_m"] for a in "xyz"])
        for b in scene.bodies
    )
    tight.summary["tolerance_change_m"] = dist
    if not dist <= crit["converge_m"]:
        reasons.append(f"final positions at rtol {TOL_LOOSE:g} and {TOL_TIGHT:g} differ by {dist:.3g} m > {crit['converge_m']} m")
    return not reasons, reasons


def main(argv=None) -> int:
    from tetherlab.scene import load_scene
    from tetherlab.summaries import invariants
    from tetherlab.sweep import run_sweep

    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out")
    ap.add_argument("--skip-long", action="store_true", help="leave out the 35-day case")
    ap.add_argument("--scheduler")
    ap.add_argument("--workers", type=int)
    ap.add_argument("--quiet", action="store_true")
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    cases = [c for c in CASES if not (args.skip_long and c[3].get("long"))]
    scenes, params, labels, base = [], [], [], {}
    for name, fname, changes, _ in cases:
        sc = load_scene(SCENES / fname).replace(**changes) if changes else load_scene(SCENES / fname)
        base[name] = sc
        for tol in (TOL_LOOSE, TOL_TIGHT):
            scenes.append(sc.replace(**{"integrator.rtol": tol, "integrator.atol": tol}))
            params.append({"case": name, "tol": tol})
            labels.append(f"{name} rtol {tol:g}")
    res = run_sweep(scenes, invariants, cache_dir=out / "cache", scheduler=args.scheduler, workers=args.workers,
                    labels=labels, params=params, progress=not args.quiet, description="hard cases")
    md = ["## Hard cases", "",
          f"Two runs per case (rtol = atol = {TOL_LOOSE:g}, {TOL_TIGHT:g}). Pass: no NaN; |dH| <= {H_BOUND:g} I n "
          f"(tether's own angular momentum); energy model |dE| <= {E_BOUND:g} I n^2; final positions of the two "
          "runs within the stated distance; cases outside the model's validity stop with a SimulationError "
          "naming the rod.", "",
          "| case | result | dH/(I n) | dE/(I n^2) | tolerance change (m) | bound (m) | wall tight (s) | notes |",
          "|---|---|---|---|---|---|---|---|"]
    failed = []
    for k, (name, fname, changes, crit) in enumerate(cases):
        loose, tight = res.records[2 * k], res.records[2 * k + 1]
        ok, reasons = check(name, changes, crit, loose, tight, base[name])
        if not ok:
            failed.append(name)
        s = tight.summary
        if "expect_error" in crit:
            note = (tight.error or "").replace("|", "/")[:160]
            md.append(f"| {name} | {'PASS' if ok else 'FAIL'} | | | | | {tight.wall_s:.3g} | {note}; {'; '.join(reasons)} |")
        else:
            md.append(
                f"| {name} | {'PASS' if ok else 'FAIL'} | {s.get('angmom_error_own', math.nan):.3g} | "
                f"{s.get('energy_error_own', math.nan):.3g} | {s.get('tolerance_change_m', math.nan):.3g} | "
                f"{crit['converge_m']} | {s.get('wall_s', math.nan):.3g} | {'; '.join(reasons)} |"
            )
    md += ["", f"Slack-tether cases: {len(SLACK_SLOT)} (tension-only tether, switches located as events).", ""]
    res.frame().to_csv(out / "hard_cases.csv", index=False, float_format="%.9g")
    (out / "hard_cases.md").write_text("\n".join(md))
    print("\n".join(md))
    if failed:
        print(f"FAILED: {', '.join(failed)}", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
