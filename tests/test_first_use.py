"""What a new user meets in the first hour: the Python API, the command line, the checks made at
load, the orbital outputs, the run summary's warnings and the figures of ``tetherlab plot``.

Each test uses the input a user wrote (a scene written with ``a = "800 km"`` for an altitude, a
wrong ``--method`` on the command line, ``tetherlab plot`` on a directory that holds no run ...).
"""

from __future__ import annotations

import json
import math
import os
import stat
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import tetherlab
from tetherlab.cli import main, run_summary
from tetherlab.errors import SceneError
from tetherlab.scene import Scene, load_scene

from .helpers import MU_EARTH, ROOT, SCENES

R_EARTH = 6378137.0  # m, the scene preset "earth" (WGS 84 a; tetherlab/scene/data.py CENTRAL_BODY_PRESETS)


def _scene(**changes) -> dict:
    """The README's first scene as a dictionary, with dotted-key changes."""
    import tomllib

    from tetherlab.scene.keys import _set_dotted

    data = tomllib.loads((SCENES / "libration-inplane.toml").read_text())
    for k, v in changes.items():
        _set_dotted(data, k, v)
    return data


# -- the Python API ------------------------------------------------------------------------------


def test_the_package_exports_what_a_user_needs():
    from tetherlab.errors import SceneError as SE
    from tetherlab.pipeline import SimulationError
    from tetherlab.result import Result
    from tetherlab.runstore import RunDirError

    assert tetherlab.Scene is Scene
    assert tetherlab.Result is Result
    assert tetherlab.SceneError is SE
    assert tetherlab.SimulationError is SimulationError
    assert tetherlab.RunDirError is RunDirError
    assert {"Scene", "Result", "SceneError", "SimulationError", "load_scene", "simulate"} <= set(tetherlab.__all__)
    scene = tetherlab.Scene.from_dict(_scene())  # building a scene from a dict needs no deep import
    assert scene.name == "libration-inplane"


@pytest.mark.parametrize("bad, fragment", [(None, "NoneType"), ("studies/scenes/libration-inplane.toml", "load_scene"),
                                           ({"name": "x"}, "from_dict")])  # fmt: skip
def test_simulate_of_something_else_than_a_scene_is_a_clear_type_error(bad, fragment):
    with pytest.raises(TypeError) as info:
        tetherlab.simulate(bad)
    assert "expected a tetherlab.Scene" in str(info.value)
    assert fragment in str(info.value)


# -- checks made at load -------------------------------------------------------------------------


def test_a_semi_major_axis_written_for_an_altitude_is_refused_at_load():
    # the user's scene: a = "800 km" meant as an altitude, 5578 km below the surface
    with pytest.raises(SceneError) as info:
        Scene.from_dict(_scene(**{"orbit.elements": {"a": "800 km", "e": 0.0}}))
    err = info.value
    assert err.key == "orbit.elements.a"
    assert "below" in str(err) and "altitude" in str(err)


def test_a_body_placed_inside_the_earth_is_refused_and_free_space_is_not_checked():
    data = {"duration": "10 s", "effects": {"central_gravity": {}}, "output": {"count": 2},
            "bodies": {"b": {"mass": "1 kg", "position": ["6000 km", "0 km", "0 km"], "velocity": ["0 m/s", "7 km/s", "0 m/s"]}}}  # fmt: skip
    with pytest.raises(SceneError) as info:
        Scene.from_dict(data)
    assert info.value.key == "bodies.b.position"
    # the same position in free space (no central body's gravity) is a valid scene
    data["effects"] = {}
    assert Scene.from_dict(data).bodies[0].position_m[0] == 6.0e6


def test_altitudes_instead_of_a_semi_major_axis():
    alt = Scene.from_dict(_scene(**{"orbit.elements": {"altitude": "800 km", "e": 0.0}}))
    assert alt.orbit.elements.a_m == R_EARTH + 800e3  # a = R + h (docs/scenes.md, Elements)
    pa = Scene.from_dict(_scene(**{"orbit.elements": {"perigee_altitude": "300 km", "apogee_altitude": "1000 km"}}))
    rp, ra = R_EARTH + 300e3, R_EARTH + 1000e3
    assert pa.orbit.elements.a_m == pytest.approx(0.5 * (rp + ra), rel=1e-15)
    assert pa.orbit.elements.e == pytest.approx((ra - rp) / (ra + rp), rel=1e-15)
    r, _ = pa.orbit.state(MU_EARTH)  # nu = 0: the start is the perigee
    assert np.linalg.norm(r) - R_EARTH == pytest.approx(300e3, abs=1e-6)
    p = Scene.from_dict(_scene(**{"orbit.elements": {"perigee_altitude": "300 km", "e": 0.1}}))
    assert p.orbit.elements.a_m == pytest.approx(rp / 0.9, rel=1e-15)
    # round trip: written back as a, read back the same
    assert Scene.from_dict(pa.to_dict()) == pa
    with pytest.raises(SceneError) as info:
        Scene.from_dict(_scene(**{"orbit.elements": {"a": "7400 km", "altitude": "800 km", "e": 0.0}}))
    assert info.value.key == "orbit.elements.a" and "a and altitude" in str(info.value)
    with pytest.raises(SceneError) as info:
        Scene.from_dict(_scene(**{"orbit.elements": {"perigee_altitude": "300 km", "apogee_altitude": "1000 km", "e": 0.1}}))
    assert info.value.key == "orbit.elements.e"


