"""The reduced model of the SEDS-like deployment and the pieces of its budget (docs/deployment.md
12.1-12.2, studies/seds_reduced.py): its line tension closes on the end mass's pull (the energy
equation (12.2) is the momentum balance), and its linearisation predicts a perturbed model.
The comparison with the TMED run and its control are `make verify`'s (deployment part J)."""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from .helpers import import_study

_SR = import_study("seds_reduced")


def test_the_line_tension_closes_on_the_end_mass_pull():
    # docs/deployment.md 12.2 (b): T(l) from the exit's rho l'^2 + F_b and the axial balance of each
    # element equals m (c (l - sigma) - l'' + sigma''), exactly when (12.2) is the momentum balance
    t_end, _y, sol = _SR.seds_reduced()
    for t in np.linspace(0.0, t_end, 9):
        p = _SR.parts(sol(t))
        line = float(_SR.line_tension(p, np.array([p["l"]]))[0])
        assert abs(line - _SR.tip_tension(p)) <= 1e-12, (t, line, _SR.tip_tension(p))  # N, round-off of ~0.1 N terms
        assert p["exit_tension"] > 0.0


def test_sensitivity_predicts_a_perturbed_reduced_model():
    """A small constant push f of theta'' moves (l, theta) by int Phi(t) Phi(tau)^-1 e_3 f dtau,
    to second order in f (the budget's propagation, 12.2)."""
    om = _SR.constants()["om"]
    f = 1e-3 * om**2
    t = np.linspace(0.0, 2000.0, 801)
    s = _SR.sensitivity(t)

    def pushed(_t, y):
        d = _SR.rhs(_t, y)
        return [d[0], d[1], d[2], d[3] + f]

    c = _SR.SEDS
    y0 = [c["L0"], c["v0"], 0.0, 0.0]
    kw = dict(method="DOP853", t_eval=t, rtol=1e-11, atol=1e-12)
    moved = solve_ivp(pushed, (0.0, t[-1]), y0, **kw).y - solve_ivp(_SR.rhs, (0.0, t[-1]), y0, **kw).y
    inv = np.linalg.inv(s["phi"])
    dt = t[1] - t[0]
    pred = np.array([np.trapezoid((s["phi"][i] @ inv[: i + 1])[:, :, 3], dx=dt, axis=0) * f if i else np.zeros(4)
                     for i in range(len(t))]).T  # fmt: skip
    for row, unit in ((2, "rad"), (0, "m")):
        err, scale = np.abs(moved[row] - pred[row]).max(), np.abs(moved[row]).max()
        assert scale > 0 and err <= 0.02 * scale, (unit, err, scale)


def test_the_bow_bound_grows_with_the_pay_out_and_sets_the_window():
    # 12.2 (b): y_max <= q l^2 T_max / (8 T_min^2) at most 5 % of l up to about 43 min of the 68 min
    t_end, _y, sol = _SR.seds_reduced()
    t_w = _SR.window_end(sol, t_end)
    assert 2000.0 <= t_w <= 3000.0, t_w  # s: 2600 s measured (docs/deployment.md 12.2)
    early, late = sol(600.0), sol(t_w + 600.0)
    assert _SR.bow(_SR.parts(early))["y"] < 0.01 * early[0]
    assert _SR.bow(_SR.parts(late))["y"] > _SR.BOW_MAX * late[0]
