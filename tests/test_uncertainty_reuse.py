"""Parameter-only samples reuse a prepared model (tetherlab/uncertainty/reuse.py): bit for bit equal
to the full path, refused for keys that change the layout or the initial state; the epoch and the
initial libration angles as dispersed keys (docs/uncertainty.md)."""

from __future__ import annotations

import copy
import json
from pathlib import Path

import numpy as np
import pytest

from tetherlab.pipeline import integrate_prepared
from tetherlab.scene import load_scene
from tetherlab.sweep import scene_hash
from tetherlab.uncertainty import reuse
from tetherlab.uncertainty.reuse import ParameterSample, prepared, reuse_refusal
from tetherlab.uncertainty.runner import run_study, sample_inputs
from tetherlab.uncertainty.study import parse_study

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "studies" / "scenes" / "deorbit-ed.toml"
STUDY_PATH = ROOT / "studies" / "uncertainty" / "deorbit_verify.toml"
SHORT = {"duration": "1 d", "stop.altitude": "200000.0 m"}  # 16 orbits: the same kernels, a short run

STUDY = {
    "name": "reuse", "scene": "../scenes/deorbit-ed.toml", "summary": "tetherlab.uncertainty.summaries:deorbit_days",
    "quantities": ["deorbit_days"], "set": {"orbit.elements.a": "6778.137 km", "output.step": "1 d"},
    "sampling": {"method": "sobol", "samples": 2, "seed": 7},
    "dispersion": [
        {"key": "effects.electrodynamic.current", "dist": "normal", "mean": "2 A", "sd": "0.1 A"},
        {"key": "effects.electrodynamic.dipole_strength", "dist": "uniform", "low": "7.6e15 T m3",
         "high": "8.2e15 T m3"},
    ],
}


def _base():
    return load_scene(SCENE)


def _run(item, changes=SHORT):
    prep, p = prepared(item, changes)
    res, _ = integrate_prepared(prep, p, None)
    return prep, p, res


def test_parameter_sample_runs_bit_for_bit_as_the_full_scene():
    base = _base()
    values = (("effects.electrodynamic.current", "2.0731234567891 A"),
              ("effects.electrodynamic.dipole_strength", "7.912345678e+15 T m3"))
    sample = ParameterSample(base, scene_hash(base), values)
    reuse._CACHE.clear()
    prep_s, p_s, res_s = _run(sample)
    assert reuse.reuse_state()[sample.base_hash] is True  # the worker's check against the full path
    prep_f, p_f, res_f = _run(base.replace(**dict(values)))
    assert np.array_equal(p_s, p_f)
    assert np.array_equal(res_s.t, res_f.t) and np.array_equal(res_s.y, res_f.y)
    # the second sample of the same base reuses the prepared model (no second prepare)
    other = ParameterSample(base, sample.base_hash, ((values[0][0], "1.9 A"), values[1]))
    prep_o, p_o, res_o = _run(other)
    assert prep_o is prep_s and not np.array_equal(p_o, p_s)
    assert np.array_equal(res_o.y, _run(base.replace(**dict(other.values)))[2].y)


def test_repack_writes_only_the_changed_effect_slice():
    base = _base()
    sample = ParameterSample(base, "x", (("effects.electrodynamic.current", "4.0 A"),))
    reuse._CACHE.clear()
    prep, p = prepared(sample, SHORT)
    changed = np.flatnonzero(p != prep.model.p)
    from tetherlab.model.params import ParamView

    v = ParamView(p)
    e = [u.name for u in base.effects].index("electrodynamic")
    off = v.effect(e).par_offset
    assert changed.size >= 1 and np.all((changed >= off) & (changed < off + v.effect(e).n_par))