@pytest.mark.parametrize("effects", [
    {"central_gravity": {}, "moon_de421": {}},
    {"central_gravity": {}, "electrodynamic": {"current": "1 A", "field": "igrf14"}},
    {"central_gravity": {}, "electrodynamic": {"current": "1 A", "eclipse": "conical"}},
    {"central_gravity": {}, "drag": {"area": "1 m2", "atmosphere": "nrlmsis21", "f107": 150, "f107a": 150, "ap": 4}},
])  # fmt: skip
def test_a_dated_model_without_an_epoch_is_refused_at_load(effects):
    with pytest.raises(SceneError) as info:
        Scene.from_dict(_scene(effects=effects))
    assert info.value.key == "epoch"
    assert "dated" in str(info.value)
    # with an epoch the same scene loads
    Scene.from_dict(_scene(effects=effects, epoch="2026-01-01T00:00:00"))


def test_a_stop_altitude_above_the_start_is_refused_at_load():
    with pytest.raises(SceneError) as info:
        Scene.from_dict(_scene(stop={"altitude": "1500 km"}))  # the orbit starts at 1022 km
    assert info.value.key == "stop.altitude" and "below the start" in str(info.value)
    Scene.from_dict(_scene(stop={"altitude": "200 km"}))


def test_the_effects_table_of_the_docs_names_every_effect_and_parameter():
    from tetherlab.forces import EFFECTS

    doc = (ROOT / "docs" / "scenes.md").read_text()
    start = doc.index("| effect | parameters |")
    table = doc[start : doc.index("\n\n", start)]
    for name, spec in EFFECTS.items():
        row = next((line for line in table.splitlines() if f"`{name}`" in line), None)
        assert row is not None, f"docs/scenes.md effects table has no row for {name}"
        for pname in spec.params:
            assert f"`{pname}`" in row, f"docs/scenes.md: effect {name} row lacks parameter {pname}"


# -- orbital outputs -----------------------------------------------------------------------------


def test_geodetic_coordinates_against_astropy():
    from astropy import units as u
    from astropy.coordinates import EarthLocation

    from tetherlab.orbits.osculating import geodetic

    rng = np.random.default_rng(3)
    r = rng.normal(size=(200, 3))
    r *= (R_EARTH + rng.uniform(-5e3, 4e7, size=200))[:, None] / np.linalg.norm(r, axis=1)[:, None]
    r = np.vstack([r, [[6378137.0, 0, 0], [0, 0, 6356752.314245], [0, 0, -7e6]]])
    lat, lon, h = geodetic(r)
    # oracle: astropy's EarthLocation (ERFA gc2gd, WGS 84), an independent closed-form solution.
    # Budget: 1 mm on the ground (1.5e-10 rad at the surface), far below what a ground track or
    # an altitude history resolves; an error in the ellipsoid or the iteration is metres to km
    loc = EarthLocation.from_geocentric(r[:, 0] * u.m, r[:, 1] * u.m, r[:, 2] * u.m).to_geodetic("WGS84")
    assert np.max(np.abs(lat - loc.lat.to_value(u.rad))) < 1.5e-10
    assert np.max(np.abs(np.angle(np.exp(1j * (lon - loc.lon.to_value(u.rad)))))) < 1.5e-10
    assert np.max(np.abs(h - loc.height.to_value(u.m))) < 1e-3  # m
    # the equator and the pole of the ellipsoid are at height 0 (NIMA TR8350.2 a and b)
    assert abs(h[-3]) < 1e-6 and abs(h[-2]) < 1e-6 and lat[-2] == pytest.approx(math.pi / 2, abs=1e-15)


