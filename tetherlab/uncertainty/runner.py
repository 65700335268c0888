"""Running an uncertainty study: samples -> scenes -> the sweep (cache, pool or Dask) -> statistics.

:func:`sample_inputs` turns the sampler's unit-cube points into values of the dispersed keys
(copula, then each inverse CDF); :func:`run_study` builds one scene per sample
(``base.replace(**values)``), runs them through :func:`tetherlab.sweep.run_sweep` (cached under
``out_dir/cache``: a study run again, or extended to more samples, reads back what it has), and
writes ``samples.csv`` (one row per sample: index, inputs, quantities, ok, error), ``stats.json``,
``failures.csv`` and the figures.  A sample whose values do not form a valid scene (a normal mass
drawn negative) is a failed sample with the scene's error, like one whose run fails: counted and
listed, never dropped.

Samples that change only parameters of the parameter block (a non-conservative effect's
quantities: the current, the field strength, a drag coefficient) with a summary function that
takes them (``accepts_parameter_samples``) are sent as :class:`~.reuse.ParameterSample` s: each
worker prepares the base scene once and re-packs every sample's values into a copy of its
parameter block (tetherlab/uncertainty/reuse.py, bit for bit equal to the full path).  Any other
study takes the full path; ``stats.json`` says which and why.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..sweep import RunRecord, resolve, run_sweep, scene_hash
from .dispersions import apply_copula
from .reuse import ParameterSample, reuse_refusal
from .statistics import describe
from .study import UncertaintyStudy


def sample_inputs(study: UncertaintyStudy, n: int | None = None, points: np.ndarray | None = None) -> list[dict]:
    """The dispersed keys' scene values of samples 0 .. n-1 (or of the given unit-cube points)."""
    u = study.sampler().points(n or study.samples) if points is None else np.asarray(points, dtype=float)
    u = apply_copula(u, study.dispersions, study.correlation)
    cols = [d.ppf(u[:, j]) for j, d in enumerate(study.dispersions)]
    return [{d.key: d.scene_value(cols[j][i]) for j, d in enumerate(study.dispersions)} for i in range(u.shape[0])]


def _numeric(v: Any) -> Any:
    """A scene value as a table entry: the number of '2.03 A', anything else unchanged."""
    if isinstance(v, str):
        head = v.split(" ", 1)[0]
        try:
            return float(head)
        except ValueError:
            return v
    return v


@dataclass
class StudyResult:
    study: UncertaintyStudy
    inputs: list[dict]
    records: list[RunRecord]
    stats: dict[str, dict]
    n_run: int
    n_cached: int
    wall_s: float
    path: str = "full"  # "parameter-only" (prepared model reused) or "full: <why not>"

    @property
    def failed(self) -> list[tuple[int, RunRecord]]:
        return [(i, r) for i, r in enumerate(self.records) if not r.ok]

    def values(self, quantity: str) -> np.ndarray:
        return np.array([r.summary[quantity] for r in self.records if r.ok and quantity in r.summary])

    def frame(self):
        import pandas as pd

        rows = []
        for i, (x, r) in enumerate(zip(self.inputs, self.records)):
            row = {"sample": i, **{k: _numeric(v) for k, v in x.items()}}
            row.update({q: r.summary.get(q, math.nan) for q in self.study.quantities})
            row.update(ok=r.ok, error=r.error or "", wall_s=r.wall_s, scene_hash=r.scene_hash)
            rows.append(row)
        return pd.DataFrame(rows)


def build_scenes(study: UncertaintyStudy, inputs: list[dict]) -> tuple[list, list[RunRecord | None]]:
    """One scene per sample; a sample that is not a valid scene gets a failed record instead."""
    base = study.base_scene()
    scenes, early = [], []
    for x in inputs:
        try:
            scenes.append(base.replace(**x))
            early.append(None)
        except ValueError as exc:  # SceneError: a drawn value outside what the key admits
            scenes.append(None)
            early.append(RunRecord(scene_hash="", label="", params=dict(x), ok=False,
                                   error=f"{type(exc).__name__}: {exc}", wall_s=0.0))
    return scenes, early


def sample_path(study: UncertaintyStudy, summary, reuse: bool = True) -> str:
    """"parameter-only" when the study's samples may reuse a prepared model, else "full: <why>"."""
    if not reuse:
        return "full: reuse switched off"
    if not getattr(summary, "accepts_parameter_samples", False):
        return f"full: the summary {study.summary} takes scenes only"
    why = reuse_refusal(study.base_scene(), study.keys)
    return "parameter-only" if why is None else f"full: {why}"


