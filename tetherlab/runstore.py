"""Runs that write as they go and can be continued: ``tetherlab run --out DIR`` / ``--resume DIR``.

A run directory holds

* ``run.json`` -- the scene (whole), the run's state (``running``, ``interrupted``, ``complete``,
  ``failed``), its message, statistics, library versions and the layout below;
* ``states.npy`` -- the integrator's output buffer itself, a memory-mapped ``(outputs, n)`` file
  (numpy ``.npy``): the kernel writes each output row straight into it, so outputs never have to
  fit in memory and every row written is on disk (in the page cache) as soon as it is computed;
* ``timeseries/part-NNNNNN.parquet`` and ``diagnostics/part-NNNNNN.parquet`` -- the same columns
  as ``Result.timeseries``/``Result.diagnostics``, as a Parquet dataset (pyarrow): part k holds
  output rows ``[k B, (k+1) B)`` with B = ``part_rows`` fixed in ``run.json`` when the run starts
  (``pandas.read_parquet(DIR / "timeseries")`` reads it whole);
* ``checkpoint.npz`` -- everything the integration loop carries from one kernel call to the next
  (tetherlab/integrators/driver.py ``_loop_state``): time, state vector, next step size, the
  event state, RADAU5's workspace, the step statistics, the located events, the remaining step
  budget, and the whole parameter block ``p`` (effect evaluation counters, failure header, the
  kernel's scratch).  Written every ``checkpoint_s`` seconds of wall time, atomically (temporary
  file + ``os.replace``), after the state rows it covers are flushed.

What is identical, and why.  The driver calls the compiled kernel in chunks of accepted steps;
each call returns right after an accepted step, and a call that starts from the returned
(t, y, h, p, event state, RADAU5 workspace) takes exactly the steps one long call would have
taken (the only other thing the kernels carry between steps is f(t, y), recomputed from the same
numbers).  A checkpoint is such a between-chunks state, so a run continued from it takes the same
steps and writes the same output rows, bit for bit, as the run that was never interrupted -- and
as ``simulate()``, which uses the same loop.  The derived columns of a part are computed from
that part's rows only (plus the first row, the reference of the relative errors), and parts have
fixed row ranges, so the Parquet files hold the same numbers too.  Not identical: wall times, the
number of chunks, and ``n_rhs`` with the effect evaluation counters (each kernel call evaluates
f(t, y) once more at its start, and chunk sizes follow the measured speed of the machine).

Ctrl-C (SIGINT) or SIGTERM: the signal only sets a flag; after the kernel call in progress
returns (about half a second), the state is checkpointed, the rows computed are written as
Parquet, ``run.json`` says ``interrupted``, and :class:`Interrupted` tells the caller (the CLI
prints how to resume).  A SIGKILL leaves the last checkpoint: the run continues from there.

Every formulation but DROMO's sigma form runs through the one segment loop
(tetherlab/pipeline.py ``run_segments``): a run is a list of segments (cowell-orbit re-anchors its
frame every ANCHOR_ORBITS periods; Cowell and DROMO's time form are one segment), each with its own
state layout.  Cowell rows go straight into ``states.npy``; another formulation's rows go into
``segments/seg-KKKKK.npy`` (its own state, ``(rows of the segment, its state length)``) and are
turned into Cowell rows of ``states.npy`` when the segment ends, so ``states.npy`` and the
Parquet parts are one Cowell table whatever the formulation (parts are written as their rows are
final: per chunk for Cowell and for DROMO's time form, whose rows turn into Cowell rows one by one
(``SegmentPlan.rowwise``: they are converted after every chunk, the same bits as at the end), per
segment for cowell-orbit).  The checkpoint adds the loop's own state
(segment index, its start time and Cowell start state, the rows before it, the step budget, the
summed statistics, the events, the frame anchors): a resumed run re-enters the same segment with
the same anchor and continues the driver from its checkpoint, so it is identical across segments
too.  A run with a native method (dop853, vern9, radau5) is checkpointed.

DROMO's sigma form (a point mass) integrates in sigma, not in time, and finds its output times with
its own clock loop (propagation/dromo.py): with DOP853, Vern9 or ABM that loop is compiled and
called in chunks of a constant number of accepted steps (CLOCK_CHUNK_STEPS).  After each call it
hands the store the output rows it completed (Cowell rows [r, v], straight into ``states.npy``,
full parts written) and its state (sigma, the 8-element state, the step size, the next output, the
step budget, the sigma bound, the step statistics, the whole parameter block, ABM's history); the
checkpoint holds that state (keys ``sigma_*``).  A resumed run restarts the loop from it, which is
what the uninterrupted run does at the same step count: the same rows, bit for bit.  The sigma
form with RADAU5 (a sigma grid and a Newton search per output) and scipy runs write the same files
when they end, and cannot be resumed.
"""

