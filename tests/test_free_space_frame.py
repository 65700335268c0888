"""Free space has no orbital frame (docs/model.md 7): the libration angles and a rigid body's
roll, pitch and yaw are NaN there by design, without a floating-point warning, and the tumbling
warning, which reads them, is not raised; ``orbital_frame`` gives NaN rows where (r, v) defines
no frame and the plain quotients' bits elsewhere."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import tetherlab
from tetherlab.deployment import simulate_reel
from tetherlab.diagnostics import has_orbital_frame, orbital_frame
from tetherlab.pipeline import prepare
from tetherlab.regime import check, check_parts

from .helpers import SCENES, import_study

_STUDY = import_study("deployment")


def test_orbital_frame_is_nan_where_there_is_none_and_exact_elsewhere():
    # warnings are errors in the suite: a division by |r| = 0 or |r x v| = 0 would fail here
    r = np.array([[0.0, 0.0, 0.0], [7.0e6, 1.0, 2.0], [1.0, 0.0, 0.0]])
    v = np.array([[0.0, 0.0, 0.0], [3.0, 7.5e3, 1.0], [2.0, 0.0, 0.0]])  # rows: origin, an orbit, radial
    f = orbital_frame(r, v)
    assert np.isnan(f[0]).all() and np.isnan(f[2]).all()
    x = r[1] / np.linalg.norm(r[1])
    h = np.cross(r[1], v[1])
    z = h / np.linalg.norm(h)
    assert np.array_equal(f[1], np.stack([x, np.cross(z, x), z]))


@pytest.fixture(scope="module")
def spoke():
    # the four spokes of reel-hub-spoke (docs/deployment.md 9.5): the centre of mass drifts a few mm
    # from the origin, and a frame built from it gave +-90 deg from the first output on
    scene = tetherlab.load_scene(SCENES / "reel-hub-spoke.toml").replace(duration="2 s", **{"output": {"count": 3}})
    return scene, simulate_reel(scene)


def test_a_free_space_reel_run_has_nan_angles(spoke):
    scene, run = spoke
    assert not has_orbital_frame(prepare(scene).model)
    dg = run.phases[0].diagnostics
    cols = [c for c in dg.columns if c.endswith((".theta_rad", ".phi_rad", "roll_rad", "pitch_rad", "yaw_rad"))]
    assert len(cols) == 4 * 2 + 3  # four tethers' theta and phi, the hub's three angles
    assert dg[cols].isna().all().all()


def test_a_free_space_hub_raises_no_tumbling_warning(spoke):
    # the run summary's check (tetherlab run prints it) on the run's outputs: the spokes at +-90 deg
    # of the frame that is not there warned "tumbling from t = 0 s" for each of the four
    scene, run = spoke
    assert check_parts(scene, [(ph.timeseries, ph.diagnostics) for ph in run.phases]) == []


def test_tumbling_is_checked_only_about_a_central_body():
    # outputs whose angle passes 90 deg at t = 71 s (as a run directory written before free space's
    # angles were NaN would hold): a tumbling warning about a central body, none in free space
    t = np.linspace(0.0, 100.0, 101)
    dg = pd.DataFrame({"t_s": t, "main.theta_rad": np.where(t > 70, 2.0, 0.1), "main.phi_rad": 0 * t})
    orbit = {"effects": {"central_gravity": {}}, "tethers": {"main": {}}}
    free = {"effects": {}, "tethers": {"main": {}}}
    assert [(w["kind"], w["t_s"]) for w in check(orbit, None, dg)] == [("tumbling", 71.0)]
    assert check(free, None, dg) == []


def test_a_point_mass_free_space_run_off_the_origin_has_nan_angles():
    # studies/deployment.py free_scene: the centre of mass ~12 m from the origin (10 kg at 150 m and
    # the 1.5 kg line's middle at 75 m, of 131.5 kg) and moving, so r x v != 0, yet no central body:
    # no orbital frame either
    run = simulate_reel(_STUDY.free_scene(duration="2 s", count=3))
    dg = run.phases[0].diagnostics
    assert float(dg["com_radius_m"].iloc[0]) > 10.0  # meters
    assert dg[["main.theta_rad", "main.phi_rad"]].isna().all().all()


def test_an_orbit_keeps_its_angles():
    scene = tetherlab.load_scene(SCENES / "libration-inplane.toml").replace(duration="60 s", **{"output": {"count": 3}})
    assert has_orbital_frame(prepare(scene).model)
    dg = tetherlab.simulate(scene, progress=False).diagnostics
    assert np.isfinite(dg["main.theta_rad"]).all() and np.isfinite(dg["main.phi_rad"]).all()
