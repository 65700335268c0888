"""Cost of an uncertainty study: per-sample overhead and throughput against the worker count.

Rows of :func:`bench_rows` (``make bench``, section "uncertainty"):

* ``deorbit overhead, full path`` / ``parameter-only path``: for one de-orbit sample
  (studies/scenes/deorbit-ed.toml, n = 1, RADAU5 at rtol 1e-8) with the current and the field
  strength dispersed, the per-sample cost outside the integration: the full path is
  ``scene.replace`` of the dispersed keys, the summary's own ``replace`` (duration, stop) and
  ``pipeline.prepare`` (model, layout, relative equilibrium); the parameter-only path
  (tetherlab/uncertainty/reuse.py) is the copy of the prepared block and the re-pack of the
  changed effect, once the worker holds the prepared base.  Overhead against a 1-second run (the
  target: < 5 %) and against this de-orbit's own integration (from 1000 km);
* ``machinery N``: the whole per-sample cost of the study machinery with a summary that costs
  nothing (the closed form, tetherlab.uncertainty.summaries): sampling, copula, ``replace``, scene
  hash, cache write and read, statistics -- for N = 32, 128, 512, one process, to show it stays
  flat in N;
* ``workers W``: throughput of de-orbit samples (the verify study's scene from 400 km,
  studies/uncertainty/deorbit_verify.toml, parameter-only path; samples per hour, and per hour per
  worker) with W = 1, 2, 3 local worker processes (spawned: each loads the numba cache and
  prepares the base once) on this 2-core machine, 12 samples per worker, end to end and in steady
  state; last row: the fitted exponents of throughput against W over W <= the core count
  (1 = linear scaling).

Command line: ``python -m tetherlab.benchmarks.uncertainty``.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
STUDIES = ROOT / "studies" / "uncertainty"


def deorbit_overhead(reps: int = 9) -> list[dict]:
    """Per-sample cost outside the integration, full path against parameter-only path (medians
    of ``reps`` alternating repetitions: the shared machine's load drifts within seconds)."""
    import statistics

    from ..pipeline import prepare
    from ..scene import load_scene
    from ..sweep import scene_hash
    from ..uncertainty import reuse
    from ..uncertainty.summaries import deorbit_days

    base = load_scene(ROOT / "studies" / "scenes" / "deorbit-ed.toml")
    changes = {"effects.electrodynamic.current": "2.05 A", "effects.electrodynamic.dipole_strength": "7.9e15 T m3"}
    summary_changes = {"duration": "200 d", "stop.altitude": "200000.0 m"}
    h = scene_hash(base)
    sample = reuse.ParameterSample(base, h, tuple(changes.items()))
    reuse.prepared(sample, summary_changes)  # the worker's first sample: prepare the base, check it
    full_ms, fast_ms = [], []
    for _ in range(reps):
        t0 = time.perf_counter()
        prepare(base.replace(**changes).replace(**summary_changes))
        full_ms.append(1e3 * (time.perf_counter() - t0))
        t0 = time.perf_counter()
        reuse.prepared(sample, summary_changes)
        fast_ms.append(1e3 * (time.perf_counter() - t0))
    run = deorbit_days(sample)
    integrate_s = run["integrate_wall_s"]
    rows = []
    for case, ms in (("deorbit overhead, full path", full_ms), ("deorbit overhead, parameter-only path", fast_ms)):
        med = statistics.median(ms)
        rows.append({"case": case, "overhead_ms": med, "overhead_min_ms": min(ms),
                     "pct_of_1_s_run": 100.0 * med / 1e3, "integrate_s": integrate_s,
                     "pct_of_this_run": 100.0 * med / (1e3 * integrate_s), "deorbit_days": run["deorbit_days"]})
    return rows


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


def throughput(workers=(1, 2, 3), n: int = 12) -> list[dict]:
    """De-orbit samples per hour against the worker count: end to end (the pool's start-up
    included: W = 1 runs in this process, W > 1 spawns W processes that each load the kernels
    and prepare the base) and in steady state (W samples over the median in-worker wall time of a
    sample, which leaves out each worker's first sample, the one that loads the kernels: what a
    long study approaches).  The 1-minute load average is recorded beside each row
    (the machine is shared)."""
    import os
    import statistics

    from ..benchmarks.cost_vs_n import fit_exponent
    from ..uncertainty.runner import run_study
    from ..uncertainty.study import load_uncertainty_study

    from ..benchmarks.deorbit import run_until_altitude
    from ..scene import load_scene

    # compile (or load) the kernels here first: the spawned workers then load them from the disk cache
    run_until_altitude(load_scene(ROOT / "studies" / "scenes" / "deorbit-ed.toml").replace(duration="1 d"), max_days=1)
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    rows = []
    for w in workers:
        study = load_uncertainty_study(STUDIES / "deorbit_verify.toml", samples=n * w)
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            res = run_study(study, tmp, workers=w, progress=False, figures=False, n_boot=200)
            wall = time.perf_counter() - t0
        per_sample = [r.wall_s for r in res.records if r.ok]
        rate = len(res.records) / wall * 3600.0
        # the median: each spawned worker's first sample also loads the kernels from the disk cache
        steady = w * 3600.0 / statistics.median(per_sample) if per_sample else float("nan")
        rows.append({"case": f"workers {w}", "samples": len(res.records), "wall_s": wall,
                     "samples_per_hour": rate, "steady_samples_per_hour": steady,
                     "steady_per_worker": steady / w, "failed": len(res.failed), "path": res.path,
                     "load_1min": os.getloadavg()[0]})
    fit = [r for r in rows if int(r["case"].split()[1]) <= cores]
    ws = [int(r["case"].split()[1]) for r in fit]
    rows.append({"case": f"fitted exponent, throughput ~ W^k over W <= {cores} (the cores)",
                 "end_to_end": fit_exponent(ws, [r["samples_per_hour"] for r in fit]),
                 "steady": fit_exponent(ws, [r["steady_samples_per_hour"] for r in fit])})
    return rows


def bench_rows() -> list[dict]:
    """``make bench`` entry (a few minutes on a quiet 2-core machine: 49 de-orbits from 400 km,
    one from 1000 km)."""
    rows = [*deorbit_overhead(), *machinery(), *throughput()]
    # one set of columns for the whole table (make bench prints the first row's keys as its header)
    keys = list(dict.fromkeys(k for r in rows for k in r))
    return [{k: r.get(k, "") for k in keys} for r in rows]


if __name__ == "__main__":
    for row in bench_rows():
        print(row)
