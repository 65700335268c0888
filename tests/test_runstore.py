"""Runs that lose nothing (docs/runs.md): outputs written as the run goes, checkpoints, resumption
bit for bit, Ctrl-C and kill -9 mid-run, unwritable output directories, a NaN from an effect.

Expected values here are not numbers from a model but identities: a resumed run must reproduce
the uninterrupted run exactly (tetherlab/runstore.py says why), so the tests compare with
``np.array_equal`` (NaN equal to NaN), never with a tolerance.
"""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from tetherlab.cli import main
from tetherlab.errors import SceneError
from tetherlab.integrators import driver
from tetherlab.pipeline import SimulationError, simulate
from tetherlab.result import Result
from tetherlab.runstore import CHECKPOINT, Interrupted, RunDirError, resume_dir, run_to_dir
from tetherlab.scene import Scene, load_scene

from .helpers import ROOT, SCENES

_REAL_CALL_KERNEL = driver._call_kernel

# 0.3 orbits of the in-plane libration with 301 outputs: a few hundred accepted steps, < 1 s.
CHANGES = {"duration": "0.3 orbits", "output.count": 301}
PART_ROWS = 40  # 301 rows -> 8 parts, the last one partial


def _scene(**more):
    return load_scene(SCENES / "libration-inplane.toml").replace(**{**CHANGES, **more})


def _scene_file(tmp_path: Path) -> Path:
    text = (SCENES / "libration-inplane.toml").read_text()
    text = text.replace('duration = "10 orbits"', 'duration = "0.3 orbits"').replace("count = 1001", "count = 301")
    f = tmp_path / "lib.toml"
    f.write_text(text)
    return f


@pytest.fixture
def small_chunks(monkeypatch):
    """Kernel calls of 16 accepted steps each (instead of ~0.5 s of work): many chunk boundaries,
    hence many checkpoints, on a run that lasts a fraction of a second."""
    monkeypatch.setattr(driver, "_FIRST_CHUNK_STEPS", 16)
    monkeypatch.setattr(driver, "_MAX_CHUNK_GROWTH", 1)


def _tables(out: Path):
    return pd.read_parquet(out / "timeseries"), pd.read_parquet(out / "diagnostics")


def _same(a: pd.DataFrame, b: pd.DataFrame) -> None:
    assert list(a.columns) == list(b.columns) and len(a) == len(b)
    for c in a.columns:
        assert np.array_equal(a[c].to_numpy(), b[c].to_numpy(), equal_nan=True), c


def test_streamed_run_equals_simulate_bit_for_bit(tmp_path, small_chunks):
    # Same loop, same steps (the chunking is by accepted steps, which the kernels continue
    # exactly): the Parquet dataset holds the very numbers simulate() returns.
    scene = _scene()
    rec = run_to_dir(scene, tmp_path / "o", progress=False, checkpoint_s=0.0, part_rows=PART_ROWS)
    assert rec["state"] == "complete" and rec["ok"] and rec["rows_done"] == 301
    assert len(list((tmp_path / "o" / "timeseries").glob("part-*.parquet"))) == math.ceil(301 / PART_ROWS)
    assert not (tmp_path / "o" / CHECKPOINT).exists()  # a finished run needs none
    ref = simulate(scene, progress=False)
    ts, dg = _tables(tmp_path / "o")
    _same(ts, ref.timeseries)
    _same(dg, ref.diagnostics)
    assert rec["stats"]["n_accepted"] == ref.stats["n_accepted"]
    # Result.load reads the run directory back
    back = Result.load(tmp_path / "o")
    assert back.ok and len(back.timeseries) == 301


def _interrupt_on_call(monkeypatch, k: int, signum=signal.SIGINT):
    """Deliver ``signum`` to this process during the k-th kernel call (as a user's Ctrl-C)."""
    calls = [0]
    real = driver._call_kernel

    def call(*args, **kw):
        calls[0] += 1
        if calls[0] == k:
            signal.raise_signal(signum)
        return real(*args, **kw)

    monkeypatch.setattr(driver, "_call_kernel", call)
    return calls


def _slack_scene():
    # a tension-only tether starting 1 % slack: 112 slack/taut events in 0.05 orbits, each a
    # restart of the kernel with a forced side (the event state a checkpoint must carry)
    return load_scene(SCENES / "hard-slack-snap.toml").replace(**{"duration": "0.05 orbits", "output.count": 301})