def test_osculating_elements_agree_with_the_scalar_conversion():
    from tetherlab.orbits.kepler import cartesian_to_elements, elements_to_cartesian
    from tetherlab.orbits.osculating import elements

    cases = [(7.4e6, 0.0, 0.0, 0.0, 0.0, 0.3), (7.0e6, 0.1, 0.6, 1.0, 2.0, 0.5), (8e6, 0.3, math.pi, 4.0, 5.0, 3.0),
             (-9e6, 1.5, 0.4, 0.1, 0.2, 0.3)]  # fmt: skip
    rv = [elements_to_cartesian(MU_EARTH, *c) for c in cases]
    out = elements(MU_EARTH, np.array([r for r, _ in rv]), np.array([v for _, v in rv]))
    for k, (r, v) in enumerate(rv):
        ref = cartesian_to_elements(MU_EARTH, r, v)  # the package's scalar form (tests/test_kepler.py)
        assert out["a_m"][k] == pytest.approx(ref.a, rel=1e-14)
        assert out["eccentricity"][k] == pytest.approx(ref.e, abs=1e-14)
        assert out["inclination_rad"][k] == pytest.approx(ref.i, abs=1e-14)
        assert out["raan_rad"][k] == pytest.approx(ref.raan, abs=1e-12)
        if ref.e > 1e-12:
            assert np.angle(np.exp(1j * (out["argp_rad"][k] - ref.argp))) == pytest.approx(0.0, abs=1e-12)
    # a rectilinear state has no orbital plane: NaN, not a number that looks right
    assert np.isnan(elements(MU_EARTH, np.array([[7e6, 0, 0]]), np.array([[1e3, 0, 0]]))["inclination_rad"][0])


@pytest.fixture(scope="module")
def inplane_run(tmp_path_factory):
    """The README's first example for 600 s (the compression starts at 443 s), run by the CLI."""
    out = tmp_path_factory.mktemp("inplane") / "run"
    scene = tmp_path_factory.mktemp("scene") / "libration-inplane.toml"
    text = (SCENES / "libration-inplane.toml").read_text().replace('duration = "10 orbits"', 'duration = "600 s"')
    scene.write_text(text)
    assert main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
    return out


def test_every_orbital_run_has_altitude_elements_and_geodetic_columns(inplane_run):
    from tetherlab.result import Result

    dg = Result.load(inplane_run).diagnostics
    for col in ("altitude_m", "a_m", "eccentricity", "inclination_rad", "raan_rad", "argp_rad",
                "latitude_rad", "longitude_rad", "geodetic_height_m"):  # fmt: skip
        assert col in dg.columns, col
    # t = 0: the centre of mass is on the scene's circular orbit a = 7400 km (the scene file)
    assert dg["altitude_m"].iloc[0] == pytest.approx(7400e3 - R_EARTH, abs=1e-6)
    # over the run the tether's pull changes the centre of mass's osculating a by far less than
    # 1 km (measured ~0.5 m; an error would show as the whole tether length, 5 km)
    assert np.max(np.abs(dg["a_m"] - 7400e3)) < 1e3
    # equatorial orbit: latitude 0 within the ellipsoid's flattening (the geodetic height is
    # above the ellipsoid, the altitude above the mean sphere: they differ by < 21.4 km)
    assert np.max(np.abs(dg["latitude_rad"])) < 1e-9
    assert np.max(np.abs(dg["geodetic_height_m"] - dg["altitude_m"])) < 21.4e3


# -- the command line ----------------------------------------------------------------------------


def test_version_and_help(capsys):
    with pytest.raises(SystemExit) as info:
        main(["--version"])
    assert info.value.code == 0
    assert capsys.readouterr().out.strip() == f"tetherlab {tetherlab.__version__}"
    for argv in (["--help"], ["run", "--help"], ["validate", "--help"], ["plot", "--help"], ["sweep", "--help"]):
        with pytest.raises(SystemExit):
            main(argv)
        text = capsys.readouterr().out
        assert "``" not in text and "`" not in text, f"RST markup in {argv}: {text}"


def test_a_bad_method_on_the_command_line_is_a_command_line_error(tmp_path, capsys):
    rc = main(["run", str(SCENES / "libration-inplane.toml"), "--out", str(tmp_path / "x"), "--method", "rk45"])
    err = capsys.readouterr().err
    assert rc == 2
    assert err.startswith("tetherlab: argument --method: expected one of dop853") and "'rk45'" in err
    assert "scene key" not in err and not (tmp_path / "x").exists()


@pytest.mark.parametrize("where", ["missing", "empty", "file"])
def test_plot_on_a_wrong_directory_is_a_clear_error(tmp_path, capsys, where):
    target = tmp_path / "nothing-here"
    if where == "empty":
        target.mkdir()
    elif where == "file":
        target.write_text("x")
    rc = main(["plot", str(target)])
    err = capsys.readouterr().err
    assert rc == 2
    assert err.startswith("tetherlab: ") and ("not a run directory" in err or "not a directory" in err)
    assert "Traceback" not in err


def test_a_subprocess_plot_on_a_wrong_directory_prints_no_traceback(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "tetherlab", "plot", str(tmp_path / "no-run")],
                          capture_output=True, text=True, timeout=120)  # fmt: skip
    assert proc.returncode == 2 and "Traceback" not in proc.stderr and "not a directory" in proc.stderr


