"""A scene with reels written as it goes: ``tetherlab run`` and ``--resume`` across births.

A deployment is a list of phases of a fixed rod count (tetherlab/deployment.py); each birth,
retirement or table knot ends one.  The phase loop is :func:`deployment.run_phases`, the same
loop ``simulate`` runs in memory; here its sink, :class:`DirPhases`, writes each phase as the
run store writes a run of one model (tetherlab/runstore.py: the segment loop, the chunked driver,
``states.npy`` and the Parquet parts) into a folder of its own, because the state length and the
per-rod columns change from phase to phase.  The run directory:

* ``run.json`` -- as for any run, plus ``"reel": true``, ``phases`` (per phase: index, start and
  end time, rods per reel tether, rows, state length, its step statistics) and
  ``changes`` (the births and retirements);
* ``phases/phase-PPPPP/`` -- the phase's ``phase.json`` (written as it starts: index, start time,
  rods per reel tether, state length and named blocks), its ``states.npy`` (rows in that phase's
  layout) and its ``timeseries/`` and ``diagnostics/`` parts, the columns of that phase's ``Result``;
* ``reel/part-PPPPP.parquet`` and ``invariants/part-PPPPP.parquet`` -- the phase's rows of
  ``DeploymentResult.reel`` and ``.invariants`` (the integrated exit energies are added when read
  back: they run over the whole run);
* ``checkpoint.npz`` -- the phase loop's state (keys ``reel_*``: phase, start time and state,
  rods, the rods and lengths the current model was built with, the changes) and, once the phase
  has taken steps, the driver's state inside it (the keys of runstore.py).  One is written at the
  start of every phase (a kill at a birth resumes from the remapped state) and every
  ``checkpoint_s`` of wall time within a phase.

A resumed run rebuilds the phase's model from the stored rods and lengths, re-enters the phase
loop at the stored phase and, inside it, the driver at its checkpoint: the numbers of the run
that was never interrupted, bit for bit, and of ``simulate`` (tests/test_reel_run.py).

Read back as one table (:func:`read_tables`, ``Result.load``): the phases' rows in order, with a
``phase`` column and a ``<tether>.rods`` column per reel tether.  The per-rod columns are those of
each phase's model, numbered from the tether's ``from`` end as in every Result; a column that a
phase does not have (a rod not yet born, or retired) is NaN in that phase's rows.  A phase's
first row repeats the time of its predecessor's last row (the same instant before and after the
remap).  :func:`load` reads the directory as the :class:`DeploymentResult` ``simulate`` returns.
"""

from __future__ import annotations

import json
import shutil
import time
from pathlib import Path

import numpy as np
import pandas as pd

from .runstore import (
    CHECKPOINT, FORMAT, RUN_JSON, TABLES, Clock, Interrupted, RunDirError, _code_digest, _read_json, _Signals, _Store,
    _write_checkpoint, _write_json, driver_restart, regime_warnings, stream_segments, write_last_parts,
)  # fmt: skip

PHASES = "phases"
REEL_TABLES = ("reel", "invariants")
# the per-phase statistics summed into the run's
SUMMED = ("n_accepted", "n_rejected", "n_rhs", "n_jac", "n_lu", "n_events", "n_segments", "compile_s")


def phase_dir(out: Path, ph: int) -> Path:
    return out / PHASES / f"phase-{ph:05d}"


def _part(folder: Path, ph: int) -> Path:
    return folder / f"part-{ph:05d}.parquet"


def _loop_arrays(loop: dict) -> dict:
    """The phase loop's state as checkpoint arrays (floats through JSON keep every bit: repr)."""
    return {
        "reel_phase": loop["phase"], "reel_t_a": loop["t_a"], "reel_y": np.asarray(loop["y"], float),
        "reel_rods": json.dumps(loop["rods"]), "reel_model_rods": json.dumps(loop["model_rods"]),
        "reel_changes": json.dumps(loop["changes"]),
    }  # fmt: skip


def _loop_from(z) -> dict:
    return {
        "phase": int(z["reel_phase"]), "t_a": float(z["reel_t_a"]), "y": z["reel_y"].copy(),
        "rods": json.loads(str(z["reel_rods"])), "model_rods": json.loads(str(z["reel_model_rods"])),
        "changes": json.loads(str(z["reel_changes"])),
    }  # fmt: skip


def _write_frame(path: Path, frame: pd.DataFrame) -> None:
    import os
    import tempfile

    import pyarrow as pa
    import pyarrow.parquet as pq

    from .runstore import _file_mode

    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".part-", suffix=".tmp")
    os.fchmod(fd, _file_mode())
    os.close(fd)
    try:
        pq.write_table(pa.Table.from_pandas(frame, preserve_index=False), tmp)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