from __future__ import annotations

import json
import math
import os
import signal
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

FORMAT = 1
STATES = "states.npy"
CHECKPOINT = "checkpoint.npz"
SEGMENTS = "segments"  # a formulation's own rows of the running segment (not Cowell's)
RUN_JSON = "run.json"
TABLES = ("timeseries", "diagnostics")


class RunDirError(RuntimeError):
    """The output directory cannot hold the run (unwritable, or holds another unfinished run),
    or a directory to resume is not a resumable run.  Raised before anything is integrated."""


class Interrupted(Exception):
    """The run was stopped by SIGINT/SIGTERM after saving a checkpoint."""

    def __init__(self, out_dir: Path, t: float, t_end: float, rows: int, resumable: bool = True):
        self.out_dir, self.t, self.t_end, self.rows, self.resumable = out_dir, t, t_end, rows, resumable
        if resumable:
            text = (f"interrupted at t = {t:.9g} s of {t_end:.9g} s; {rows} output rows saved in {out_dir}/. "
                    f"Continue with: tetherlab run --resume {out_dir}")  # fmt: skip
        else:
            text = (f"interrupted; this run (a scipy method, or DROMO's sigma form with radau5) keeps no "
                    f"checkpoints, nothing was saved in {out_dir}/: run it again (runs with dop853, vern9 or "
                    f"radau5, and the sigma form with dop853, vern9 or abm, can be resumed)")  # fmt: skip
        super().__init__(text)


# ----------------------------------------------------------------------------------------------
# small file helpers
# ----------------------------------------------------------------------------------------------
def _file_mode() -> int:
    """The mode an ordinary new file gets under the process's umask (0644 under umask 022):
    mkstemp's temporary files are 0600, which would make run.json unreadable to the group while
    the Parquet parts beside it are readable."""
    mask = os.umask(0)
    os.umask(mask)
    return 0o666 & ~mask


def _atomic_write_bytes(path: Path, data: bytes) -> None:
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        os.fchmod(fd, _file_mode())
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def _write_checkpoint(out: Path, **arrays) -> None:
    """The checkpoint written whole or not at all: a temporary file beside it, then one rename."""
    fd, tmp = tempfile.mkstemp(dir=out, prefix=".checkpoint-", suffix=".npz")
    os.close(fd)
    try:
        np.savez(tmp, **arrays)
        os.replace(tmp, out / CHECKPOINT)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def _write_json(path: Path, data: dict) -> None:
    from .result import _json_default

    _atomic_write_bytes(path, json.dumps(data, indent=2, default=_json_default).encode())


def _read_json(path: Path) -> dict:
    return json.loads(path.read_text())


def check_writable(out: Path) -> None:
    """Create ``out`` and prove a file can be written there, else RunDirError (before any run)."""
    try:
        out.mkdir(parents=True, exist_ok=True)
        fd, probe = tempfile.mkstemp(dir=out, prefix=".write-test-")
        os.write(fd, b"x")
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        reason = exc.strerror or type(exc).__name__
        raise RunDirError(
            f"cannot write the output directory {str(out)!r}: {reason}. Nothing was run; choose another --out"
        ) from None


def _part_name(k: int) -> str:
    return f"part-{k:06d}.parquet"