def test_validate_checks_and_estimates_without_running(tmp_path, capsys):
    rc = main(["validate", str(SCENES / "deorbit-ed.toml")])
    out = capsys.readouterr().out
    assert rc == 0
    assert "valid scene" in out and "memory:" in out and "disk:" in out and "outputs: 6482 rows (output.step)" in out
    bad = tmp_path / "bad.toml"
    bad.write_text((SCENES / "libration-inplane.toml").read_text().replace('a = "7400 km"', 'a = "800 km"'))
    assert main(["validate", str(bad)]) == 2
    assert "orbit.elements.a" in capsys.readouterr().err


def test_run_json_is_0644_rerunnable_and_the_default_out_is_runs_name(inplane_run, tmp_path, monkeypatch, capsys):
    old = os.umask(0o022)
    try:
        mode = stat.S_IMODE((inplane_run / "run.json").stat().st_mode)
        part = next((inplane_run / "timeseries").glob("part-*.parquet"))
        assert mode == stat.S_IMODE(part.stat().st_mode) == 0o644
        monkeypatch.chdir(tmp_path)
        # the run directory's run.json, run again with no --out: runs/<scene name>
        assert main(["run", str(inplane_run / "run.json")]) == 0
        out = capsys.readouterr().out
        assert (tmp_path / "runs" / "libration-inplane" / "run.json").is_file()
        assert "end of the duration (600.0 s) at 600 s" in out
        # a second time the default directory is taken: runs/<name>-2, never over the first
        assert main(["run", str(inplane_run), "--quiet"]) == 0
        assert (tmp_path / "runs" / "libration-inplane-2" / "run.json").is_file()
    finally:
        os.umask(old)
    from tetherlab.result import Result

    a = Result.load(inplane_run).timeseries
    b = Result.load(tmp_path / "runs" / "libration-inplane").timeseries
    assert a.equals(b)  # the stored scene reruns to the same numbers, bit for bit


def test_the_summary_says_why_the_run_stopped_and_its_times_add_up():
    record = {"ok": True, "status": 0, "rows_done": 5, "t_s": 3.3e6, "scene": {"name": "d", "stop": {"altitude": "200 km"}},
              "segments": 2,
              "stats": {"stopped_by": "stop.altitude", "compile_s": 2.0, "wall_s": 50.0, "session_wall_s": 30.0,
                        "n_accepted": 1, "n_rejected": 0, "n_rhs": 10, "n_jac": 0}}  # fmt: skip
    text = run_summary(record, "runs/d", 33.5)
    assert "stop altitude 200 km reached at 38.19 d" in text
    # set-up 3.5 + compile 2 + integrate 28 = 33.5 (this session); a resumed run also says the total
    assert "set-up 3.50 s + compile 2.00 s + integrate and write 28.00 s = total 33.50 s" in text
    assert "every session of this run so far, 2 sessions: 50.00 s" in text


def test_sweep_is_a_subcommand(tmp_path, capsys):
    study = tmp_path / "s.toml"
    scene = tmp_path / "p.toml"
    scene.write_text('duration = "100 s"\n[effects]\ncentral_gravity = {}\n[bodies.b]\nmass = "1 kg"\n'
                     '[orbit]\nreference = "b"\nelements = { altitude = "700 km", e = 0.0 }\n[output]\ncount = 3\n')  # fmt: skip
    study.write_text('name = "t"\n[[case]]\nid = "c"\nscene = "p.toml"\nsummary = "tetherlab.summaries:final_state"\n'
                     '[case.grid]\n"integrator.rtol" = [1e-8, 1e-9]\n')  # fmt: skip
    rc = main(["sweep", str(study), "--out", str(tmp_path / "o"), "--workers", "1", "--quiet"])
    assert rc == 0, capsys.readouterr()
    assert (tmp_path / "o" / "c.csv").is_file()


# -- warnings of the run summary -----------------------------------------------------------------


def test_a_tether_in_compression_is_reported_with_its_time(inplane_run):
    record = json.loads((inplane_run / "run.json").read_text())
    kinds = {w["kind"]: w for w in record["warnings"]}
    assert "compression" in kinds
    w = kinds["compression"]
    # the README scene starts straight and unstrained at 30 deg: the rods shorten within the run
    assert 0.0 < w["t_s"] < 600.0 and "tension_only" in w["text"] and "'main'" in w["text"]


def test_a_tension_only_tether_is_not_reported_in_compression():
    import pandas as pd

    from tetherlab.regime import compression

    ts = pd.DataFrame({"t_s": [0.0, 1.0], "main.rod1.strain": [1e-4, -1e-3], "main.rod1.axial_force_N": [5.0, -50.0]})
    assert compression(ts, {"tethers": {"main": {"tension_only": True}}}) == []
    found = compression(ts, {"tethers": {"main": {}}})
    assert found[0]["t_s"] == 1.0 and "50 N" in found[0]["text"]
    # round-off around zero strain is no compression (COMPRESSION_STRAIN = -1e-9)
    ts["main.rod1.strain"] = [1e-4, -1e-15]
    assert compression(ts, {"tethers": {"main": {}}}) == []


