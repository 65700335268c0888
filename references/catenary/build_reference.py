"""Build the catenary oracle: Irvine's elastic catenary for the case of paper section 4.2.

Independent of tetherlab (numpy and scipy only).  The cable of unstretched length L0, axial
stiffness EA and weight w per unit *unstretched* length hangs between support A = (0, 0) and the
end mass B = (l, h) (x horizontal, z up).  With s in [0, L0] the unstretched (Lagrangian)
coordinate from A, H the horizontal component of the tension (constant, no horizontal load) and
V the vertical force the support exerts on the cable at A, Irvine (Cable Structures, MIT Press
1981, section 2.2, eqs. 2.21-2.22 in his notation with z measured upwards here) gives

    x(s) = H s / EA + (H / w) [asinh(V / H) - asinh((V - w s) / H)]
    z(s) = (w s^2 / 2 - V s) / EA + (1 / w) [sqrt(H^2 + (w s - V)^2) - sqrt(H^2 + V^2)]
    T(s) = sqrt(H^2 + (V - w s)^2)

and (H, V) solve x(L0) = l, z(L0) = h.  docs/catenary.md restates the derivation.

A second, independent method checks the closed form: shooting on the cable's ODEs
dx/ds = H/T + H/EA, dz/ds = (w s - V)/T + (w s - V)/EA, integrated by scipy's DOP853 at
rtol 1e-13 with (H, V) found again by root finding.  The two must agree to 1e-10 m.

Writes reference.json next to this file.  Run:  python references/catenary/build_reference.py
"""

from __future__ import annotations

import datetime
import json
import platform
import sys
import time
from pathlib import Path

import numpy as np
import scipy
from scipy.integrate import solve_ivp
from scipy.optimize import root

# ---- the case (paper section 4.2; the tether mass and end mass are our choice, see PROVENANCE) --
L0_M = 1.0  # unstretched length, paper section 4.2
EA_N = 40.06  # axial stiffness, paper section 4.2
SPAN_M = 0.9  # horizontal distance of the ends, paper section 4.2
HEIGHT_M = 0.0  # same height ("placed horizontally separated 0.9 m")
TETHER_MASS_KG = 0.1  # not in the paper: 100 g/m, strain ~1.3 %, so elasticity matters
END_MASS_KG = 0.1  # not in the paper: the held end mass m_f (changes R_f, not the shape)
G_M_S2 = 9.80665  # standard gravity (3rd CGPM 1901)
W_N_M = TETHER_MASS_KG * G_M_S2 / L0_M  # weight per unstretched length
SAMPLES = 4001  # shape and tension samples along s


def shape(s, H, V):
    """(x, z, T) at unstretched coordinate s for horizontal tension H and support force V."""
    w = W_N_M
    x = H * s / EA_N + (H / w) * (np.arcsinh(V / H) - np.arcsinh((V - w * s) / H))
    z = (0.5 * w * s * s - V * s) / EA_N + (np.hypot(H, w * s - V) - np.hypot(H, V)) / w
    return x, z, np.hypot(H, V - w * s)


def solve_closed_form():
    def miss(u):
        H, V = u
        x, z, _ = shape(L0_M, H, V)
        return [x - SPAN_M, z - HEIGHT_M]

    # starting point: a parabola's horizontal tension, half the weight at each end
    W = W_N_M * L0_M
    sag = np.sqrt(3.0 * SPAN_M * (L0_M - SPAN_M) / 8.0)
    sol = root(miss, [W * SPAN_M / (8.0 * sag), 0.5 * W], method="hybr", options={"xtol": 1e-15})
    if not sol.success:
        raise RuntimeError(sol.message)
    return sol.x, float(np.max(np.abs(miss(sol.x))))