class DirPhases:
    """The sink of :func:`deployment.run_phases` that writes a run directory (module docstring)."""

    def __init__(self, out: Path, scene, record: dict, part_rows: int, sig, checkpoint_s: float, clock: Clock,
                 chunks_before: int, resume: dict | None = None, restart: dict | None = None):  # fmt: skip
        self.out, self.scene, self.record = out, scene, record
        self.part_rows = int(part_rows)
        self.sig, self.checkpoint_s, self.clock, self.chunks_before = sig, checkpoint_s, clock, chunks_before
        self.resume = resume
        self.restart = restart  # the driver's state inside the resumed phase (None: the phase starts afresh)
        self.prepare_options = {"outputs_in_memory": False}  # the disk was checked once, for the whole run
        self.loop = None
        self.rows_before = sum(int(ph["rows"]) for ph in record["phases"])

    def _interrupted(self, t: float, rows: int):
        rec = self.record
        rec["state"] = "interrupted"
        rec["message"] = f"interrupted (signal {self.sig.hit}) at t = {t:.9g} s"
        rec["t_s"] = t
        rec["rows_done"] = rows
        _write_json(self.out / RUN_JSON, rec)
        raise Interrupted(self.out, t, float(self.record["t_end_s"]), rows)

    def start_phase(self, loop: dict) -> None:
        self.loop = loop
        if self.restart is not None and loop["phase"] == self.resume["phase"]:
            return  # continuing inside this phase from the driver's checkpoint
        _write_checkpoint(self.out, wall_s=self.clock.wall_s(), n_chunks=self.chunks_before, **_loop_arrays(loop))
        self.clock.last_checkpoint = time.perf_counter()
        if self.sig.hit is not None:  # a signal during the last phase's end: stop at the birth
            self._interrupted(loop["t_a"], self.rows_before)

    def run_phase(self, loop: dict, prep, p, update):
        ph = loop["phase"]
        folder = phase_dir(self.out, ph)
        folder.mkdir(parents=True, exist_ok=True)
        lay = prep.model.state
        # the phase's layout beside its rows, from its start (an interrupted phase reads back too)
        blocks = [[b.name, b.start, b.stop] for b in lay.blocks()]
        _write_json(folder / "phase.json", {"phase": ph, "t_a_s": float(prep.t0_s), "rods": dict(loop["rods"]),
                                            "state_length": int(lay.size), "state_blocks": blocks})  # fmt: skip
        store = _Store(folder, self.scene, prep, self.part_rows)
        store.checkpoint_dir = self.out
        shape = (int(prep.t_out.size), int(prep.model.state.size))
        restart = self.restart if self.restart is not None and ph == self.resume["phase"] else None
        self.restart = None
        if restart is not None:
            states = np.lib.format.open_memmap(folder / "states.npy", mode="r+")
            if states.shape != shape:
                raise RunDirError(f"{str(folder / 'states.npy')!r}: shape {states.shape}, the phase's model rebuilds "
                                  f"to {shape} (rods {loop['rods']})")  # fmt: skip
            store.drop_parts_from(restart["done"] // self.part_rows)  # past the checkpoint: rebuilt
        else:
            states = np.lib.format.open_memmap(folder / "states.npy", mode="w+", dtype=np.float64, shape=shape)
            store.drop_parts_from(0)

        def interrupted(state, done):
            self._interrupted(state["t"], self.rows_before + done)

        res, p = stream_segments(store, states, p, restart, update, self.sig, self.checkpoint_s, self.clock,
                                 self.chunks_before, interrupted, extra=lambda: _loop_arrays(self.loop))  # fmt: skip
        write_last_parts(store, res, p, states)
        return res, p

    def end_phase(self, loop: dict, prep, res, stats: dict, message: str, p, d, reel_parts, inv) -> None:
        from .deployment import rows_frame

        ph = loop["phase"]
        _write_frame(_part(self.out / "reel", ph), rows_frame(reel_parts))
        _write_frame(_part(self.out / "invariants", ph), rows_frame([inv]))
        lay = prep.model.state
        rows = int(len(res.t))
        self.record["phases"] = self.record["phases"][:ph] + [{
            "phase": ph, "t_a_s": float(prep.t0_s), "t_b_s": float(res.t_end), "rods": dict(loop["rods"]),
            "rows": rows, "state_length": int(lay.size),  # (its named blocks: the phase's phase.json)
            "status": int(res.status), "message": message,
            "stats": {k: stats[k] for k in (*SUMMED, "stopped_by", "formulation") if k in stats},
        }]  # fmt: skip
        self.rows_before += rows
        self.record["rows_done"] = self.rows_before
        self.record["t_s"] = float(res.t_end)
        _write_json(self.out / RUN_JSON, self.record)


def _check_method(scene, prep) -> None:
    from .errors import SceneError
    from .integrators.driver import NATIVE_METHODS

    if prep.method not in NATIVE_METHODS:
        raise SceneError("integrator.method", f"one of {', '.join(NATIVE_METHODS)} for a reel scene run with "
                         f"`tetherlab run` (its phases are checkpointed; tetherlab.simulate(scene) runs any method)",
                         repr(prep.method))  # fmt: skip


def run_to_dir(scene, out: Path, *, progress=None, checkpoint_s: float = 5.0, part_rows: int | None = None) -> dict:
    """A reel scene into ``out`` (already checked writable and free); returns the run.json record."""
    from .deployment import check_law
    from .pipeline import prepare
    from .runstore import _part_rows_for

    prep = prepare(scene, outputs_in_memory=False, out_dir=out)  # the disk for the whole run, checked once
    _check_method(scene, prep)
    check_law(scene, float(prep.t_out[-1]))
    for f in (RUN_JSON, CHECKPOINT):
        (out / f).unlink(missing_ok=True)
    for name in (PHASES, *TABLES, *REEL_TABLES, "segments"):
        shutil.rmtree(out / name, ignore_errors=True)
    (out / "states.npy").unlink(missing_ok=True)
    record = {
        "format": FORMAT,
        "state": "running",
        "scene": scene.to_dict(),
        "reel": True,
        "rows": int(prep.t_out.size),
        "t_end_s": float(prep.t_out[-1]),
        "part_rows": int(part_rows) if part_rows else _part_rows_for(scene, int(prep.t_out.size)),
        "code_digest": _code_digest(),
        "resumable": True,
        "segments": 0,
        "phases": [],
        "model": {"effects": prep.model.effect_names, "method": prep.method, "rtol": prep.rtol,
                  "ref_radius_m": prep.ref_radius_m, "ref_period_s": prep.ref_period_s},
    }
    _write_json(out / RUN_JSON, record)
    return _run(scene, out, record, None, None, progress, checkpoint_s)


def resume(scene, out: Path, record: dict, *, progress=None, checkpoint_s: float = 5.0) -> dict:
    """Continue the reel run in ``out`` from its checkpoint (phase loop, and driver inside the phase)."""
    ck = out / CHECKPOINT
    loop = restart = None
    if ck.exists():
        with np.load(ck, allow_pickle=False) as z:
            loop = _loop_from(z)
            restart = driver_restart(z) if "t" in z.files else None
            wall_s, n_chunks = float(z["wall_s"]), int(z["n_chunks"])
    if loop is None:  # killed before its first checkpoint: start it over
        return run_to_dir(scene, out, progress=progress, checkpoint_s=checkpoint_s, part_rows=record["part_rows"])
    ph = loop["phase"]
    # what lies past the checkpoint (phases after it, or the phase itself when it restarts afresh) is redone
    record["phases"] = record["phases"][:ph]
    if (out / PHASES).is_dir():
        for d in (out / PHASES).glob("phase-*"):
            if int(d.name[6:]) > ph or (int(d.name[6:]) == ph and restart is None):
                shutil.rmtree(d)
    for name in REEL_TABLES:
        for f in (out / name).glob("part-*.parquet") if (out / name).is_dir() else ():
            if int(f.name[5:10]) >= ph:
                f.unlink()
    return _run(scene, out, record, loop, restart, progress, checkpoint_s, wall_s, n_chunks)


def _run(scene, out, record, loop, restart, progress, checkpoint_s, wall_before=0.0, chunks_before=0) -> dict:
    from .deployment import run_phases
    from .pipeline import _ProgressBar
    from .result import library_versions

    record["segments"] = int(record.get("segments", 0)) + 1
    record["state"] = "running"
    _write_json(out / RUN_JSON, record)
    clock = Clock(wall_before)
    bar = _ProgressBar(record["t_end_s"], enabled=progress)
    with _Signals() as sig:
        sink = DirPhases(out, scene, record, record["part_rows"], sig, checkpoint_s, clock, chunks_before, loop,
                         restart)  # fmt: skip
        try:
            status, message, stopped, changes = run_phases(scene, sink, progress=bar.update)
        finally:
            bar.close()
    wall_s = clock.wall_s()
    stats: dict = {k: 0 for k in SUMMED}
    for ph in record["phases"]:
        for k in SUMMED:
            stats[k] += ph["stats"].get(k, 0)
    last = record["phases"][-1]["stats"]
    stats.update(stopped_by=stopped, formulation=last.get("formulation"), n_phases=len(record["phases"]),
                 wall_s=wall_s, n_chunks=chunks_before, session_wall_s=time.perf_counter() - clock.start)  # fmt: skip
    record.update(
        state="complete" if status == 0 else "failed", status=int(status), ok=status == 0,
        message=message or ("" if status == 0 else "failed"), stats=stats, changes=changes,
        versions=library_versions(),
        # (no slow-down warning: the progress trace counts each birth's model building and remap)
        warnings=regime_warnings(scene, sorted((out / PHASES).glob("phase-*")), ())
        + missed_birth_warnings(scene, _read_folder(out / "reel") if (out / "reel").is_dir() else pd.DataFrame()),
    )  # fmt: skip
    _write_json(out / RUN_JSON, record)
    (out / CHECKPOINT).unlink(missing_ok=True)
    return record


def missed_birth_warnings(scene, reel: pd.DataFrame) -> list[dict]:
    """A spool law's first rod longer than its birth bound by more than half a rod: a birth the
    run did not take (its event is located only as the rod crosses the bound from below, so a rod
    that starts a phase already past it -- two reels at their bounds at one instant, the other
    one's birth ending the phase -- grows on unnoticed).  The run is still a solution of the
    equations, with longer rods than the scene asks for; the warning says so, with where and when."""
    out = []
    if reel.empty:
        return out
    for t in scene.tethers:
        r = t.reel
        if r is None or r.spool is None:
            continue
        rows = reel[reel["reel"] == t.name]
        if rows.empty:
            continue
        first = rows["deployed_length_m"].to_numpy() - (rows["rods"].to_numpy() - 1) * r.rod_length_m
        bad = np.flatnonzero(first > r.birth_length_m + 0.5 * r.rod_length_m)
        if bad.size:
            j = int(bad[0])
            t_s = float(rows["t_s"].to_numpy()[j])
            out.append({"kind": "missed birth", "t_s": t_s,
                        "text": f"reel {t.name!r}: its first rod is {float(first.max()):.6g} m long at most, past its "
                                f"birth bound ({r.birth_length_m:.6g} m) by more than half a rod from t = {t_s:.6g} s: "
                                f"a birth was not taken there (it started a phase already past the bound), so its rods "
                                f"are longer than tethers.{t.name}.reel.rod_length asks"})  # fmt: skip
    return out


# ----------------------------------------------------------------------------------------------
# reading a reel run back
# ----------------------------------------------------------------------------------------------
def _read_folder(folder: Path) -> pd.DataFrame:
    from .result import _read_parts

    return _read_parts(folder)


def read_phase_tables(out) -> list[tuple[pd.DataFrame, pd.DataFrame]]:
    """Per phase on disk, its (timeseries, diagnostics) as its own Result has them."""
    out = Path(out)
    dirs = sorted((out / PHASES).glob("phase-*")) if (out / PHASES).is_dir() else []
    return [tuple(_read_folder(d / name) for name in TABLES) for d in dirs]


def read_tables(out) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The run's (timeseries, diagnostics) as one table each (module docstring: the phases' rows
    in order, ``phase`` and ``<tether>.rods`` columns, NaN where a phase has no such column)."""
    out = Path(out)
    dirs = sorted((out / PHASES).glob("phase-*")) if (out / PHASES).is_dir() else []
    rods = [_read_json(d / "phase.json")["rods"] for d in dirs]
    tables = ([], [])
    for ph, frames in enumerate(read_phase_tables(out)):
        for acc, frame in zip(tables, frames):
            frame = frame.copy()
            at = 1 if "t_s" in frame.columns else 0
            frame.insert(at, "phase", ph)
            for j, (name, n) in enumerate(rods[ph].items()):
                frame.insert(at + 1 + j, f"{name}.rods", n)
            acc.append(frame)
    return tuple(pd.concat(acc, ignore_index=True) if acc else pd.DataFrame() for acc in tables)


def load(out):
    """A reel run directory as the :class:`~tetherlab.deployment.DeploymentResult` ``simulate``
    returns (an interrupted or failed run with the phases computed so far)."""
    from .deployment import DeploymentResult, integrated_tables
    from .result import Result

    out = Path(out)
    record = _read_json(out / RUN_JSON)
    if not record.get("reel"):
        raise RunDirError(f"{str(out)!r} holds a run without a reel: read it with tetherlab.Result.load")
    phases = []
    for ph, (ts, dg) in zip(record["phases"], read_phase_tables(out)):
        phases.append(Result(ts, dg, ph["stats"], ph["status"], ph["message"], record["scene"], {"phase": ph}))
    reel, inv = (_read_folder(out / name) for name in REEL_TABLES)
    if len(inv):
        integrated_tables(reel, inv)
    status = record.get("status", 0 if record.get("state") == "complete" else -1)
    return DeploymentResult(phases, reel, inv, record.get("changes", []), status, record.get("message", ""),
                            (record.get("stats") or {}).get("stopped_by"))  # fmt: skip