@pytest.mark.parametrize(
    "case, signum",
    [("dop853", signal.SIGINT), ("dop853", signal.SIGTERM), ("vern9", signal.SIGINT), ("radau5", signal.SIGINT),
     ("slack", signal.SIGINT), ("wheels", signal.SIGINT)],
)  # fmt: skip
def test_interrupted_run_resumes_to_the_same_numbers(tmp_path, monkeypatch, small_chunks, case, signum):
    scene = {"slack": _slack_scene, "wheels": _wheel_limits_scene}.get(case, lambda: _scene(**{"integrator.method": case}))()
    ref = tmp_path / "ref"
    run_to_dir(scene, ref, progress=False, part_rows=PART_ROWS)
    out = tmp_path / "o"
    # checkpoint_s = 1e9: the only checkpoint is the one the signal forces
    _interrupt_on_call(monkeypatch, 6, signum)
    with pytest.raises(Interrupted) as info:
        run_to_dir(scene, out, progress=False, checkpoint_s=1e9, part_rows=PART_ROWS)
    assert f"tetherlab run --resume {out}" in str(info.value)
    run = json.loads((out / "run.json").read_text())
    assert run["state"] == "interrupted" and (out / CHECKPOINT).exists()
    # what was computed is readable now, in row order, and is the start of the reference
    partial, _ = _tables(out)
    assert 0 < len(partial) == run["rows_done"] < 301
    _same(partial, _tables(ref)[0].iloc[: len(partial)].reset_index(drop=True))
    # a new run may not overwrite the unfinished one
    with pytest.raises(RunDirError, match="--resume"):
        run_to_dir(scene, out, progress=False)
    monkeypatch.setattr(driver, "_call_kernel", _REAL_CALL_KERNEL)
    rec = resume_dir(out, progress=False)
    assert rec["state"] == "complete" and rec["segments"] == 2
    for a, b in zip(_tables(out), _tables(ref)):
        _same(a, b)
    assert np.array_equal(np.load(out / "states.npy"), np.load(ref / "states.npy"))
    ref_stats = json.loads((ref / "run.json").read_text())["stats"]
    for k in ("n_accepted", "n_rejected", "n_jac", "n_lu", "events"):
        assert rec["stats"][k] == ref_stats[k], k
    if case == "slack":
        assert len(rec["stats"]["events"]) > 50
    if case == "wheels":
        assert len(rec["stats"]["events"]) == 5


def _wheel_limits_scene():
    # a wheel's torque and speed limits entered and left (5 located events, each locking a branch:
    # the sides a checkpoint must carry) and a torque table's corner (a breakpoint), 301 outputs
    from .test_wheel_scenario import _limits_dict

    d = _limits_dict()
    d["integrator"]["max_step"] = "0.1 s"
    d["output"] = {"count": 301}
    return Scene.from_dict(d)


# The child process: kernel calls of 16 steps, each slowed by 20 ms, so the run lasts a few
# seconds and the parent can signal it mid-way (the slowing changes the wall time, not a number).
_CHILD = """
import sys, time
from tetherlab.integrators import driver
driver._FIRST_CHUNK_STEPS = 16
driver._MAX_CHUNK_GROWTH = 1
real = driver._call_kernel
def slow(*a, **k):
    time.sleep(0.02)
    return real(*a, **k)
driver._call_kernel = slow
from tetherlab.cli import main
from tetherlab.errors import SceneError
sys.exit(main(sys.argv[1:]))
"""


def _child(args, tmp_path):
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    return subprocess.Popen([sys.executable, "-c", _CHILD, *args], env=env, cwd=tmp_path,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)  # fmt: skip


def _wait_for_checkpoint(proc, out: Path, timeout=120.0):
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        if (out / CHECKPOINT).exists() and proc.poll() is None:
            time.sleep(0.3)  # let a few more chunks pass: the kill lands mid-run, not at its start
            return
        if proc.poll() is not None:
            break
        time.sleep(0.05)
    proc.kill()
    pytest.fail(f"the child never checkpointed (rc {proc.returncode}): {proc.communicate()[1][-2000:]}")


