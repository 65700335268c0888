"""A scene with reels through ``tetherlab run`` (tetherlab/reelstore.py): each phase streamed to
its own folder, checkpoints at births and inside phases, ``--resume`` across births, the run read
back as one table and as the DeploymentResult ``simulate`` returns.

Expected values are identities, not numbers from a model: the run store and ``simulate`` run the
one phase loop (deployment.run_phases) and a resumed run continues the driver and the phase loop
from the exact state they had, so every comparison is ``np.array_equal`` (NaN equal to NaN).
The negative controls break the resume on purpose (the reel's length or its rod count lost) and
check that the comparison, or the resume's own check, catches it.
"""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pandas as pd
import pytest

from tests.helpers import interrupt_at_birth
from tetherlab import deployment, reelstore
from tetherlab.cli import main
from tetherlab.errors import SceneError
from tetherlab.integrators import driver
from tetherlab.result import Result
from tetherlab.runstore import CHECKPOINT, Interrupted, RunDirError, resume_dir, run_to_dir

from .helpers import ROOT, import_study

_REAL_CALL_KERNEL = driver._call_kernel
_STUDY = import_study("deployment")
PART_ROWS = 16

# The verify study's free-space deployment (150 m of 50 m rods paid out at 2 m/s for 120 s, births
# when the first rod reaches 75 m: at 12.5 s, then every 25 s): 5 births, 6 phases; 121 outputs.
SHORT = {"duration": "120 s", "count": 121}


def _scene(**kw):
    return _STUDY.free_scene(**{**SHORT, **kw})


@pytest.fixture
def small_chunks(monkeypatch):
    """Kernel calls of 16 accepted steps: many chunk boundaries (checkpoints) on a short run."""
    monkeypatch.setattr(driver, "_FIRST_CHUNK_STEPS", 16)
    monkeypatch.setattr(driver, "_MAX_CHUNK_GROWTH", 1)


def _same(a: pd.DataFrame, b: pd.DataFrame) -> None:
    assert list(a.columns) == list(b.columns) and len(a) == len(b)
    for c in a.columns:
        x, y = a[c].to_numpy(), b[c].to_numpy()
        numeric = x.dtype.kind in "fiub" and y.dtype.kind in "fiub"
        assert np.array_equal(x, y, equal_nan=numeric), c


def _same_run(a, b) -> None:
    """Two DeploymentResults hold the same numbers: every phase's tables, the reel table, the
    invariants (with the exit energies integrated over the run) and the changes."""
    assert len(a.phases) == len(b.phases)
    for x, y in zip(a.phases, b.phases):
        _same(x.timeseries, y.timeseries)
        _same(x.diagnostics, y.diagnostics)
        assert x.stats["n_accepted"] == y.stats["n_accepted"]
    _same(a.reel, b.reel)
    _same(a.invariants, b.invariants)
    assert a.changes == b.changes and a.stopped_by == b.stopped_by and a.status == b.status


def _states(out):
    return [np.load(d / "states.npy") for d in sorted((out / reelstore.PHASES).glob("phase-*"))]


def _same_dirs(out, ref) -> None:
    _same_run(reelstore.load(out), reelstore.load(ref))
    for a, b in zip(_states(out), _states(ref), strict=True):
        assert np.array_equal(a, b)


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """The uninterrupted run written to a directory, and the same scene in memory."""
    out = tmp_path_factory.mktemp("reel") / "ref"
    rec = run_to_dir(_scene(), out, progress=False, part_rows=PART_ROWS)
    return out, rec, deployment.simulate_reel(_scene())


def test_reel_run_equals_simulate_bit_for_bit(reference):
    out, rec, mem = reference
    assert rec["state"] == "complete" and rec["ok"] and rec["reel"]
    assert [c["change"] for c in rec["changes"]] == ["birth"] * 5
    assert [ph["rods"]["main"] for ph in rec["phases"]] == [3, 4, 5, 6, 7, 8]
    # each phase's layout is recorded with it: 3 more floats of q and of q' per rod
    lengths = [ph["state_length"] for ph in rec["phases"]]
    assert [b - a for a, b in zip(lengths, lengths[1:])] == [6] * 5
    assert not (out / CHECKPOINT).exists()
    assert rec["stats"]["n_accepted"] == sum(ph.stats["n_accepted"] for ph in mem.phases)
    _same_run(reelstore.load(out), mem)
    # the summary's warnings are those of the phases' tables in order (the line pushes from 5.5 s)
    from tetherlab.regime import check_parts

    expected = check_parts(_scene(), [(ph.timeseries, ph.diagnostics) for ph in mem.phases])
    assert [w["text"] for w in rec["warnings"]] == [w["text"] for w in expected]
    assert any("compression" in w["text"] for w in rec["warnings"])