def solve_shooting():
    w = W_N_M

    def rhs(s, y, H, V):
        t = np.hypot(H, w * s - V)
        return [H / t + H / EA_N, (w * s - V) / t + (w * s - V) / EA_N]

    def end(u):
        H, V = u
        sol = solve_ivp(rhs, (0.0, L0_M), [0.0, 0.0], method="DOP853", rtol=1e-13, atol=1e-15, args=(H, V))
        return [sol.y[0, -1] - SPAN_M, sol.y[1, -1] - HEIGHT_M]

    W = W_N_M * L0_M
    sol = root(end, [0.5, 0.5 * W], method="hybr", options={"xtol": 1e-14})
    H, V = sol.x
    s = np.linspace(0.0, L0_M, SAMPLES)
    path = solve_ivp(rhs, (0.0, L0_M), [0.0, 0.0], method="DOP853", rtol=1e-13, atol=1e-15, t_eval=s, args=(H, V))
    return (H, V), path.y


def main() -> None:
    t0 = time.perf_counter()
    (H, V), miss = solve_closed_form()
    s = np.linspace(0.0, L0_M, SAMPLES)
    x, z, T = shape(s, H, V)
    (H2, V2), xz2 = solve_shooting()
    shoot_dist = float(np.max(np.hypot(xz2[0] - x, xz2[1] - z)))
    if shoot_dist > 1e-10:
        raise RuntimeError(f"closed form and shooting disagree by {shoot_dist:.3g} m")
    W = W_N_M * L0_M
    # lowest point (for the report): where the vertical tension component vanishes, s = V / w
    s_low = V / W_N_M
    x_low, z_low, _ = shape(s_low, H, V)
    # forces in the 3-D scene frame of the TMED comparison: x along the span, z up, y = 0
    nail_force = [-H, 0.0, V]  # support on cable at A
    tip_pull = [-H, 0.0, V - W]  # cable on the end mass at B
    holding = [H, 0.0, W - V + END_MASS_KG * G_M_S2]  # R_f: tip_pull + m_f g + R_f = 0
    stretched = float(np.sum(np.hypot(np.diff(x), np.diff(z))))
    out = {
        "case": {
            "L0_m": L0_M, "EA_N": EA_N, "span_m": SPAN_M, "height_m": HEIGHT_M,
            "tether_mass_kg": TETHER_MASS_KG, "end_mass_kg": END_MASS_KG, "g_m_s2": G_M_S2,
            "weight_per_length_N_m": W_N_M,
            "frame": "nail A at the origin, end mass B at (span, 0, height); z up; gravity -z",
        },
        "solution": {
            "H_N": H, "V_A_N": V, "V_B_N": W - V, "closure_miss_m": miss,
            "tension_A_N": float(T[0]), "tension_B_N": float(T[-1]),
            "nail_force_on_tether_N": nail_force, "tether_pull_on_end_mass_N": tip_pull,
            "holding_force_on_end_mass_N": holding,
            "lowest_point_m": [float(x_low), 0.0, float(z_low)], "lowest_point_s_m": s_low,
            "stretched_length_m": stretched,
        },
        "samples": {"s_m": s.tolist(), "x_m": x.tolist(), "z_m": z.tolist(), "tension_N": T.tolist()},
        "second_method": {
            "what": "shooting on the cable ODEs, scipy DOP853 rtol 1e-13, root finding on (H, V)",
            "H_N": float(H2), "V_A_N": float(V2), "max_shape_distance_m": shoot_dist,
        },
        "provenance": {
            "builder": "references/catenary/build_reference.py",
            "python": sys.version.split()[0], "numpy": np.__version__, "scipy": scipy.__version__,
            "machine": f"{platform.system()} {platform.machine()}",
            "date_utc": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d"),
            "build_s": round(time.perf_counter() - t0, 2),
        },
    }
    path = Path(__file__).with_name("reference.json")
    path.write_text(json.dumps(out, indent=1) + "\n")
    print(f"H = {H:.15g} N, V_A = {V:.15g} N, T_A = {T[0]:.15g} N, sag = {-z_low:.12g} m")
    print(f"closed form vs shooting: {shoot_dist:.3g} m; |H - H2| = {abs(H - H2):.3g} N; wrote {path}")


if __name__ == "__main__":
    main()
