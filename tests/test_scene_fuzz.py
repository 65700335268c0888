"""Property test: every scene, valid or not, either is refused with a SceneError that
names a key, or runs to completion with finite outputs, or stops with a SimulationError that says
when (a time), and why -- no other exception type, ever.

Scenes are generated from small valid templates (a Kepler orbit, two masses on a tether in free
space, an orbiting tether, hub and spoke) and from random topologies of bodies and tethers, then
damaged: keys removed, values replaced by wrong units, negative, zero, huge or non-finite values,
NaN strings, wrong types.  Runs are kept tiny: durations of seconds to minutes, few outputs, at
most 3000 accepted steps (a longer run stops with max_steps, itself a SimulationError).  The
machine is declared to have 2 GiB of memory (tetherlab/resources.py), so a request for 1e12 rods
or outputs is refused the same way on every machine.
"""

from __future__ import annotations

import copy
import math
import re

import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from tetherlab import resources
from tetherlab.errors import SceneError
from tetherlab.pipeline import SimulationError, simulate
from tetherlab.scene import Scene

MAX_STEPS = 3000
MAX_OUTPUTS = 200

KEPLER = {
    "name": "fuzz-kepler",
    "duration": "120 s",
    "central_body": {"name": "earth"},
    "effects": {"central_gravity": {}},
    "bodies": {"sat": {"mass": "10 kg", "elements": {"a": "7000 km", "e": 0.01, "i": "10 deg"}}},
    "integrator": {"method": "dop853", "rtol": 1e-9, "atol": 1e-9},
    "output": {"count": 5},
}
FREE_PAIR = {
    "name": "fuzz-pair",
    "duration": "5 s",
    "effects": {},
    "bodies": {
        "a": {"mass": "10 kg", "position": ["0 m", "0 m", "0 m"], "velocity": ["0 m/s", "0 m/s", "0 m/s"]},
        "b": {"mass": "5 kg", "position": ["101 m", "0 m", "0 m"], "velocity": ["0 m/s", "1 m/s", "0 m/s"]},
    },
    "tethers": {"t": {"from": "a", "to": "b", "rods": 2, "length": "100 m", "EA": "1e3 N", "mass": "1 kg"}},
    "integrator": {"method": "dop853", "rtol": 1e-8, "atol": 1e-8},
    "output": {"step": "1 s"},
}
ORBITING = {
    "name": "fuzz-orbiting",
    "duration": "30 s",
    "central_body": {"name": "earth"},
    "effects": {"central_gravity": {}},
    "bodies": {"m0": {"mass": "1000 kg"}, "mf": {"mass": "100 kg"}},
    "orbit": {"reference": "center_of_mass", "elements": {"a": "7400 km", "e": 0.0}, "motion": "corotating"},
    "tethers": {
        "main": {
            "from": "m0", "to": "mf", "rods": 2, "length": "5 km", "EA": "5e4 N", "mass": "10 kg",
            "initial": {"shape": "straight", "theta": "30 deg", "phi": "0 deg", "side": "up"},
        }
    },
    "integrator": {"method": "dop853", "rtol": 1e-9, "atol": 1e-9},
    "output": {"count": 4},
}  # fmt: skip
HUB = {
    "name": "fuzz-hub",
    "duration": "3 s",
    "effects": {},
    "bodies": {
        "hub": {"mass": "100 kg", "position": ["0 m", "0 m", "0 m"], "velocity": ["0 m/s", "0 m/s", "0 m/s"]},
        "s1": {"mass": "1 kg", "position": ["50 m", "0 m", "0 m"], "velocity": ["0 m/s", "2 m/s", "0 m/s"]},
        "s2": {"mass": "1 kg", "position": ["-50 m", "0 m", "0 m"], "velocity": ["0 m/s", "-2 m/s", "0 m/s"]},
    },
    "tethers": {
        "k1": {"from": "hub", "to": "s1", "rods": 1, "length": "49.9 m", "EA": "2e3 N", "mass": "0.2 kg"},
        "k2": {"from": "hub", "to": "s2", "rods": 1, "length": "49.9 m", "EA": "2e3 N", "mass": "0.2 kg",
               "tension_only": True},
    },
    "integrator": {"method": "dop853", "rtol": 1e-8, "atol": 1e-8},
    "output": {"count": 4},
}  # fmt: skip
TEMPLATES = [KEPLER, FREE_PAIR, ORBITING, HUB]