def test_tumbling_and_slow_down_are_reported_with_their_times():
    import pandas as pd

    from tetherlab.regime import slowdown, tumbling

    t = np.linspace(0.0, 100.0, 101)
    dg = pd.DataFrame({"t_s": t, "main.theta_rad": np.arctan2(np.sin(0.03 * t), np.cos(0.03 * t)), "main.phi_rad": 0 * t})
    found = tumbling(dg)
    assert len(found) == 1 and found[0]["t_s"] == pytest.approx(53.0)  # first output past pi/2 / 0.03 = 52.4 s
    dg["main.theta_rad"] = 0.5 * np.sin(t)
    assert tumbling(dg) == []
    # 0.5 s chunks advancing 100 s each, then 0.5 s chunks advancing 0.5 s: 200 times slower
    trace = [(0.5 * k, 100.0 * k) for k in range(20)] + [(9.5 + 0.5 * k, 1900.0 + 0.5 * k) for k in range(1, 10)]
    found = slowdown(trace)
    assert len(found) == 1 and "200 times" in found[0]["text"] and found[0]["t_s"] == 1900.0
    assert slowdown([(0.5 * k, 100.0 * k) for k in range(40)]) == []


def test_a_very_light_rod_is_warned_about():
    from tetherlab.regime import EPS, light_rods

    # the user's scene: a 1e-6 kg rod under a 50 kg tip, rtol 1e-10: floor EPS * 5e7 = 1.1e-8
    scene = Scene.from_dict(_scene(**{"tethers.main.mass": "1e-6 kg", "bodies.mf.mass": "50 kg"}))
    found = light_rods(scene)
    assert len(found) == 1 and found[0]["kind"] == "light rod" and "'main'" in found[0]["text"]
    assert "1.1e-08 relative" in found[0]["text"]
    # 1e-4 kg (the user's stable case): floor 1.1e-10, just above rtol 1e-10, warned; at rtol
    # 1e-9 it is not, nor is the README's 10 kg tether at any rtol the scene allows
    m4 = Scene.from_dict(_scene(**{"tethers.main.mass": "1e-4 kg", "bodies.mf.mass": "50 kg"}))
    assert len(light_rods(m4)) == 1
    assert light_rods(m4.replace(**{"integrator.rtol": 1e-9})) == []
    assert light_rods(Scene.from_dict(_scene(**{"integrator.rtol": 1e-13}))) == []
    assert EPS == 2.0**-52


# -- figures -------------------------------------------------------------------------------------


def _labels(fig):
    return [(a.get_xlabel(), a.get_ylabel(), a.get_title("left") or a.get_title()) for a in fig.axes]


def test_plot_figures_have_units_legends_and_a_readable_invariants_axis(inplane_run):
    import matplotlib.pyplot as plt

    from tetherlab.plots import figures

    figs = figures(inplane_run)
    try:
        assert {"libration.png", "tension.png", "invariants.png", "shape.png", "altitude.png", "elements.png",
                "ground-track.png"} <= set(figs)  # fmt: skip
        inv = figs["invariants.png"]
        top, bottom = inv.axes
        # energy: the paper model is not energy-conserving: drawn as a change, on a linear axis, said so
        assert top.get_yscale() == "linear" and "not conserved" in top.get_title("left")
        # angular momentum: an error on a log axis that starts near the smallest non-zero error,
        # never at the 1e-300 floor a zero at t = 0 would put there
        assert bottom.get_yscale() == "log" and bottom.get_ylim()[0] > 1e-19
        assert "error" in bottom.get_ylabel() and "conserved by the model" in bottom.get_title("left")
        lib = figs["libration.png"]
        assert lib.axes[0].get_ylabel() == "in-plane θ (deg)" and lib.axes[1].get_xlabel() == "t (s)"
        assert [t.get_text() for t in lib.axes[0].get_legend().get_texts()] == ["tether main"]
        ten = figs["tension.png"].axes[0]
        assert ten.get_ylabel().endswith("(N)") and ten.get_legend().get_texts()[0].get_text() == "tether main (rods 1-2)"
        shape = figs["shape.png"]
        assert [a.get_xlabel() for a in shape.axes] == ["along-track (m)", "cross-track (m)"]
        assert all(t.get_text().endswith(" s") for t in shape.axes[0].get_legend().get_texts())
        alt = figs["altitude.png"].axes[0]
        assert alt.get_ylabel() == "altitude (km)"
        km = alt.get_lines()[0].get_ydata()
        assert km[0] == pytest.approx((7400e3 - R_EARTH) / 1e3, abs=1e-9)
        el = figs["elements.png"]
        assert [a.get_ylabel() for a in el.axes] == ["a (km)", "e (-)", "i (deg)", "Ω (deg)", "ω (deg)"]
        gt = figs["ground-track.png"].axes[0]
        assert gt.get_xlabel() == "longitude (deg)" and gt.get_ylabel() == "geodetic latitude (deg)"
    finally:
        for f in figs.values():
            plt.close(f)


