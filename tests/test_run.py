"""The run pipeline: CLI files, failures that keep their outputs, effects evaluated only when named,
and agreement between integrators on the same scene."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from tetherlab.cli import main
from tetherlab.errors import SceneError
from tetherlab.scene import Scene, load_scene
from tetherlab.pipeline import SimulationError, simulate

from .helpers import SCENES


def _short(scene_name="bench-libration.toml", **changes):
    base = {"duration": "0.2 orbits", "output.count": 41}
    base.update(changes)
    return load_scene(SCENES / scene_name).replace(**base)


def test_cli_run_writes_readable_results_and_plots(tmp_path):
    scene_file = tmp_path / "s.toml"
    text = (SCENES / "bench-libration.toml").read_text()
    text = text.replace('duration = "10 orbits"', 'duration = "0.1 orbits"').replace("count = 1001", "count = 21")
    scene_file.write_text(text)
    out = tmp_path / "out"
    assert main(["run", str(scene_file), "--out", str(out), "--quiet"]) == 0
    # Parquet datasets written as the run goes (tetherlab/runstore.py), read whole by pandas
    ts = pd.read_parquet(out / "timeseries")
    dg = pd.read_parquet(out / "diagnostics")
    run = json.loads((out / "run.json").read_text())
    assert len(ts) == 21 and len(dg) == 21
    for col in ("t_s", "m0.x_m", "mf.vz_m_s", "main.node1.y_m", "main.rod2.strain", "main.rod1.axial_force_N",
                "main.joint0.reaction_N"):
        assert col in ts.columns
    for col in ("energy_J", "angmom_z_kg_m2_s", "main.theta_rad", "main.phi_rad", "energy_error_rel"):
        assert col in dg.columns
    assert run["ok"] and run["versions"]["numba"]
    assert Scene.from_dict(run["scene"]) == load_scene(scene_file)  # the scene is stored whole
    assert run["stats"]["n_accepted"] > 0 and run["stats"]["n_rhs"] > run["stats"]["n_accepted"]
    assert main(["plot", str(out)]) == 0
    for name in ("libration.png", "tension.png", "invariants.png", "shape.png"):
        assert (out / name).stat().st_size > 1000


def test_cli_reports_a_bad_scene_with_its_key(tmp_path, capsys):
    scene_file = tmp_path / "bad.toml"
    scene_file.write_text((SCENES / "bench-libration.toml").read_text().replace('rods = 2', 'rods = 0'))
    assert main(["run", str(scene_file), "--out", str(tmp_path / "o")]) == 2
    assert "tethers.main.rods" in capsys.readouterr().err


def _collapsing_scene():
    # Two bodies in free space rushing together along a 100 m tether: compression drives the
    # single rod to zero length, where the TMED model breaks (u = d/|d| undefined, eq. 8).
    return Scene.from_dict(
        {
            "name": "collapse",
            "duration": "100 s",
            "effects": {},
            "bodies": {
                "a": {"mass": "10 kg", "position": ["1000 m", "0 m", "0 m"], "velocity": ["5 m/s", "0 m/s", "0 m/s"]},
                "b": {"mass": "10 kg", "position": ["1100 m", "0 m", "0 m"], "velocity": ["-5 m/s", "0 m/s", "0 m/s"]},
            },
            "tethers": {"t": {"from": "a", "to": "b", "rods": 1, "length": "100 m", "EA": "1 N", "mass": "1 kg"}},
            "integrator": {"method": "dop853", "rtol": 1e-9, "atol": 1e-9},
            "output": {"step": "1 s"},
        }
    )


def test_failed_run_says_when_where_why_and_keeps_outputs(tmp_path):
    with pytest.raises(SimulationError) as info:
        simulate(_collapsing_scene(), progress=False)
    msg = str(info.value)
    assert "collapsed" in msg and "tether 't', rod 1 of 1" in msg and "t = " in msg
    res = info.value.result
    assert not res.ok
    t = res.timeseries["t_s"].to_numpy()
    # closing at 10 m/s relative, 100 m apart with a 1 N tether: collapse near t = 9 s, so the
    # outputs before it (t = 0 ... 8 s at least) are kept and nothing after the failure is
    assert 8.0 <= t[-1] < 10.0
    assert np.all(np.isfinite(res.timeseries.to_numpy()))
    res.save(tmp_path / "partial")
    assert not json.loads((tmp_path / "partial" / "run.json").read_text())["ok"]


def test_cli_keeps_partial_results_and_exits_nonzero(tmp_path):
    out = tmp_path / "o"
    f = tmp_path / "c.toml"
    f.write_text(
        """name = "collapse"
