"""Cost of an uncertainty study: per-sample overhead and throughput against the worker count.

Rows of :func:`bench_rows` (``make bench``, section "uncertainty"):

* ``deorbit overhead``: for one de-orbit sample (studies/scenes/deorbit-ed.toml, n = 1, RADAU5 at
  rtol 1e-8, the ~1.5 s integration of docs/effects-electrodynamic.md 6 on a quiet machine), the
  time of ``scene.replace`` of the dispersed keys, of ``pipeline.prepare`` (model, layout,
  relative equilibrium), and of the integration; overhead = (replace + prepare) / integration;
* ``machinery N``: the whole per-sample cost of the study machinery with a summary that costs
  nothing (the closed form, tetherlab.uncertainty.summaries): sampling, copula, ``replace``, scene
  hash, cache write and read, statistics -- for N = 32, 128, 512, one process, to show it stays
  flat in N;
* ``workers W``: throughput of de-orbit samples (samples per hour, and per hour per core) with
  W = 1, 2 local worker processes (spawned, so the numba cache is loaded once per worker).

Command line: ``python -m tetherlab.benchmarks.uncertainty``.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
STUDIES = ROOT / "studies" / "uncertainty"


def deorbit_overhead() -> dict:
    from ..benchmarks.deorbit import run_until_altitude
    from ..pipeline import prepare
    from ..scene import load_scene

    base = load_scene(ROOT / "studies" / "scenes" / "deorbit-ed.toml")
    run_until_altitude(base.replace(duration="1 d"), max_days=1)  # compile / load the kernels first
    changes = {"effects.electrodynamic.current": "2.05 A", "bodies.end_mass.mass": "395.0 kg"}
    reps = 5
    t0 = time.perf_counter()
    for _ in range(reps):
        sc = base.replace(**changes)
    t_replace = (time.perf_counter() - t0) / reps
    stop = sc.replace(**{"duration": "200 d", "stop.altitude": "200000.0 m"})
    t0 = time.perf_counter()
    for _ in range(reps):
        prepare(stop)
    t_prepare = (time.perf_counter() - t0) / reps
    m = run_until_altitude(sc)
    return {"case": "deorbit overhead", "replace_ms": 1e3 * t_replace, "prepare_ms": 1e3 * t_prepare,
            "integrate_s": m.wall_s, "overhead_pct": 100.0 * (t_replace + t_prepare) / m.wall_s,
            "deorbit_days": m.crossing_s / 86400.0}


def machinery(ns=(32, 128, 512)) -> list[dict]:
    from ..uncertainty.runner import run_study
    from ..uncertainty.study import load_uncertainty_study

    rows = []
    for n in ns:
        study = load_uncertainty_study(STUDIES / "closed_form.toml", samples=n)
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            run_study(study, tmp, workers=1, progress=False, figures=False, n_boot=200)
            first = time.perf_counter() - t0
            t0 = time.perf_counter()
            run_study(study, tmp, workers=1, progress=False, figures=False, n_boot=200)
            cached = time.perf_counter() - t0
        rows.append({"case": f"machinery N={n}", "per_sample_ms": 1e3 * first / n,
                     "per_sample_cached_ms": 1e3 * cached / n})
    return rows


def throughput(workers=(1, 2), n: int = 4) -> list[dict]:
    from ..uncertainty.runner import run_study
    from ..uncertainty.study import load_uncertainty_study

    rows = []
    for w in workers:
        study = load_uncertainty_study(STUDIES / "deorbit_small.toml", samples=n * w)
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            res = run_study(study, tmp, workers=w, progress=False, figures=False, n_boot=200)
            wall = time.perf_counter() - t0
        rate = len(res.records) / wall * 3600.0
        rows.append({"case": f"workers {w}", "samples": len(res.records), "wall_s": wall,
                     "samples_per_hour": rate, "samples_per_hour_per_core": rate / w,
                     "failed": len(res.failed)})
    return rows


def bench_rows() -> list[dict]:
    """``make bench`` entry (about a minute on a quiet 2-core machine: 13 de-orbits)."""
    return [deorbit_overhead(), *machinery(), *throughput()]


if __name__ == "__main__":
    for row in bench_rows():
        print(row)