def test_the_run_reads_back_as_one_table(reference):
    """One table: the phases' rows in order, a phase and a rod-count column, per-rod columns of
    rods a phase does not have NaN in its rows (reelstore's docstring states the rule)."""
    out, rec, mem = reference
    back = Result.load(out)
    ts = back.timeseries
    assert len(ts) == sum(len(ph.timeseries) for ph in mem.phases) == rec["rows_done"]
    assert ts["phase"].tolist() == [k for k, ph in enumerate(mem.phases) for _ in range(len(ph.timeseries))]
    assert ts["main.rods"].tolist() == [ph["rods"]["main"] for ph in rec["phases"] for _ in range(ph["rows"])]
    late = [c for c in mem.phases[-1].timeseries.columns if c not in mem.phases[0].timeseries.columns]
    assert late, "the last phase has per-rod columns the first lacks"
    for k, ph in enumerate(mem.phases):
        rows = ts[ts["phase"] == k].reset_index(drop=True)
        # its own columns hold its own values, untouched; the others (rods it lacks) are NaN
        _same(rows[list(ph.timeseries.columns)], ph.timeseries)
        missing = [c for c in ts.columns if c not in ph.timeseries.columns and c not in ("phase", "main.rods")]
        assert rows[missing].isna().all().all()
        assert len(missing) == len(set(ts.columns)) - 2 - len(ph.timeseries.columns)
    assert back.ok and len(back.diagnostics) == len(ts)


def test_plot_of_a_reel_run_draws_its_deployment_and_material_invariants(reference):
    """``tetherlab plot`` on a reel run: the reel's length and rod count, and the invariants of the
    material (stored tether and exit work included) drawn from the run's own invariants table."""
    from tetherlab.plots import _plt, figures

    out, _, mem = reference
    figs = figures(out)
    assert {"deployment.png", "invariants.png", "tension.png"} <= set(figs)
    length = figs["deployment.png"].axes[0].lines[0].get_ydata()
    assert np.array_equal(length, mem.reel["deployed_length_m"].to_numpy())
    energy = figs["invariants.png"].axes[2]
    title = energy.get_title(loc="left")
    assert "exit" in title and "no effect: conserved" in title
    E = mem.invariants["energy_plus_exit_work_J"].to_numpy()
    drawn = energy.lines[0].get_ydata() * float(mem.invariants["kinetic_J"].abs().max())
    assert np.allclose(drawn, E - E[0], rtol=1e-12, atol=0.0)
    for fig in figs.values():
        _plt().close(fig)


def _interrupt_on_call(monkeypatch, k: int, signum=signal.SIGINT):
    """Deliver ``signum`` to this process during the k-th kernel call (as a user's Ctrl-C)."""
    calls = [0]

    def call(*args, **kw):
        calls[0] += 1
        if calls[0] == k:
            signal.raise_signal(signum)
        return _REAL_CALL_KERNEL(*args, **kw)

    monkeypatch.setattr(driver, "_call_kernel", call)