# ----------------------------------------------------------------------------------------------
# the store
# ----------------------------------------------------------------------------------------------
class _Store:
    def __init__(self, out: Path, scene, prep, part_rows: int):
        self.out = out
        self.checkpoint_dir = out  # a reel run's phases share the run's one checkpoint
        self.scene = scene
        self.prep = prep
        self.part_rows = int(part_rows)
        self.m = int(prep.t_out.size)
        self.n = int(prep.model.state.size)
        # the located events so far (the wheel limits' branches the diagnostics evaluate with)
        self.events: list = []

    # -- derived tables ------------------------------------------------------------------------
    def write_part(self, k: int, t: np.ndarray, Y: np.ndarray, p: np.ndarray, first: np.ndarray | None) -> None:
        """Part k from output rows (t, Y); ``first`` is the state at t_out[0] (the reference of
        the relative-error columns) when the part does not start with it."""
        import pyarrow as pa
        import pyarrow.parquet as pq

        from . import diagnostics as diag
        from .result import Result

        if first is not None:
            t = np.concatenate([[self.prep.t_out[0]], t])
            Y = np.concatenate([first[None, :], Y])
        Y = np.asarray(Y)
        from .pipeline import branch_spans

        d = diag.compute(self.prep.model, t, Y, branch_spans(self.prep, self.events))
        r = Result.from_run(self.scene, self.prep, t, Y, d, {}, 0, "", p)
        for name, frame in zip(TABLES, (r.timeseries, r.diagnostics)):
            if first is not None:
                frame = frame.iloc[1:]
            table = pa.Table.from_pandas(frame, preserve_index=False)
            folder = self.out / name
            folder.mkdir(exist_ok=True)
            fd, tmp = tempfile.mkstemp(dir=folder, prefix=".part-", suffix=".tmp")
            os.fchmod(fd, _file_mode())  # pyarrow writes into the file mkstemp made 0600
            os.close(fd)
            try:
                pq.write_table(table, tmp)
                os.replace(tmp, folder / _part_name(k))
            except BaseException:
                if os.path.exists(tmp):
                    os.unlink(tmp)
                raise

    def parts_present(self) -> set[int]:
        have = None
        for name in TABLES:
            ks = {int(f.name[5:11]) for f in (self.out / name).glob("part-*.parquet")} if (self.out / name).is_dir() else set()
            have = ks if have is None else have & ks
        return have or set()

    def drop_parts_from(self, k0: int) -> None:
        for name in TABLES:
            folder = self.out / name
            if folder.is_dir():
                for f in folder.glob("part-*.parquet"):
                    if int(f.name[5:11]) >= k0:
                        f.unlink()

    def write_full_parts(self, states, done: int, p: np.ndarray, have: set[int]) -> None:
        """Every part whose rows are all computed and that is not on disk yet."""
        B = self.part_rows
        for k in range(done // B):
            if k in have:
                continue
            a, b = k * B, (k + 1) * B
            self.write_part(k, self.prep.t_out[a:b], states[a:b], p, None if a == 0 else states[0])
            have.add(k)


# ----------------------------------------------------------------------------------------------
# running
# ----------------------------------------------------------------------------------------------
def _streamable(prep) -> bool:
    from .integrators.driver import NATIVE_METHODS

    if prep.formulation == "dromo-sigma":
        from .propagation.dromo import CLOCK_METHODS

        return prep.method in CLOCK_METHODS
    return prep.method in NATIVE_METHODS


def _part_rows_for(scene, m: int) -> int:
    from .resources import STREAM_BATCH_BYTES, estimate

    need = estimate(scene)
    per = need.row_bytes_memory if need is not None else 8 * 64
    return int(max(1, min(m, STREAM_BATCH_BYTES // max(per, 1))))


def _code_digest() -> str:
    from ._jit import CACHE_DIR

    return CACHE_DIR.name


def run_to_dir(scene, out_dir, *, progress=None, checkpoint_s: float = 5.0, part_rows: int | None = None,
               overwrite_unfinished: bool = False):  # fmt: skip
    """Integrate ``scene`` writing into ``out_dir`` as it goes; returns the run.json record.

    Raises RunDirError (before integrating) when ``out_dir`` cannot be written or holds an
    unfinished run, SceneError for a bad or too large scene, :class:`Interrupted` on SIGINT or
    SIGTERM.  A run that fails is recorded (``state = "failed"``, every output so far kept) and
    returned with ``ok`` false: the caller decides how to report it.
    """
    from .pipeline import prepare

    out = Path(out_dir)
    old = out / RUN_JSON
    if old.exists() and not overwrite_unfinished:
        try:
            state = _read_json(old).get("state")
        except (OSError, ValueError):
            state = None
        if state in ("running", "interrupted"):
            raise RunDirError(
                f"{str(out)!r} holds an unfinished run (state {state!r}); continue it with "
                f"`tetherlab run --resume {out}`, or choose another --out"
            )
    check_writable(out)
    if any(t.reel is not None for t in scene.tethers):  # phases of changing rod counts (reelstore.py)
        from . import reelstore

        return reelstore.run_to_dir(scene, out, progress=progress, checkpoint_s=checkpoint_s, part_rows=part_rows)
    prep = prepare(scene, outputs_in_memory=False, out_dir=out)
    if not _streamable(prep):  # integrated in memory, written at the end
        from .resources import check_scene

        check_scene(scene, outputs_in_memory=True)
    for f in (STATES, CHECKPOINT):
        (out / f).unlink(missing_ok=True)
    import shutil

    shutil.rmtree(out / SEGMENTS, ignore_errors=True)
    m = int(prep.t_out.size)
    B = int(part_rows) if part_rows else _part_rows_for(scene, m)
    store = _Store(out, scene, prep, B)
    store.drop_parts_from(0)
    record = {
        "format": FORMAT,
        "state": "running",
        "scene": scene.to_dict(),
        "rows": m,
        "state_length": int(prep.model.state.size),
        # the named blocks of every states.npy row (model/state.py: StateLayout.blocks)
        "state_blocks": [[b.name, b.start, b.stop] for b in prep.model.state.blocks()],
        "part_rows": B,
        "code_digest": _code_digest(),
        "resumable": _streamable(prep),
        "segments": 0,
    }
    _write_json(out / RUN_JSON, record)
    if not _streamable(prep):
        return _run_in_memory(store, record, progress)
    states = np.lib.format.open_memmap(out / STATES, mode="w+", dtype=np.float64, shape=(m, prep.model.state.size))
    return _run_streamed(store, record, states, prep.model.fresh_params(), None, progress, checkpoint_s)


def resume_dir(out_dir, *, progress=None, checkpoint_s: float = 5.0):
    """Continue the run in ``out_dir`` from its last checkpoint (see the module docstring)."""
    from .pipeline import prepare
    from .scene import Scene

    out = Path(out_dir)
    try:
        record = _read_json(out / RUN_JSON)
    except FileNotFoundError:
        raise RunDirError(f"{str(out)!r} is not a run directory (no {RUN_JSON}); start a run with --out") from None
    except (OSError, ValueError) as exc:
        raise RunDirError(f"cannot read {str(out / RUN_JSON)!r}: {exc}") from None
    state = record.get("state")
    if record.get("format") != FORMAT:
        raise RunDirError(f"{str(out)!r}: run directory format {record.get('format')!r}, expected {FORMAT}")
    if state in ("complete", "failed"):
        raise RunDirError(f"{str(out)!r}: nothing to resume, the run is {state} ({record.get('message', '')})")
    if not record.get("resumable"):
        raise RunDirError(f"{str(out)!r}: this run cannot be resumed (scipy methods, and DROMO's sigma form "
                          f"with RADAU5, keep no checkpoints); start it again with --out")  # fmt: skip
    if record.get("code_digest") != _code_digest():
        raise RunDirError(
            f"{str(out)!r} was started by other tetherlab sources (digest {record.get('code_digest')}, these are "
            f"{_code_digest()}): its continuation would not be the same computation; start it again with --out"
        )
    check_writable(out)
    scene = Scene.from_dict(record["scene"])
    if record.get("reel"):
        from . import reelstore

        return reelstore.resume(scene, out, record, progress=progress, checkpoint_s=checkpoint_s)
    prep = prepare(scene, outputs_in_memory=False, out_dir=out)
    m = int(prep.t_out.size)
    if m != record["rows"] or prep.model.state.size != record["state_length"]:
        raise RunDirError(f"{str(out)!r}: the stored scene rebuilds to {m} outputs of {prep.model.state.size} "
                          f"floats, the run has {record['rows']} of {record['state_length']}")  # fmt: skip
    store = _Store(out, scene, prep, record["part_rows"])
    p = prep.model.fresh_params()
    restart = None
    ck = out / CHECKPOINT
    if ck.exists() and (out / STATES).exists():
        with np.load(ck, allow_pickle=False) as z:
            restart = _sigma_restart(z) if "sigma_k" in z.files else driver_restart(z)
        states = np.lib.format.open_memmap(out / STATES, mode="r+")
        if states.shape != (m, prep.model.state.size):
            raise RunDirError(f"{str(out / STATES)!r}: shape {states.shape}, expected {(m, prep.model.state.size)}")
    else:  # killed before its first checkpoint: nothing to continue from, start it over
        states = np.lib.format.open_memmap(out / STATES, mode="w+", dtype=np.float64, shape=(m, prep.model.state.size))
    done = restart["done"] if restart else 0
    # Parts past the checkpoint (written after it, or a partial last part) are rebuilt.
    store.drop_parts_from(done // store.part_rows)
    return _run_streamed(store, record, states, p, restart, progress, checkpoint_s)


def driver_restart(z) -> dict:
    """The segment loop's and the driver's state from a checkpoint (written by
    :func:`stream_segments`), as ``_SegmentStore`` and ``run_segments`` take it."""
    return {
        # the kernel's whole block (the model's, with the formulation's block appended)
        "p_full": z["p"].copy(),
        "t": float(z["t"]), "h": float(z["h"]), "done": int(z["done"]), "budget": int(z["budget"]),
        "y": z["y"].copy(), "stats": z["stats"].copy(), "ev": z["ev"].copy(),
        "ws": [z[f"ws{i}"].copy() for i in range(int(z["n_ws"]))], "resume": bool(z["resume"]),
        "events": [tuple(e) for e in z["events"].tolist()], "sides": z["sides"].tolist(),
        "wall_s": float(z["wall_s"]), "n_chunks": int(z["n_chunks"]),
        # the segment loop's state (pipeline.run_segments) and the driver's rows in it
        "seg_done": int(z["seg_done"]),
        "loop": {
            "k": int(z["seg_k"]), "t_a": float(z["seg_t_a"]), "y_in": z["seg_y_in"].copy(),
            "k_out": int(z["seg_k_out"]), "budget": int(z["seg_budget"]),
            "sums": json.loads(str(z["seg_sums"])),
            "events": [(float(a), int(b), float(c)) for a, b, c in z["seg_events"].tolist()],
            "anchors": json.loads(str(z["seg_anchors"])),
        },
    }  # fmt: skip


class Clock:
    """The wall time of a run over all its sessions (``before``: the sessions before this one) and
    the time of the last checkpoint."""

    def __init__(self, before: float = 0.0):
        self.before = before
        self.start = time.perf_counter()
        self.last_checkpoint = self.start

    def wall_s(self) -> float:
        return self.before + time.perf_counter() - self.start


class _Signals:
    """SIGINT/SIGTERM set a flag while a run is integrating (main thread only)."""

    def __init__(self):
        self.hit = None
        self.saved = {}

    def __enter__(self):
        if threading.current_thread() is threading.main_thread():
            for s in (signal.SIGINT, signal.SIGTERM):
                self.saved[s] = signal.signal(s, self._handler)
        return self

    def _handler(self, signum, frame):
        self.hit = signum

    def __exit__(self, *exc):
        for s, h in self.saved.items():
            signal.signal(s, h)
        return False


def _plain(x):
    """NumPy scalars in the loop's statistics as JSON numbers."""
    return x.item()


class _SegmentStore:
    """The streamed run's side of the segment loop (the ``store`` of pipeline.run_segments)."""

    def __init__(self, store: _Store, states, p, restart, on_chunk, leave=None):
        self.store = store
        # a formulation whose rows turn into Cowell rows one by one (SegmentPlan.rowwise): its rows
        # go into states.npy, and full parts are written, after every chunk, not at the segment's end
        self.leave = leave
        self.converted = 0  # rows of the running segment already in states.npy
        self.states = states
        self.p = p
        self.on_chunk = on_chunk
        self.resume = restart["loop"] if restart else None
        self.restart = restart
        self.direct = store.prep.formulation == "cowell"  # its rows are Cowell rows
        self.have = store.parts_present()
        self.y_out = None
        self.loop = None

    def begin(self, k, seg_t, n, loop, ctx) -> dict:
        """The driver's y_out, checkpoint and restart for segment k (``loop``: the loop's state at
        its start, saved with every checkpoint of the segment)."""
        self.loop = loop
        restart = None
        if self.restart is not None and k == self.resume["k"]:
            restart = dict(self.restart, done=self.restart["seg_done"])
        self.restart = None
        self.seg_t, self.ctx = seg_t, ctx
        # (a resumed segment: the rows before its checkpoint were converted and flushed with it)
        self.converted = restart["seg_done"] if restart is not None else 0
        if self.direct:
            self.y_out = self.states[loop["k_out"] : loop["k_out"] + seg_t.size]
        else:
            folder = self.store.out / SEGMENTS
            folder.mkdir(exist_ok=True)
            path = folder / f"seg-{k:05d}.npy"
            if restart is not None:
                self.y_out = np.lib.format.open_memmap(path, mode="r+")
                if self.y_out.shape != (seg_t.size, n):
                    raise RunDirError(f"{str(path)!r}: shape {self.y_out.shape}, expected {(seg_t.size, n)}")
            else:
                self.y_out = np.lib.format.open_memmap(path, mode="w+", dtype=np.float64, shape=(seg_t.size, n))
        return {"y_out": self.y_out, "checkpoint": self._chunk, "restart": restart}

    def _chunk(self, state):
        # rows final in states.npy: the driver's for Cowell, those converted so far for a row-wise
        # formulation, else those of the segments done
        k_out = self.loop["k_out"]
        if self.direct:
            done = k_out + state["done"]
        elif self.leave is not None:
            b = min(int(state["done"]), self.states.shape[0] - k_out)
            a = self.converted
            if b > a:
                self.states[k_out + a : k_out + b] = self.leave(self.ctx, self.seg_t[a:b], self.y_out[a:b])
                self.converted = b
            done = k_out + self.converted
        else:
            done = k_out
        self.on_chunk(state, done, self.loop, self.y_out)

    def end(self, k, k_out, t, y_rows) -> None:
        """Segment k ended: its Cowell rows into states.npy (from row k_out), full parts written."""
        m = self.states.shape[0]
        rows = min(len(y_rows), m - k_out)
        if not self.direct:
            self.states[k_out : k_out + rows] = y_rows[:rows]
            self.states.flush()
        self.store.write_full_parts(self.states, k_out + rows, self.p, self.have)

    def result(self, res, t, y_end, stats, events):
        import dataclasses

        rows = min(len(t), self.states.shape[0])
        return dataclasses.replace(res, t=t[:rows], y=self.states[:rows], y_end=y_end, stats=stats, events=events)


def stream_segments(store: _Store, states, p, restart, update, sig, checkpoint_s: float, clock: Clock,
                    chunks_before: int, interrupted, extra=None):
    """Run the store's prepared model through the one segment loop, rows into ``states``, full
    Parquet parts as they complete, a checkpoint every ``checkpoint_s`` of wall time and when a
    signal was caught (``sig.hit``), after which ``interrupted(state, done)`` is called and must
    raise.  ``extra()``: more arrays for every checkpoint (a reel run's phase loop).  Returns the
    loop's result and the parameter block the kernels wrote."""
    from .pipeline import run_segments, segment_plan

    prep = store.prep
    out = store.out
    plan = segment_plan(prep, p)
    if restart is not None:
        if restart["p_full"].shape != plan.pe.shape:
            raise RunDirError(f"{str(out / CHECKPOINT)!r}: parameter block of {restart['p_full'].size} floats, "
                              f"the model and its formulation have {plan.pe.size}")  # fmt: skip
        plan.pe[:] = restart["p_full"]
    p = plan.pe  # the block the kernels write (counters, failure records): the one checkpointed
    have = store.parts_present()
    if restart is not None:
        store.events = list(restart["loop"]["events"]) + list(restart["events"])
        store.write_full_parts(states, restart["done"], p, have)  # any a kill left unwritten

    def save_checkpoint(state, done, loop, y_out):
        states.flush()
        y_out.flush()
        arrays = {f"ws{i}": a for i, a in enumerate(state["ws"])}
        ev = np.array(state["events"], dtype=float).reshape(-1, 3)
        _write_checkpoint(
            store.checkpoint_dir, t=state["t"], h=state["h"], done=done, budget=state["budget"], y=state["y"],
            stats=state["stats"], ev=state["ev"], resume=state["resume"], events=ev, p=p,
            sides=np.asarray(state["sides"], float),
            n_ws=len(state["ws"]), wall_s=clock.wall_s(),
            n_chunks=chunks_before, seg_done=state["done"], seg_k=loop["k"], seg_t_a=loop["t_a"],
            seg_y_in=np.asarray(loop["y_in"], float), seg_k_out=loop["k_out"], seg_budget=loop["budget"],
            seg_sums=json.dumps(loop["sums"], default=_plain),
            seg_anchors=json.dumps(loop["anchors"], default=_plain),
            seg_events=np.array(loop["events"], dtype=float).reshape(-1, 3), **arrays, **(extra() if extra else {}),
        )  # fmt: skip
        clock.last_checkpoint = time.perf_counter()

    def on_chunk(state, done, loop, y_out):
        store.events = list(loop["events"]) + list(state["events"])
        store.write_full_parts(states, done, p, have)
        if sig.hit is not None or time.perf_counter() - clock.last_checkpoint >= checkpoint_s:
            save_checkpoint(state, done, loop, y_out)
        if sig.hit is not None:
            k = done // store.part_rows
            a = k * store.part_rows
            if done > a:  # the rows of the unfinished part, readable now, rebuilt on resume
                store.write_part(k, prep.t_out[a:done], states[a:done], p, None if a == 0 else states[0])
            interrupted(state, done)

    seg_store = _SegmentStore(store, states, p, restart, on_chunk, plan.leave if plan.rowwise else None)
    seg_store.have = have
    return run_segments(prep, plan, update, store=seg_store), p


def _run_streamed(store: _Store, record: dict, states, p, restart, progress, checkpoint_s):
    from .pipeline import _ProgressBar

    prep = store.prep
    out = store.out
    if prep.formulation == "dromo-sigma":
        return _run_sigma_streamed(store, record, states, p, restart, progress, checkpoint_s)
    wall_before = restart["wall_s"] if restart else 0.0
    chunks_before = restart["n_chunks"] if restart else 0
    record["segments"] = int(record.get("segments", 0)) + 1
    record["state"] = "running"
    _write_json(out / RUN_JSON, record)
    bar = _ProgressBar(prep.t_out[-1], enabled=progress)
    clock = Clock(wall_before)

    with _Signals() as sig:

        def interrupted(state, done):
            record["state"] = "interrupted"
            record["message"] = f"interrupted (signal {sig.hit}) at t = {state['t']:.9g} s"
            record["t_s"] = state["t"]
            record["rows_done"] = done
            _write_json(out / RUN_JSON, record)
            raise Interrupted(out, state["t"], float(prep.t_out[-1]), done)

        try:
            res, p = stream_segments(store, states, p, restart, bar.update, sig, checkpoint_s, clock, chunks_before,
                                     interrupted)  # fmt: skip
        finally:
            bar.close()
        # (still under the handlers: a signal now, with the integration done, lets it finish)
        return _finish(store, record, res, p, states, clock.wall_s(), chunks_before, session_start=clock.start,
                       trace=bar.trace)  # fmt: skip


def _sigma_restart(z) -> dict:
    """The sigma form's loop state from a checkpoint (propagation/dromo.py CLOCK_STATE_*)."""
    from .propagation.dromo import CLOCK_STATE_ARRAYS, CLOCK_STATE_SCALARS

    loop = {name: z["sigma_" + name].copy() for name in CLOCK_STATE_ARRAYS}
    loop.update({name: z["sigma_" + name].item() for name in CLOCK_STATE_SCALARS})
    return {"sigma": loop, "done": int(z["done"]), "wall_s": float(z["wall_s"]), "n_chunks": int(z["n_chunks"])}


class _SigmaStore:
    """The streamed run's side of DROMO's sigma-form clock loop (the ``store`` of
    propagation/dromo.py integrate_sigma): rows into states.npy, full parts, checkpoints."""

    def __init__(self, states, restart, on_chunk):
        self.states = states
        self.resume = restart["sigma"] if restart else None
        self.on_chunk = on_chunk

    def rows(self, j0, t, Y) -> None:
        self.states[j0 : j0 + len(Y)] = Y

    def chunk(self, state) -> None:
        self.on_chunk(state)

    def table(self, k):
        return self.states[:k]


def _run_sigma_streamed(store: _Store, record: dict, states, p, restart, progress, checkpoint_s):
    """DROMO's sigma form (a point mass, its own output clock in sigma): the clock loop hands its
    rows and its state to the store after every compiled call; rows go to states.npy and full
    Parquet parts, the state to checkpoint.npz (every ``checkpoint_s`` of wall time, and on a
    signal); a resumed run restarts the loop from that state."""
    from .pipeline import _integrate_dromo, _ProgressBar
    from .propagation.dromo import CLOCK_STATE_ARRAYS, CLOCK_STATE_SCALARS

    prep = store.prep
    out = store.out
    have = store.parts_present()
    if restart is not None:
        store.write_full_parts(states, restart["done"], restart["sigma"]["p"], have)  # any a kill left unwritten
    chunks_before = restart["n_chunks"] if restart else 0
    record["segments"] = int(record.get("segments", 0)) + 1
    record["state"] = "running"
    _write_json(out / RUN_JSON, record)
    bar = _ProgressBar(prep.t_out[-1], enabled=progress)
    t_wall = time.perf_counter()
    last_ck = [time.perf_counter()]

    def save_checkpoint(state):
        states.flush()
        arrays = {"sigma_" + name: np.asarray(state[name]) for name in CLOCK_STATE_ARRAYS}
        scalars = {"sigma_" + name: np.asarray(state[name]) for name in CLOCK_STATE_SCALARS}
        _write_checkpoint(out, done=state["k"], wall_s=state["wall_s"], n_chunks=chunks_before, **arrays, **scalars)
        last_ck[0] = time.perf_counter()

    with _Signals() as sig:

        def on_chunk(state):
            done = int(state["k"])
            store.write_full_parts(states, done, state["p"], have)
            if state["ended"]:  # the run is over: it finishes, whatever the signal
                return
            if sig.hit is not None or time.perf_counter() - last_ck[0] >= checkpoint_s:
                save_checkpoint(state)
            if sig.hit is not None:
                k = done // store.part_rows
                a = k * store.part_rows
                if done > a:  # the rows of the unfinished part, readable now, rebuilt on resume
                    store.write_part(k, prep.t_out[a:done], states[a:done], state["p"], None if a == 0 else states[0])
                record["state"] = "interrupted"
                record["message"] = f"interrupted (signal {sig.hit}) at t = {state['t']:.9g} s"
                record["t_s"] = state["t"]
                record["rows_done"] = done
                _write_json(out / RUN_JSON, record)
                raise Interrupted(out, state["t"], float(prep.t_out[-1]), done)

        try:
            res, pe = _integrate_dromo(prep, p, bar.update, store=_SigmaStore(states, restart, on_chunk))
        finally:
            bar.close()
        return _finish(store, record, res, pe, states, float(res.stats["wall_s"]), chunks_before)


def _run_in_memory(store: _Store, record: dict, progress):
    """scipy runs and DROMO's sigma form with RADAU5: integrated in memory, written when they end
    (no checkpoints)."""
    from .pipeline import _ProgressBar, integrate_prepared

    prep = store.prep
    p = prep.model.fresh_params()
    bar = _ProgressBar(prep.t_out[-1], enabled=progress)
    t_wall = time.perf_counter()
    try:
        res, p = integrate_prepared(prep, p, bar.update)
    except KeyboardInterrupt:
        record["state"] = "interrupted"
        record["message"] = ("interrupted; this run keeps no checkpoints (a scipy method, or DROMO's sigma form with "
                             "radau5): "
                             "nothing was saved")
        _write_json(store.out / RUN_JSON, record)
        raise Interrupted(store.out, math.nan, float(prep.t_out[-1]), 0, resumable=False) from None
    finally:
        bar.close()
    return _finish(store, record, res, p, None, time.perf_counter() - t_wall, 0, session_start=t_wall, trace=bar.trace)


def _regime_warnings(store: _Store, trace) -> list[dict]:
    return regime_warnings(store.scene, [store.out], trace)


def regime_warnings(scene, outs, trace) -> list[dict]:
    """The run summary's warnings (tetherlab/regime.py), from the columns they need read back
    from the parts on disk one part at a time (strains, axial forces, libration angles), over the
    run directories ``outs`` in order (a reel run's phases: tetherlab/reelstore.py)."""
    import pyarrow.parquet as pq

    from .regime import check_parts

    def wanted(c: str) -> bool:
        return c == "t_s" or c.endswith((".strain", ".axial_force_N", ".theta_rad", ".phi_rad"))

    def parts():
        for out in outs:
            folders = [out / name for name in TABLES]
            files = [sorted(f.glob("part-*.parquet")) for f in folders]
            for ts_file, dg_file in zip(*files):
                yield tuple(pq.read_table(f, columns=[c for c in pq.read_schema(f).names if wanted(c)]).to_pandas()
                            for f in (ts_file, dg_file))  # fmt: skip

    return check_parts(scene, parts(), trace)


def write_last_parts(store: _Store, res, p, states) -> int:
    """The parts a run's end leaves to write (the last, partial one, and any not on disk); returns
    the number of output rows."""
    rows = int(len(res.t))
    # the driver returns a view of the states file, with a terminal event's stop row in the first
    # unreached row; only a stop after the last output time comes back as a copy in memory
    Y = res.y if (states is None or rows > states.shape[0]) else states
    if states is not None:
        states.flush()
    B = store.part_rows
    have = store.parts_present()
    store.events = list(res.events)
    for k in range(math.ceil(rows / B)):
        a, b = k * B, min((k + 1) * B, rows)
        if k in have and b - a == B:
            continue
        store.write_part(k, res.t[a:b], Y[a:b], p, None if a == 0 else Y[0])
    return rows


def _finish(store: _Store, record: dict, res, p, states, wall_s: float, chunks_before: int,
            session_start: float | None = None, trace=()) -> dict:
    from .pipeline import run_outcome
    from .result import library_versions

    t_finish = time.perf_counter()
    prep = store.prep
    out = store.out
    rows = write_last_parts(store, res, p, states)
    stats, message = run_outcome(prep, res, p, wall_s)
    stats["wall_s"] = wall_s
    stats["n_chunks"] = int(stats.get("n_chunks", 0)) + chunks_before
    record.update(
        state="complete" if res.status == 0 else "failed",
        status=int(res.status),
        ok=res.status == 0,
        message=message,
        stats=stats,
        rows_done=rows,
        t_s=float(res.t_end),
        versions=library_versions(),
        model={
            "rods": [t.rods for t in prep.model.tethers],
            "effects": prep.model.effect_names,
            "method": prep.method,
            "rtol": prep.rtol,
            "ref_radius_m": prep.ref_radius_m,
            "ref_period_s": prep.ref_period_s,
        },
    )
    from .result import _effect_counts

    record["effect_evaluations"] = _effect_counts(p, prep.model)
    record["effect_meta"] = prep.model.effect_meta
    record["warnings"] = _regime_warnings(store, trace)
    # this session's wall time to here, the last parts written (wall_s counts every session of a
    # resumed run and stops before the writing): the command line's times add up with it
    stats["session_wall_s"] = time.perf_counter() - (session_start if session_start is not None else t_finish - wall_s)
    _write_json(out / RUN_JSON, record)
    (out / CHECKPOINT).unlink(missing_ok=True)
    return record