def test_long_runs_are_drawn_as_bands_and_days_are_the_unit():
    import matplotlib.pyplot as plt

    from tetherlab.plots import ENVELOPE_BINS, _draw, time_axis

    t = np.linspace(0.0, 40 * 86400.0, 200001)
    x, label = time_axis(t, 6000.0)
    assert label == "t (days)" and x[-1] == pytest.approx(40.0)
    fig, ax = plt.subplots()
    try:
        line = _draw(ax, x, np.sin(t / 600.0))
        assert len(line.get_xdata()) == ENVELOPE_BINS  # bin means, not 200 001 points
        band = ax.collections[0].get_paths()[0].vertices
        assert band[:, 1].max() == pytest.approx(1.0, abs=1e-3) and band[:, 1].min() == pytest.approx(-1.0, abs=1e-3)
    finally:
        plt.close(fig)


def test_a_rigid_body_gets_its_attitude_figure(tmp_path):
    import matplotlib.pyplot as plt

    from tetherlab.plots import figures

    scene = load_scene(SCENES / "rigid-wheels-control.toml").replace(duration="60 s", output={"count": 13})
    tetherlab.simulate(scene, progress=False).save(tmp_path)
    figs = figures(tmp_path)
    try:
        att = [k for k in figs if k.startswith("attitude-")]
        assert att, list(figs)
        fig = figs[att[0]]
        assert [a.get_ylabel() for a in fig.axes] == ["attitude (deg)", "inertial rate, body axes (deg/s)",
                                                    "wheel speed (rpm)", "control torque, body axes (N m)"]  # fmt: skip
        assert [t.get_text() for t in fig.axes[0].get_legend().get_texts()] == ["roll", "pitch", "yaw"]
        assert all(t.get_text().startswith("wheel ") for t in fig.axes[2].get_legend().get_texts())
    finally:
        for f in figs.values():
            plt.close(f)


# -- spinning systems ----------------------------------------------------------------------------


def _spin_scene(**spin) -> dict:
    return {"name": "spin", "duration": "2 spins", "effects": {"central_gravity": {}},
            "bodies": {"m0": {"mass": "1000 kg"}, "mf": {"mass": "100 kg"}},
            "orbit": {"elements": {"altitude": "1000 km", "e": 0.0, "i": "30 deg"}, "motion": "translating", "spin": spin},
            "tethers": {"main": {"from": "m0", "to": "mf", "rods": 4, "length": "1 km", "EA": "1e6 N", "mass": "5 kg",
                                 "initial": {"shape": "straight", "theta": "20 deg"}}},
            "integrator": {"rtol": 1e-10, "atol": 1e-10}, "output": {"count": 5}}  # fmt: skip


def test_a_spin_in_the_initial_layout_and_a_duration_in_spins():
    from tetherlab.diagnostics import orbital_frame

    scene = Scene.from_dict(_spin_scene(rate="1 deg/s"))
    assert scene.duration_seconds() == pytest.approx(720.0, rel=1e-15)  # 2 turns of 1 deg/s
    assert Scene.from_dict(scene.to_dict()) == scene
    res = tetherlab.simulate(scene.replace(duration="20 s"), progress=False)
    ts = res.timeseries.iloc[0]
    pos = [np.array([ts[f"{p}.{a}_m"] for a in "xyz"]) for p in ("m0", "mf")]
    vel = [np.array([ts[f"{p}.v{a}_m_s"] for a in "xyz"]) for p in ("m0", "mf")]
    pos += [np.array([ts[f"main.node{j}.{a}_m"] for a in "xyz"]) for j in range(5)]
    m = np.array([1000.0, 100.0])
    rc = (m[0] * pos[0] + m[1] * pos[1]) / m.sum()  # the rods' mass shifts it; the relation below holds for any point
    vc = (m[0] * vel[0] + m[1] * vel[1]) / m.sum()
    frame = orbital_frame(rc[None], vc[None])[0]
    w = math.radians(1.0) * frame[2]  # about the orbit normal (default axis and frame)
    # translating motion + spin: every body's velocity is v_ref + w x (r - r_ref), so the
    # relative velocity of the two end bodies is w x their separation (rigid rotation)
    dv = vel[1] - vel[0]
    expected = np.cross(w, pos[1] - pos[0])
    assert np.linalg.norm(dv - expected) < 1e-9 * np.linalg.norm(expected)  # m/s, round-off of 1 km x 1 deg/s
    # inertial axis: the same rate about inertial z
    Scene.from_dict(_spin_scene(rate="-2 deg/s", axis=[0, 0, 1], frame="inertial"))