duration = "100 s"
[effects]
[bodies.a]
mass = "10 kg"
position = ["1000 m", "0 m", "0 m"]
velocity = ["5 m/s", "0 m/s", "0 m/s"]
[bodies.b]
mass = "10 kg"
position = ["1100 m", "0 m", "0 m"]
velocity = ["-5 m/s", "0 m/s", "0 m/s"]
[tethers.t]
from = "a"
to = "b"
rods = 1
length = "100 m"
EA = "1 N"
mass = "1 kg"
[integrator]
method = "dop853"
rtol = 1e-9
atol = 1e-9
[output]
step = "1 s"
"""
    )
    assert main(["run", str(f), "--out", str(out), "--quiet"]) == 1
    assert len(pd.read_parquet(out / "timeseries")) >= 9


def test_only_named_effects_are_evaluated():
    # No effect named: the kernel must never reach an effect (all counters stay zero).
    res = simulate(_short().replace(**{"effects.central_gravity": None}), progress=False)
    assert all(v == 0 for v in res.meta["effect_evaluations"].values())
    res = simulate(_short(), progress=False)
    counts = res.meta["effect_evaluations"]
    assert counts["central_gravity"] > 0
    assert all(v == 0 for k, v in counts.items() if k != "central_gravity")


@pytest.mark.parametrize("name", ["j2", "zonal", "moon_de421", "sun_de421"])
def test_a_named_gravity_effect_is_evaluated_and_no_other(name):
    # The gravity family (forces/zonal.py, forces/third_body.py) on the tethered scene: the named
    # effect runs (on bodies and rods), every effect not named keeps a zero counter.
    res = simulate(_short(**{f"effects.{name}": {}, "epoch": "2026-01-01T00:00:00"}), progress=False)
    counts = res.meta["effect_evaluations"]
    assert counts[name] > 0
    # evaluated wherever central gravity is (root, tip and every rod quadrature node): rods too
    assert counts[name] == counts["central_gravity"]
    assert all(v == 0 for k, v in counts.items() if k not in (name, "central_gravity"))


@pytest.mark.parametrize("method", ["radau5", "scipy:DOP853"])
def test_integrators_agree_on_the_benchmark_scene(method):
    # Same scene, same compiled right-hand side, rtol = atol = 1e-10 (in scale units): the tip
    # positions must agree to within what that tolerance allows over 0.2 orbits.  Bound: 1 cm,
    # i.e. ~1e-9 of the 7400 km orbit radius (10x the tolerance, for global error growth).
    ref = simulate(_short(), progress=False).timeseries
    other = simulate(_short(**{"integrator.method": method}), progress=False).timeseries
    cols = ["mf.x_m", "mf.y_m", "mf.z_m"]
    diff = np.linalg.norm(ref[cols].to_numpy() - other[cols].to_numpy(), axis=1)
    assert diff.max() < 0.01


def test_a_chain_runs_from_its_explicit_states():
    # a chain a - b - c (not a star) runs; at t = 0 every body sits at its explicit
    # state (the layout's straight tethers between placed ends), and with no effect the total
    # momentum keeps its initial value to round-off (bound: 1e-12 N s, ~1e3 eps of the
    # |m v| ~ 10 kg x 0.1 m/s terms summed; RK steps conserve a linear invariant exactly up to
    # round-off, and P is linear in the state for point masses)
    scene = Scene.from_dict(
        {
            "duration": "10 s",
            "effects": {},
            "bodies": {
                "a": {"mass": "10 kg", "position": ["1000 m", "0 m", "0 m"], "velocity": ["0 m/s", "0 m/s", "0 m/s"]},
                "b": {"mass": "10 kg", "position": ["1100 m", "0 m", "0 m"], "velocity": ["0 m/s", "0 m/s", "0 m/s"]},
                "c": {"mass": "10 kg", "position": ["1200 m", "0 m", "0 m"], "velocity": ["0 m/s", "0 m/s", "0 m/s"]},
            },
            "tethers": {
                "t1": {"from": "a", "to": "b", "rods": 1, "length": "100 m", "EA": "1e3 N", "mass": "1 kg"},
                "t2": {"from": "b", "to": "c", "rods": 1, "length": "100 m", "EA": "1e3 N", "mass": "1 kg"},
            },
            "output": {"count": 3},
        }
    )
    res = simulate(scene.replace(**{"bodies.b.velocity": ["0 m/s", "0.1 m/s", "0 m/s"],
                                    "bodies.a.velocity": ["0 m/s", "-0.05 m/s", "0 m/s"],
                                    "bodies.c.velocity": ["0 m/s", "-0.05 m/s", "0 m/s"]}), progress=False)
    ts = res.timeseries
    for name, x in (("a", 1000.0), ("b", 1100.0), ("c", 1200.0)):
        assert ts[f"{name}.x_m"].iloc[0] == pytest.approx(x, abs=1e-9)
    for ax in "xyz":
        P = res.diagnostics[f"momentum_{ax}_N_s"].to_numpy()
        assert np.abs(P - P[0]).max() < 1e-12