# Values that do not belong where they are put: wrong units, signs, magnitudes, types.
BAD_VALUES = [
    "-5 m", "5 kg", "5 N s", "0 m", "0 kg", "0 s", "-1 s", "nan m", "NaN", "nan", "inf s", "-inf N",
    "1e300 m", "1e300 kg", "1e300 N", "1e300 s", "-1e300 m", "1e-300 m", "1e-300 kg", "", "abc",
    "1 orbits", "3 deg", "2 rad", "7000 km", "5e4 N", "1 m/s", -1, 0, 1, 2, 0.5, -0.5, 1e300, -1e300,
    float("nan"), float("inf"), 10**12, -(10**12), True, False, [], {}, [1, 2], ["1 m", "2 m"],
    ["1 m", "2 m", "x"], {"a": "1 m"}, None, "radau5", "vern9", "scipy:DOP853", "dromo", "equilibrium",
    "down", "center_of_mass", "m0", "a", "hub",
]  # fmt: skip
NAMES = ["a", "b", "c", "d"]
EXTRA_EFFECTS = [
    ("j2", {"J2": 1.08e-3, "radius": "6378 km"}),
    ("zonal", {"J2": 1.08e-3, "J3": -2.5e-6, "J4": -1.6e-6}),
    ("moon_de421", {"mu": "4.9e12 m3/s2"}),
    ("sun_de421", {}),
    ("stiefel_moon", {"mu": "4.9e12 m3/s2", "orbit_radius": "384400 km", "rate": "2.66e-6 rad/s"}),
    ("uniform_gravity", {"g": "9.81 m/s2"}),
    ("applied_force", {"body": 1, "fx": "0.1 N", "fy": "0 N", "fz": "0 N"}),
    ("drag", {"area": "1 m2", "cd": 2.2, "tether_cd": 2.2}),
    ("electrodynamic", {"current": "1 A", "field": "aligned"}),
    ("no_such_effect", {}),
]


def _paths(d, prefix=()):
    """Every key path of a nested dict (inner tables and leaves)."""
    out = []
    for k, v in d.items():
        out.append(prefix + (k,))
        if isinstance(v, dict):
            out.extend(_paths(v, prefix + (k,)))
    return out


def _set(d, path, value, delete=False):
    for k in path[:-1]:
        d = d[k]
    if delete:
        del d[path[-1]]
    else:
        d[path[-1]] = value


@st.composite
def topologies(draw):
    """Random bodies (1-4, free space) and random tethers between any two names (possibly the
    same body, an unknown body, loops, chains, several roots)."""
    nb = draw(st.integers(1, 4))
    bodies = {}
    for i in range(nb):
        x = draw(st.sampled_from([0.0, 40.0, 100.0, -70.0, 150.0]))
        bodies[NAMES[i]] = {
            "mass": draw(st.sampled_from(["1 kg", "10 kg", "0.5 kg"])),
            "position": [f"{x + 0.5 * i} m", f"{3.0 * i} m", "0 m"],
            "velocity": [f"{draw(st.sampled_from([0.0, 1.0, -2.0]))} m/s", "0 m/s", "0 m/s"],
        }
    tethers = {}
    for j in range(draw(st.integers(0, 3))):
        tethers[f"t{j}"] = {
            # mostly from the first body (the shapes the solver takes), sometimes anything
            "from": draw(st.sampled_from(["a", "a", "a", "b", "c", "zz"])),
            "to": draw(st.sampled_from(NAMES[1:nb] or NAMES)) if draw(st.booleans()) else draw(st.sampled_from(NAMES)),
            "rods": draw(st.integers(1, 3)),
            "length": draw(st.sampled_from(["30 m", "100 m", "160 m"])),
            "EA": "1e3 N",
            "mass": "0.5 kg",
        }
    return {
        "name": "fuzz-topology",
        "duration": "2 s",
        "effects": draw(st.sampled_from([{}, {"uniform_gravity": {}}])),
        "bodies": bodies,
        "tethers": tethers,
        "integrator": {"method": "dop853", "rtol": 1e-8, "atol": 1e-8},
        "output": {"count": 3},
    }


@st.composite
def scenes(draw):
    if draw(st.integers(0, 9)) < 7:
        d = copy.deepcopy(draw(st.sampled_from(TEMPLATES)))
    else:
        d = draw(topologies())
    if draw(st.integers(0, 2)) == 0:
        # one more effect, with its parameters or without (required ones then missing)
        name, params = draw(st.sampled_from(EXTRA_EFFECTS))
        effects = d.get("effects")
        if isinstance(effects, dict):
            effects[name] = copy.deepcopy(params) if draw(st.booleans()) else {}
            if name.endswith("_de421") or name == "electrodynamic":
                d["epoch"] = "2026-01-01T00:00:00"
    if draw(st.booleans()):
        d.setdefault("integrator", {})["method"] = draw(st.sampled_from(["dop853", "vern9", "radau5", "scipy:DOP853"]))
    for _ in range(draw(st.sampled_from([0, 0, 1, 1, 1, 2, 3]))):
        paths = _paths(d)
        if not paths:
            break
        path = draw(st.sampled_from(paths))
        old = _get(d, path)
        kind = draw(st.integers(0, 3))
        if kind == 0:
            _set(d, path, None, delete=True)
        elif kind == 1 and isinstance(old, str) and _NUMBER.match(old):
            # a valid value of another size (same unit): scenes that run, or stop, differently
            factor = draw(st.sampled_from([1e-6, 0.01, 0.3, 3.0, 100.0, 1e6, -1.0]))
            number, unit = _NUMBER.match(old).groups()
            _set(d, path, f"{float(number) * factor!r}{unit}")
        else:
            _set(d, path, draw(st.sampled_from(BAD_VALUES)))
    return d