def build_items(study: UncertaintyStudy, inputs: list[dict], path: str) -> tuple[list, list[RunRecord | None]]:
    """What the sweep runs, one per sample: scenes (full path) or parameter samples."""
    if path != "parameter-only":
        return build_scenes(study, inputs)
    base = study.base_scene()
    h = scene_hash(base)
    items = [ParameterSample(base, h, tuple(x.items()), name=f"sample {i}") for i, x in enumerate(inputs)]
    return items, [None] * len(items)


def run_study(study: UncertaintyStudy, out_dir: str | Path, *, scheduler: Any = None, workers: int | None = None,
              progress: bool = True, figures: bool = True, n_boot: int = 2000, reuse: bool = True) -> StudyResult:
    """Run every sample (cached: a study run again or extended reads back what it has); ``reuse``:
    parameter-only samples reuse a prepared model (module docstring)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    inputs = sample_inputs(study)
    summary = resolve(study.summary)
    path = sample_path(study, summary, reuse)
    scenes, early = build_items(study, inputs, path)
    idx = [i for i, s in enumerate(scenes) if s is not None]
    res = run_sweep([scenes[i] for i in idx], summary, cache_dir=out / "cache", scheduler=scheduler,
                    workers=workers, labels=[f"sample {i}" for i in idx], params=[inputs[i] for i in idx],
                    progress=progress, description=study.name)
    records: list[RunRecord] = list(early)  # type: ignore[arg-type]
    for i, rec in zip(idx, res.records):
        rec.label = f"sample {i}"
        records[i] = rec
    n_failed = sum(not r.ok for r in records)
    stats = {}
    for q in study.quantities:
        x = np.array([r.summary[q] for r in records if r.ok and q in r.summary])
        missing = sum(1 for r in records if r.ok and q not in r.summary)
        stats[q] = describe(x, deadlines=study.deadlines.get(q, ()), n_failed=n_failed + missing,
                            n_boot=n_boot, seed=study.seed)
    result = StudyResult(study, inputs, records, stats, res.n_run, res.n_cached, res.wall_s, path)
    _write(result, out, figures)
    return result


def _write(result: StudyResult, out: Path, figures: bool) -> None:
    study = result.study
    frame = result.frame()
    frame.to_csv(out / "samples.csv", index=False, float_format="%.17g")
    fails = frame[~frame["ok"]][["sample", "error"]]
    fails.to_csv(out / "failures.csv", index=False)
    doc = {
        "study": study.name, "method": study.method, "samples": study.samples, "seed": study.seed,
        "n_ok": int(frame["ok"].sum()), "n_failed": int((~frame["ok"]).sum()),
        "n_run_now": result.n_run, "n_cached": result.n_cached, "wall_s": result.wall_s, "sample_path": result.path,
        "dispersions": [{"key": d.key, "dist": d.dist, "unit": d.unit, "kind": d.kind, **d.params,
                         **({"values": list(d.values), "weights": list(d.weights)} if d.dist == "choice" else {})}
                        for d in study.dispersions],
        "correlation": None if study.correlation is None else
        {"keys": list(study.correlation.keys), "matrix": study.correlation.matrix.tolist()},
        "stats": result.stats,
        "failures": [{"sample": int(s), "error": e} for s, e in zip(fails["sample"], fails["error"])],
    }
    (out / "stats.json").write_text(json.dumps(doc, indent=1, default=float))
    if figures:
        from .figures import study_figures

        study_figures(result, out)


def stats_table(result: StudyResult) -> list[dict]:
    """Rows (quantity, statistic, value, low, high) for printing or a report table."""
    rows = []
    for q, st in result.stats.items():
        for name, v in st.items():
            rows.append({"quantity": q, "statistic": name, **v})
    return rows


def hashes(study: UncertaintyStudy, n: int | None = None, reuse: bool = True) -> list[str]:
    """The samples' sweep-cache identities (scene or parameter-sample hashes): equal for equal samples."""
    path = sample_path(study, resolve(study.summary), reuse)
    scenes, _ = build_items(study, sample_inputs(study, n), path)
    return [scene_hash(s) if s is not None else "" for s in scenes]