@pytest.mark.parametrize("spin, key, fragment", [
    ({}, "orbit.spin.rate", "missing"),
    ({"rate": "0 deg/s"}, "orbit.spin.rate", "non-zero"),
    ({"rate": "1 deg/s", "axis": [0, 0, 0]}, "orbit.spin.axis", "non-zero"),
    ({"rate": "1 kg"}, "orbit.spin.rate", "angular rate"),
])  # fmt: skip
def test_bad_spins_are_refused_naming_the_key(spin, key, fragment):
    with pytest.raises(SceneError) as info:
        Scene.from_dict(_spin_scene(**spin))
    assert info.value.key == key and fragment in str(info.value)


def test_n_spins_without_a_spin_is_refused():
    d = _spin_scene(rate="1 deg/s")
    del d["orbit"]["spin"]
    with pytest.raises(SceneError) as info:
        Scene.from_dict(d)
    assert info.value.key == "duration" and "[orbit] spin" in str(info.value)


# -- the verification report, for a reader who was not there -------------------------------------


def test_every_gate_has_evidence_outside_the_gate_table():
    import tomllib

    from tetherlab.verify.sections import gate_section

    gates = tomllib.loads((ROOT / "references" / "gates.toml").read_text())
    home = {g: gate_section(g) for g in gates if isinstance(gates[g], dict)}
    assert [g for g, sec in home.items() if sec == "gates"] == []


def test_report_tables_leave_out_nan_columns_and_say_so():
    from tetherlab.report import _unit, table

    md = table([{"case": "n = 1", "days": 35.1, "paper": float("nan")}, {"case": "n = 4", "days": 35.2, "paper": "nan"}])
    assert "paper" not in md.splitlines()[0] and "| nan" not in md
    assert "left out, no value in any row: paper" in md
    assert _unit("1") == "ratio (no unit)" and _unit("m") == "m"
    # a column with a value in some rows keeps them; the rows without one read a dash
    md = table([{"case": "cowell", "ratio": float("nan")}, {"case": "dromo", "ratio": 0.5}])
    assert "| cowell | – |" in md and "| dromo | 0.5 |" in md and "nan" not in md


def test_the_fidelity_figure_shows_each_level_against_the_first(tmp_path, monkeypatch):
    import matplotlib.pyplot as plt

    from .helpers import forget_study, import_study

    fid = import_study("fidelity")
    drawn = {}
    monkeypatch.setattr(plt.Figure, "savefig", lambda self, path, **kw: drawn.setdefault("fig", self))
    t = np.linspace(0.0, 35.0, 200)
    series = [{"label": f"level {k}", "t_d": t * (1 + 0.01 * k), "alt_km": 1000.0 - 800.0 * t / 35.0} for k in range(3)]
    try:
        fid.plot(series, tmp_path / "f.png")
    finally:
        forget_study("fidelity")
    top, diff = drawn["fig"].axes
    assert top.get_ylabel() == "satellite altitude (km)" and diff.get_ylabel() == "altitude − level 0 (km)"
    assert len(diff.get_lines()) == 2 + 1  # levels 1 and 2, and the zero line
    # level 2 is 2 % slower: at t = 30 d it is 800 * 30/35 * (1 - 1/1.02) = 13.4 km higher
    line = diff.get_lines()[1]  # level 1, level 2, then the zero line
    x, y = line.get_xdata(), line.get_ydata()
    assert np.interp(30.0, x, y) == pytest.approx(800.0 * 30.0 / 35.0 * (1 - 1 / 1.02), rel=1e-3)
    plt.close(drawn["fig"])


def test_a_first_run_says_that_it_compiles(tmp_path, monkeypatch, caplog):
    import logging

    from tetherlab import _jit

    monkeypatch.setattr(_jit, "CACHE_DIR", tmp_path / "empty-cache")
    with caplog.at_level(logging.INFO, logger="tetherlab"):
        _jit.announce_compilation()
    assert "compiling the numerical kernels" in caplog.text and "once" in caplog.text
    caplog.clear()
    (tmp_path / "empty-cache").mkdir()
    (tmp_path / "empty-cache" / "k.nbi").write_text("")
    with caplog.at_level(logging.INFO, logger="tetherlab"):
        _jit.announce_compilation()
    assert caplog.text == ""  # a warm cache: nothing to say