@pytest.mark.parametrize("signum", [signal.SIGKILL, signal.SIGINT])
def test_run_killed_mid_way_by_a_signal_resumes_identically(tmp_path, signum):
    scene_file = _scene_file(tmp_path)
    ref = tmp_path / "ref"
    assert main(["run", str(scene_file), "--out", str(ref), "--quiet", "--part-rows", str(PART_ROWS)]) == 0
    out = tmp_path / "o"
    proc = _child(["run", str(scene_file), "--out", str(out), "--quiet", "--checkpoint-every", "0",
                   "--part-rows", str(PART_ROWS)], tmp_path)  # fmt: skip
    _wait_for_checkpoint(proc, out)
    proc.send_signal(signum)
    _, err = proc.communicate(timeout=120)
    run = json.loads((out / "run.json").read_text())
    if signum == signal.SIGKILL:
        assert proc.returncode == -signal.SIGKILL and run["state"] == "running"
    else:
        # Ctrl-C: no traceback, the rows computed saved, the command to continue printed
        assert proc.returncode == 130, err
        assert "Traceback" not in err and f"tetherlab run --resume {out}" in err
        assert run["state"] == "interrupted" and len(pd.read_parquet(out / "timeseries")) == run["rows_done"]
    assert (out / CHECKPOINT).exists()
    assert main(["run", "--resume", str(out), "--quiet"]) == 0
    for a, b in zip(_tables(out), _tables(ref)):
        _same(a, b)
    assert np.array_equal(np.load(out / "states.npy"), np.load(ref / "states.npy"))


