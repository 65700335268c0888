"""Continuing a finished run with a changed input (``continue_from``, ``tetherlab run --from``).

A mission in two phases, motor on for 5 s then off, run as two scenes (the second starting from
the first's run directory) against one scene whose torque table jumps at 5 s: the jump is a
breakpoint, where the single run lands a step and restarts as from a new initial value, so the
two must agree bit for bit (np.array_equal) at the split and at every later output.  Bad
continuations are refused with a SceneError naming ``continue_from``.
"""

from __future__ import annotations

import json
import tomllib

import numpy as np
import pytest

from tetherlab.errors import SceneError
from tetherlab.pipeline import simulate
from tetherlab.runstore import run_to_dir
from tetherlab.scene import Scene

from .test_wheel_scenario import USER_SCENE


def _scene(torque, duration="10 s", **top) -> Scene:
    d = tomllib.loads(USER_SCENE)
    d["duration"] = duration
    d["bodies"]["sat"]["wheels"]["w1"]["torque"] = torque
    d.update(top)
    return Scene.from_dict(d)


ONE_RUN = {"times": ["0 s", "5 s", "5 s", "10 s"], "values": ["0.1 N m", "0.1 N m", "0 N m", "0 N m"]}


@pytest.mark.parametrize("method", ["dop853", "radau5"])
def test_two_phases_equal_one_run_bit_for_bit(tmp_path, method):
    one = simulate(_scene(ONE_RUN).replace(**{"integrator.method": method}), progress=False)
    run_to_dir(_scene("0.1 N m", "5 s").replace(**{"integrator.method": method}), tmp_path / "phase1", progress=False)
    two = simulate(_scene("0 N m", "5 s", continue_from=str(tmp_path / "phase1")).replace(
        **{"integrator.method": method}), progress=False)  # fmt: skip
    t1 = one.timeseries["t_s"].to_numpy()
    t2 = two.timeseries["t_s"].to_numpy()
    assert t2[0] == 5.0 and t2[-1] == 10.0
    k = np.searchsorted(t1, t2[0])
    assert np.array_equal(t1[k:], t2)
    cols = [c for c in one.timeseries.columns if c.startswith("sat.")]
    assert np.array_equal(one.timeseries[cols].to_numpy()[k:], two.timeseries[cols].to_numpy())


def test_cli_from_flag(tmp_path):
    from tetherlab.cli import main

    p1 = tmp_path / "p1.toml"
    p2 = tmp_path / "p2.toml"
    base = USER_SCENE.replace('duration = "10 s"', 'duration = "5 s"')
    p1.write_text(base)
    p2.write_text(base.replace('values = ["0.1 N m", "0.1 N m", "0 N m", "0 N m"]', 'values = ["0 N m", "0 N m", "0 N m", "0 N m"]'))
    assert main(["run", str(p1), "--out", str(tmp_path / "r1"), "--quiet"]) == 0
    assert main(["run", str(p2), "--out", str(tmp_path / "r2"), "--from", str(tmp_path / "r1"), "--quiet"]) == 0
    rec = json.loads((tmp_path / "r2" / "run.json").read_text())
    assert rec["t_s"] == 10.0 and rec["scene"]["continue_from"] == str((tmp_path / "r1").resolve())


def test_refused_continuations(tmp_path):
    with pytest.raises(SceneError) as e:
        simulate(_scene("0 N m", "5 s", continue_from=str(tmp_path / "nothing")), progress=False)
    assert e.value.key == "continue_from" and "no such directory" in str(e.value)
    run_to_dir(_scene("0.1 N m", "5 s"), tmp_path / "r1", progress=False)
    # a scene with another state layout: a second wheel
    d = tomllib.loads(USER_SCENE)
    d["bodies"]["sat"]["wheels"]["w2"] = {"axis": [1.0, 0.0, 0.0], "inertia": "0.1 kg m2"}
    d["continue_from"] = str(tmp_path / "r1")
    with pytest.raises(SceneError) as e:
        simulate(Scene.from_dict(d), progress=False)
    assert e.value.key == "continue_from" and "wheels" in str(e.value) and "state layout" in str(e.value)
    # a run that did not finish
    rec = json.loads((tmp_path / "r1" / "run.json").read_text())
    rec["state"] = "interrupted"
    (tmp_path / "r1" / "run.json").write_text(json.dumps(rec))
    with pytest.raises(SceneError) as e:
        simulate(_scene("0 N m", "5 s", continue_from=str(tmp_path / "r1")), progress=False)
    assert "--resume" in str(e.value)


@pytest.mark.parametrize("form", ["cowell-orbit", "dromo"])
def test_other_formulations_continue(tmp_path, form):
    """A tethered orbit continued in the turning frame and in DROMO's time form: not bit for bit
    (each starts its frame or elements afresh at the split), within the integration's own error."""
    from tetherlab.scene import load_scene

    from .helpers import SCENES

    sc = load_scene(SCENES / "libration-inplane.toml").replace(**{"output.count": 3, "integrator.formulation": form})
    one = simulate(sc.replace(duration="0.5 orbits"), progress=False)
    run_to_dir(sc.replace(duration="0.25 orbits"), tmp_path / "a", progress=False)
    two = simulate(sc.replace(duration="0.25 orbits", continue_from=str(tmp_path / "a")), progress=False)
    assert two.stats["formulation"] == ("dromo-time" if form == "dromo" else form)
    a, b = one.timeseries.iloc[-1], two.timeseries.iloc[-1]
    assert a["t_s"] == b["t_s"]
    # Budget: rtol = atol = 1e-10 on a 7400 km orbit, the position scale: 7.4e-4 m per unit of
    # the error norm; taken 1e-3 m for the end mass (measured: 5e-8 to 1.5e-7 m over one orbit).
    for c in ("mf.x_m", "mf.y_m", "mf.z_m"):
        assert abs(a[c] - b[c]) <= 1e-3, c


def test_cli_refuses_to_continue_into_its_own_directory(tmp_path, capsys):
    from tetherlab.cli import main

    p1 = tmp_path / "p1.toml"
    p1.write_text(USER_SCENE.replace('duration = "10 s"', 'duration = "5 s"'))
    assert main(["run", str(p1), "--out", str(tmp_path / "r1"), "--quiet"]) == 0
    assert main(["run", str(p1), "--out", str(tmp_path / "r1"), "--from", str(tmp_path / "r1"), "--quiet"]) == 2
    assert "overwrite the run it starts from" in capsys.readouterr().err
    assert json.loads((tmp_path / "r1" / "run.json").read_text())["state"] == "complete"