@pytest.mark.parametrize("where", ["mid-phase", "at-birth"])
def test_interrupted_reel_run_resumes_bit_for_bit(tmp_path, monkeypatch, small_chunks, reference, where):
    ref, rec_ref, _ = reference
    out = tmp_path / "o"
    if where == "mid-phase":
        _interrupt_on_call(monkeypatch, 40)  # inside the second phase or later, between two chunks
    else:
        interrupt_at_birth(monkeypatch, 2)
    with pytest.raises(Interrupted) as info:
        run_to_dir(_scene(), out, progress=False, checkpoint_s=1e9, part_rows=PART_ROWS)
    assert f"tetherlab run --resume {out}" in str(info.value)
    run = json.loads((out / "run.json").read_text())
    assert run["state"] == "interrupted" and (out / CHECKPOINT).exists()
    with np.load(out / CHECKPOINT) as z:
        inside = "t" in z.files
        phase = int(z["reel_phase"])
    assert inside == (where == "mid-phase") and phase >= 1
    if where == "at-birth":
        assert phase == 2 and len(run["phases"]) == 2  # stopped with the remapped state, before phase 2
    # what was computed is readable now and is the start of the reference
    partial = Result.load(out).timeseries
    full = Result.load(ref).timeseries
    assert 0 < len(partial) == run["rows_done"] < len(full)
    _same(partial, full.iloc[: len(partial)].reset_index(drop=True)[list(partial.columns)])
    with pytest.raises(RunDirError, match="--resume"):
        run_to_dir(_scene(), out, progress=False)
    monkeypatch.undo()
    rec = resume_dir(out, progress=False)
    assert rec["state"] == "complete" and rec["segments"] == 2
    _same_dirs(out, ref)
    for k in ("n_accepted", "n_rejected", "n_phases"):
        assert rec["stats"][k] == rec_ref["stats"][k], k
    assert not (out / CHECKPOINT).exists()


def _interrupted_mid_phase(tmp_path, monkeypatch):
    out = tmp_path / "o"
    _interrupt_on_call(monkeypatch, 40)
    monkeypatch.setattr(driver, "_FIRST_CHUNK_STEPS", 16)
    monkeypatch.setattr(driver, "_MAX_CHUNK_GROWTH", 1)
    with pytest.raises(Interrupted):
        run_to_dir(_scene(), out, progress=False, checkpoint_s=1e9, part_rows=PART_ROWS)
    monkeypatch.setattr(driver, "_call_kernel", _REAL_CALL_KERNEL)
    return out


def test_a_resume_that_loses_the_reels_length_is_caught(tmp_path, monkeypatch, reference):
    """Negative control: a resume that rebuilds the phase's model with the reel's deployed length
    1 m off the checkpointed one (the reel's state lost or recomputed) runs to the end, and its
    numbers differ from the uninterrupted run's: the bit-for-bit comparison catches it."""
    ref, _, _ = reference
    out = _interrupted_mid_phase(tmp_path, monkeypatch)
    real = reelstore._loop_from

    def lossy(z):
        loop = real(z)
        loop["model_rods"] = {k: [n, length + 1.0] for k, (n, length) in loop["model_rods"].items()}
        return loop

    monkeypatch.setattr(reelstore, "_loop_from", lossy)
    assert resume_dir(out, progress=False)["ok"]
    with pytest.raises(AssertionError):
        _same_dirs(out, ref)


def test_a_resume_with_another_rod_count_is_refused(tmp_path, monkeypatch):
    """Negative control: a resume that loses the rod count (the scene's 3 rods in a later phase)
    is refused by the resume's own check, naming the states file and both shapes."""
    out = _interrupted_mid_phase(tmp_path, monkeypatch)
    real = reelstore._loop_from

    def lossy(z):
        loop = real(z)
        loop["rods"] = {"main": 3}
        loop["model_rods"] = {"main": [3, loop["model_rods"]["main"][1]]}
        return loop

    monkeypatch.setattr(reelstore, "_loop_from", lossy)
    with pytest.raises(RunDirError, match="states.npy.*rebuilds to"):
        resume_dir(out, progress=False)


def test_retrieval_of_the_whole_tether_stops_with_its_outputs_kept(tmp_path):
    scene = _STUDY.free_scene(speed="-2 m/s", length="100 m", duration="48 s", count=49)
    rec = run_to_dir(scene, tmp_path / "o", progress=False, part_rows=PART_ROWS)
    assert rec["ok"] and rec["state"] == "complete" and rec["stats"]["stopped_by"] == "reel.main.retrieved"
    assert "retrieved" in rec["message"] and rec["t_s"] == pytest.approx(43.75)  # tests/test_reel.py: 12.5 m at 2 m/s
    _same_run(reelstore.load(tmp_path / "o"), deployment.simulate_reel(scene, raise_on_failure=False))


