"""The verification section for the uncertainty machinery: problems with known answers.

:func:`run(out_dir) <run>` returns ``{"gates": {name: value}, "figures": [paths], "tables":
[(title, rows)]}``; every gate is a line of references/gates.toml (value <= threshold passes).

A. Known distribution, end to end (study file -> scenes -> sweep -> statistics).  The closed-form
   decay (docs/effects-electrodynamic.md 5, eq. 6) is T = k / I; with I = 2 A exp(s Z) (log-normal,
   s = 0.1) T = T_med exp(-s Z): mean T_med exp(s^2/2), variance T_med^2 exp(s^2)(exp(s^2) - 1),
   quantiles T_med exp(s Phi^-1(p)), P(T <= D) = Phi(ln(D / T_med) / s).  Gate
   ``uq_known_distribution_over_ci``: the largest |estimate - truth| over the half-width of its
   bootstrap interval (on the truth's side), the six intervals at level 1 - 0.05/6 (Bonferroni: the
   family of six covers the truth with probability >= 95 %).
B. Interval coverage over 200 independent replications (plain MC, N = 400, the same problem,
   vectorised): the fraction of replications whose 95 % interval holds the truth, for each of the
   six statistics.  Gate ``uq_ci_coverage_floor_over_min``: floor / smallest coverage, floor =
   0.95 - 3 sqrt(0.95 0.05 / 200) = 0.904 (three binomial standard deviations below nominal).
   Negative control ``uq_ci_coverage_negative_control``: the same with a sampler whose 4 workers
   share one seed (:class:`SharedSeedSampler`: every point 4 times), smallest coverage over the
   floor; it must fail the coverage gate (value < 1).
C. Sobol' indices against analytic ones.  Ishigami (a = 7, b = 0.1, inputs uniform on [-pi, pi];
   Ishigami & Homma 1990; S1 = 0.3139, 0.4424, 0; ST = 0.5576, 0.4424, 0.2437), and log T of the
   closed form with log-normal current (s = 0.1) and dipole strength (s = 0.2) through scenes:
   log T is linear in the two normal scores, S1 = ST = s_k^2 / (0.1^2 + 0.2^2) = 0.2, 0.8.  Gate
   ``uq_sobol_indices_over_ci``: the largest |S - S_true| over SALib's bootstrap half-width at level
   1 - 0.05/10 (ten indices).
D. Convergence: the width of the mean's interval against N (16 independent replications; 2 z sd of
   their means), plain MC and scrambled Sobol', N = 64 ... 4096, fitted slopes in log-log.  Gates
   ``uq_mc_slope_vs_half``: |slope_MC + 1/2| over three standard errors of the fit;
   ``uq_sobol_slope_steeper``: slope_Sobol' + 3 se + 1/2 (passes below 0: steeper than MC by more than
   three standard errors).
E. Negative controls of A, C and D (B has its own, above).  Gate ``uq_machinery_negative_controls``:
   the number of these controls that pass the gate they must fail (0 allowed):
   * A: the study's decay times with every current 3 % high (T / 1.03: exact, T ~ 1/I), truth
     unchanged -- a median shifted by 3 %, 2.3 times the median's Bonferroni half-width at N = 512;
   * C: Ishigami with x1 and x2 swapped in the function, the analytic indices unchanged;
   * D (MC): a sampler whose stream wraps after 64 points (a reset seed): the width stops shrinking;
   * D (Sobol'): plain pseudo-random points where the scrambled Sobol' ones should be: slope -1/2.

``python -m tetherlab.uncertainty.verification OUT_DIR`` writes OUT_DIR/uncertainty.md, its gates
as JSON and the figures (the verify section ``study-uncertainty``).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from scipy.special import ndtr, ndtri

from .dispersions import Dispersion, apply_copula
from .samplers import MonteCarlo, SharedSeedSampler, Sobol
from .statistics import describe, fit_slope, replicated_width

ROOT = Path(__file__).resolve().parents[2]
SIGMA = 0.1
DEADLINE_D = 40.0
STATS = ("mean", "var", "q05", "q50", "q95", f"p_meet_{DEADLINE_D!r}")
ISHIGAMI_S1 = (0.3139051827, 0.4424111447, 0.0)
ISHIGAMI_ST = (0.5575888553, 0.4424111447, 0.2436836727)
REPLICATIONS = 200
COVERAGE_N = 400


def _truth(t_med: float, s: float = SIGMA) -> dict[str, float]:
    return {
        "mean": t_med * math.exp(s * s / 2.0),
        "var": t_med**2 * math.exp(s * s) * (math.exp(s * s) - 1.0),
        "q05": t_med * math.exp(s * float(ndtri(0.05))),
        "q50": t_med,
        "q95": t_med * math.exp(s * float(ndtri(0.95))),
        f"p_meet_{DEADLINE_D!r}": float(ndtr(math.log(DEADLINE_D / t_med) / s)),
    }


def _over_ci(st: dict, truth: dict) -> dict[str, float]:
    out = {}
    for k, t in truth.items():
        v, lo, hi = st[k]["value"], st[k]["low"], st[k]["high"]
        half = (v - lo) if t < v else (hi - v)
        out[k] = abs(v - t) / half if half > 0 else math.inf
    return out


def _closed_form_study(samples: int = 512):
    from .study import load_uncertainty_study

    return load_uncertainty_study(ROOT / "studies" / "uncertainty" / "closed_form.toml", samples=samples)


def known_distribution(out_dir: Path) -> tuple[float, list[dict], float, float]:
    from .runner import run_study
    from .summaries import closed_form_decay_days

    study = _closed_form_study()
    t_med = closed_form_decay_days(study.base_scene())["decay_days"]
    res = run_study(study, out_dir / "known_distribution", workers=1, progress=False)
    level = 1.0 - 0.05 / len(STATS)
    st = describe(res.values("decay_days"), deadlines=[DEADLINE_D], n_failed=len(res.failed), level=level,
                  seed=study.seed)
    truth = _truth(t_med)
    ratio = _over_ci(st, truth)
    rows = [{"statistic": k, "truth": truth[k], "estimate": st[k]["value"], "low": st[k]["low"],
             "high": st[k]["high"], "error_over_half_width": ratio[k]} for k in truth]
    # control: every current 3 % high (T ~ 1/I exactly), the truth kept
    bad = describe(res.values("decay_days") / 1.03, deadlines=[DEADLINE_D], level=level, seed=study.seed)
    return max(ratio.values()), rows, t_med, max(_over_ci(bad, truth).values())


def _decay(points: np.ndarray, t_med: float) -> np.ndarray:
    current = Dispersion("effects.electrodynamic.current", "lognormal", {"median": 2.0, "sigma_log": SIGMA}, "A")
    return t_med * 2.0 / current.ppf(points[:, 0])


def coverage(sampler_cls, t_med: float, **kw) -> dict[str, float]:
    truth = _truth(t_med)
    hits = {k: 0 for k in truth}
    for r in range(REPLICATIONS):
        x = _decay(sampler_cls(1, 1000 + r, **kw).points(COVERAGE_N), t_med)
        st = describe(x, deadlines=[DEADLINE_D], n_boot=500, seed=r)
        for k, t in truth.items():
            hits[k] += st[k]["low"] <= t <= st[k]["high"]
    return {k: h / REPLICATIONS for k, h in hits.items()}


def _ishigami(x: np.ndarray, a: float = 7.0, b: float = 0.1) -> np.ndarray:
    return np.sin(x[:, 0]) + a * np.sin(x[:, 1]) ** 2 + b * x[:, 2] ** 4 * np.sin(x[:, 0])


def _ishigami_swapped(x: np.ndarray) -> np.ndarray:
    return _ishigami(x[:, [1, 0, 2]])


def sobol_check(out_dir: Path) -> tuple[float, list[dict], float]:
    from .sensitivity import run_sensitivity, sobol_of_function
    from .study import parse_study

    level = 1.0 - 0.05 / 10
    disp = [Dispersion(f"x{i + 1}", "uniform", {"low": -math.pi, "high": math.pi}) for i in range(3)]
    ish = sobol_of_function(_ishigami, disp, 2048, seed=3, level=level)
    swapped = sobol_of_function(_ishigami_swapped, disp, 2048, seed=3, level=level)
    control = max(abs(swapped[d.key][kind] - true[i]) / swapped[d.key][f"{kind}_conf"]
                  for i, d in enumerate(disp) for kind, true in (("S1", ISHIGAMI_S1), ("ST", ISHIGAMI_ST)))
    rows = []
    for i, d in enumerate(disp):
        for kind, true in (("S1", ISHIGAMI_S1[i]), ("ST", ISHIGAMI_ST[i])):
            v, c = ish[d.key][kind], ish[d.key][f"{kind}_conf"]
            rows.append({"problem": "Ishigami", "input": d.key, "index": kind, "analytic": true, "estimate": v,
                         "half_width": c, "error_over_half_width": abs(v - true) / c})
    data = {
        "name": "closed-form-sensitivity", "scene": "../scenes/deorbit-ed.toml",
        "summary": "tetherlab.uncertainty.summaries:closed_form_decay_days", "quantities": ["log_decay_days"],
        "sampling": {"method": "sobol", "samples": 1, "seed": 5}, "sensitivity": {"method": "sobol", "samples": 256},
        "dispersion": [
            {"key": "effects.electrodynamic.current", "dist": "lognormal", "median": "2 A", "sigma_log": 0.1},
            {"key": "effects.electrodynamic.dipole_strength", "dist": "lognormal", "median": "8e15 T m3",
             "sigma_log": 0.2},
        ],
    }
    study = parse_study(data, ROOT / "studies" / "uncertainty" / "closed_form.toml")
    idx = run_sensitivity(study, out_dir / "sobol_closed_form", workers=1, progress=False,
                          level=level)["log_decay_days"]
    shares = {"effects.electrodynamic.current": 0.01 / 0.05, "effects.electrodynamic.dipole_strength": 0.04 / 0.05}
    for k, true in shares.items():
        for kind in ("S1", "ST"):
            v, c = idx[k][kind], idx[k][f"{kind}_conf"]
            rows.append({"problem": "closed-form log T", "input": k, "index": kind, "analytic": true, "estimate": v,
                         "half_width": c, "error_over_half_width": abs(v - true) / c})
    return max(r["error_over_half_width"] for r in rows), rows, control


class _WrappingMC(MonteCarlo):
    """Negative control: a plain-MC stream that restarts after 64 points (a seed reset)."""

    def _points(self, n):
        base = super()._points(min(n, 64))
        return np.resize(base, (n, self.dim))


def convergence(out_dir: Path, t_med: float):
    from .figures import convergence_figure

    ns = [64, 128, 256, 512, 1024, 2048, 4096]
    designs = {"MC": MonteCarlo, "Sobol'": Sobol, "control: MC wrapping after 64": _WrappingMC,
               "control: MC in place of Sobol'": MonteCarlo}
    curves, slopes = {}, {}
    for name, cls in designs.items():
        seed0 = 900 if name.startswith("control: MC in place") else 500
        curves[name] = replicated_width(lambda n, r, cls=cls, s0=seed0: cls(1, s0 + r).points(n),
                                        lambda u: _decay(u, t_med), ns, replications=16)
        slopes[name] = fit_slope(curves[name])
    fig = convergence_figure(curves, slopes, out_dir / "uq_convergence.png",
                             "95 % interval width of the mean decay time (d)")
    rows = [{"design": name, "N": n, "width_d": w} for name, rows_ in curves.items() for n, w in rows_]
    rows += [{"design": f"{name} fitted slope", "N": "", "width_d": f"{s:.3f} +- {se:.3f}"} for name, (s, se) in slopes.items()]
    return slopes, rows, fig


def run(out_dir) -> dict:
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    gates, tables, figures = {}, [], []
    worst, rows, t_med, control_a = known_distribution(out)
    gates["uq_known_distribution_over_ci"] = worst
    tables.append(("Known distribution: closed-form decay time under a log-normal current (512 MC samples "
                   "through the study runner)", rows))
    figures += sorted((out / "known_distribution").glob("decay_days_*.png"))

    floor = 0.95 - 3.0 * math.sqrt(0.95 * 0.05 / REPLICATIONS)
    cov = coverage(MonteCarlo, t_med)
    bad = coverage(SharedSeedSampler, t_med, workers=4)
    gates["uq_ci_coverage_floor_over_min"] = floor / min(cov.values())
    gates["uq_ci_coverage_negative_control"] = min(bad.values()) / floor
    tables.append((f"Coverage of the 95 % bootstrap intervals over {REPLICATIONS} replications, N = {COVERAGE_N} "
                   f"(floor {floor:.3f})", [{"statistic": k, "MC": cov[k], "shared-seed control": bad[k]} for k in cov]))

    worst_s, srows, control_c = sobol_check(out)
    gates["uq_sobol_indices_over_ci"] = worst_s
    tables.append(("Sobol' indices against analytic ones (SALib, Saltelli design)", srows))

    slopes, crows, fig = convergence(out, t_med)
    s_mc, se_mc = slopes["MC"]
    s_so, se_so = slopes["Sobol'"]
    gates["uq_mc_slope_vs_half"] = abs(s_mc + 0.5) / (3.0 * se_mc)
    gates["uq_sobol_slope_steeper"] = s_so + 3.0 * se_so + 0.5
    tables.append(("Convergence of the mean's interval width (16 replications per N)", crows))
    figures.append(fig)

    s_w, se_w = slopes["control: MC wrapping after 64"]
    s_f, se_f = slopes["control: MC in place of Sobol'"]
    controls = [
        ("A: every current 3 % high", "uq_known_distribution_over_ci", control_a, 1.0),
        ("C: Ishigami x1, x2 swapped", "uq_sobol_indices_over_ci", control_c, 1.0),
        ("D: MC stream wrapping after 64 points", "uq_mc_slope_vs_half", abs(s_w + 0.5) / (3.0 * se_w), 1.0),
        ("D: MC points in place of Sobol'", "uq_sobol_slope_steeper", s_f + 3.0 * se_f + 0.5, 0.0),
    ]
    gates["uq_machinery_negative_controls"] = float(sum(v <= thr for _c, _g, v, thr in controls))
    tables.append(("Negative controls: each must fail its gate",
                   [{"control": c, "gate": g, "value": v, "threshold": thr, "fails it": v > thr}
                    for c, g, v, thr in controls]))
    return {"gates": gates, "figures": [str(p) for p in figures], "tables": tables}


def write_section(out: Path, stem: str, title: str, intro: str, result: dict) -> None:
    """A verification run's tables, figures and gates as ``out/<stem>.md`` and ``<stem>_gates.json``
    (the command line of this module and of verification_deorbit)."""
    import json

    from ..report import table

    md = [f"# {title}", "", intro, ""]
    for name, rows in result["tables"]:
        md += [f"**{name}**", "", table(rows), ""]
    md += [f"![{Path(p).stem}]({Path(p).resolve().relative_to(out.resolve()).as_posix()})" for p in result["figures"]]
    (out / f"{stem}.md").write_text("\n".join(md) + "\n")
    (out / f"{stem}_gates.json").write_text(json.dumps(result["gates"], indent=1))
    print(json.dumps(result["gates"], indent=1))


def main(argv=None) -> int:
    import sys

    argv = sys.argv[1:] if argv is None else argv
    out = Path(argv[0] if argv else "reports/uncertainty")
    write_section(out, "uncertainty", "Uncertainty machinery against known answers",
                  "tetherlab/uncertainty/verification.py (docs/uncertainty.md 6) has the budget of every gate.",
                  run(out))  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