_NUMBER = re.compile(r"^\s*([-+0-9.eE]+)(\s.*)$")


def _get(d, path):
    for k in path:
        d = d[k]
    return d


_WHEN = re.compile(r"t ?= ?[-+]?(\d|nan|inf)", re.IGNORECASE)


def _tame(scene: Scene) -> Scene:
    """Keep a valid scene's run tiny (few outputs, a step budget): the property is about how a
    run ends, not about how long it takes."""
    changes = {}
    if scene.integrator.max_steps is None or scene.integrator.max_steps > MAX_STEPS:
        changes["integrator.max_steps"] = MAX_STEPS
    rows = resources.output_rows(scene)
    if rows is not None and rows[0] > MAX_OUTPUTS and rows[0] < 10**9:
        # (a request of a billion outputs is left alone: the memory check must refuse it)
        changes["output"] = {"count": 20}
    return scene.replace(**changes) if changes else scene


def check_scene_outcome(d: dict) -> str:
    try:
        scene = Scene.from_dict(d)
        scene = _tame(scene)
        result = simulate(scene, progress=False)
    except SceneError as exc:
        # names a key (a dotted path), which the message shows
        assert isinstance(exc.key, str) and exc.key, f"SceneError without a key: {exc}"
        assert repr(exc.key) in str(exc)
        return "refused"
    except SimulationError as exc:
        msg = str(exc)
        assert _WHEN.search(msg), f"SimulationError without a time: {msg}"
        assert exc.result is not None and not exc.result.ok
        # the states kept are finite; a force derived from the last of them may be NaN when the
        # failure is that it cannot be computed (a singular reaction system, said in the message)
        ts = exc.result.timeseries
        states = ts[[c for c in ts.columns if c.endswith(("_m", "_m_s")) or c == "t_s"]].to_numpy()
        assert np.all(np.isfinite(states)), f"non-finite states kept before the failure: {msg}"
        return "stopped"
    # completed: finite outputs, the last one at the end of the run
    assert result.ok
    ts = result.timeseries
    assert len(ts) >= 1 and np.all(np.isfinite(ts.to_numpy())), "a run that completed with non-finite outputs"
    stopped = result.stats.get("stopped_by")
    if stopped is None:
        assert math.isclose(ts["t_s"].iloc[-1], float(simulate_end(scene)), rel_tol=1e-12, abs_tol=1e-9)
    return "completed"


def simulate_end(scene) -> float:
    from tetherlab.pipeline import prepare

    return float(prepare(scene).t_out[-1])


@pytest.fixture
def small_machine(monkeypatch):
    monkeypatch.setattr(resources, "available_memory_bytes", lambda: 2 * 2**30)


_FAST = settings(max_examples=250, deadline=None, derandomize=True,
                 suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])  # fmt: skip
_SLOW = settings(max_examples=1500, deadline=None,
                 suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])  # fmt: skip


@_FAST
@given(scenes())
def test_every_scene_is_refused_or_runs_or_stops_with_a_reason(small_machine, d):
    event(check_scene_outcome(d))  # the outcome counts: pytest --hypothesis-show-statistics


@pytest.mark.slow
@_SLOW
@given(scenes())
def test_every_scene_is_refused_or_runs_or_stops_with_a_reason_many(small_machine, d):
    event(check_scene_outcome(d))


@pytest.mark.parametrize("template", TEMPLATES, ids=lambda t: t["name"])
def test_the_templates_themselves_run(template):
    # the undamaged templates are valid scenes that run to their end (so the fuzzing starts from
    # scenes that work, and a refusal is caused by the damage)
    assert check_scene_outcome(copy.deepcopy(template)) == "completed"


@pytest.mark.slow
@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(scenes())
def test_tetherlab_run_ends_the_same_way_as_simulate(small_machine, d):
    # The run-directory path (tetherlab/runstore.py) on the same scenes: the same outcome as
    # simulate(), recorded in run.json, the outputs readable back.
    import tempfile

    from tetherlab.result import Result
    from tetherlab.runstore import run_to_dir

    outcome = check_scene_outcome(d)
    with tempfile.TemporaryDirectory() as tmp:
        try:
            rec = run_to_dir(_tame(Scene.from_dict(d)), tmp, progress=False)
        except SceneError as exc:
            assert outcome == "refused" and exc.key
            return
        assert outcome == ("completed" if rec["ok"] else "stopped"), rec.get("message")
        assert rec["state"] == ("complete" if rec["ok"] else "failed")
        back = Result.load(tmp)
        assert len(back.timeseries) == rec["rows_done"]