def test_a_failed_reel_run_keeps_every_phase_computed(tmp_path):
    """A step budget (per phase) that runs out in the third phase (measured: 161, 409 and 435
    accepted steps in the first three): the run is recorded failed, and the phases before it and
    the rows of the failing one are on disk, equal to simulate's."""
    scene = _scene().replace(**{"integrator.max_steps": 425})
    mem = deployment.simulate_reel(scene, raise_on_failure=False)
    assert not mem.ok and len(mem.phases) == 3
    rec = run_to_dir(scene, tmp_path / "o", progress=False, part_rows=PART_ROWS)
    assert rec["state"] == "failed" and not rec["ok"] and rec["message"] == mem.message
    back = reelstore.load(tmp_path / "o")
    assert not back.ok
    _same_run(back, mem)


def test_cli_runs_and_resumes_a_reel_scene(tmp_path, capsys):
    ref = tmp_path / "ref"
    run_to_dir(_scene(), ref, progress=False, part_rows=PART_ROWS)
    out = tmp_path / "o"
    assert main(["run", str(ref / "run.json"), "--out", str(out), "--part-rows", str(PART_ROWS)]) == 0
    _same_dirs(out, ref)
    said = capsys.readouterr().out
    assert "6 phases: 5 births, 0 retirements" in said and "steps" in said
    assert main(["run", "--resume", str(out)]) == 2  # a finished run: nothing to resume
    assert "nothing to resume" in capsys.readouterr().err


def test_reel_run_with_a_scipy_method_is_refused_naming_the_key(tmp_path):
    with pytest.raises(SceneError) as err:
        run_to_dir(_scene().replace(**{"integrator.method": "DOP853"}), tmp_path / "o", progress=False)
    assert err.value.key == "integrator.method"


# The child process: kernel calls of 16 steps, each slowed by 20 ms, so that the parent can kill it
# mid-run (the slowing changes the wall time, not a number).
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
sys.exit(main(sys.argv[1:]))
"""


@pytest.mark.slow
def test_reel_run_killed_by_sigkill_resumes_identically(tmp_path, reference):
    ref, _, _ = reference
    out = tmp_path / "o"
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.Popen([sys.executable, "-c", _CHILD, "run", str(ref / "run.json"), "--out", str(out), "--quiet",
                             "--checkpoint-every", "0", "--part-rows", str(PART_ROWS)], env=env, cwd=tmp_path,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)  # fmt: skip
    t0 = time.monotonic()
    while time.monotonic() - t0 < 120:  # kill once the run is past its first birth
        if (out / "run.json").exists() and len(json.loads((out / "run.json").read_text()).get("phases", [])) >= 1:
            break
        if proc.poll() is not None:
            pytest.fail(f"the child ended before its first birth: {proc.communicate()[1][-2000:]}")
        time.sleep(0.02)
    time.sleep(0.2)
    proc.kill()
    proc.communicate(timeout=60)
    assert proc.returncode == -signal.SIGKILL
    assert json.loads((out / "run.json").read_text())["state"] == "running" and (out / CHECKPOINT).exists()
    assert main(["run", "--resume", str(out), "--quiet"]) == 0
    _same_dirs(out, ref)
    assert math.isfinite(json.loads((out / "run.json").read_text())["stats"]["wall_s"])


def test_a_reel_run_killed_before_its_first_checkpoint_starts_over(tmp_path, monkeypatch, reference):
    """No checkpoint.npz (a kill before the first was written): --resume runs it from the start,
    to the uninterrupted run's numbers."""
    ref, _, _ = reference
    out = _interrupted_mid_phase(tmp_path, monkeypatch)
    (out / CHECKPOINT).unlink()
    rec = resume_dir(out, progress=False)
    assert rec["state"] == "complete"
    _same_dirs(out, ref)


def test_load_of_a_run_without_a_reel_says_what_to_use(tmp_path):
    out = tmp_path / "o"
    out.mkdir()
    (out / "run.json").write_text(json.dumps({"state": "complete", "phases": []}))
    with pytest.raises(RunDirError, match="Result.load"):
        reelstore.load(out)