def test_unwritable_output_directory_is_refused_before_integrating(tmp_path, capsys, monkeypatch):
    scene_file = _scene_file(tmp_path)
    blocker = tmp_path / "a-file"
    blocker.write_text("not a directory")
    calls = _interrupt_on_call(monkeypatch, 10**9)  # counts kernel calls, never interrupts
    assert main(["run", str(scene_file), "--out", str(blocker / "out"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "cannot write the output directory" in err and str(blocker / "out") in err
    assert calls[0] == 0  # nothing was integrated
    assert blocker.read_text() == "not a directory"
    if os.geteuid() != 0:  # root writes through permission bits
        ro = tmp_path / "ro"
        ro.mkdir()
        ro.chmod(0o500)
        try:
            assert main(["run", str(scene_file), "--out", str(ro), "--quiet"]) == 2
            assert "cannot write the output directory" in capsys.readouterr().err
        finally:
            ro.chmod(0o700)
    assert calls[0] == 0


def _poison_applied_force_after(monkeypatch, t_poison: float):
    """Fault injection: after the first progress report past ``t_poison``, the applied_force
    effect's fx parameter in the run's parameter block becomes NaN, so the effect itself returns
    a NaN force from then on."""
    from tetherlab import pipeline, system
    from tetherlab.model.params import ParamView

    blocks = []
    real_fresh = system.Model.fresh_params

    def fresh(self):
        p = real_fresh(self)
        blocks.append(p)
        return p

    def update(self, t):
        for p in blocks if t > t_poison else ():  # (the diagnostics build blocks of their own)
            for par in ParamView(p).effects_with_code(41):  # forces/applied_force.py CODE
                p[par + 1] = float("nan")

    monkeypatch.setattr(system.Model, "fresh_params", fresh)
    monkeypatch.setattr(pipeline._ProgressBar, "update", update)


def test_an_effect_producing_nan_mid_run_is_named_with_its_time(tmp_path, monkeypatch, small_chunks):
    scene = _scene(**{"effects.applied_force": {"body": 1, "fx": "0.01 N"}})
    t_end = scene.duration_seconds()
    _poison_applied_force_after(monkeypatch, 0.3 * t_end)
    with pytest.raises(SimulationError) as info:
        simulate(scene, progress=False)
    msg = str(info.value)
    assert "'applied_force' returned a non-finite force at t = " in msg and "run stopped at t = " in msg
    res = info.value.result
    t = res.timeseries["t_s"].to_numpy()
    # the NaN struck after the first progress report past 0.3 t_end (a chunk of 16 steps, a few
    # output spacings of t_end/300): every output before it is kept, none after
    t_fail = float(msg.split("returned a non-finite force at t = ")[1].split(" s")[0])
    assert 0.3 * t_end < t_fail < 0.5 * t_end
    assert t_fail - 0.05 * t_end < t[-1] <= t_fail and np.all(np.isfinite(res.timeseries.to_numpy()))
    # the same through `tetherlab run`: recorded as failed, the rows so far in the Parquet dataset
    rec = run_to_dir(scene, tmp_path / "o", progress=False, part_rows=PART_ROWS)
    assert rec["state"] == "failed" and "'applied_force'" in rec["message"]
    ts, _ = _tables(tmp_path / "o")
    assert len(ts) == rec["rows_done"] and ts["t_s"].iloc[-1] > 0.25 * t_end


# -- valid but huge requests -------------------------------------------------------------------
# The machine's memory and free disk are fixed by monkeypatching, so the tests do not depend on
# the machine they run on.  Sizes: the Cowell state of a tether of k rods has n = 6 (1 + k)
# floats (root position, k rod vectors, and their velocities; docs/model.md), 8 bytes each.


def _machine(monkeypatch, memory_gib: float, disk_gib: float = 1e6):
    from tetherlab import resources

    monkeypatch.setattr(resources, "available_memory_bytes", lambda: int(memory_gib * 2**30))
    monkeypatch.setattr(resources, "free_disk_bytes", lambda path: int(disk_gib * 2**30))


def test_huge_output_count_is_refused_naming_the_key(monkeypatch):
    _machine(monkeypatch, 16.0)
    calls = _interrupt_on_call(monkeypatch, 10**9)
    scene = load_scene(SCENES / "libration-inplane.toml").replace(**{"output.count": 200_000_000})
    # the output buffer alone: 2e8 rows x 18 floats x 8 B = 26.8 GiB > 16 GiB available
    with pytest.raises(SceneError) as info:
        simulate(scene, progress=False)
    assert info.value.key == "output.count"
    msg = str(info.value)
    assert "GiB in memory" in msg and "16 GiB available" in msg and "200000000" in msg
    assert calls[0] == 0


def test_huge_rod_count_is_refused_naming_the_tether(monkeypatch):
    _machine(monkeypatch, 4.0)
    scene = load_scene(SCENES / "libration-inplane.toml").replace(**{"tethers.main.rods": 200_000})
    # 1001 rows x 6 (1 + 2e5) floats x 8 B = 8.95 GiB of output buffer > 4 GiB available
    with pytest.raises(SceneError) as info:
        simulate(scene, progress=False)
    assert info.value.key == "tethers.main.rods" and "rods = 200000" in str(info.value)


def test_streamed_run_checks_the_disk_and_cli_reports_it(tmp_path, monkeypatch, capsys):
    _machine(monkeypatch, 64.0, disk_gib=50.0)
    calls = _interrupt_on_call(monkeypatch, 10**9)
    f = tmp_path / "huge.toml"
    f.write_text((SCENES / "libration-inplane.toml").read_text().replace("count = 1001", "count = 200000000"))
    # streamed, the rows need no memory; on disk the states alone are 26.8 GiB and the 29 time-
    # series columns another 2e8 x 29 x 8 B = 43.2 GiB: more than the 50 GiB free
    assert main(["run", str(f), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "'output.count'" in err and "50 GiB free" in err and "Traceback" not in err
    assert calls[0] == 0 and not (tmp_path / "o" / "states.npy").exists()


# -- the other paths through `tetherlab run` ----------------------------------------------------
KEPLER = {
    "name": "kepler-stop",
    "duration": "6000 s",  # the period is 2 pi sqrt(a^3 / mu) = 5828 s
    "central_body": {"name": "earth"},
    "effects": {"central_gravity": {}},
    # perigee radius a (1 - e) = 6930 km, below the stop radius 6378.137 + 571.863 = 6950 km
    "bodies": {"sat": {"mass": "10 kg", "elements": {"a": "7000 km", "e": 0.01, "nu": "90 deg"}}},
    "integrator": {"method": "dop853", "rtol": 1e-10, "atol": 1e-10},
    "output": {"count": 50},
}


def test_a_terminal_stop_row_is_written_like_simulate_writes_it(tmp_path):
    from tetherlab.scene import Scene

    scene = Scene.from_dict({**KEPLER, "stop": {"altitude": "571.863 km"}})
    ref = simulate(scene, progress=False)
    assert ref.stats["stopped_by"] == "stop.altitude"
    rec = run_to_dir(scene, tmp_path / "o", progress=False, part_rows=7)
    assert rec["ok"] and rec["stats"]["stopped_by"] == "stop.altitude"
    ts, dg = _tables(tmp_path / "o")
    _same(ts, ref.timeseries)  # the stop state itself is the last row, in both
    _same(dg, ref.diagnostics)


def test_a_dromo_sigma_radau5_run_is_written_when_it_ends_and_is_not_resumable(tmp_path):
    # the sigma form with RADAU5 finds its outputs by a sigma grid and Newton searches in Python,
    # with no loop state to checkpoint: written at its end, refused by --resume
    from tetherlab.scene import Scene

    integ = {**KEPLER["integrator"], "formulation": "dromo", "method": "radau5"}
    scene = Scene.from_dict({**KEPLER, "integrator": integ})
    rec = run_to_dir(scene, tmp_path / "o", progress=False, part_rows=16)
    assert rec["ok"] and not rec["resumable"] and not (tmp_path / "o" / "states.npy").exists()
    assert rec["stats"]["formulation"] == "dromo-sigma"
    _same(_tables(tmp_path / "o")[0], simulate(scene, progress=False).timeseries)
    with pytest.raises(RunDirError, match="nothing to resume"):
        resume_dir(tmp_path / "o")


def _sigma_scene(method):
    # the sigma form on a J2-perturbed 7000 km orbit, 3 revolutions, 120 outputs: tens of accepted
    # steps (ABM: 64 a revolution) and thousands of right-hand sides (the landing steps)
    from tetherlab.scene import Scene

    return Scene.from_dict({
        **KEPLER, "duration": "17500 s", "effects": {"central_gravity": {}, "j2": {}},
        "integrator": {**KEPLER["integrator"], "formulation": "dromo", "method": method},
        "output": {"count": 120},
    })  # fmt: skip


def _interrupted_sigma_run(tmp_path, monkeypatch, method):
    """(uninterrupted run dir, its record, a run dir interrupted on the clock loop's 5th call),
    with the loop called every 2 accepted steps."""
    from tetherlab.propagation import dromo as drive

    monkeypatch.setattr(drive, "CLOCK_CHUNK_STEPS", 2)
    scene = _sigma_scene(method)
    ref = tmp_path / "ref"
    rec_ref = run_to_dir(scene, ref, progress=False, part_rows=PART_ROWS)
    assert rec_ref["ok"] and rec_ref["resumable"] and rec_ref["stats"]["formulation"] == "dromo-sigma"
    assert rec_ref["stats"]["n_accepted"] > 5 * 2, rec_ref["stats"]  # several chunk boundaries
    mem = simulate(scene, progress=False)
    _same(_tables(ref)[0], mem.timeseries)
    _same(_tables(ref)[1], mem.diagnostics)
    name = "_abm_clock_run" if method == "abm" else "_clock_run"
    real = getattr(drive, name)
    calls = [0]

    def call(*args):
        calls[0] += 1
        if calls[0] == 5:
            signal.raise_signal(signal.SIGINT)
        return real(*args)

    monkeypatch.setattr(drive, name, call)
    out = tmp_path / "o"
    with pytest.raises(Interrupted) as info:
        run_to_dir(scene, out, progress=False, checkpoint_s=1e9, part_rows=PART_ROWS)
    monkeypatch.setattr(drive, name, real)
    assert f"tetherlab run --resume {out}" in str(info.value)
    return ref, rec_ref, out


@pytest.mark.parametrize("method", ["dop853", "vern9", "abm"])
def test_dromo_sigma_streams_and_resumes_bit_for_bit(tmp_path, monkeypatch, method):
    """DROMO's sigma form keeps its own output clock (propagation/dromo.py): its compiled loop is
    called in chunks of CLOCK_CHUNK_STEPS accepted steps, and the store streams the rows and
    checkpoints the loop between calls.  Interrupted on its 5th call and resumed, the run ends
    with the numbers of the uninterrupted run and of simulate(), bit for bit."""
    ref, rec_ref, out = _interrupted_sigma_run(tmp_path, monkeypatch, method)
    run = json.loads((out / "run.json").read_text())
    assert run["state"] == "interrupted" and (out / CHECKPOINT).exists()
    partial, _ = _tables(out)  # written as it went: the start of the reference, readable now
    assert 0 < len(partial) == run["rows_done"] < 120
    _same(partial, _tables(ref)[0].iloc[: len(partial)].reset_index(drop=True))
    rec = resume_dir(out, progress=False)
    assert rec["state"] == "complete" and rec["segments"] == 2
    for a, b in zip(_tables(out), _tables(ref)):
        _same(a, b)
    assert np.array_equal(np.load(out / "states.npy"), np.load(ref / "states.npy"))
    for k in ("n_accepted", "n_rejected", "sigma_end", "search_n_accepted", "time_residual_max_s"):
        assert rec["stats"][k] == rec_ref["stats"][k], k


def test_a_sigma_resume_that_loses_the_step_size_is_caught(tmp_path, monkeypatch):
    # negative control of the comparison above: the same interrupted run, resumed from a
    # checkpoint whose step size is dropped (the method picks its own first step again), does
    # not end with the uninterrupted run's numbers
    from tetherlab import runstore

    ref, _, out = _interrupted_sigma_run(tmp_path, monkeypatch, "dop853")
    real = runstore._sigma_restart

    def lossy(z):
        restart = real(z)
        restart["sigma"]["h"] = 0.0
        return restart

    monkeypatch.setattr(runstore, "_sigma_restart", lossy)
    assert resume_dir(out, progress=False)["state"] == "complete"
    assert not np.array_equal(np.load(out / "states.npy"), np.load(ref / "states.npy"))


def test_resume_refuses_what_it_cannot_continue(tmp_path):
    with pytest.raises(RunDirError, match="not a run directory"):
        resume_dir(tmp_path)
    assert main(["run", "--resume", str(tmp_path), "--quiet"]) == 2


def _interrupt_after_time(monkeypatch, t_s: float, n_more: int = 2, signum=signal.SIGINT):
    """Deliver ``signum`` during the n-th kernel call that starts past ``t_s`` (a later segment)."""
    calls = [0]
    real = driver._call_kernel

    def call(*args, **kw):
        if args[2] > t_s:
            calls[0] += 1
            if calls[0] == n_more:
                signal.raise_signal(signum)
        return real(*args, **kw)

    monkeypatch.setattr(driver, "_call_kernel", call)
    return calls


@pytest.mark.parametrize("form", ["cowell-orbit", "dromo-time"])
def test_segmented_formulations_resume_bit_for_bit(tmp_path, monkeypatch, small_chunks, form):
    """The one segment loop streams and resumes every formulation with a time-stepping driver: a
    cowell-orbit run re-anchored every 0.1 periods (3 segments) interrupted in its second
    segment, and a DROMO time-form run, continue to the numbers of the uninterrupted run and of
    simulate()."""
    from tetherlab import pipeline

    monkeypatch.setattr(pipeline, "ANCHOR_ORBITS", 0.1)
    scene = _scene(**{"integrator.formulation": form})
    ref = tmp_path / "ref"
    rec_ref = run_to_dir(scene, ref, progress=False, part_rows=PART_ROWS)
    assert rec_ref["ok"] and rec_ref["resumable"] and rec_ref["stats"]["formulation"] == form
    if form == "cowell-orbit":
        anchors = rec_ref["stats"]["frame_anchors"]
        assert len(anchors) == 3
        _interrupt_after_time(monkeypatch, anchors[1][0])
    else:
        _interrupt_on_call(monkeypatch, 6)
    out = tmp_path / "o"
    with pytest.raises(Interrupted):
        run_to_dir(scene, out, progress=False, checkpoint_s=1e9, part_rows=PART_ROWS)
    run = json.loads((out / "run.json").read_text())
    assert run["state"] == "interrupted" and (out / CHECKPOINT).exists()
    # the rows computed are final and readable: cowell-orbit's first segment, and DROMO's time form
    # (one segment) row by row as its kernel calls complete them
    partial, _ = _tables(out)
    assert 0 < len(partial) == run["rows_done"] < 301
    _same(partial, _tables(ref)[0].iloc[: len(partial)].reset_index(drop=True))
    monkeypatch.setattr(driver, "_call_kernel", _REAL_CALL_KERNEL)
    rec = resume_dir(out, progress=False)
    assert rec["state"] == "complete" and rec["segments"] == 2
    for a, b in zip(_tables(out), _tables(ref)):
        _same(a, b)
    assert np.array_equal(np.load(out / "states.npy"), np.load(ref / "states.npy"))
    for k in ("n_accepted", "n_rejected", "n_segments", "frame_anchors", "events"):
        assert rec["stats"].get(k) == rec_ref["stats"].get(k), k
    mem = simulate(scene, progress=False)
    _same(_tables(out)[0], mem.timeseries)
    _same(_tables(out)[1], mem.diagnostics)