def test_validate_with_a_probe_extrapolates_the_run_time(tmp_path, capsys, inplane_run):
    scene = tmp_path / "long.toml"
    scene.write_text((SCENES / "libration-inplane.toml").read_text().replace('duration = "10 orbits"', 'duration = "1000 orbits"'))
    assert main(["validate", str(scene), "--probe", "1"]) == 0
    out = capsys.readouterr().out
    probe = next(line for line in out.splitlines() if "probe:" in line)
    assert "s simulated per second" in probe and "would integrate in about" in probe


def test_warnings_from_parts_equal_warnings_from_the_whole_run():
    import pandas as pd

    from tetherlab.regime import check, check_parts

    t = np.linspace(0.0, 100.0, 101)
    ts = pd.DataFrame({"t_s": t, "main.rod1.strain": np.where(t > 40, -1e-3, 1e-3) * (1 + 0.01 * t),
                       "main.rod1.axial_force_N": np.where(t > 40, -5.0, 5.0) * (1 + 0.01 * t)})  # fmt: skip
    dg = pd.DataFrame({"t_s": t, "main.theta_rad": np.where(t > 70, 2.0, 0.1), "main.phi_rad": 0 * t})
    scene = {"tethers": {"main": {}}}
    whole = check(scene, ts, dg)
    parts = check_parts(scene, [(ts.iloc[a:a + 30], dg.iloc[a:a + 30]) for a in range(0, 101, 30)])
    assert whole == parts
    assert [w["kind"] for w in whole] == ["compression", "tumbling"]
    assert whole[0]["t_s"] == 41.0 and "at 60 of 101 outputs" in whole[0]["text"] and "10 N" in whole[0]["text"]
    assert whole[1]["t_s"] == 71.0


def test_the_summary_times_of_a_resumed_run_add_up_to_its_session(tmp_path, monkeypatch, capsys):
    import re
    import time

    from tetherlab.integrators import driver
    from tetherlab.runstore import Interrupted, run_to_dir

    from .test_runstore import PART_ROWS, _interrupt_on_call, _scene

    monkeypatch.setattr(driver, "_FIRST_CHUNK_STEPS", 16)
    monkeypatch.setattr(driver, "_MAX_CHUNK_GROWTH", 1)
    real = driver._call_kernel
    out = tmp_path / "o"
    _interrupt_on_call(monkeypatch, 6)
    with pytest.raises(Interrupted):
        run_to_dir(_scene(), out, progress=False, checkpoint_s=1e9, part_rows=PART_ROWS)
    monkeypatch.setattr(driver, "_call_kernel", real)
    t0 = time.perf_counter()
    assert main(["run", "--resume", str(out)]) == 0
    wall = time.perf_counter() - t0
    text = capsys.readouterr().out
    m = re.search(r"set-up ([\d.]+) s \+ compile ([\d.]+) s \+ integrate and write ([\d.]+) s = total ([\d.]+) s", text)
    assert m, text
    setup, comp, integ, total = map(float, m.groups())
    assert abs(setup + comp + integ - total) <= 0.015  # printed to 0.01 s each
    assert total <= wall + 0.01  # this session's time, not the interrupted session's as well
    assert "every session of this run so far" in text


def test_a_study_without_its_own_markdown_says_what_it_checks(tmp_path):
    from tetherlab.verify.studies import _summary_md

    md = _summary_md("deorbit", tmp_path)
    assert md.startswith("**What this study checks, against what:** The electrodynamic de-orbit of paper section 5")
    assert "``" not in md and ":func:" not in md and "PYTHONPATH" not in md


def test_shape_snapshots_of_a_spinning_tether_cover_one_turn_in_free_space_too():
    import pandas as pd

    from tetherlab.plots import _snapshot_rows

    # a 100 m tether spinning at 0.1 rad/s about z for 600 s (period 62.8 s), outputs every
    # 62.8 s / 1.0001: evenly spaced snapshots over the run would all show nearly the same phase
    t = np.arange(0.0, 600.0, 2 * np.pi / 0.1 / 1.0001 / 4)
    ts = pd.DataFrame({"t_s": t, "main.node0.x_m": 0 * t, "main.node0.y_m": 0 * t, "main.node0.z_m": 0 * t,
                       "main.node1.x_m": 100 * np.cos(0.1 * t), "main.node1.y_m": 100 * np.sin(0.1 * t),
                       "main.node1.z_m": 0 * t})  # fmt: skip
    dg = pd.DataFrame({"t_s": t, "main.theta_rad": np.full(len(t), np.nan)})  # free space: no orbit frame
    rows = _snapshot_rows(ts, dg, ["main"], count=4)
    phases = np.mod(0.1 * t[rows], 2 * np.pi)
    # one snapshot per quarter turn (to the output spacing): four different directions
    assert len(rows) == 4 and np.ptp(phases) > np.pi
    assert t[rows[-1]] < 2 * np.pi / 0.1  # within the first turn