def test_a_key_wrongly_taken_for_a_parameter_falls_back_to_the_full_path():
    # a mass moves the relative equilibrium: were it re-packed as a parameter, the worker's check of
    # its first sample against the full path would see it and run the full path
    base = _base()
    values = (("bodies.end_mass.mass", "380.0 kg"),)
    sample = ParameterSample(base, "wrong", values)
    reuse._CACHE.clear()
    _prep, _p, res_s = _run(sample)
    assert reuse.reuse_state()["wrong"] is False
    assert np.array_equal(res_s.y, _run(base.replace(**dict(values)))[2].y)


@pytest.mark.parametrize("key, words", [
    ("bodies.end_mass.mass", "not a parameter"),
    ("tethers.main.rods", "not a parameter"),
    ("orbit.elements.a", "not a parameter"),
    ("effects.central_gravity.mu", "conservative"),
    ("effects.electrodynamic.field", "not a quantity"),
    ("effects.drag.cd", "not a parameter"),  # no drag effect in this scene
])
def test_reuse_is_refused_for_layout_and_state_keys(key, words):
    assert words in reuse_refusal(_base(), [key])


def test_reuse_is_refused_when_the_start_is_solved_under_every_effect():
    base = _base().replace(**{"orbit.motion": "quasi-static"})
    assert "quasi-static" in reuse_refusal(base, ["effects.electrodynamic.current"])
    assert reuse_refusal(_base(), ["effects.electrodynamic.current", "effects.electrodynamic.dipole_strength"]) is None


def test_study_with_parameter_samples_equals_the_full_path_and_extends_from_cache(tmp_path):
    # two de-orbits from 400 km (~0.5 s each): the reused and the full path give the same bits
    st = parse_study(copy.deepcopy(STUDY), STUDY_PATH)
    fast = run_study(st, tmp_path / "fast", workers=1, progress=False, figures=False, n_boot=50)
    full = run_study(st, tmp_path / "full", workers=1, progress=False, figures=False, n_boot=50, reuse=False)
    assert fast.path == "parameter-only" and full.path.startswith("full")
    assert json.loads((tmp_path / "fast" / "stats.json").read_text())["sample_path"] == "parameter-only"
    days = [r.summary["deorbit_days"] for r in fast.records]
    assert days == [r.summary["deorbit_days"] for r in full.records] and not fast.failed
    # docs/effects-electrodynamic.md 5: ~8.9 d from 400 km at 2 A, 8e15 T m3 (T ~ 1/(I K))
    assert all(7.5 < d < 10.5 for d in days)
    again = run_study(st, tmp_path / "fast", workers=1, progress=False, figures=False, n_boot=50)
    assert (again.n_run, again.n_cached) == (0, 2)


# ------------------------------------------------------------------------------------------
# The epoch and the initial libration angles as dispersed keys
# ------------------------------------------------------------------------------------------

EPOCH_STUDY = {
    "name": "epoch", "scene": "../scenes/deorbit-ed.toml",
    "summary": "tetherlab.uncertainty.summaries:closed_form_decay_days", "quantities": ["decay_days"],
    "set": {"epoch": "2026-01-01T00:00:00"}, "sampling": {"method": "mc", "samples": 400, "seed": 3},
    "dispersion": [{"key": "epoch", "dist": "normal", "mean": "2026-03-01T12:00:00", "sd": "30 d"}],
}


def test_epoch_disperses_as_a_date_about_its_mean():
    from astropy.time import Time

    st = parse_study(copy.deepcopy(EPOCH_STUDY), STUDY_PATH)
    dates = [x["epoch"] for x in sample_inputs(st)]
    jd = Time(dates, format="isot", scale="tdb").jd
    mean_jd = Time("2026-03-01T12:00:00", format="isot", scale="tdb").jd
    # 400 normal draws: the sample mean is within 4 standard errors (4 x 30 d / 20 = 6 d)
    assert abs(jd.mean() - mean_jd) < 6.0 and 25.0 < jd.std() < 35.0
    scene = st.base_scene().replace(epoch=dates[0])
    assert scene.epoch == dates[0]
    # uniform between two dates: every sample inside, written to the microsecond
    st = parse_study({**copy.deepcopy(EPOCH_STUDY), "dispersion": [
        {"key": "epoch", "dist": "uniform", "low": "2026-01-01T00:00:00", "high": "2026-01-11T00:00:00"}]},
        STUDY_PATH)
    dates = [x["epoch"] for x in sample_inputs(st, 50)]
    assert all("2026-01-01" <= d < "2026-01-11" for d in dates) and all(len(d.split(".")[1]) == 6 for d in dates)


