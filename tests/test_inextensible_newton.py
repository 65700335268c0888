"""RADAU5 on the inextensible hanging chain, end to end: the structured Newton matrix
(docs/inextensible.md 8, tether/newton_inextensible.py) against RADAU5's own dense one on the same
scene, through ``simulate``.  The Newton matrix changes how the stage equations are iterated, not
what they are, so the two runs must give the same first lateral frequency to within their
integration errors."""

from __future__ import annotations

import functools
import math

import pytest

import tetherlab
from tetherlab.oracles.continuum import fit_frequencies
from tetherlab.oracles.hanging_chain import continuum_frequencies
from tetherlab.pipeline import simulate
from tetherlab.tether import newton_solver
from tests.helpers import SCENES

N_RODS = 16
LENGTH_M = 10.0
DURATION_S = 35.0  # the scene's


@functools.lru_cache(maxsize=None)
def _omega(amplitude_m, rtol, request):
    """omega_1 (rad/s) fitted to the end mass's sideways motion, and the run's stats (cached: two
    tests read the same runs)."""
    s = tetherlab.load_scene(SCENES / "hanging-chain.toml").replace(**{
        "tethers.main.model": "inextensible", "tethers.main.rods": N_RODS, "integrator.method": "radau5",
        "integrator.rtol": rtol, "integrator.atol": rtol,
        "tethers.main.initial": {"shape": "equilibrium", "release": {"mode": 1, "amplitude": f"{amplitude_m} m"}},
    })  # fmt: skip
    with newton_solver._forcing(request):
        res = simulate(s, progress=False)
    assert res.ok, res.message
    ts = res.timeseries
    guesses = continuum_frequencies(LENGTH_M, 1.0, 0.5, 9.80665, count=3)
    w, _, _ = fit_frequencies(ts["t_s"].to_numpy(), ts["tip.x_m"].to_numpy(), guesses)
    return float(w[0]), res.stats


def _budget(amplitude_m, rtol, omega):
    """The two runs' integration errors in omega_1, relative.  Each rod's d carries a global error
    of about rtol (1 + |d|) (atol = rtol; RADAU5's tolerance map is calibrated so that the global
    error tracks rtol: Hairer and Wanner, IV.8), so the end mass, the sum of the n rods' 2 sqrt3 d,
    is off by at most rtol (2 sqrt3 n + L) metres; over the swing's amplitude A that is a phase
    error, which the fit over T = 35 s turns into d omega / omega = phase / (omega T).  Two runs,
    each within it."""
    tip_m = rtol * (2.0 * math.sqrt(3.0) * N_RODS + LENGTH_M)
    return 2.0 * tip_m / amplitude_m / (omega * DURATION_S)


@pytest.mark.parametrize(
    "amplitude_m, rtol",
    [
        (0.01, 1e-10),  # the small swing: one Jacobian serves the whole run
        (1.0, 1e-8),  # a 1 m swing: the chain's shape, hence its Jacobian, changes along the run
    ],
)
def test_structured_and_dense_newton_matrices_give_the_same_frequency(amplitude_m, rtol):
    w_s, st_s = _omega(amplitude_m, rtol, "structured")
    w_d, st_d = _omega(amplitude_m, rtol, "dense")
    assert st_s["newton_matrix"] == "structured"
    assert st_d["newton_matrix"].startswith("dense")
    # (measured: 1.8e-9 at 1 cm, 8.8e-12 at 1 m, against 3.5e-8 for both)
    assert abs(w_s / w_d - 1.0) <= _budget(amplitude_m, rtol, w_d)
    # the same discretisation: steps within a few per cent of each other (the Newton iterates
    # differ, so the error estimates and the step sequences differ slightly)
    assert abs(st_s["n_accepted"] - st_d["n_accepted"]) <= 0.1 * st_d["n_accepted"]
    assert st_s["n_newton_fail"] == 0


def test_structured_matrix_is_kept_across_steps_while_newton_converges():
    """Hairer's reuse rule on the structured matrix (newton_solver.INEXTENSIBLE_REFRESH): the small
    swing keeps one Jacobian for the whole run, the large one forms it again as the shape changes."""
    _, small = _omega(0.01, 1e-8, "structured")
    _, large = _omega(1.0, 1e-8, "structured")
    assert small["n_jac"] <= 2 < small["n_accepted"]
    assert 2 < large["n_jac"] < large["n_accepted"] / 2


def test_forcing_switch_is_scoped_and_checked():
    assert newton_solver._FORCED[0] is None
    with newton_solver._forcing("dense"):
        assert newton_solver._FORCED[0] == "dense"
    assert newton_solver._FORCED[0] is None
    with pytest.raises(ValueError, match="expected 'auto', 'dense' or 'structured'"):
        with newton_solver._forcing("sparse"):
            pass
