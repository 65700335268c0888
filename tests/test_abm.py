"""Adams-Bashforth-Moulton PECE (tetherlab/integrators/abm.py): coefficients, order, start, stops.

Expected values: HNW = Hairer, Norsett & Wanner, "Solving ODEs I", 2nd ed., section III.1
(Tables 1.1 and 1.2: the Adams coefficients in ordinate form); the harmonic oscillator's exact
solution (cos t, -sin t).
"""

from __future__ import annotations

import math
from fractions import Fraction as Fr

import numpy as np
import pytest
from numba import carray

from tetherlab._jit import rhs_cfunc
from tetherlab.integrators import abm
from tetherlab.integrators.tableau import TableauError


@rhs_cfunc
def _oscillator(t, y_ptr, dy_ptr, p_ptr):
    """y0' = y1, y1' = -y0, y2' = 1 (a clock for the level stop)."""
    y = carray(y_ptr, (3,))
    dy = carray(dy_ptr, (3,))
    dy[0] = y[1]
    dy[1] = -y[0]
    dy[2] = 1.0
    return 0


@rhs_cfunc
def _level_event(t, y_ptr, g_ptr, p_ptr):
    """g = y2 - p[0]: the level stop written as an event (the stop DROMO's time element needs)."""
    g = carray(g_ptr, (1,))
    g[0] = y_ptr[2] - p_ptr[0]
    return 0


def _run(k, h, t_stop, adapt=False, tol=1.0, comp=-1, level=0.0, y=None, F=None, head=-1, t=0.0,
         stats=None, use_event=False):  # fmt: skip
    """``use_event``: the same stop through the event g = y2 - level (abm_core's event mode)."""
    y = np.array([1.0, 0.0, 0.0]) if y is None else y
    ws = abm.workspace(3)
    F = ws["F"] if F is None else F
    stats = np.zeros(8, np.int64) if stats is None else stats
    fix = np.zeros(6)
    p = np.array([level, 0.0, 0.0, 0.0])
    st, t, h, head = abm.abm_core(_oscillator, t, y, h, k, F, ws["S"], head, p, tol,
                                  np.full(3, tol), t_stop, comp, level, 2 * math.pi, 10**7, adapt,
                                  stats, ws["K"], ws["w"], fix, _level_event, use_event)  # fmt: skip
    return st, t, h, head, y, F, stats, fix


def test_adams_coefficients_match_the_printed_tables():
    ab4, _ = abm.adams_coefficients(4)
    _, am3 = abm.adams_coefficients(3)
    # HNW Table 1.1 (explicit Adams, k = 4): (55, -59, 37, -9)/24
    assert ab4 == [Fr(55, 24), Fr(-59, 24), Fr(37, 24), Fr(-9, 24)]
    # HNW Table 1.2 (implicit Adams, k = 3, order 4): (9, 19, -5, 1)/24
    assert am3 == [Fr(9, 24), Fr(19, 24), Fr(-5, 24), Fr(1, 24)]
    # ...and k = 1: AB1 is Euler (1), AM of order 2 is the trapezoidal rule (1/2, 1/2)
    assert abm.adams_coefficients(1) == ([Fr(1)], [Fr(1, 2), Fr(1, 2)])


def test_float_tables_are_the_exact_coefficients_rounded():
    for k in abm.ORDERS:
        ab, am = abm.adams_coefficients(k)
        assert list(abm.AB_TABLE[k, :k]) == [float(x) for x in ab]
        assert list(abm.AM_TABLE[k, : k + 1]) == [float(x) for x in am]
        assert not abm.AB_TABLE[k, k:].any() and not abm.AM_TABLE[k, k + 1 :].any()


def test_order_check_catches_a_wrong_coefficient():
    """Negative control for the import-time check."""
    ab, am = abm.adams_coefficients(8)
    abm.check_adams(8, ab, am)
    bad = list(am)
    bad[5] += Fr(1, 10**12)
    with pytest.raises(TableauError, match="AM k=8"):
        abm.check_adams(8, ab, bad)
    bad = list(ab)
    bad[0] -= Fr(1, 10**12)
    with pytest.raises(TableauError, match="AB k=8"):
        abm.check_adams(8, bad, am)


@pytest.mark.parametrize("k", [4, 6, 8])
def test_order_by_slope_fit_is_k_plus_1(k):
    """PECE with AB_k and AM_{k+1}: order k + 1 (module docstring, HNW III.1).  Global error at
    t ~ 10 against cos t, for steps where round-off is far below the error.  (For k >= 11 the
    asymptotic range is squeezed between steps where the parasitic roots still matter -- the
    error falls faster than h^(k+1) there -- and the round-off floor near 1e-14 on this problem.)"""
    ns = {4: (100, 140, 200, 280), 6: (60, 85, 120, 170), 8: (60, 75, 95, 120)}[k]
    hs, errs = [], []
    for n in ns:
        h = 2 * math.pi / n
        st, t, _, _, y, *_ = _run(k, h, 10.0)
        assert st == abm.OK
        hs.append(h)
        errs.append(math.hypot(y[0] - math.cos(t), y[1] + math.sin(t)))
    slope = np.polyfit(np.log(hs), np.log(errs), 1)[0]
    assert abs(slope - (k + 1)) < 0.5, (slope, errs)