@pytest.mark.parametrize("disp, words", [
    ({"dist": "normal", "mean": "2026-03-01T00:00:00", "sd": "30 kg"}, "a time"),
    ({"dist": "normal", "mean": "March 2026", "sd": "30 d"}, "ISO date"),
    ({"dist": "normal", "mean": "2026-03-01T00:00:00", "sd": "-3 d"}, "'sd' > 0"),
    ({"dist": "uniform", "low": "2026-03-01T00:00:00", "high": "2026-02-01T00:00:00"}, "low < high"),
    ({"dist": "lognormal", "median": "2026-03-01T00:00:00", "sigma_log": 0.1}, "for a date"),
])
def test_bad_epoch_dispersion_is_refused_naming_the_key(disp, words):
    data = {**copy.deepcopy(EPOCH_STUDY), "dispersion": [{"key": "epoch", **disp}]}
    with pytest.raises(ValueError) as err:
        parse_study(data, STUDY_PATH)
    assert "'epoch'" in str(err.value) and words in str(err.value), str(err.value)


def test_epoch_needs_a_base_epoch():
    data = {**copy.deepcopy(EPOCH_STUDY), "set": {}}
    with pytest.raises(ValueError, match="no such key"):
        parse_study(data, STUDY_PATH)


def test_libration_angles_disperse_on_an_equilibrium_scene():
    # deorbit-ed starts in its relative equilibrium on the default straight shape, which to_dict omits
    data = {**copy.deepcopy(STUDY), "summary": "tetherlab.uncertainty.summaries:closed_form_decay_days",
            "quantities": ["decay_days"], "sampling": {"method": "mc", "samples": 4, "seed": 1},
            "dispersion": [{"key": "tethers.main.initial.theta", "dist": "normal", "mean": "0 deg", "sd": "2 deg"},
                           {"key": "tethers.main.initial.phi", "dist": "uniform", "low": "-1 deg", "high": "1 deg"}]}
    st = parse_study(data, STUDY_PATH)
    assert st.base_scene().orbit.motion == "equilibrium"
    x = sample_inputs(st)[0]
    scene = st.base_scene().replace(**x)
    theta = scene.tethers[0].initial.theta_rad
    assert x["tethers.main.initial.theta"].endswith(" deg")  # in the dispersion's unit
    assert theta == pytest.approx(np.radians(float(x["tethers.main.initial.theta"].split()[0])), rel=1e-15)
    assert theta != 0.0
    from tetherlab.pipeline import prepare

    # the tilt reaches the initial state (the equilibrium solve keeps the laid-out direction)
    assert not np.array_equal(prepare(scene).y0, prepare(st.base_scene()).y0)
    # and a parameter-only reuse is refused for it (it moves the initial state)
    assert "not a parameter" in reuse_refusal(st.base_scene(), st.keys)


def test_bad_libration_dispersion_is_refused_naming_the_key():
    data = {**copy.deepcopy(STUDY), "dispersion": [
        {"key": "tethers.main.initial.theta", "dist": "normal", "mean": "0 kg", "sd": "2 deg"}]}
    with pytest.raises(ValueError) as err:
        parse_study(data, STUDY_PATH)
    assert "'tethers.main.initial.theta'" in str(err.value) and "dimension" in str(err.value)
    data["dispersion"] = [{"key": "tethers.mian.initial.theta", "dist": "normal", "mean": "0 deg", "sd": "2 deg"}]
    with pytest.raises(ValueError, match="no such key"):
        parse_study(data, STUDY_PATH)
