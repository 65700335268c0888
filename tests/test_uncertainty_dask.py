"""An uncertainty study on a real ``distributed`` cluster of this machine (loopback only): a
scheduler and two worker processes; one worker is killed mid-study.  Every sample finishes once,
the results equal the single-process run bit for bit, and the cache holds one valid entry per
sample (docs/uncertainty.md 5)."""

from __future__ import annotations

import json
import os
import signal
import threading
import time
from pathlib import Path

import pytest

from tetherlab.uncertainty.runner import run_study
from tetherlab.uncertainty.study import load_uncertainty_study

ROOT = Path(__file__).resolve().parent.parent
STUDY = ROOT / "studies" / "uncertainty" / "closed_form.toml"
N = 24
SLEEP_S = 0.25  # long enough per sample for the kill to land while samples are still running


def slow_closed_form(scene):
    """The closed form, made to take a while (the worker must die with work in flight)."""
    from tetherlab.uncertainty.summaries import closed_form_decay_days

    time.sleep(SLEEP_S)
    return closed_form_decay_days(scene)


def _study():
    st = load_uncertainty_study(STUDY, samples=N)
    st.summary = "tests.test_uncertainty_dask:slow_closed_form"
    return st


def _entries(out: Path) -> list[Path]:
    return sorted((out / "cache").rglob("*.json"))


@pytest.mark.slow
def test_study_survives_a_killed_worker_and_equals_one_process(tmp_path):
    distributed = pytest.importorskip("distributed")
    serial = run_study(_study(), tmp_path / "serial", workers=1, progress=False, figures=False, n_boot=100)
    assert len(serial.failed) == 0

    out = tmp_path / "dask"
    killed = {}
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None, worker_dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        pids = client.run(os.getpid)
        assert len(pids) == 2

        def killer():
            deadline = time.monotonic() + 60
            while time.monotonic() < deadline:
                if (out / "cache").is_dir() and len(_entries(out)) >= 6:
                    addr, pid = sorted(pids.items())[0]
                    killed["done_before"] = len(_entries(out))
                    os.kill(pid, signal.SIGKILL)
                    killed["pid"] = pid
                    return
                time.sleep(0.02)

        t = threading.Thread(target=killer)
        t.start()
        res = run_study(_study(), out, scheduler=client, progress=False, figures=False, n_boot=100)
        t.join()
        assert "pid" in killed, "the worker was not killed mid-study"
        assert killed["done_before"] < N
        assert set(client.run(os.getpid).values()) - set(pids.values()), "the nanny restarted no worker"

    # every sample finished, exactly once, none lost
    assert len(res.records) == N and not res.failed
    assert not any(r.lost for r in res.records)
    assert len({r.scene_hash for r in res.records}) == N
    # bit for bit against one process
    assert [r.summary for r in res.records] == [r.summary for r in serial.records]
    assert [r.scene_hash for r in res.records] == [r.scene_hash for r in serial.records]
    # the cache: one valid entry per sample, the same content as the serial run's
    from tetherlab.sweep import _read_cache

    entries = _entries(out)
    assert len(entries) == N
    assert not list((out / "cache").rglob("*.tmp"))
    serial_entries = {p.name: p for p in _entries(tmp_path / "serial")}
    for p in entries:
        data = _read_cache(p)
        assert data is not None and data["ok"]
        other = json.loads(serial_entries[p.name].read_text())
        assert data["summary"] == other["summary"] and data["scene"] == other["scene"]
    # and a rerun reads everything back
    again = run_study(_study(), out, workers=1, progress=False, figures=False, n_boot=100)
    assert again.n_run == 0 and again.n_cached == N
