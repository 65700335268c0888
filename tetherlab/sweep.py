"""Sweeps: many independent runs in parallel, cached on disk, resumable.

A sweep is a list of scenes and one *summary function*: a module-level callable
``summary(scene) -> dict[str, float]`` that runs the scene (usually through
:func:`tetherlab.pipeline.simulate`) and reduces it to a few numbers.  :func:`run_sweep` runs
every scene whose summary is not cached yet, on this machine's cores (a process pool) or on a
Dask cluster (``scheduler="tcp://host:8786"``, an address of a running ``dask scheduler``), shows
progress with tqdm, and returns one :class:`RunRecord` per scene, in the order given.

Caching and resuming.  A run is identified by the SHA-256 of its scene (``scene.to_dict()``
serialised as JSON with sorted keys: the exact SI values, so two scenes that differ in any digit
differ) and the summary function's import name.  Each finished run is written at once to
``<cache_dir>/<code digest>/<scene hash>.<summary name>.json``, so a sweep interrupted at any point
(Ctrl-C, a killed job) resumes by being called again: finished runs are read back, not redone.
The code digest (a hash of every tetherlab source file) makes a changed package recompute; a
summary function defined outside tetherlab is not covered by it.

Failures are never lost and never silent.  A run whose scene or summary raised (a
``SimulationError`` naming the rod that collapsed, a ``SceneError``, a bug) comes back with
``ok = False`` and ``error = "SimulationError: run stopped at t = ..."``, and is cached like a
success (it is as deterministic as one; ``retry_failed=True`` runs it again).  A run lost to the
machinery (a worker process killed, a cluster gone) is also recorded as failed, but *not* cached,
so the next call retries it.

Command line: ``python -m tetherlab.sweep STUDY.toml --out DIR [--scheduler tcp://...]
[--workers N]`` runs a study file (format in :func:`load_study`) and writes ``DIR/<case>.csv``;
all its cases go through one pool (:func:`run_cases`).
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import hashlib
import importlib
import importlib.util
import itertools
import json
import math
import multiprocessing
import os
import sys
import tempfile
import time
import tomllib
import traceback
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

CACHE_FORMAT = 2  # bump when the cache file layout changes (2: a SHA-256 of the record in the record)


# --------------------------------------------------------------------------------------------
# Identities
# --------------------------------------------------------------------------------------------


def scene_hash(scene) -> str:
    """Canonical SHA-256 (hex) of a scene: its ``to_dict()`` as JSON with sorted keys.

    ``Scene`` itself is unhashable (its effect parameters are dicts); ``to_dict`` writes every
    float with ``repr``, so the hash changes with any digit of any value, and two scenes built
    differently (from a file, through ``replace``) but equal have the same hash.
    """
    return _dict_hash(scene.to_dict())


def _dict_hash(scene_dict: dict) -> str:
    text = json.dumps(scene_dict, sort_keys=True, separators=(",", ":"), ensure_ascii=True)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def summary_name(fn: Callable) -> str:
    """``module:qualname`` of a summary function (part of the cache key)."""
    module = getattr(fn, "__module__", None)
    qual = getattr(fn, "__qualname__", None)
    if not module or not qual or "<lambda>" in qual or "<locals>" in qual:
        raise ValueError(
            f"summary must be a module-level function (picklable, with a stable name for the "
            f"cache), got {fn!r}"
        )
    return f"{module}:{qual}"


def resolve(name: str, base_dir: Path | None = None) -> Callable:
    """The callable named ``"package.module:function"`` or ``"file.py:function"``.

    A ``.py`` path is taken relative to ``base_dir`` (the study file's folder).  Summary
    functions must use the first form (workers import them by name); the file form is for hooks
    that run in the calling process (``adjust``).
    """
    if ":" not in name:
        raise ValueError(f"expected 'module:function' or 'file.py:function', got {name!r}")
    mod_name, func = name.rsplit(":", 1)
    if mod_name.endswith(".py"):
        path = Path(mod_name)
        if not path.is_absolute() and base_dir is not None:
            path = base_dir / path
        if not path.is_file():
            raise ValueError(f"hook file {str(path)!r} (from {name!r}) does not exist")
        spec = importlib.util.spec_from_file_location(f"_tetherlab_hook_{path.stem}", path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    else:
        module = importlib.import_module(mod_name)
    try:
        return getattr(module, func)
    except AttributeError:
        raise ValueError(f"{mod_name!r} has no function {func!r} (from {name!r})") from None


# --------------------------------------------------------------------------------------------
# One run
# --------------------------------------------------------------------------------------------


@dataclass
class RunRecord:
    """The outcome of one run of a sweep."""

    scene_hash: str
    label: str  # what the caller called it (e.g. "tethers.main.rods=8"), for tables
    params: dict[str, Any]  # the sweep coordinates of this run (may be empty)
    ok: bool
    summary: dict[str, float] = field(default_factory=dict)
    error: str | None = None  # "ExceptionType: message" when not ok
    wall_s: float = math.nan  # wall time of the run, in the worker
    cached: bool = False  # read from the cache rather than run now
    lost: bool = False  # lost to the machinery (not cached: retried next time)

    def row(self) -> dict[str, Any]:
        """A flat dict for a table: params, summary, then bookkeeping."""
        out: dict[str, Any] = {"label": self.label, **self.params, **self.summary}
        out.update(ok=self.ok, error=self.error or "", wall_s=self.wall_s, scene_hash=self.scene_hash)
        return out


def _as_summary(value: Any, name: str) -> dict[str, float]:
    if not isinstance(value, dict):
        raise TypeError(f"summary function {name} returned {type(value).__name__}, expected a dict of floats")
    out = {}
    for k, v in value.items():
        try:
            out[str(k)] = float(v)
        except (TypeError, ValueError):
            raise TypeError(
                f"summary function {name} returned {k!r} = {v!r}, expected a float"
            ) from None
    return out


def run_one(scene, summary: Callable) -> dict[str, Any]:
    """Run ``summary(scene)`` and catch everything it raises (executed in the worker).

    Returns a plain dict (ok, summary, error, wall_s): it crosses process boundaries.
    """
    name = summary_name(summary)
    t0 = time.perf_counter()
    try:
        values = _as_summary(summary(scene), name)
        return {"ok": True, "summary": values, "error": None, "wall_s": time.perf_counter() - t0}
    except Exception as exc:  # noqa: BLE001 - every failure is recorded, with its message
        text = f"{type(exc).__name__}: {exc}"
        if not str(exc):
            # an exception without a message (a bare bug) still says where it happened
            text += " at " + traceback.format_exc(limit=-1).strip().splitlines()[-2].strip()
        return {"ok": False, "summary": {}, "error": text, "wall_s": time.perf_counter() - t0}


# --------------------------------------------------------------------------------------------
# The cache
# --------------------------------------------------------------------------------------------


def _cache_path(cache_dir: Path, h: str, sname: str) -> Path:
    # The code's digest (every tetherlab source file, as for the numba cache) is part of the key:
    # after any change to the package a sweep recomputes instead of reading stale results.
    from ._jit import CACHE_DIR

    safe = "".join(c if c.isalnum() or c in "._-" else "_" for c in sname)
    return cache_dir / CACHE_DIR.name / f"{h}.{safe}.json"


def _payload_digest(data: dict) -> str:
    """SHA-256 of a cache record without its digest field (canonical JSON: sorted keys; floats
    written by repr, so they read back to the same bits and the digest can be recomputed)."""
    body = {k: v for k, v in data.items() if k != "sha256"}
    return hashlib.sha256(json.dumps(body, sort_keys=True, separators=(",", ":")).encode()).hexdigest()


def _is_number(x: Any) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)


def _read_cache(path: Path, h: str | None = None, sname: str | None = None) -> dict | None:
    """The cached record at ``path``, or None -- to be recomputed -- when it is missing or cannot
    be trusted: not JSON (truncated by a killed writer, or corrupted), another format, a digest
    that does not match its content (a flipped digit), fields of the wrong type, or a record of
    another scene or summary function than the one asked for.  A bad entry is never a result."""
    try:
        data = json.loads(path.read_text())
    except FileNotFoundError:
        return None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError):
        return None
    if not isinstance(data, dict) or data.get("format") != CACHE_FORMAT:
        return None
    if data.get("sha256") != _payload_digest(data):
        return None
    summary = data.get("summary")
    if not (
        isinstance(data.get("ok"), bool)
        and isinstance(summary, dict)
        and all(isinstance(k, str) and _is_number(v) for k, v in summary.items())
        and (data.get("error") is None or isinstance(data.get("error"), str))
        and _is_number(data.get("wall_s"))
        and isinstance(data.get("scene"), dict)
    ):
        return None
    if sname is not None and data.get("summary_function") != sname:
        return None
    if h is not None and _dict_hash(data["scene"]) != h:
        return None
    return data


def _write_cache(path: Path, record: RunRecord, sname: str, scene_dict: dict) -> None:
    data = {
        "format": CACHE_FORMAT,
        "summary_function": sname,
        "ok": record.ok,
        "summary": record.summary,
        "error": record.error,
        "wall_s": record.wall_s,
        "scene": scene_dict,
    }
    data["sha256"] = _payload_digest(data)
    path.parent.mkdir(parents=True, exist_ok=True)
    # A temporary file of its own (two sweeps, or two threads of a Dask worker, may write the
    # same entry at once), then an atomic rename: a reader sees the old file or the whole new one.
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w") as f:
            f.write(json.dumps(data, indent=1, sort_keys=True))
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


# --------------------------------------------------------------------------------------------
# The sweep
# --------------------------------------------------------------------------------------------


@dataclass
class SweepResult:
    records: list[RunRecord]
    n_run: int  # runs executed by this call (successful or not)
    n_cached: int  # runs read from the cache
    wall_s: float

    @property
    def failed(self) -> list[RunRecord]:
        return [r for r in self.records if not r.ok]

    def rows(self) -> list[dict[str, Any]]:
        return [r.row() for r in self.records]

    def frame(self):
        import pandas as pd

        return pd.DataFrame(self.rows())


def _default_workers() -> int:
    return max(1, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1))


def run_sweep(
    scenes: Sequence,
    summary: Callable | Sequence[Callable],
    *,
    cache_dir: str | Path | None = None,
    scheduler: Any = None,
    workers: int | None = None,
    labels: Sequence[str] | None = None,
    params: Sequence[dict] | None = None,
    progress: bool = True,
    retry_failed: bool = False,
    on_record: Callable[[RunRecord], None] | None = None,
    description: str = "sweep",
) -> SweepResult:
    """Run ``summary(scene)`` for every scene; return the records in the order of ``scenes``.

    summary: one module-level function for every scene, or a sequence of them, one per scene (the
        sweeps of several study cases through one pool: :func:`run_cases`).  Runs are started in
        the order of ``scenes``: put the longest first, so that none starts last on an idle pool.
    scheduler: None (a local process pool of ``workers`` processes, default all cores; with
        ``workers=1`` the runs happen in this process, one after the other), a Dask scheduler
        address (``"tcp://host:8786"``, or ``"inproc://..."`` of a ``LocalCluster(processes=
        False)``), or a ``distributed.Client``.
    cache_dir: where finished runs are kept (None: no cache).
    on_record: called in this process with each finished (or cached) record, after it is cached.
    """
    t_start = time.perf_counter()
    scenes = list(scenes)
    if callable(summary):
        summaries = [summary] * len(scenes)
    else:
        summaries = list(summary)
        if len(summaries) != len(scenes):
            raise ValueError(f"summary: expected one function or {len(scenes)} (one per scene), got {len(summaries)}")
    snames = [summary_name(f) for f in summaries]
    if labels is not None and len(labels) != len(scenes):
        raise ValueError(f"labels: expected {len(scenes)} labels (one per scene), got {len(labels)}")
    if params is not None and len(params) != len(scenes):
        raise ValueError(f"params: expected {len(scenes)} dicts (one per scene), got {len(params)}")
    if workers is not None and (not isinstance(workers, int) or workers < 1):
        raise ValueError(f"workers: expected a positive integer, got {workers!r}")
    hashes = [scene_hash(s) for s in scenes]
    labels = list(labels) if labels is not None else [s.name for s in scenes]
    params = [dict(p) for p in params] if params is not None else [{} for _ in scenes]
    cache = Path(cache_dir) if cache_dir is not None else None
    if cache is not None:
        cache.mkdir(parents=True, exist_ok=True)

    records: list[RunRecord | None] = [None] * len(scenes)
    todo: dict[tuple[str, str], list[int]] = {}  # (hash, summary) -> indices (duplicates run once)
    n_cached = 0
    for i, (h, sname) in enumerate(zip(hashes, snames)):
        data = _read_cache(_cache_path(cache, h, sname), h, sname) if cache is not None else None
        if data is not None and (data["ok"] or not retry_failed):
            records[i] = RunRecord(h, labels[i], params[i], bool(data["ok"]), dict(data["summary"]),
                                   data["error"], float(data["wall_s"]), cached=True)
            n_cached += 1
            if on_record is not None:
                on_record(records[i])
        else:
            todo.setdefault((h, sname), []).append(i)

    n_failed = sum(1 for r in records if r is not None and not r.ok)

    def finish(key: tuple[str, str], out: dict, lost: bool = False) -> None:
        nonlocal n_failed
        h, sname = key
        if not out["ok"]:
            n_failed += len(todo[key])
            if bar is not None:  # done and ETA are tqdm's own; the failures are ours
                bar.set_postfix(failed=n_failed, refresh=False)
        for j, i in enumerate(todo[key]):
            rec = RunRecord(h, labels[i], params[i], out["ok"], dict(out["summary"]), out["error"],
                            out["wall_s"], cached=False, lost=lost)
            if j == 0 and cache is not None and not lost:
                _write_cache(_cache_path(cache, h, sname), rec, sname, scenes[i].to_dict())
            records[i] = rec
            if on_record is not None:
                on_record(rec)

    jobs = [(key, scenes[idx[0]], summaries[idx[0]]) for key, idx in todo.items()]
    bar = None
    if progress and jobs:
        from tqdm import tqdm

        bar = tqdm(total=len(scenes), initial=n_cached, desc=description, unit="run", leave=True)
        bar.set_postfix(failed=n_failed, refresh=False)
    try:
        if not jobs:
            pass
        elif scheduler is not None:
            _run_dask(jobs, scheduler, finish, bar)
        elif (workers or _default_workers()) == 1 or len(jobs) == 1:
            for key, scene, fn in jobs:
                finish(key, run_one(scene, fn))
                if bar is not None:
                    bar.update(len(todo[key]))
        else:
            _run_processes(jobs, workers or _default_workers(), finish, bar)
    finally:
        if bar is not None:
            bar.close()
    done = [r for r in records if r is not None]
    return SweepResult(done, n_run=len(jobs), n_cached=n_cached, wall_s=time.perf_counter() - t_start)


def _lost(exc: BaseException) -> dict:
    return {"ok": False, "summary": {}, "error": f"lost: {type(exc).__name__}: {exc}", "wall_s": math.nan}


def _run_processes(jobs, workers, finish, bar) -> None:
    # spawn, not fork: the parent may hold threads (tqdm's monitor, a Dask client) and numba
    # state, neither of which survives a fork safely; children load numba's on-disk cache.
    ctx = multiprocessing.get_context("spawn")
    pool = cf.ProcessPoolExecutor(max_workers=min(workers, len(jobs)), mp_context=ctx)
    futures = {pool.submit(run_one, scene, fn): key for key, scene, fn in jobs}  # started in this order
    try:
        for fut in cf.as_completed(futures):
            key = futures[fut]
            try:
                out, lost = fut.result(), False
            except Exception as exc:  # noqa: BLE001 - a dead worker (BrokenProcessPool), a pickling error
                out, lost = _lost(exc), True
            finish(key, out, lost)
            if bar is not None:
                bar.update(1)
    finally:
        # on an interruption, drop what has not started; finished runs are already cached
        pool.shutdown(wait=True, cancel_futures=True)


def _run_dask(jobs, scheduler, finish, bar) -> None:
    from distributed import Client, as_completed

    own = not isinstance(scheduler, Client)
    client = Client(scheduler) if own else scheduler
    try:
        # pure=False: the same scene twice in one sweep is already merged above; keys stay unique
        futures = {client.submit(run_one, scene, fn, pure=False): key for key, scene, fn in jobs}
        try:
            for fut in as_completed(list(futures)):
                key = futures[fut]
                try:
                    out, lost = fut.result(), False
                except Exception as exc:  # noqa: BLE001 - worker death, lost connection
                    out, lost = _lost(exc), True
                finish(key, out, lost)
                if bar is not None:
                    bar.update(1)
        finally:
            for fut in futures:
                fut.cancel()
    finally:
        if own:
            client.close()


# --------------------------------------------------------------------------------------------
# Study files
# --------------------------------------------------------------------------------------------


def reel_bound_changes(base, changes: dict[str, Any]) -> dict[str, Any]:
    """``changes`` plus, for each reel whose ``rod_length`` it changes, the removal of the birth and
    retirement bounds that ``base`` has at their defaults (1.5 and 0.25 rod lengths,
    tetherlab/scene/reels.py), so that they follow the new rod length.  ``Scene.to_dict`` writes
    every bound as a length, so without this a sweep over the rod length would keep the base's
    bounds: rods of 500 m born at 3 km, not the deployment the user meant.  A bound given
    explicitly (other than the default) or changed in the same point is kept."""
    from .scene.reels import BIRTH_DEFAULT, RETIRE_DEFAULT

    out = dict(changes)
    for key in changes:
        parts = key.split(".")
        if len(parts) != 4 or parts[0] != "tethers" or parts[2:] != ["reel", "rod_length"]:
            continue
        tether = next((t for t in base.tethers if t.name == parts[1] and t.reel is not None), None)
        if tether is None:
            continue
        r = tether.reel
        for name, fraction, value in (("birth_length", BIRTH_DEFAULT, r.birth_length_m),
                                      ("retire_length", RETIRE_DEFAULT, r.retire_length_m)):  # fmt: skip
            bound = f"tethers.{parts[1]}.reel.{name}"
            if bound not in changes and math.isclose(value, fraction * r.rod_length_m, rel_tol=1e-12):
                out[bound] = None
    return out


@dataclass
class StudyCase:
    """One sweep of a study: a base scene, fixed changes, a grid, a summary function."""

    id: str
    scene_path: Path
    summary: str  # "module:function"
    set: dict[str, Any]
    grid: dict[str, list]
    quantities: list[str]
    adjust: str | None = None  # "file.py:function" or "module:function": (base, point) -> more changes
    description: str = ""

    def points(self) -> list[dict[str, Any]]:
        keys = list(self.grid)
        return [dict(zip(keys, values)) for values in itertools.product(*(self.grid[k] for k in keys))]

    def scenes(self, base_dir: Path | None = None) -> tuple[list, list[dict]]:
        from .scene import load_scene

        base = load_scene(self.scene_path)
        if self.set:
            base = base.replace(**reel_bound_changes(base, self.set))
        adjust = resolve(self.adjust, base_dir) if self.adjust else None
        scenes, points = [], self.points()
        for point in points:
            # the hook's changes go into the same replace as the point's: a rod count and the
            # per-rod angles it needs must change together to form a valid scene
            changes = {**point, **(adjust(base, point) if adjust is not None else {})}
            scenes.append(base.replace(**reel_bound_changes(base, changes)) if changes else base)
        return scenes, points


@dataclass
class Study:
    name: str
    path: Path
    cases: list[StudyCase]
    description: str = ""
    options: dict[str, Any] = field(default_factory=dict)


def load_study(path: str | Path) -> Study:
    """Read a study file (TOML)::

        name = "rod-count convergence"
        description = "..."
        [options]                      # free-form, read by the study's own script
        max_rods = 32

        [[case]]
        id = "tension"                                  # names the output table
        scene = "scenes/vertical-equilibrium.toml"      # relative to the study file
        summary = "tetherlab.summaries:attachment_tension"
        quantities = ["root_tension_N"]                 # the summary keys the study is about
        adjust = "convergence.py:first_lateral_shape"   # optional: (base, point) -> dict of changes
        [case.set]                                      # fixed changes, dotted keys
        duration = "0.05 orbits"
        [case.grid]                                     # every combination is one run
        "tethers.main.rods" = [1, 2, 4, 8]

    Errors name the key: ``ValueError("study.toml: case 2 ('lateral'): 'grid' ...")``.
    """
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise FileNotFoundError(f"study file {str(path)!r} does not exist") from None
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{path}: not valid TOML: {exc}") from None
    base = path.parent
    raw_cases = data.get("case")
    if not isinstance(raw_cases, list) or not raw_cases:
        raise ValueError(f"{path}: expected at least one [[case]] table, got {type(raw_cases).__name__}")
    cases = []
    seen = set()
    for k, c in enumerate(raw_cases, 1):
        where = f"{path}: case {k}" + (f" ({c.get('id')!r})" if isinstance(c, dict) and "id" in c else "")
        for key in ("id", "scene", "summary"):
            if not isinstance(c.get(key), str):
                raise ValueError(f"{where}: {key!r} must be a string, got {c.get(key)!r}")
        if c["id"] in seen:
            raise ValueError(f"{where}: duplicate case id {c['id']!r}")
        seen.add(c["id"])
        unknown = set(c) - {"id", "scene", "summary", "set", "grid", "quantities", "adjust", "description"}
        if unknown:
            raise ValueError(f"{where}: unknown keys {sorted(unknown)}")
        grid = c.get("grid", {})
        if not isinstance(grid, dict) or not all(isinstance(v, list) and v for v in grid.values()):
            raise ValueError(f"{where}: 'grid' must map dotted keys to non-empty lists, got {grid!r}")
        scene_path = Path(c["scene"])
        if not scene_path.is_absolute():
            scene_path = base / scene_path
        cases.append(
            StudyCase(
                id=c["id"],
                scene_path=scene_path,
                summary=c["summary"],
                set=dict(c.get("set", {})),
                grid={k2: list(v) for k2, v in grid.items()},
                quantities=list(c.get("quantities", [])),
                adjust=c.get("adjust"),
                description=c.get("description", ""),
            )
        )
    return Study(
        name=str(data.get("name", path.stem)),
        path=path,
        cases=cases,
        description=str(data.get("description", "")),
        options=dict(data.get("options", {})),
    )


def run_case(
    study: Study,
    case: StudyCase,
    out_dir: str | Path,
    *,
    scheduler: Any = None,
    workers: int | None = None,
    progress: bool = True,
    filter_point: Callable[[dict], bool] | None = None,
) -> SweepResult:
    """Run one case of a study, caching under ``out_dir/cache``; writes ``out_dir/<id>.csv``."""
    keep = None if filter_point is None else (lambda c, p: filter_point(p))
    return run_cases(study, [case], out_dir, scheduler=scheduler, workers=workers, progress=progress,
                     filter_point=keep)[case.id]


def run_cases(
    study: Study,
    cases: Sequence[StudyCase] | None,
    out_dir: str | Path,
    *,
    scheduler: Any = None,
    workers: int | None = None,
    progress: bool = True,
    filter_point: Callable[[StudyCase, dict], bool] | None = None,
    first: Callable[[StudyCase, dict], float] | None = None,
) -> dict[str, SweepResult]:
    """Run several cases of a study (None: all) as one sweep through one pool; returns
    ``{case id: SweepResult}`` and writes ``out_dir/<id>.csv`` for each, rows in grid order.

    ``first(case, point)``: a cost estimate; runs are started in decreasing order of it, so the
    longest run of any case starts at once and the others fill the remaining workers (with one
    pool per case, a case's longest run finishes alone while the other workers idle).
    ``filter_point(case, point)``: keep only the points for which it is true.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    cases = list(study.cases if cases is None else cases)
    items = []  # (case index, point index in the case, scene, point)
    for k, case in enumerate(cases):
        scenes, points = case.scenes(study.path.parent)
        for j, (sc, pt) in enumerate(zip(scenes, points)):
            if filter_point is None or filter_point(case, pt):
                items.append((k, j, sc, pt))
    if first is not None:
        items.sort(key=lambda it: -float(first(cases[it[0]], it[3])))  # stable: grid order on ties
    labels = [", ".join(f"{key}={v}" for key, v in it[3].items()) or cases[it[0]].id for it in items]
    res = run_sweep(
        [it[2] for it in items],
        [resolve(cases[it[0]].summary) for it in items],
        cache_dir=out / "cache",
        scheduler=scheduler,
        workers=workers,
        labels=labels,
        params=[it[3] for it in items],
        progress=progress,
        description=study.name if len(cases) > 1 else f"{study.name}: {cases[0].id}",
    )
    results = {}
    for k, case in enumerate(cases):
        mine = sorted(((it[1], rec) for it, rec in zip(items, res.records) if it[0] == k), key=lambda m: m[0])
        recs = [rec for _, rec in mine]
        n_cached = sum(r.cached for r in recs)
        results[case.id] = SweepResult(recs, n_run=len(recs) - n_cached, n_cached=n_cached, wall_s=res.wall_s)
        results[case.id].frame().to_csv(out / f"{case.id}.csv", index=False, float_format="%.17g")
    return results


def main(argv: Iterable[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m tetherlab.sweep", description="Run a study file as sweeps.")
    ap.add_argument("study", help="study file (TOML; see tetherlab.sweep.load_study)")
    ap.add_argument("--out", required=True, help="output directory (tables, and the run cache under cache/)")
    ap.add_argument("--scheduler", help="Dask scheduler address (tcp://host:8786); default: local processes")
    ap.add_argument("--workers", type=int, help="local worker processes (default: all cores)")
    ap.add_argument("--quiet", action="store_true", help="no progress bars")
    args = ap.parse_args(None if argv is None else list(argv))
    study = load_study(args.study)
    n_failed = 0
    results = run_cases(study, None, args.out, scheduler=args.scheduler, workers=args.workers, progress=not args.quiet)
    for case in study.cases:
        res = results[case.id]
        n_failed += len(res.failed)
        print(f"{case.id}: {len(res.records)} runs ({res.n_run} run now, {res.n_cached} cached), "
              f"{len(res.failed)} failed, {res.wall_s:.1f} s -> {Path(args.out) / (case.id + '.csv')}")
        for r in res.failed:
            print(f"  FAILED {r.label}: {r.error}", file=sys.stderr)
    return 1 if n_failed else 0


if __name__ == "__main__":
    sys.exit(main())
