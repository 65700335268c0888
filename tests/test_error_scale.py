"""integrator.error_scale (docs/integrators.md section 15): the key's validation, the default's
tolerance vector unchanged, and "tether" on the ringing start of the hanging chain.

The case: studies/scenes/hanging-chain-placed.toml (10 m, 1 kg, EA = 1e7 N, 0.5 kg end mass held
at the unstretched length 1 % off the vertical, released: the axial modes ring), 32 rods,
RADAU5 at rtol = atol = 1e-8.

Budget for the lateral answer: the rods' model error in the first lateral frequency at n = 32 is
9e-6 relative against the Bessel solution (order 2 in 1/n, docs/hanging-chain.md); the choice of
error scale must stay invisible next to it, so it may move the frequency by at most a tenth of
that, 1e-6 relative.  Over a time t that is a phase of 1e-6 * omega * t and, on the end mass's
sideways amplitude A = 0.1 m (1 % of 10 m), a sideways position difference of at most
A * 1e-6 * omega * t.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import tetherlab
from tetherlab.errors import SceneError
from tetherlab.oracles.continuum import fit_frequencies
from tetherlab.oracles.hanging_chain import continuum_frequencies
from tetherlab.pipeline import prepare
from tetherlab.system import tether_error_floor, tolerance_scales
from tests.helpers import SCENES

L_M, MASS_KG, TIP_KG, G = 10.0, 1.0, 0.5, 9.80665
SQ3 = math.sqrt(3.0)
AMPLITUDE_M = 0.1  # the end mass's placement off the vertical: 1 % of 10 m
FREQ_BUDGET = 1e-6  # relative: a tenth of the rods' model error at n = 32 (module docstring)
# first lateral mode of the continuum with the tip mass (Bessel solution; the oracle's value)
OMEGA_1 = continuum_frequencies(L_M, MASS_KG, TIP_KG, G, count=1)[0]


def _chain(n: int, scale: str | None, duration: str):
    sc = tetherlab.load_scene(SCENES / "hanging-chain-placed.toml")
    changes = {"tethers.main.rods": n, "duration": duration}
    if scale is not None:
        changes["integrator.error_scale"] = scale
    return sc.replace(**changes)


# --- the key ---------------------------------------------------------------------------------


@pytest.mark.parametrize("value, got", [("whole", "'whole'"), (1, "1"), ("Tether", "'Tether'")])
def test_error_scale_rejects_anything_but_rod_or_tether(value, got):
    sc = tetherlab.load_scene(SCENES / "hanging-chain-placed.toml")
    with pytest.raises(SceneError) as e:
        sc.replace(**{"integrator.error_scale": value})
    msg = str(e.value)
    assert "integrator.error_scale" in msg
    assert "'rod', 'tether'" in msg
    assert got in msg


def test_error_scale_defaults_to_rod_and_round_trips():
    sc = tetherlab.load_scene(SCENES / "hanging-chain-placed.toml")
    assert sc.integrator.error_scale == "rod"
    teth = sc.replace(**{"integrator.error_scale": "tether"})
    assert teth.integrator.error_scale == "tether"
    assert teth.to_dict()["integrator"]["error_scale"] == "tether"
    assert "error_scale" not in sc.to_dict()["integrator"]  # the default is not written
    assert type(teth).from_dict(teth.to_dict()) == teth


# --- the tolerance vector --------------------------------------------------------------------


def test_default_and_rod_leave_the_tolerance_vector_bit_identical():
    base = _chain(8, None, "1 s")
    prep = prepare(base)
    expected = base.integrator.atol * tolerance_scales(prep.model, L_M, 1.0)
    assert np.array_equal(prep.atol, expected)  # bit for bit, not to a tolerance
    assert np.array_equal(prepare(_chain(8, "rod", "1 s")).atol, prep.atol)


def test_tether_adds_rtol_times_the_tether_half_separation_to_rods_only():
    n = 8
    rod = prepare(_chain(n, "rod", "1 s"))
    teth = prepare(_chain(n, "tether", "1 s"))
    lay = rod.model.state
    rtol = 1e-8  # the scene's
    extra = teth.atol - rod.atol
    floor = tether_error_floor(rod.model, 1.0)
    for g in range(n):
        # L/(2 sqrt 3) of the whole 10 m tether; the time unit is 1 s in a surface frame
        assert np.allclose(extra[lay.rod(g)], rtol * L_M / (2 * SQ3), rtol=1e-12, atol=0)
        assert np.allclose(floor[lay.rod(g)], L_M / (2 * SQ3), rtol=1e-12, atol=0)
    rods = np.zeros(lay.size, bool)
    for g in range(n):
        rods[lay.rod(g)] = True
    rates = np.zeros(lay.size, bool)
    rates[lay.qd] = rods[lay.q]
    assert np.allclose(extra[rates], rtol * L_M / (2 * SQ3), rtol=1e-12, atol=0)
    others = ~(rods | rates)
    assert np.count_nonzero(others) > 0
    assert np.array_equal(teth.atol[others], rod.atol[others])  # root and everything else untouched


# --- the ringing start -----------------------------------------------------------------------


def test_tether_scale_takes_several_times_fewer_steps_on_the_ringing_start():
    t_s = 3.5  # a little over half a lateral period: the rod scale's steps are already ~ 30 000
    runs = {s: tetherlab.simulate(_chain(32, s, f"{t_s} s"), progress=False) for s in ("rod", "tether")}
    steps = {s: r.stats["n_accepted"] for s, r in runs.items()}
    assert steps["tether"] * 5 <= steps["rod"], steps
    x = {s: r.timeseries["tip.x_m"].to_numpy() for s, r in runs.items()}
    # the sideways position, the lateral mode's answer, within the frequency budget's phase
    bound_m = AMPLITUDE_M * FREQ_BUDGET * OMEGA_1 * t_s
    assert np.max(np.abs(x["tether"] - x["rod"])) <= bound_m


def test_negative_control_a_loose_tolerance_breaks_the_sideways_bound():
    # the bound above must be able to fail: rtol = atol = 1e-4 on the tether scale (ten thousand
    # times looser) moves the sideways position beyond it (measured: 15 times the bound)
    t_s = 3.5
    loose = _chain(32, "tether", f"{t_s} s").replace(**{"integrator.rtol": 1e-4, "integrator.atol": 1e-4})
    ref = tetherlab.simulate(_chain(32, "tether", f"{t_s} s"), progress=False)
    bad = tetherlab.simulate(loose, progress=False)
    bound_m = AMPLITUDE_M * FREQ_BUDGET * OMEGA_1 * t_s
    diff = np.max(np.abs(bad.timeseries["tip.x_m"].to_numpy() - ref.timeseries["tip.x_m"].to_numpy()))
    assert diff > bound_m


@pytest.mark.slow
def test_tether_scale_keeps_the_lateral_frequency_within_budget_over_35_s():
    runs = {s: tetherlab.simulate(_chain(32, s, "35 s"), progress=False) for s in ("rod", "tether")}
    w = {}
    for s, r in runs.items():
        ts = r.timeseries
        w[s] = fit_frequencies(ts["t_s"].to_numpy(), ts["tip.x_m"].to_numpy(), [OMEGA_1])[0][0]
    assert runs["tether"].stats["n_accepted"] * 5 <= runs["rod"].stats["n_accepted"]
    assert abs(w["tether"] - w["rod"]) / w["rod"] <= FREQ_BUDGET
    # and both are the rods' model (9e-6 off Bessel at n = 32), not something else
    assert abs(w["tether"] - OMEGA_1) / OMEGA_1 <= 2e-5


def test_each_tether_gets_its_own_length():
    # studies/scenes/chain3.toml: t1 of 2 km in 4 rods, then t2 of 1 km in 4 rods (scene file)
    sc = tetherlab.load_scene(SCENES / "chain3.toml").replace(**{"integrator.error_scale": "tether"})
    prep = prepare(sc)
    lay = prep.model.state
    floor = tether_error_floor(prep.model, 1.0)
    for g, whole_m in [(0, 2000.0), (3, 2000.0), (4, 1000.0), (7, 1000.0)]:
        assert np.allclose(floor[lay.rod(g)], whole_m / (2 * SQ3), rtol=1e-9, atol=0)
    # the run's atol: the scene's rtol times the floor on top of the rod scale (orbit time unit)
    base = prepare(sc.replace(**{"integrator.error_scale": "rod"}))
    t_unit = base.atol[lay.rod(0)][0] / base.atol[lay.qd][3]  # d_1's scale over its rate's: T_u
    expected = base.atol + sc.integrator.rtol * tether_error_floor(prep.model, t_unit)
    assert np.allclose(prep.atol, expected, rtol=1e-12, atol=0)


def test_validate_names_the_tether_scale_and_not_the_default(tmp_path, capsys):
    from tetherlab.cli import main

    text = (SCENES / "hanging-chain-placed.toml").read_text()
    assert main(["validate", str(SCENES / "hanging-chain-placed.toml")]) == 0
    assert "error scale" not in capsys.readouterr().out
    path = tmp_path / "tether.toml"
    path.write_text(text.replace('method = "radau5"', 'method = "radau5"\nerror_scale = "tether"'))
    assert main(["validate", str(path)]) == 0
    assert "error scale tether" in capsys.readouterr().out
    path.write_text(text.replace('method = "radau5"', 'method = "radau5"\nerror_scale = "rods"'))
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err
    assert "integrator.error_scale" in err and "'rods'" in err