def test_starting_values_are_far_more_accurate_than_a_step():
    """abm_start: k - 1 Vern9 intervals (2 substeps each) -- their error must be negligible
    against the method's own local error (here ~1e-9 per step at h = 2 pi / 30, k = 10)."""
    k, h = 10, 2 * math.pi / 30
    y = np.array([1.0, 0.0, 0.0])
    ws = abm.workspace(3)
    stats = np.zeros(8, np.int64)
    st = abm.abm_start(_oscillator, 0.0, y, h, k, ws["F"], ws["S"], np.zeros(4), ws["K"], ws["w"],
                       abm.START_SUBSTEPS, stats)  # fmt: skip
    assert st == abm.OK
    t = (k - 1) * h
    assert abs(y[0] - math.cos(t)) < 1e-14 and abs(y[1] + math.sin(t)) < 1e-14
    for j in range(k):  # the history: f(t_j, y_j) = (-sin t_j, -cos t_j, 1); S[j] = y_j
        assert abs(ws["S"][j, 0] - math.cos(j * h)) < 1e-14 and ws["S"][j, 2] == pytest.approx(j * h)
        assert abs(ws["F"][j, 0] + math.sin(j * h)) < 1e-14
        assert abs(ws["F"][j, 1] + math.cos(j * h)) < 1e-14
    # rhs calls: 1 + (k - 1) * (2 substeps * 16 Vern9 stages + 1)
    assert stats[2] == 1 + (k - 1) * (2 * 16 + 1)


def test_adaptive_restarts_fix_a_bad_first_step():
    """From a step 20x too long, rejections shrink it; the error over 10 periods is then within
    a few hundred local tolerances (628 steps a period... each within tol)."""
    tol = 1e-10
    st, t, h, _, y, _, stats, _ = _run(12, 1.0, 20 * math.pi, adapt=True, tol=tol)
    assert st == abm.OK
    assert stats[1] >= 1  # at least one rejection
    err = math.hypot(y[0] - math.cos(t), y[1] + math.sin(t))
    assert err < 1e-7, err
    assert 0.05 < h < 0.6  # 10-120 steps a period: a sane step for k=12 at 1e-10


@pytest.mark.parametrize("use_event", [False, True], ids=["level", "event"])
def test_level_stop_and_resume_are_bit_for_bit(use_event):
    """Stop when y2 (= t) would reach 3.3 inside a step; resuming gives the same trajectory as
    a run that never stopped.  With ``use_event`` fix[0] is g = y2 - 3.3 after the step."""
    k, h = 9, 0.1
    st, t, _, head, y, F, stats, fix = _run(k, h, 6.0, comp=2, level=3.3, use_event=use_event)
    assert st == abm.LEVEL
    after = fix[0] + 3.3 if use_event else fix[0]
    assert t <= 3.3 <= t + h * (1 + 1e-12) and after >= 3.3 and fix[1] == 1.0
    st2, t2, _, _, y2, *_ = _run(k, h, 6.0, y=y.copy(), F=F.copy(), head=head, t=t)
    st3, t3, _, _, y3, *_ = _run(k, h, 6.0)
    assert st2 == st3 == abm.OK and t2 == t3
    assert np.array_equal(y2, y3)


@pytest.mark.parametrize("use_event", [False, True], ids=["level", "event"])
def test_level_crossed_inside_the_starting_procedure(use_event):
    """The starting procedure always runs to its end (outputs never change the path); a level it
    passed is reported with its bracket among the starting states S."""
    k, h = 9, 0.1
    ws = abm.workspace(3)
    st, t, _, head, y, F, stats, fix = _run(k, h, 6.0, comp=2, level=0.35, F=ws["F"], use_event=use_event)
    assert st == abm.LEVEL_START and head == k - 1
    assert t == pytest.approx(0.8, abs=1e-15)  # the end of the k - 1 starting intervals
    # bracket y2 in [0.3, 0.4]: fix[0] is y2 = 0.4 there (level) or g = 0.4 - 0.35 (event)
    assert int(fix[5]) == 4 and fix[0] == pytest.approx(0.05 if use_event else 0.4, abs=1e-15)
    assert fix[4] == 0.0  # the starting procedure began at t = 0
