"""A deployment's per-phase bookkeeping (docs/deployment.md 8d): the rows kept as arrays and
framed once give the table one frame per phase gave; the running exit work by one cumulative sum
is the loop over the rows bit for bit; a phase's Result is built once, at its first read."""

import numpy as np
import pandas as pd

from tetherlab.deployment import _trapezoid_sums, rows_frame
from tetherlab.result import DeferredResult, Result


def _parts():
    rng = np.random.default_rng(7)
    parts = []
    for ph, n in enumerate((3, 1, 4)):
        t = np.cumsum(rng.random(n)) + ph
        for name, rods in (("main", 2 + ph), ("aux", 1)):
            parts.append({"t_s": t, "phase": ph, "reel": name, "rods": rods, "power_W": rng.normal(size=n)})
    return parts


def test_rows_frame_is_the_concatenation_of_one_frame_per_part():
    # expected: what the phase loop built before (pd.concat of pd.DataFrame per part), dtypes included
    parts = _parts()
    expected = pd.concat([pd.DataFrame(p) for p in parts], ignore_index=True)
    got = rows_frame(parts)
    pd.testing.assert_frame_equal(got, expected, check_exact=True)
    assert list(got.dtypes) == list(expected.dtypes)


def test_trapezoid_sums_are_the_row_loop_bit_for_bit():
    # expected: the loop integrated_tables ran over the rows (an interval across phases adds nothing)
    rng = np.random.default_rng(3)
    t = np.concatenate([[0.0, 0.5, 1.25], [1.25, 2.0], [2.0, 2.5, 3.5, 4.0]])
    phase = np.array([0, 0, 0, 1, 1, 2, 2, 2, 2])
    power = rng.normal(size=t.size) * 1e3
    loop = np.zeros(t.size)
    acc = 0.0
    for j in range(1, t.size):
        if phase[j] == phase[j - 1]:
            acc += 0.5 * (power[j] + power[j - 1]) * (t[j] - t[j - 1])
        loop[j] = acc
    got = _trapezoid_sums(t, power, phase)
    assert got.view(np.uint64).tolist() == loop.view(np.uint64).tolist()
    assert _trapezoid_sums(np.zeros(0), np.zeros(0), np.zeros(0, int)).size == 0


def test_deferred_result_builds_once_at_the_first_read():
    calls = []
    ts = pd.DataFrame({"t_s": [0.0, 1.0]})

    def build():
        calls.append(1)
        return Result(ts, pd.DataFrame({"t_s": [0.0, 1.0]}), {}, 0, "", {"name": "x"}, {"model": {}})

    r = DeferredResult(build, {"n_accepted": 5}, 0, "")
    assert r.ok and r.stats["n_accepted"] == 5 and not calls  # the statistics need no table
    assert r.timeseries is ts and r.scene_dict == {"name": "x"} and r.meta == {"model": {}}
    _ = r.diagnostics
    assert len(calls) == 1
