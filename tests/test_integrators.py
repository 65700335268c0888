"""Tests of tetherlab.integrators: tableaus, orders, accuracy, dense output, stiffness, failures,
continuation, the scipy backend and input validation.

Every expected value has its source in a comment: analytic solutions (harmonic oscillator, Kepler's
equation), the theoretical order of the method, or scipy's independent implementation.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from tetherlab._jit import rhs_cfunc
from tetherlab.integrators import (
    TableauError,
    check_tableau,
    dop853_run,
    integrate,
    radau5_core,
    radau5_run,
    radau5_workspace,
    tableau,
    vern9_run,
    warm_up,
)
from tetherlab.integrators.radau5 import lu_factor, lu_solve


# ------------------------------------------------------------------------------------------------
# test problems (cfuncs with the kernel ABI)
# ------------------------------------------------------------------------------------------------
@rhs_cfunc
def osc(t, y, dydt, p):
    # y'' = -y  ->  y = cos t, y' = -sin t for y(0) = (1, 0).
    dydt[0] = y[1]
    dydt[1] = -y[0]
    return 0


@rhs_cfunc
def kepler(t, y, dydt, p):
    # Planar two-body problem with mu = 1: r'' = -r/|r|^3.
    r2 = y[0] * y[0] + y[1] * y[1]
    r3 = r2 * math.sqrt(r2)
    dydt[0] = y[2]
    dydt[1] = y[3]
    dydt[2] = -y[0] / r3
    dydt[3] = -y[1] / r3
    return 0


@rhs_cfunc
def vdp(t, y, dydt, p):
    # Van der Pol, x'' = mu (1 - x^2) x' - x, mu = p[0] (Hairer & Wanner II, IV.1 use the same
    # problem, rescaled, as their standard stiff test).
    dydt[0] = y[1]
    dydt[1] = p[0] * (1.0 - y[0] * y[0]) * y[1] - y[0]
    return 0


@rhs_cfunc
def osc_fails_after_1p5(t, y, dydt, p):
    # Model failure (e.g. a rod collapsed) from t = 1.5 on: status code 7.
    if t > 1.5:
        return 7
    dydt[0] = y[1]
    dydt[1] = -y[0]
    return 0


@rhs_cfunc
def osc_nan_after_1p5(t, y, dydt, p):
    # A model that produces NaN (e.g. sqrt of a negative) from t = 1.5 on, without a status.
    dydt[0] = y[1]
    dydt[1] = -y[0] if t <= 1.5 else math.nan
    return 0


E = 0.5  # Kepler eccentricity
Y0_KEPLER = np.array([1.0 - E, 0.0, 0.0, math.sqrt((1.0 + E) / (1.0 - E))])  # pericenter, a = 1
PERIOD = 2.0 * math.pi  # a = 1, mu = 1: T = 2 pi sqrt(a^3/mu)
NO_P = np.zeros(1)


def kepler_exact(t):
    """Kepler orbit (a = 1, mu = 1, e = E, pericenter at t = 0) at the times t.

    Source: Kepler's equation M = E_a - e sin E_a with mean anomaly M = n t, n = 1, solved by
    Newton's method to machine precision; x = cos E_a - e, y = sqrt(1-e^2) sin E_a, and the
    velocity from dE_a/dt = n / (1 - e cos E_a).
    """
    t = np.atleast_1d(np.asarray(t, dtype=float))
    M = t.copy()
    ea = M + E * np.sin(M)
    for _ in range(50):
        d = (ea - E * np.sin(ea) - M) / (1.0 - E * np.cos(ea))
        ea = ea - d
        if np.max(np.abs(d)) < 1e-16:
            break
    b = math.sqrt(1.0 - E * E)
    edot = 1.0 / (1.0 - E * np.cos(ea))
    return np.stack(
        [np.cos(ea) - E, b * np.sin(ea), -np.sin(ea) * edot, b * np.cos(ea) * edot], axis=1
    )


def osc_exact(t):
    t = np.atleast_1d(np.asarray(t, dtype=float))
    return np.stack([np.cos(t), -np.sin(t)], axis=1)


def run_kernel(kernel, rhs, t0, y0, t_out, rtol, atol, h=0.0, h_max=0.0, max_steps=10**6,
               fixed_step=False, p=NO_P):  # fmt: skip
    y = np.array(y0, dtype=float)
    t_out = np.asarray(t_out, dtype=float)
    y_out = np.full((t_out.size, y.size), -999.0)  # sentinel: rows never written stay -999
    stats = np.zeros(8, dtype=np.int64)
    atol = np.full(y.size, float(atol))
    res = kernel(rhs, t0, y, t_out, p, rtol, atol, h, h_max, max_steps, y_out, stats, fixed_step)
    return res, y, y_out, stats


KERNELS = {"dop853": dop853_run, "vern9": vern9_run, "radau5": radau5_run}


# ------------------------------------------------------------------------------------------------
# tableaus
# ------------------------------------------------------------------------------------------------
def test_tableaus_pass_their_checks():
    # The import already ran them; run again explicitly so a regression shows here by name.
    tableau._check_dop853()
    tableau._check_vern9()
    tableau._check_radau()
    check_tableau("DOP853", tableau.DOP_A, tableau.DOP_B, tableau.DOP_C, order=8)
    check_tableau("Radau IIA", tableau.RADAU_A, tableau.RADAU_B, tableau.RADAU_C, order=5)


def test_broken_tableaus_fail_the_checker():
    a, b, c = tableau.RADAU_A.copy(), tableau.RADAU_B.copy(), tableau.RADAU_C.copy()
    bad_a = a.copy()
    bad_a[0, 1] += 1e-9  # one wrong digit in A: row sum != c
    with pytest.raises(TableauError, match="row 0"):
        check_tableau("broken", bad_a, b, c)
    bad_b = b.copy()
    bad_b[0] += 1e-9  # sum(b) != 1
    with pytest.raises(TableauError, match="sum"):
        check_tableau("broken", a, bad_b, c)
    bad_b2 = b.copy()
    bad_b2[0] += 1e-9
    bad_b2[1] -= 1e-9  # sum(b) still 1, but the quadrature is no longer of order 5
    with pytest.raises(TableauError, match="expected 1/2"):
        check_tableau("broken", a, bad_b2, c, order=5)
    dop_b = tableau.DOP_B.copy()
    dop_b[[5, 6]] = dop_b[[6, 5]]  # two weights swapped: sum(b) = 1 but order 8 lost
    with pytest.raises(TableauError):
        check_tableau("broken", tableau.DOP_A, dop_b, tableau.DOP_C, order=8)


def test_lu_matches_numpy_real_and_complex():
    rng = np.random.default_rng(1)
    for dtype in (np.float64, np.complex128):
        a = rng.standard_normal((7, 7)).astype(dtype)
        if dtype == np.complex128:
            a = a + 1j * rng.standard_normal((7, 7))
        a[0, 0] = 0.0  # forces a pivot swap
        b = rng.standard_normal(7).astype(dtype)
        lu = a.copy()
        piv = np.zeros(7, dtype=np.int64)
        assert lu_factor(lu, piv) == 0
        x = b.copy()
        lu_solve(lu, piv, x)
        # Reference: LAPACK via numpy.linalg.solve.
        np.testing.assert_allclose(x, np.linalg.solve(a, b), rtol=1e-12, atol=1e-12)
    singular = np.ones((3, 3))
    assert lu_factor(singular, np.zeros(3, dtype=np.int64)) != 0


# ------------------------------------------------------------------------------------------------
# order of convergence (fixed steps)
# ------------------------------------------------------------------------------------------------
def _fixed_step_errors(kernel, steps, rtol):
    errs = []
    for n_steps in steps:
        (status, t_end, _, _), y, _, stats = run_kernel(
            kernel, osc, 0.0, [1.0, 0.0], [math.pi], rtol, rtol, h=math.pi / n_steps,
            fixed_step=True,
        )  # fmt: skip
        assert status == 0 and t_end == math.pi
        assert stats[0] == n_steps and stats[1] == 0  # exactly n steps, none rejected
        errs.append(np.max(np.abs(y - [-1.0, 0.0])))  # exact: (cos pi, -sin pi)
    return np.array(errs)


def test_order_dop853_is_8():
    # Errors from 3e-8 (4 steps) down to 4e-12 (12 steps): above round-off (1e-15) and in the
    # asymptotic regime (successive ratios already match h^8); 16+ steps hit round-off.
    steps = np.array([4, 5, 6, 8, 10, 12])
    errs = _fixed_step_errors(dop853_run, steps, 1e-10)
    slope = np.polyfit(np.log(steps), np.log(errs), 1)[0]
    assert abs(-slope - 8.0) < 0.5, (slope, errs)  # DOP853 has order 8 (Hairer I, II.10)


def test_order_vern9_is_9():
    # Verner's pair has order 9 (every tree condition: tests/test_vern9.py); here the slope of
    # the fixed-step error.  Errors 4.8e-12 (8 steps) .. 2.7e-14 (14 steps), above round-off
    # (1e-15).  Local slopes fall from 9.5 (6 steps) to 9.2 (14): a large order-10 term, so the
    # coarse steps are left out.  A lost order (8) or a wrong digit (order <= 8) fails by > 1.
    steps = np.array([8, 10, 12, 14])
    errs = _fixed_step_errors(vern9_run, steps, 1e-10)
    slope = np.polyfit(np.log(steps), np.log(errs), 1)[0]
    assert abs(-slope - 9.0) < 0.5, (slope, errs)


def test_order_radau5_is_5():
    # Radau IIA with s = 3 has order 2s - 1 = 5 at step ends (Hairer & Wanner II, IV.5).  Errors
    # 4e-6 .. 4e-12 for 8..128 steps; rtol 1e-13 makes the Newton tolerance negligible there.
    steps = np.array([8, 16, 32, 64, 128])
    errs = _fixed_step_errors(radau5_run, steps, 1e-13)
    slope = np.polyfit(np.log(steps), np.log(errs), 1)[0]
    assert abs(-slope - 5.0) < 0.5, (slope, errs)


# ------------------------------------------------------------------------------------------------
# adaptive accuracy and dense output
# ------------------------------------------------------------------------------------------------
def _tol_units(y, exact, rtol, atol):
    return np.max(np.abs(y - exact) / (atol + rtol * np.abs(exact)))


def _rms_units(y, exact, rtol, atol):
    """Largest over the output times of Hairer's error norm, RMS_i |err_i|/(atol + rtol |y_i|):
    the quantity the step-size controller works with."""
    w = (y - exact) / (atol + rtol * np.abs(exact))
    return np.max(np.sqrt(np.mean(w * w, axis=1)))


@pytest.mark.parametrize("method", ["dop853", "vern9"])
@pytest.mark.parametrize("rtol", [1e-6, 1e-8, 1e-10])
def test_explicit_kepler_error_in_tolerance_units(method, rtol):
    # The controller bounds the *local* error of each step by ~1 tolerance unit; over one orbit
    # (15-50 steps) the global error is the propagated sum, and on the e = 0.5 orbit an error in
    # energy becomes a phase error that grows along the orbit (~3 pi da/a per revolution).
    # Measured 2.9, 7.6, 25.6 units; scipy's DOP853 gives the same numbers (and both reach ~70 at
    # rtol 1e-12: DOP853's tolerance proportionality is not perfect), so 50 is a bound with
    # margin that a broken controller, error norm or tableau (errors >> 100 units) exceeds.
    # Vern9 (the error of its order-8 embedded solution controls an order-9 one, safety 0.8)
    # measured 0.19, 1.05, 0.73 units.
    t_out = np.linspace(0.0, PERIOD, 9)
    (status, _, _, _), _, y_out, stats = run_kernel(KERNELS[method], kepler, 0.0, Y0_KEPLER, t_out,
                                                    rtol, rtol)  # fmt: skip
    assert status == 0
    units = _rms_units(y_out, kepler_exact(t_out), rtol, rtol)
    assert units < 50.0, units
    assert stats[0] < 200  # an adaptive run, not a brute-force one


@pytest.mark.parametrize("rtol", [1e-5, 1e-7])
def test_radau5_kepler_error_in_tolerance_units(rtol):
    # RADAU5 maps the tolerance to rtol' = 0.1 rtol^(2/3) (Hairer's calibration for stiff
    # problems), so on this non-stiff orbit the error is measured in units of the internal
    # tolerance; the same factor-50 argument as for DOP853 applies.  (Measured ~3 units.)
    rtol_i = 0.1 * rtol ** (2.0 / 3.0)
    t_out = np.linspace(0.0, PERIOD, 9)
    (status, _, _, _), _, y_out, _ = run_kernel(radau5_run, kepler, 0.0, Y0_KEPLER, t_out, rtol,
                                                rtol)  # fmt: skip
    assert status == 0
    units = _tol_units(y_out, kepler_exact(t_out), rtol_i, rtol_i)
    assert units < 50.0, units


@pytest.mark.parametrize("method,rtol", [("dop853", 1e-10), ("vern9", 1e-10), ("radau5", 1e-8)])
def test_dense_output_matches_kepler_between_steps(method, rtol):
    t_out = np.linspace(0.0, PERIOD, 2001)
    (status, _, _, _), _, y_out, stats = run_kernel(KERNELS[method], kepler, 0.0, Y0_KEPLER,
                                                    t_out, rtol, rtol)  # fmt: skip
    assert status == 0
    # Far more outputs than steps: nearly all outputs are interior points of a step.
    assert stats[0] * 10 < t_out.size
    tol = 0.1 * rtol ** (2.0 / 3.0) if method == "radau5" else rtol
    err_dense = _tol_units(y_out, kepler_exact(t_out), tol, tol)
    # Interpolation error (7th-order interpolant / collocation polynomial) must stay at the level
    # of the integration error itself, not orders above it.
    assert err_dense < 50.0, err_dense


def test_output_at_start_and_repeated_times():
    t_out = np.array([0.0, 0.0, 0.5, 0.5, 1.0])
    for kernel in KERNELS.values():
        (status, t_end, _, n_done), y, y_out, _ = run_kernel(kernel, osc, 0.0, [1.0, 0.0], t_out,
                                                             1e-10, 1e-10)  # fmt: skip
        assert status == 0 and n_done == 5 and t_end == 1.0
        assert np.array_equal(y_out[0], [1.0, 0.0]) and np.array_equal(y_out[1], [1.0, 0.0])
        assert np.array_equal(y_out[2], y_out[3])
        assert np.array_equal(y_out[4], y)  # the end point is the state itself
        np.testing.assert_allclose(y_out, osc_exact(t_out), atol=1e-8)  # y = cos t


# ------------------------------------------------------------------------------------------------
# stiff problem
# ------------------------------------------------------------------------------------------------
def test_van_der_pol_stiff():
    mu = np.array([1000.0])
    t_out = np.linspace(0.0, 2000.0, 201)  # one relaxation period is ~(3 - 2 ln 2) mu = 1614
    y0 = [2.0, 0.0]
    res = integrate("radau5", vdp, 0.0, y0, t_out, mu, 1e-8, 1e-8)
    assert res.status == 0, res.message
    st = res.stats
    # Reference: scipy's independent Radau IIA implementation on the same compiled rhs.
    ref = integrate("scipy:Radau", vdp, 0.0, y0, t_out, mu, 1e-8, 1e-8)
    assert ref.status == 0, ref.message
    assert np.all(np.abs(res.y - ref.y) <= 1e-5 * (1.0 + np.abs(ref.y)))
    # Modest step count: no more than scipy's Radau at the same rtol (measured 710 vs 1853;
    # fewer because RADAU5's tolerance map loosens the internal rtol, see radau5.py).
    assert st["n_accepted"] <= ref.stats["n_accepted"], (st, ref.stats)
    # Jacobians and LUs are reused across steps (fewer than steps: measured 362 and 594 for
    # 710 steps), and every fresh Jacobian brings a new LU.
    assert 0 < st["n_jac"] < st["n_accepted"], st
    assert st["n_jac"] <= st["n_lu"] < st["n_accepted"] + st["n_rejected"], st
    # DOP853 is stability-limited (h lambda must stay in its bounded stability region, and on the
    # slow branches lambda ~ -mu (x^2 - 1), down to -3 mu): it gets there, but with hundreds of
    # times the steps (measured 600418).
    slow = integrate("dop853", vdp, 0.0, y0, t_out, mu, 1e-6, 1e-6)
    assert slow.status == 0, slow.message
    assert slow.stats["n_accepted"] > 100 * st["n_accepted"]
    assert np.all(np.abs(slow.y - ref.y) <= 1e-3 * (1.0 + np.abs(ref.y)))


@pytest.mark.parametrize("problem", ["kepler", "vdp"])
def test_radau5_reduced_newton_systems_match_full_ones(problem):
    # With second_order=True RADAU5 factorises the m1 x m1 matrix g I - A_v - A_q/g instead of
    # the n x n matrix g I - J (Hairer's M1 = M2 structure).  That is the same linear algebra
    # done in another order, so the solution must agree with the full-size solve to round-off
    # amplified by the Newton stopping test, and the step sequence must match.
    if problem == "kepler":
        rhs, y0, t_out, p, tol = kepler, Y0_KEPLER, np.linspace(0.0, PERIOD, 9), NO_P, 1e-9
    else:  # stiff: the reduced matrix must carry A_q / g correctly when J is large
        rhs, y0, t_out, p, tol = vdp, [2.0, 0.0], np.linspace(0.0, 2000.0, 21), np.array([1000.0]), 1e-8
    full = integrate("radau5", rhs, 0.0, y0, t_out, p, tol, tol)
    red = integrate("radau5", rhs, 0.0, y0, t_out, p, tol, tol, second_order=True)
    assert full.status == 0 and red.status == 0
    rtol_i = 0.1 * tol ** (2.0 / 3.0)  # RADAU5's internal tolerance
    assert np.max(np.abs(red.y - full.y) / (rtol_i * (1.0 + np.abs(full.y)))) < 1e-2
    assert abs(red.stats["n_accepted"] - full.stats["n_accepted"]) <= 0.02 * full.stats["n_accepted"]


def test_second_order_needs_an_even_state():
    with pytest.raises(ValueError, match="second_order"):
        integrate("radau5", osc, 0.0, [1.0, 0.0, 0.0], [1.0], NO_P, 1e-6, 1e-6, second_order=True)


# ------------------------------------------------------------------------------------------------
# events
# ------------------------------------------------------------------------------------------------
@rhs_cfunc
def osc_events(t, y, g, p):
    # g0 = x (zero at t = pi/2 + k pi for x = cos t), g1 = x - 0.5 (zero at t = pi/3, 5pi/3, ...)
    g[0] = y[0]
    g[1] = y[0] - 0.5
    return 0


@rhs_cfunc
def kinked_osc(t, y, dydt, p):
    # x'' = -x for x >= 0 and x'' = -4 x for x < 0: a kink in the force at x = 0, like a tether
    # going slack.  From x = 1, x' = 0: x = cos t until t = pi/2 (x' = -1), then
    # x = -sin(2 (t - pi/2))/2 until t = pi/2 + pi/2 = pi (x' = 1), then x = sin(t - pi): the
    # period is 3 pi / 2 and the solution is exact piecewise.
    dydt[0] = y[1]
    dydt[1] = -y[0] if y[0] >= 0.0 else -4.0 * y[0]
    return 0


def kinked_exact(t):
    t = np.mod(np.atleast_1d(t), 1.5 * math.pi)
    x = np.where(t < math.pi / 2, np.cos(t),
                 np.where(t < math.pi, -0.5 * np.sin(2.0 * (t - math.pi / 2)), np.sin(t - math.pi)))
    return x


@rhs_cfunc
def x_event(t, y, g, p):
    g[0] = y[0]
    return 0


@pytest.mark.parametrize("method", ["dop853", "vern9", "radau5"])
def test_events_are_located_to_round_off_and_outputs_are_untouched(method):
    # x = cos t crosses 0.5 at pi/3 and 5 pi/3 and 0 at pi/2 and 3 pi/2 (exact).
    t_out = np.linspace(0.0, 6.0, 61)
    plain = integrate(method, osc, 0.0, [1.0, 0.0], t_out, NO_P, 1e-12, 1e-12)
    res = integrate(method, osc, 0.0, [1.0, 0.0], t_out, NO_P, 1e-12, 1e-12, event=osc_events,
                    n_events=2)  # fmt: skip
    assert res.status == 0 and res.stopped_by is None
    got = [(round(t, 9), k, side) for t, k, side in res.events]
    pi = math.pi
    want = [(round(pi / 3, 9), 1, -1), (round(pi / 2, 9), 0, -1), (round(3 * pi / 2, 9), 0, 1),
            (round(5 * pi / 3, 9), 1, 1)]  # fmt: skip
    assert [(k, s) for _, k, s in got] == [(k, s) for _, k, s in want]
    exact = [pi / 3, pi / 2, 3 * pi / 2, 5 * pi / 3]
    # Located within the integration error of x (<= 1e-9 here; bracket width is ~1e-14 s).
    assert max(abs(t - te) for (t, _, _), te in zip(res.events, exact)) < 1e-8
    assert np.array_equal(res.t, t_out)
    np.testing.assert_allclose(res.y, osc_exact(t_out), atol=1e-8)  # y = cos t
    # Restarts change the steps, not the answer: same as without events to the tolerance.
    np.testing.assert_allclose(res.y, plain.y, atol=1e-8)


@pytest.mark.parametrize("method", ["dop853", "vern9", "radau5"])
def test_kink_at_event_keeps_full_accuracy(method):
    # Without event location a step straddles each kink of kinked_osc and its dense output
    # and error estimate see a non-smooth solution; with it, every step lies on one branch.
    t_out = np.linspace(0.0, 6 * math.pi, 121)
    res = integrate(method, kinked_osc, 0.0, [1.0, 0.0], t_out, NO_P, 1e-11, 1e-11,
                    event=x_event, n_events=1)  # fmt: skip
    assert res.status == 0
    assert len(res.events) == 8  # two kinks per period of 3 pi/2, 4 periods
    err = np.max(np.abs(res.y[:, 0] - kinked_exact(t_out)))
    tol_i = 0.1 * 1e-11 ** (2.0 / 3.0) if method == "radau5" else 1e-11
    assert err < 100 * tol_i, err  # measured in units of the (internal) tolerance


@pytest.mark.parametrize("method", ["dop853", "vern9", "radau5"])
def test_terminal_event_stops_with_the_stop_state_last(method):
    t_out = np.linspace(0.0, 6.0, 7)
    res = integrate(method, osc, 0.0, [1.0, 0.0], t_out, NO_P, 1e-12, 1e-12, event=osc_events,
                    n_events=2, terminal=(True, False))  # fmt: skip
    assert res.status == 0 and res.stopped_by == 0
    assert "terminal event 0" in res.message
    # outputs 0 and 1 s, then the stop at pi/2 where x = cos t = 0
    np.testing.assert_allclose(res.t, [0.0, 1.0, math.pi / 2], atol=1e-9)
    assert abs(res.y[-1, 0]) < 1e-9 and abs(res.y[-1, 1] + 1.0) < 1e-9


def test_event_arguments_are_checked():
    with pytest.raises(ValueError, match="event"):
        integrate("scipy:DOP853", osc, 0.0, [1.0, 0.0], [1.0], NO_P, 1e-6, 1e-6, event=x_event,
                  n_events=1)  # fmt: skip
    with pytest.raises(ValueError, match="n_events"):
        integrate("dop853", osc, 0.0, [1.0, 0.0], [1.0], NO_P, 1e-6, 1e-6, event=x_event)
    with pytest.raises(ValueError, match="terminal"):
        integrate("dop853", osc, 0.0, [1.0, 0.0], [1.0], NO_P, 1e-6, 1e-6, event=x_event,
                  n_events=1, terminal=(True, True))  # fmt: skip


# ------------------------------------------------------------------------------------------------
# failures
# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("method", ["dop853", "vern9", "radau5"])
def test_rhs_status_failure_keeps_earlier_outputs(method):
    t_out = np.linspace(0.0, 3.0, 31)
    (status, t_end, _, n_done), y, y_out, stats = run_kernel(
        KERNELS[method], osc_fails_after_1p5, 0.0, [1.0, 0.0], t_out, 1e-8, 1e-8
    )
    assert status == 3 and stats[5] == 7
    assert 1.5 - 1e-6 < t_end <= 1.5  # the steps close in on the failure time
    assert n_done == 15  # outputs 0.0 .. 1.4; t = 1.5 itself is not reached (t_end < 1.5)
    np.testing.assert_allclose(y_out[:n_done], osc_exact(t_out[:n_done]), atol=1e-7)
    assert np.all(y_out[n_done:] == -999.0)  # rows after the failure are not written
    np.testing.assert_allclose(y, osc_exact(t_end)[0], atol=1e-7)  # state at t_end is valid

    res = integrate(method, osc_fails_after_1p5, 0.0, [1.0, 0.0], t_out, NO_P, 1e-8, 1e-8)
    assert res.status == 3 and res.stats["rhs_status"] == 7
    assert "status 7" in res.message and repr(res.t_end) in res.message
    assert res.y.shape == (15, 2) and np.array_equal(res.t, t_out[:15])


@pytest.mark.parametrize("method", ["dop853", "vern9", "radau5"])
def test_nan_rhs_fails_cleanly(method):
    t_out = np.linspace(0.0, 3.0, 31)
    res = integrate(method, osc_nan_after_1p5, 0.0, [1.0, 0.0], t_out, NO_P, 1e-8, 1e-8)
    assert res.status == 4, res.message
    assert "non-finite" in res.message
    assert np.all(np.isfinite(res.y)) and np.all(np.isfinite(res.y_end))
    assert res.t[-1] < 1.5 and res.y.shape[0] == 15


# ------------------------------------------------------------------------------------------------
# continuation
# ------------------------------------------------------------------------------------------------
def test_dop853_max_steps_continuation_is_bitwise():
    t_out = np.linspace(0.0, 3 * PERIOD, 50)
    (s1, t1, h1, n1), y1, out1, st1 = run_kernel(dop853_run, kepler, 0.0, Y0_KEPLER, t_out, 1e-9,
                                                 1e-9)  # fmt: skip
    assert s1 == 0 and n1 == 50
    y = Y0_KEPLER.copy()
    out = np.zeros_like(out1)
    stats = np.zeros(8, dtype=np.int64)
    t, h, done, calls = 0.0, 0.0, 0, 0
    while True:
        s, t, h, nd = dop853_run(kepler, t, y, t_out[done:], NO_P, 1e-9, np.full(4, 1e-9), h,
                                 0.0, 3, out[done:], stats, False)  # fmt: skip
        done += nd
        calls += 1
        if s != 1:
            break
    assert s == 0 and calls > 10 and done == 50
    assert np.array_equal(out, out1) and np.array_equal(y, y1) and t == t1
    assert stats[0] == st1[0]  # same steps, accumulated over the calls
    assert h == h1


def test_radau5_workspace_continuation_is_bitwise_and_plain_restart_is_close():
    mu = np.array([100.0])
    t_out = np.linspace(0.0, 300.0, 61)
    atol = np.full(2, 1e-7)
    ref = np.zeros((61, 2))
    y_ref = np.array([2.0, 0.0])
    st_ref = np.zeros(8, dtype=np.int64)
    s, _, _, _ = radau5_core(vdp, 0.0, y_ref, t_out, mu, 1e-7, atol, 0.0, 0.0, 10**6, ref,
                             st_ref, False, *radau5_workspace(2), False, vdp, 0,
                             np.array([0.0, -1.0, -1.0, 0.0]))  # fmt: skip
    assert s == 0

    ws = radau5_workspace(2)
    y = np.array([2.0, 0.0])
    out = np.zeros((61, 2))
    stats = np.zeros(8, dtype=np.int64)
    t, h, done, resume = 0.0, 0.0, 0, False
    while True:
        s, t, h, nd = radau5_core(vdp, t, y, t_out[done:], mu, 1e-7, atol, h, 0.0, 7,
                                  out[done:], stats, False, *ws, resume, vdp, 0,
                                  np.array([0.0, -1.0, -1.0, 0.0]))  # fmt: skip
        done += nd
        resume = True
        if s != 1:
            break
    assert s == 0 and done == 61
    assert np.array_equal(out, ref) and np.array_equal(y, y_ref)
    assert np.array_equal(stats[:5], st_ref[:5])  # same steps, Jacobians and LUs

    # The plain ABI entry restarts Newton and the Jacobian on every call: a valid continuation,
    # equal to the one-call result only to the Newton/integration tolerance.
    y = np.array([2.0, 0.0])
    out = np.zeros((61, 2))
    t, h, done = 0.0, 0.0, 0
    while True:
        s, t, h, nd = radau5_run(vdp, t, y, t_out[done:], mu, 1e-7, atol, h, 0.0, 25,
                                 out[done:], stats, False)  # fmt: skip
        done += nd
        if s != 1:
            break
    assert s == 0 and done == 61
    assert np.all(np.abs(out - ref) <= 1e-4 * (1.0 + np.abs(ref)))


@pytest.mark.parametrize("method", ["dop853", "vern9", "radau5"])
def test_driver_chunking_does_not_change_results(method):
    t_out = np.linspace(0.0, 10 * PERIOD, 40)  # > 250 steps: many chunks after the first 64
    one = integrate(method, kepler, 0.0, Y0_KEPLER, t_out, NO_P, 1e-9, 1e-9, chunk_seconds=1e3)
    seen = []
    # chunk_seconds = 1e-9 makes every chunk after the first a single step.
    many = integrate(method, kepler, 0.0, Y0_KEPLER, t_out, NO_P, 1e-9, 1e-9,
                     chunk_seconds=1e-9, progress=seen.append)  # fmt: skip
    assert one.status == many.status == 0
    assert many.stats["n_chunks"] > 20
    assert np.array_equal(one.y, many.y) and np.array_equal(one.y_end, many.y_end)
    assert one.stats["n_accepted"] == many.stats["n_accepted"]
    assert len(seen) == many.stats["n_chunks"] and seen == sorted(seen)
    assert seen[-1] == t_out[-1]


def test_driver_max_steps_budget():
    t_out = np.linspace(0.0, PERIOD, 5)
    res = integrate("dop853", kepler, 0.0, Y0_KEPLER, t_out, NO_P, 1e-9, 1e-9, max_steps=5)
    assert res.status == 1 and res.stats["n_accepted"] == 5
    assert "max_steps=5" in res.message and 0.0 < res.t_end < PERIOD
    assert np.all(res.t <= res.t_end)


def test_warm_up_and_compile_time_are_reported():
    for method in ("dop853", "radau5"):
        warm_up(method, kepler, 4, NO_P)
        again = warm_up(method, kepler, 4, NO_P)
        assert 0.0 <= again < 0.5  # compiled already: only a trivial call
        res = integrate(method, kepler, 0.0, Y0_KEPLER, [0.0, 1.0], NO_P, 1e-6, 1e-6)
        assert res.stats["compile_s"] >= 0.0 and res.stats["wall_s"] >= 0.0
    assert warm_up("scipy:Radau", kepler, 4, NO_P) == 0.0


# ------------------------------------------------------------------------------------------------
# scipy backend
# ------------------------------------------------------------------------------------------------
def test_scipy_backend_agrees_with_dop853_and_equals_solve_ivp():
    rtol = 1e-9
    t_out = np.linspace(0.0, PERIOD, 25)
    ours = integrate("dop853", kepler, 0.0, Y0_KEPLER, t_out, NO_P, rtol, rtol)
    sp = integrate("scipy:DOP853", kepler, 0.0, Y0_KEPLER, t_out, NO_P, rtol, rtol)
    assert ours.status == sp.status == 0
    # Both are within a few tolerance units of the exact orbit, hence of each other.
    assert _tol_units(ours.y, sp.y, rtol, rtol) < 50.0
    assert _tol_units(sp.y, kepler_exact(t_out), rtol, rtol) < 50.0

    # The backend's step loop is solve_ivp's: identical numbers (reference: solve_ivp itself,
    # with a pure-Python rhs computing the same expressions).
    def f(t, y):
        r2 = y[0] * y[0] + y[1] * y[1]
        r3 = r2 * math.sqrt(r2)
        return np.array([y[2], y[3], -y[0] / r3, -y[1] / r3])

    ref = solve_ivp(f, (0.0, PERIOD), Y0_KEPLER, method="DOP853", t_eval=t_out, rtol=rtol,
                    atol=rtol)  # fmt: skip
    assert np.array_equal(sp.y, ref.y.T)


@pytest.mark.parametrize("method", ["scipy:RK45", "scipy:Radau", "scipy:LSODA", "scipy:BDF"])
def test_scipy_backend_keeps_outputs_on_failure(method):
    t_out = np.linspace(0.0, 3.0, 31)
    res = integrate(method, osc_fails_after_1p5, 0.0, [1.0, 0.0], t_out, NO_P, 1e-8, 1e-8)
    assert res.status == 3 and res.stats["rhs_status"] == 7
    assert "status 7" in res.message
    assert 10 <= res.y.shape[0] <= 15 and res.t[-1] < 1.5
    np.testing.assert_allclose(res.y, osc_exact(res.t), atol=1e-6)
    nan = integrate(method, osc_nan_after_1p5, 0.0, [1.0, 0.0], t_out, NO_P, 1e-8, 1e-8)
    assert nan.status == 4 and np.all(np.isfinite(nan.y)) and nan.t[-1] < 1.5


# ------------------------------------------------------------------------------------------------
# input validation
# ------------------------------------------------------------------------------------------------
GOOD = dict(method="dop853", rhs=osc, t0=0.0, y0=[1.0, 0.0], t_out=[0.5, 1.0], p=NO_P,
            rtol=1e-6, atol=1e-6)  # fmt: skip


@pytest.mark.parametrize(
    "change,name",
    [
        ({"method": "rk4"}, "method"),
        ({"rhs": lambda t, y: y}, "rhs"),
        ({"t0": math.nan}, "t0"),
        ({"y0": [[1.0, 0.0]]}, "y0"),
        ({"y0": [1.0, math.inf]}, "y0"),
        ({"y0": []}, "y0"),
        ({"t_out": [1.0, 0.5]}, "t_out"),
        ({"t_out": [-1.0, 1.0]}, "t_out"),
        ({"t_out": []}, "t_out"),
        ({"t_out": [0.5, math.nan]}, "t_out"),
        ({"p": np.zeros(2, dtype=np.float32)}, "p"),
        ({"p": [1.0]}, "p"),
        ({"rtol": 0.0}, "rtol"),
        ({"rtol": 1.0}, "rtol"),
        ({"rtol": math.nan}, "rtol"),
        ({"atol": -1e-6}, "atol"),
        ({"atol": [1e-6, 1e-6, 1e-6]}, "atol"),
        ({"h0": -0.1}, "h0"),
        ({"h_max": math.inf}, "h_max"),
        ({"max_steps": 0}, "max_steps"),
        ({"max_steps": 2.5}, "max_steps"),
        ({"chunk_seconds": 0.0}, "chunk_seconds"),
        ({"progress": 3}, "progress"),
        ({"fixed_step": True}, "h0"),
        ({"fixed_step": True, "h0": 0.1, "method": "scipy:RK45"}, "fixed_step"),
    ],
)
def test_bad_inputs_raise_value_error_naming_the_argument(change, name):
    kwargs = {**GOOD, **change}
    with pytest.raises(ValueError, match=rf"^{name}: expected"):
        integrate(**kwargs)


def test_bad_method_lists_valid_ones():
    with pytest.raises(ValueError, match="scipy:LSODA"):
        integrate(**{**GOOD, "method": "lsoda"})


@pytest.mark.parametrize("method,n_rhs", [("dop853", 12), ("vern9", 16)])
def test_erk_step_is_the_kernels_fixed_step(method, n_rhs):
    """erk_step (used by DROMO's output clock) is exactly one step of the kernel."""
    from tetherlab.integrators.erk import DOP853, K_ROWS, VERN9, erk_step

    h = 0.37
    (s, t, _, _), y_kernel, _, _ = run_kernel(KERNELS[method], kepler, 0.0, Y0_KEPLER,
                                               np.array([h]), 1e-9, 1e-9, h=h, fixed_step=True)  # fmt: skip
    assert s == 0 and t == h
    K = np.empty((K_ROWS, 4))
    y_new = np.empty(4)
    stats = np.zeros(8, dtype=np.int64)
    kind = VERN9 if method == "vern9" else DOP853
    st = erk_step(kind, kepler, 0.0, Y0_KEPLER.copy(), h, NO_P, K, np.empty(4), y_new, stats)
    assert st == 0 and stats[2] == n_rhs
    assert np.array_equal(y_new, y_kernel)


def test_raw_pointers_address_the_right_elements_and_refuse_strided_views():
    import numba
    from numba.core.errors import TypingError

    from tetherlab._jit import ptr, row_ptr

    @numba.njit
    def read(a, i):
        return ptr(a[i])[1], row_ptr(a, i)[2]

    a = np.arange(12.0).reshape(3, 4)
    assert read(a, 2) == (a[2, 1], a[2, 2])

    @numba.njit
    def strided(a):
        return ptr(a[:, 1])[0]

    with pytest.raises(TypingError):
        strided(a)
