"""tetherlab.sweep: local processes and a local Dask cluster give the same records, an
interrupted sweep resumes without redoing finished runs, failures are recorded with their message."""

from __future__ import annotations

import json
import math

import pytest

from tetherlab.scene import Scene
from tetherlab.sweep import load_study, run_case, run_cases, run_sweep, scene_hash

# A tether-free Keplerian orbit: cheap (a fraction of an orbit, dop853), so the sweep machinery is
# what is tested.  The summary is compared against the two-body radius, which is conserved on a
# circular orbit (|r| = a exactly, up to the integration tolerance).
BASE = {
    "name": "sweep-test",
    "duration": "600 s",
    "central_body": {"name": "earth"},
    "effects": {"central_gravity": {}},
    "bodies": {"sat": {"mass": "10 kg", "elements": {"a": "7000 km", "e": 0.0}}},
    "integrator": {"method": "dop853", "rtol": 1e-10, "atol": 1e-10},
    "output": {"count": 11},
}


def orbit_radius(scene) -> dict:
    """Final orbital radius (m) of the body 'sat' (module level: picklable by name)."""
    from tetherlab.pipeline import simulate

    ts = simulate(scene, progress=False).timeseries
    r = math.sqrt(sum(ts[f"sat.{a}_m"].iloc[-1] ** 2 for a in "xyz"))
    return {"radius_m": r, "a_m": scene.bodies[0].elements.a_m}


STARTED: list[float] = []  # semi-major axes (m) in the order orbit_period started (workers=1: this process)


def orbit_period(scene) -> dict:
    """Keplerian period (s) of the body 'sat', without a run; logs the start order."""
    a = scene.bodies[0].elements.a_m
    STARTED.append(a)
    return {"period_s": 2 * math.pi * math.sqrt(a**3 / scene.central_body.mu_m3_s2)}


def failing_summary(scene) -> dict:
    raise RuntimeError(f"deliberate failure for {scene.name}")


def scenes(radii_km=(7000, 7100, 7200)):
    base = Scene.from_dict(BASE)
    return [base.replace(**{"bodies.sat.elements.a": f"{a} km"}) for a in radii_km]


def test_scene_hash_is_canonical():
    a, b = scenes((7000, 7000.000001))
    # the same scene built twice hashes alike; one digit of one value changes the hash
    assert scene_hash(a) == scene_hash(Scene.from_dict(a.to_dict()))
    assert scene_hash(a) != scene_hash(b)


def test_resume_after_interruption_runs_nothing_twice(tmp_path):
    sc = scenes()
    seen = []

    def interrupt(record):
        seen.append(record)
        raise KeyboardInterrupt  # the user presses Ctrl-C after the first finished run

    with pytest.raises(KeyboardInterrupt):
        run_sweep(sc, orbit_radius, cache_dir=tmp_path, workers=1, progress=False, on_record=interrupt)
    assert len(seen) == 1 and len(list(tmp_path.glob("*/*.json"))) == 1
    first = run_sweep(sc, orbit_radius, cache_dir=tmp_path, workers=1, progress=False)
    assert (first.n_cached, first.n_run) == (1, 2)  # only the two unfinished runs
    again = run_sweep(sc, orbit_radius, cache_dir=tmp_path, workers=1, progress=False)
    assert (again.n_cached, again.n_run) == (3, 0)
    assert [r.summary for r in again.records] == [r.summary for r in first.records]
    for r in again.records:
        # circular two-body orbit: |r| = a; rtol 1e-10 over 600 s -> well under 1 mm
        assert abs(r.summary["radius_m"] - r.summary["a_m"]) < 1e-3


def test_failed_runs_are_recorded_with_their_message(tmp_path):
    sc = scenes((7000,))
    bad = sc[0].replace(**{"bodies.sat.elements.a": "6600 km"})  # the summary fails, not the scene
    res = run_sweep([bad], failing_summary, cache_dir=tmp_path, workers=1, progress=False)
    (rec,) = res.records
    assert not rec.ok and rec.error == "RuntimeError: deliberate failure for sweep-test"
    # cached like a success (deterministic), with the message, so it is never lost
    cached = json.loads(next(tmp_path.glob("*/*.json")).read_text())
    assert cached["ok"] is False and "deliberate failure" in cached["error"]
    again = run_sweep([bad], failing_summary, cache_dir=tmp_path, workers=1, progress=False)
    assert again.n_run == 0 and again.records[0].error == rec.error
    retried = run_sweep([bad], failing_summary, cache_dir=tmp_path, workers=1, progress=False, retry_failed=True)
    assert retried.n_run == 1


