"""The sweep cache under faults (docs/runs.md): a corrupt or truncated entry is recomputed and never
read as a result; two sweeps writing one cache directory at once leave only whole entries.

The summary is the Keplerian period 2 pi sqrt(a^3 / mu) (tests/test_sweep.py::orbit_period): an
analytic value, so a result read from a damaged entry would show as a wrong number."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys

import pytest

from tetherlab.sweep import _cache_path, run_sweep, scene_hash, summary_name

from .helpers import MU_EARTH, ROOT
from .test_sweep import orbit_period, scenes


def _period(a_m: float) -> float:
    return 2 * math.pi * math.sqrt(a_m**3 / MU_EARTH)  # Kepler's third law


def _corrupt_truncated(text, other):
    return text[: len(text) // 2]


def _corrupt_empty(text, other):
    return ""


def _corrupt_digit(text, other):
    # still valid JSON, one digit of the summary changed: only the record's digest can tell
    data = json.loads(text)
    data["summary"]["period_s"] *= 1.0000001
    return json.dumps(data)


def _corrupt_type(text, other):
    data = json.loads(text)
    data["summary"] = "5828.5"
    return json.dumps(data)


def _corrupt_swapped(text, other):
    return other  # a whole, valid record of another scene under this scene's name


def _corrupt_binary(text, other):
    return "\x00\xff" * 50


@pytest.mark.parametrize(
    "corrupt", [_corrupt_truncated, _corrupt_empty, _corrupt_digit, _corrupt_type, _corrupt_swapped, _corrupt_binary]
)
def test_a_damaged_cache_entry_is_recomputed(tmp_path, corrupt):
    sc = scenes((7000, 7100))
    first = run_sweep(sc, orbit_period, cache_dir=tmp_path, workers=1, progress=False)
    assert (first.n_run, first.n_cached) == (2, 0)
    sname = summary_name(orbit_period)
    path = _cache_path(tmp_path, scene_hash(sc[0]), sname)
    other = _cache_path(tmp_path, scene_hash(sc[1]), sname).read_text()
    path.write_bytes(corrupt(path.read_text(), other).encode("utf-8", "surrogatepass"))
    again = run_sweep(sc, orbit_period, cache_dir=tmp_path, workers=1, progress=False)
    assert (again.n_run, again.n_cached) == (1, 1)  # the damaged one only
    assert not again.records[0].cached
    for rec, a in zip(again.records, (7000e3, 7100e3)):
        assert rec.ok and rec.summary["period_s"] == pytest.approx(_period(a), rel=1e-15)
    # and the entry is whole again
    third = run_sweep(sc, orbit_period, cache_dir=tmp_path, workers=1, progress=False)
    assert (third.n_run, third.n_cached) == (0, 2)


_SWEEP = """
import json, sys
from tests.test_sweep import orbit_period, scenes
from tetherlab.sweep import run_sweep
radii = [7000 + k for k in range(int(sys.argv[2]))]
res = run_sweep(scenes(radii), orbit_period, cache_dir=sys.argv[1], workers=1, progress=False)
print(json.dumps({"periods": [r.summary["period_s"] for r in res.records], "n_run": res.n_run}))
"""


def test_two_sweeps_share_one_cache_directory_at_once(tmp_path):
    # Two processes run the same 150 scenes in the same order, so they write (os.replace) and
    # read the same entries at the same moments.
    n = 150
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    procs = [
        subprocess.Popen([sys.executable, "-c", _SWEEP, str(tmp_path), str(n)], cwd=ROOT, env=env,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)  # fmt: skip
        for _ in range(2)
    ]
    outs = [p.communicate(timeout=300) for p in procs]
    radii_m = [(7000 + k) * 1e3 for k in range(n)]
    for p, (out, err) in zip(procs, outs):
        assert p.returncode == 0, err[-3000:]
        periods = json.loads(out.strip().splitlines()[-1])["periods"]
        assert periods == pytest.approx([_period(a) for a in radii_m], rel=1e-15)
    files = list(tmp_path.rglob("*"))
    assert not [f for f in files if f.name.endswith(".tmp")]  # no temporary file left behind
    # every entry is whole: a third sweep reads all of them and runs nothing
    third = run_sweep(scenes([7000 + k for k in range(n)]), orbit_period, cache_dir=tmp_path, workers=1,
                      progress=False)  # fmt: skip
    assert (third.n_run, third.n_cached) == (0, n)
