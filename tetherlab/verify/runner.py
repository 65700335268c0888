"""verify's task runner: the report's sections as tasks, run in worker processes longest first,
with their timings; results do not depend on which worker ran a task or when."""

from __future__ import annotations

import math
import os
import time
import tomllib
from pathlib import Path

from .checkout import ROOT
from .checks import section_43_figures
from .controls import run_negative_controls
from .hanging_chain_modes import figures as hanging_chain_figures
from .sections import CHECKS
from .studies import STUDIES, run_studies

def _cores() -> int:
    return max(1, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1))


# -- running the sections: in worker processes, assembled in a fixed order ------------------------
#: measured wall time of each section alone (s, quiet 2-core machine, kernels compiled; the studies
#: with their sweeps in one process): only the order in which sections are handed to the workers
#: (longest first, so that none starts last on an idle pool) depends on these, never a result
SECTION_COST_S = {
    "study:fidelity": 255, "study:hard_cases": 210, "study:workprecision": 200, "study:convergence": 180,
    "study:deorbit": 170, "study:uncertainty_deorbit": 150, "study:rigid_bodies": 56, "controls": 55,
    "study:bead_vs_tmed": 50, "study:uncertainty": 25, "study:deployment": 25,
    "study:stiefel_table": 34, "study:rigid_scenes": 33, "figures": 20, "check:invariants": 13,
    "check:vertical": 12, "check:hanging-chain": 15, "check:hanging-chain-bessel": 10, "check:inextensible": 60, "check:libration": 7, "check:reproducible": 5, "study:catenary": 5,
}


def section_tasks(only=None, no_controls=False) -> list[str]:
    """Every section of a verify run, in the report's (canonical) order: the checks, the section
    4.3 figures, the studies (``only`` restricts them), the negative controls."""
    tasks = [f"check:{sid}" for sid, _t, _fn in CHECKS] + ["figures"]
    tasks += [f"study:{name}" for _t, name, *_ in STUDIES if only is None or name in only]
    return tasks + ([] if no_controls else ["controls"])


def run_task(task: str, out: str, study_workers: int | None = None) -> dict:
    """Run one section (in a worker process or in this one) and return what the report needs.

    Never raises: a section that fails returns its error beside everything it computed before
    the failure (the rows so far; a study's own files stay in its directory)."""
    out = Path(out)
    t0, c0 = time.perf_counter(), time.process_time()
    res = {"task": task, "rows": [], "values": {}, "error": None}
    try:
        if task.startswith("check:"):
            sid = task.split(":", 1)[1]
            fn = next(f for s, _t, f in CHECKS if s == sid)
            res["values"] = fn(res["rows"])
        elif task == "figures":
            res["figures"] = section_43_figures(out, res["rows"])
            res["figures"] += hanging_chain_figures(out)  # a failure here keeps the scenes' figures
        elif task.startswith("study:"):
            name = task.split(":", 1)[1]
            sections, values, failures = run_studies(out, [name], study_workers=study_workers)
            res.update(studies=sections, values=values, failures=failures)
        elif task == "controls":
            gates = tomllib.loads((ROOT / "references" / "gates.toml").read_text())
            cells, _baseline = run_negative_controls(res["rows"], gates)
            res["cells"] = cells
        else:
            raise ValueError(f"task: expected check:<id>, figures, study:<name> or controls, got {task!r}")
    except Exception as exc:  # report and go on: the other sections still run
        import traceback

        res["error"] = f"{type(exc).__name__}: {exc}"
        res["traceback"] = traceback.format_exc()[-2000:]
    res["wall_s"] = time.perf_counter() - t0
    res["cpu_s"] = time.process_time() - c0  # this process only: the studies' sweeps run in it (workers=1)
    res["pid"] = os.getpid()
    return res


def idle_machine_wall_s(results: dict, jobs: int) -> float:
    """The wall time the sections would take on ``jobs`` idle cores: their CPU times handed out
    longest-first (as run_tasks does) to the first free worker.  On a shared machine the measured
    wall time includes the other users' load; this estimate does not (it omits the start-up of the
    workers and a section's waiting on anything but its own CPU)."""
    free = [0.0] * max(1, jobs)
    for t in sorted(results, key=lambda t: -SECTION_COST_S.get(t, 1)):
        k = free.index(min(free))
        free[k] += results[t].get("cpu_s", math.nan)
    return max(free)


def run_tasks(tasks: list[str], out: Path, jobs: int, log=print) -> dict:
    """Run the sections on ``jobs`` worker processes (1: here, one after the other); return
    task -> result.  Sections start longest first (SECTION_COST_S); the results do not depend on
    which worker ran them or when (each section is deterministic and writes only its own files),
    and the caller assembles them in the canonical order.  A worker that dies takes the sections
    it was running with it: they are retried once in a fresh pool, then reported as lost."""
    results = {}
    order = sorted(tasks, key=lambda t: -SECTION_COST_S.get(t, 1))
    if jobs <= 1:
        for t in order:
            results[t] = run_task(t, str(out))
            log(f"[verify] {t}: {results[t]['wall_s']:.0f} s{' FAILED' if results[t]['error'] else ''}")
        return results
    import concurrent.futures as cf
    import multiprocessing

    pending = list(order)
    for attempt in (1, 2):
        if not pending:
            break
        # spawn: the workers load the numba kernels from the on-disk cache (no fork of this
        # process's threads); studies run their sweeps inside the worker (study_workers=1), so
        # at most ``jobs`` processes compute at any time
        pool = cf.ProcessPoolExecutor(max_workers=min(jobs, len(pending)), mp_context=multiprocessing.get_context("spawn"))
        futures = {pool.submit(run_task, t, str(out), 1): t for t in pending}
        lost = []
        try:
            for fut in cf.as_completed(futures):
                t = futures[fut]
                try:
                    results[t] = fut.result()
                    log(f"[verify] {t}: {results[t]['wall_s']:.0f} s (worker {results[t]['pid']})"
                        f"{' FAILED: ' + results[t]['error'] if results[t]['error'] else ''}", flush=True)
                except Exception as exc:  # noqa: BLE001 - a dead worker (BrokenProcessPool)
                    lost.append(t)
                    results[t] = {"task": t, "rows": [], "values": {}, "wall_s": math.nan,
                                  "error": f"worker lost (attempt {attempt}): {type(exc).__name__}: {exc}"}
        finally:
            pool.shutdown(wait=True, cancel_futures=True)
        pending = lost
    return results