def test_bad_summary_function_is_refused():
    with pytest.raises(ValueError, match="module-level function"):
        run_sweep(scenes((7000,)), lambda s: {}, progress=False)
    with pytest.raises(ValueError, match="workers"):
        run_sweep(scenes((7000,)), orbit_radius, workers=0, progress=False)


def test_processes_and_dask_give_identical_results(tmp_path):
    distributed = pytest.importorskip("distributed")
    sc = scenes()
    local = run_sweep(sc, orbit_radius, cache_dir=tmp_path / "p", workers=2, progress=False)
    with distributed.LocalCluster(n_workers=1, processes=False, threads_per_worker=1,
                                  dashboard_address=None) as cluster:
        dask = run_sweep(sc, orbit_radius, cache_dir=tmp_path / "d", scheduler=cluster.scheduler_address,
                         progress=False)
    assert local.n_run == dask.n_run == 3
    assert all(r.ok for r in local.records + dask.records)
    # same code, same inputs, same floats: bitwise equality
    assert [r.summary for r in local.records] == [r.summary for r in dask.records]


def _write_circular_orbit_scene(path):
    """A 600 s circular-orbit point-mass scene, the base of the study-file tests."""
    path.write_text(
        'name = "s"\nduration = "600 s"\n[central_body]\nname = "earth"\n[effects]\ncentral_gravity = {}\n'
        '[bodies.sat]\nmass = "1 kg"\nelements = { a = "7000 km", e = 0.0 }\n[output]\ncount = 3\n'
    )


def test_study_file_is_read_and_checked(tmp_path):
    _write_circular_orbit_scene(tmp_path / "s.toml")
    study = tmp_path / "study.toml"
    study.write_text(
        'name = "t"\n[[case]]\nid = "r"\nscene = "s.toml"\nsummary = "tests.test_sweep:orbit_radius"\n'
        '[case.grid]\n"bodies.sat.elements.a" = ["7000 km", "8000 km"]\n"integrator.rtol" = [1e-8, 1e-9]\n'
    )
    st = load_study(study)
    sc, points = st.cases[0].scenes()
    assert len(sc) == 4 and points[3] == {"bodies.sat.elements.a": "8000 km", "integrator.rtol": 1e-9}
    assert sc[3].bodies[0].elements.a_m == 8.0e6 and sc[3].integrator.rtol == 1e-9
    study.write_text('name = "t"\n[[case]]\nid = "r"\nscene = "s.toml"\nsummary = 3\n')
    with pytest.raises(ValueError, match="'summary' must be a string"):
        load_study(study)


def test_several_cases_run_as_one_sweep_longest_first(tmp_path):
    _write_circular_orbit_scene(tmp_path / "s.toml")
    study = tmp_path / "study.toml"
    study.write_text(
        'name = "t"\n'
        '[[case]]\nid = "radius"\nscene = "s.toml"\nsummary = "tests.test_sweep:orbit_radius"\n'
        '[case.grid]\n"bodies.sat.elements.a" = ["7000 km", "7100 km"]\n'
        '[[case]]\nid = "period"\nscene = "s.toml"\nsummary = "tests.test_sweep:orbit_period"\n'
        '[case.grid]\n"bodies.sat.elements.a" = ["7000 km", "7200 km", "7100 km"]\n'
    )
    st = load_study(study)

    def km(point):
        return float(point["bodies.sat.elements.a"].split()[0])

    STARTED.clear()
    res = run_cases(st, None, tmp_path / "out", workers=1, progress=False, first=lambda case, p: km(p),
                    filter_point=lambda case, p: case.id != "radius" or km(p) < 7050)
    # started by decreasing cost estimate across cases; each case's records in its grid order
    assert STARTED == [7.2e6, 7.1e6, 7.0e6]
    assert [r.params["bodies.sat.elements.a"] for r in res["period"].records] == ["7000 km", "7200 km", "7100 km"]
    assert [r.label for r in res["radius"].records] == ["bodies.sat.elements.a=7000 km"]
    assert abs(res["radius"].records[0].summary["radius_m"] - 7.0e6) < 1e-3
    assert res["period"].records[1].summary["period_s"] > res["period"].records[2].summary["period_s"]
    assert (res["period"].n_run, res["radius"].n_run) == (3, 1)
    assert (tmp_path / "out" / "period.csv").read_text().count("\n") == 4  # header and 3 rows
    # one case through the same cache: nothing runs again
    again = run_case(st, st.cases[1], tmp_path / "out", workers=1, progress=False)
    assert (again.n_run, again.n_cached) == (0, 3)
    assert [r.summary for r in again.records] == [r.summary for r in res["period"].records]


def test_one_summary_per_scene_must_match_the_scenes():
    with pytest.raises(ValueError, match="one per scene"):
        run_sweep(scenes((7000, 7100)), [orbit_radius], progress=False)
