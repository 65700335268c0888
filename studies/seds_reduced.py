"""An independent reduced model of the SEDS-like deployment (docs/deployment.md 12.1): a straight,
inextensible, massive line of length l at the in-plane angle theta from the local vertical, with
the end mass at its end and the stage (with the stored line) at its start, in the Hill frame of the
system's centre of mass; the canister's jump rho l'^2 and Carnot loss and the Coulomb brake with
the scene's smooth sign. Integrated with scipy, nothing of the simulator imported: a measurement
to set beside the TMED run (studies/reel_laws.py seds_scene), not yet a gate."""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp

from studies.reel_laws import MU, SEDS


def seds_reduced(*, rtol: float = 1e-10):
    """(t_end s, final state [l, l', theta, theta'], dense solution) of the reduced model from the
    scene's start (200 m out at 1.6 m/s along the local vertical, at rest in the Hill frame) to the
    end of the line; equations (12.1)-(12.2) of docs/deployment.md."""
    c = SEDS
    a_m = 6378.137e3 + c["h"]
    om = math.sqrt(MU / a_m**3)
    rho, m, line, fc, vs = c["rho"], c["m"], c["line"], c["brake"], 0.01  # vs: the scene's friction_speed
    m_tot = c["M"] + m + rho * line

    def rhs(_t, y):
        l, ld, th, thd = y
        q = rho * l + m  # deployed mass
        s1 = rho * l * l / 2 + m * l  # its first moment about the stage
        mu_l = q * (1 - q / m_tot)
        dmu = rho * (1 - 2 * q / m_tot)
        inertia = rho * l**3 / 3 + m * l * l - s1 * s1 / m_tot  # about the centre of mass
        d_inertia = rho * l * l + 2 * m * l - 2 * s1 * q / m_tot
        brake = fc * math.tanh(ld / vs)
        ldd = (-0.5 * dmu * ld * ld - brake - 0.5 * rho * ld * ld
               + d_inertia * (thd * (thd + om) - thd * thd / 2 + 1.5 * om**2 * math.cos(th) ** 2)) / mu_l
        thdd = (-d_inertia * ld * (thd + om) - 3 * om**2 * inertia * math.sin(th) * math.cos(th)) / inertia
        return [ld, ldd, thd, thdd]

    def spent(_t, y):
        return y[0] - line

    spent.terminal = True
    sol = solve_ivp(rhs, (0.0, 2e4), [c["L0"], c["v0"], 0.0, 0.0], method="Radau", rtol=rtol, atol=rtol,
                    events=spent, dense_output=True)  # fmt: skip
    if not sol.t_events[0].size:
        raise RuntimeError("reduced SEDS model: the line was not paid out within 2e4 s")
    return float(sol.t_events[0][0]), np.asarray(sol.y_events[0][0]), sol.sol


def exit_tension(ld: float) -> float:
    """The canister's exit tension of the inextensible line, rho l'^2 + F_c tanh(l'/v_s) (10.2)."""
    return SEDS["rho"] * ld * ld + SEDS["brake"] * math.tanh(ld / 0.01)
