"""Build the rigid-body oracle data (docs/rigid-oracles.md): torque-free body, gravity-gradient libration,
hub-and-spoke steady state, wheel momentum exchange.

Every value comes from tetherlab/oracles/{torque_free, gg_attitude, spinning_spokes,
wheel_exchange}.py, which import numpy and scipy only (no simulator code), and every case is
checked here by a second, independent method; the builder fails if they disagree by more than the
stated tolerance.  Derivations: docs/rigid-oracles.md.  Writes reference.json next to this file.

    PYTHONPATH=. .venv/bin/python references/rigid_bodies/build_references.py
"""

from __future__ import annotations

import datetime
import importlib.util
import json
import math
import platform
import sys
import time
from pathlib import Path

import numpy as np
import scipy

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent


def _load(name):
    # load the oracle modules by path: importing the tetherlab package is not needed (and the
    # oracles must not depend on it)
    pkg = "tetherlab_oracles_standalone"
    if pkg not in sys.modules:
        spec = importlib.util.spec_from_file_location(pkg, ROOT / "tetherlab" / "oracles" / "__init__.py",
                                                      submodule_search_locations=[str(ROOT / "tetherlab" / "oracles")])  # fmt: skip
        mod = importlib.util.module_from_spec(spec)
        sys.modules[pkg] = mod
        spec.loader.exec_module(mod)
    return importlib.import_module(f"{pkg}.{name}")


tf = _load("torque_free")
gg = _load("gg_attitude")
ss = _load("spinning_spokes")
we = _load("wheel_exchange")
fit = _load("continuum").fit_frequencies

MU_EARTH = 3.986004418e14  # the "earth" preset of tetherlab/scene/data.py (WGS 84 / IERS 2010 GM)

# -- cases (our choices; docs/rigid-oracles.md section 5 says why) --------------------------------
TORQUE_FREE = {
    # principal moments I1 < I2 < I3 (body x, y, z), kg m^2; rates rad/s (inertial, body axes);
    # initial attitude: a quaternion (scalar first, body -> inertial) far from identity
    "major": {"inertia_kg_m2": [200.0, 300.0, 450.0], "w0_rad_s": [0.02, 0.04, 0.2]},
    "minor": {"inertia_kg_m2": [200.0, 300.0, 450.0], "w0_rad_s": [0.2, 0.06, -0.04]},
}
Q0 = [math.cos(0.3), *(math.sin(0.3) * np.array([1.0, 2.0, 2.0]) / 3.0)]
PERIODS = 5
SAMPLES = 501

GG = {"inertia_roll_pitch_yaw_kg_m2": [150.0, 200.0, 100.0], "radius_m": 7.0e6, "mu_m3_s2": MU_EARTH,
      "amplitude_rad": 1e-3, "orbits": 10, "samples": 4001}  # fmt: skip

SPOKES = {
    "tether": {"length_m": 100.0, "EA_N": 2.0e4, "rho_kg_m": 0.02, "tip_mass_kg": 5.0, "damping_N_s": 2000.0},
    "omega0_rad_s": 0.5,
    "centre": {"n_spokes": 3, "hub_radius_m": 0.0, "hub_mass_kg": 100.0, "hub_axial_inertia_kg_m2": 0.0},
    "radius": {"n_spokes": 4, "hub_radius_m": 2.0, "hub_mass_kg": 100.0, "hub_axial_inertia_kg_m2": 50.0,
               "hub_transverse_inertia_kg_m2": 30.0},
    "samples": 101,
}

WHEEL = {"J_kg_m2": 10.0, "Iw_kg_m2": 0.5, "w0_rad_s": 0.2, "Omega0_rad_s": 30.0,
         "switch_times_s": [0.0, 5.0, 12.0], "torques_N_m": [0.3, -0.1, 0.0], "duration_s": 20.0, "samples": 81}  # fmt: skip


def build_torque_free():
    out = {}
    c0 = tf.quat_to_matrix(Q0)
    for name, case in TORQUE_FREE.items():
        top = tf.euler_top(case["inertia_kg_m2"], case["w0_rad_s"], c0)
        t = np.linspace(0.0, PERIODS * top.period_s, SAMPLES)
        w = tf.rates(top, t)
        C = tf.attitude(top, t)
        I = np.array(case["inertia_kg_m2"])
        H = np.einsum("nij,nj->ni", C, I * w)
        wr, Cr = tf.integrate_reference(I, case["w0_rad_s"], c0, t)
        dw = float(np.abs(w - wr).max())
        dang = float(tf.rotation_angle(C, Cr).max())
        euler_res = float(np.abs(tf.euler_residual(top, t)).max())
        if dw > 1e-10 * np.abs(w).max() or dang > 1e-9 or euler_res > 1e-13 * top.h_N_m_s * np.abs(w).max():
            raise RuntimeError(f"torque-free {name}: closed form vs DOP853: rates {dw:.3g}, attitude {dang:.3g} rad, Euler residual {euler_res:.3g}")  # fmt: skip
        out[name] = {
            **case, "q0": list(map(float, Q0)), "regime": top.regime, "m": top.m, "lam_rad_s": top.lam_rad_s,
            "period_s": top.period_s, "energy_J": 0.5 * top.energy2_J, "h_N_m_s": top.h_N_m_s,
            "h_inertial_N_m_s": top.h_inertial.tolist(),
            "samples": {"t_s": t.tolist(), "w_rad_s": w.tolist(), "q": [tf.matrix_to_quat(c).tolist() for c in C]},
            "max_h_inertial_drift_N_m_s": float(np.abs(H - top.h_inertial).max()),
            "second_method": {
                "what": "Euler's equations + quaternion kinematics, scipy DOP853 rtol 1e-13 atol 1e-15",
                "max_rate_difference_rad_s": dw, "max_attitude_difference_rad": dang,
                "max_euler_residual_N_m": euler_res,
            },
        }  # fmt: skip
    return out


def build_gg():
    Ix, Iy, Iz = GG["inertia_roll_pitch_yaw_kg_m2"]
    R, mu = GG["radius_m"], GG["mu_m3_s2"]
    n = math.sqrt(mu / R**3)
    wp = gg.pitch_frequency(n, Ix, Iy, Iz)
    lo, hi = gg.roll_yaw_frequencies(n, Ix, Iy, Iz)
    ev = np.sort(np.abs(np.linalg.eigvals(gg.roll_yaw_matrix(n, Ix, Iy, Iz)).imag))[::2]
    t = np.linspace(0.0, GG["orbits"] * 2 * math.pi / n, GG["samples"])
    A = GG["amplitude_rad"]
    pitch = gg.integrate_nonlinear((Ix, Iy, Iz), R, mu, (0.0, A, 0.0), (0.0, 0.0, 0.0), t)
    fp = fit(t, pitch[:, 1], [wp])[0][0]
    ry = gg.integrate_nonlinear((Ix, Iy, Iz), R, mu, (A, 0.0, A), (0.0, 0.0, 0.0), t)
    fr = np.sort(fit(t, ry[:, 0], [lo, hi])[0])
    fy = np.sort(fit(t, ry[:, 2], [lo, hi])[0])
    errs = {"pitch": abs(fp / wp - 1), "roll_low": abs(fr[0] / lo - 1), "roll_high": abs(fr[1] / hi - 1),
            "yaw_low": abs(fy[0] / lo - 1), "yaw_high": abs(fy[1] / hi - 1)}  # fmt: skip
    if max(errs.values()) > 1e-6 or abs(ev[0] / lo - 1) > 1e-12 or abs(ev[1] / hi - 1) > 1e-12:
        raise RuntimeError(f"gravity gradient: linear frequencies vs nonlinear run {errs}, eigenvalues {ev / n}")
    st = gg.stability(Ix, Iy, Iz)
    k1, k3 = gg.k_ratios(Ix, Iy, Iz)
    return {
        **GG, "orbit_rate_rad_s": n, "k1": k1, "k3": k3,
        "pitch_rad_s": wp, "roll_yaw_low_rad_s": lo, "roll_yaw_high_rad_s": hi,
        "pitch_over_n": wp / n, "roll_yaw_over_n": [lo / n, hi / n],
        "stable": {"pitch": st.pitch, "roll_yaw": st.roll_yaw},
        "second_method": {
            "what": "nonlinear attitude (Euler + quaternion, exact gravity-gradient torque of a small body) on the "
                    "circular orbit, scipy DOP853 rtol 1e-12, amplitude 1e-3 rad, 10 orbits; frequencies by least-squares "
                    "fit (tetherlab/oracles/continuum.py fit_frequencies); and the eigenvalues of the linear system",
            "relative_frequency_errors": errs,
            "eigenvalue_over_n": (ev / n).tolist(),
        },
    }  # fmt: skip


def build_spokes():
    tt = SPOKES["tether"]
    w0 = SPOKES["omega0_rad_s"]
    out = {"tether": tt, "omega0_rad_s": w0}
    s = np.linspace(0.0, tt["length_m"], SPOKES["samples"])
    for name in ("centre", "radius"):
        case = SPOKES[name]
        args = (tt["length_m"], tt["EA_N"], tt["rho_kg_m"], tt["tip_mass_kg"], case["hub_radius_m"])
        sp = ss.spoke_profile(w0, *args)
        bvp = ss.spoke_profile_bvp(w0, *args)
        xb, Tb = bvp.sol(s)
        dx = float(np.abs(xb - sp.x(s)).max())
        dT = float(np.abs(Tb - sp.tension(s)).max())
        if dx > 1e-8 or dT > 1e-6:
            raise RuntimeError(f"spokes {name}: closed form vs solve_bvp: x {dx:.3g} m, T {dT:.3g} N")
        inx = ss.spoke_profile_inextensible(w0, tt["length_m"], tt["rho_kg_m"], tt["tip_mass_kg"], case["hub_radius_m"])
        H = ss.angular_momentum(w0, case["n_spokes"], case["hub_axial_inertia_kg_m2"], case["hub_mass_kg"], *args)
        out[name] = {
            **case, "tip_radius_m": sp.tip_radius_m, "hub_tension_N": sp.hub_tension_N, "tip_tension_N": sp.tip_tension_N,
            "angular_momentum_N_m_s": H, "kappa_1_m": sp.kappa_1_m,
            "samples": {"s_m": s.tolist(), "x_m": sp.x(s).tolist(), "tension_N": sp.tension(s).tolist()},
            "inextensible": {"hub_tension_N": float(inx.tension(0.0)), "tip_tension_N": float(inx.tension(tt["length_m"]))},
            "second_method": {"what": "scipy solve_bvp (collocation, tol 1e-10, bc_tol 1e-14)",
                              "max_x_difference_m": dx, "max_tension_difference_N": dT},
        }  # fmt: skip
    return out


def build_wheel():
    c = {k: WHEEL[k] for k in ("J_kg_m2", "Iw_kg_m2", "w0_rad_s", "Omega0_rad_s")}
    sa = we.SingleAxis(**c, switch_times_s=tuple(WHEEL["switch_times_s"]), torques_N_m=tuple(WHEEL["torques_N_m"]))
    t = np.linspace(0.0, WHEEL["duration_s"], WHEEL["samples"])
    w, Om = sa.state(t)
    # second method: the 3-axis gyrostat integrator with the body spinning about its z axis
    J = np.diag([0.6 * c["J_kg_m2"], 0.8 * c["J_kg_m2"], c["J_kg_m2"]])
    edges = WHEEL["switch_times_s"]

    def motor(tt, _w, _O):
        k = max(i for i, a in enumerate(edges) if tt >= a)
        return [WHEEL["torques_N_m"][k]]

    # integrate piecewise so no step straddles a torque switch
    pieces = []
    y_w, y_O, y_work, C0 = [0.0, 0.0, c["w0_rad_s"]], [c["Omega0_rad_s"]], 0.0, np.eye(3)
    bounds = [*edges, WHEEL["duration_s"]]
    for a, b in zip(bounds[:-1], bounds[1:]):
        sel = (t >= a) & (t <= b) if b == bounds[-1] else (t >= a) & (t < b)
        tt = np.clip(np.concatenate([[0.0], t[sel] - a, [b - a]]), 0.0, b - a)
        r = we.integrate_gyrostat(J, [[0.0, 0.0, 1.0]], [c["Iw_kg_m2"]], y_w, y_O, C0, tt,
                                  lambda s, _w, _O, a=a: motor(s + a, _w, _O))  # fmt: skip
        pieces.append((r["w"][1:-1], r["Omega"][1:-1], r["work"][1:-1] + y_work))
        y_w, y_O, y_work, C0 = r["w"][-1], r["Omega"][-1], y_work + r["work"][-1], r["C"][-1]
    w2 = np.concatenate([p[0] for p in pieces])
    O2 = np.concatenate([p[1] for p in pieces])
    W2 = np.concatenate([p[2] for p in pieces])
    dw = float(np.abs(w2[:, 2] - w).max())
    dO = float(np.abs(O2[:, 0] - Om).max())
    dW = float(np.abs(W2 - sa.motor_work(t)).max())
    if dw > 1e-12 or dO > 1e-10 or dW > 1e-10 or float(np.abs(w2[:, :2]).max()) > 0.0:
        raise RuntimeError(f"wheel: closed form vs gyrostat DOP853: w {dw:.3g}, Omega {dO:.3g}, work {dW:.3g}")
    return {
        **WHEEL,
        "samples": {"t_s": t.tolist(), "w_rad_s": w.tolist(), "Omega_rad_s": Om.tolist(),
                    "angular_momentum_N_m_s": sa.angular_momentum(t).tolist(),
                    "wheel_absolute_momentum_N_m_s": sa.wheel_absolute_momentum(t).tolist(),
                    "energy_J": sa.energy(t).tolist(), "motor_work_J": sa.motor_work(t).tolist()},
        "second_method": {"what": "3-axis gyrostat equations (body inertia diag(6, 8, 10) kg m2, spin about z), "
                                  "scipy DOP853 rtol 1e-13 piecewise between torque switches",
                          "max_rate_difference_rad_s": dw, "max_wheel_speed_difference_rad_s": dO,
                          "max_work_difference_J": dW},
    }  # fmt: skip


def main() -> None:
    t0 = time.perf_counter()
    out = {
        "torque_free": build_torque_free(),
        "gravity_gradient": build_gg(),
        "hub_spoke": build_spokes(),
        "wheel_single_axis": build_wheel(),
        "provenance": {
            "builder": "references/rigid_bodies/build_references.py",
            "oracles": "tetherlab/oracles/{torque_free,gg_attitude,spinning_spokes,wheel_exchange}.py",
            "python": sys.version.split()[0], "numpy": np.__version__, "scipy": scipy.__version__,
            "machine": f"{platform.system()} {platform.machine()}",
            "date_utc": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d"),
        },
    }  # fmt: skip
    out["provenance"]["build_s"] = round(time.perf_counter() - t0, 1)
    path = HERE / "reference.json"
    path.write_text(json.dumps(out, indent=1) + "\n")
    for name, c in out["torque_free"].items():
        print(f"torque-free {name}: regime {c['regime']}, period {c['period_s']:.12g} s, m = {c['m']:.6g}, "
              f"vs DOP853 {c['second_method']['max_rate_difference_rad_s']:.2g} rad/s, "
              f"{c['second_method']['max_attitude_difference_rad']:.2g} rad")  # fmt: skip
    g = out["gravity_gradient"]
    print(f"gravity gradient: pitch {g['pitch_over_n']:.12g} n, roll-yaw {g['roll_yaw_over_n']} n, "
          f"nonlinear run {max(g['second_method']['relative_frequency_errors'].values()):.2g}")  # fmt: skip
    for name in ("centre", "radius"):
        c = out["hub_spoke"][name]
        print(f"hub-spoke {name}: T(0) = {c['hub_tension_N']:.12g} N, x(L) = {c['tip_radius_m']:.12g} m, "
              f"vs solve_bvp {c['second_method']['max_tension_difference_N']:.2g} N")  # fmt: skip
    print(f"wheel: {out['wheel_single_axis']['second_method']}")
    print(f"wrote {path} in {out['provenance']['build_s']} s")


if __name__ == "__main__":
    main()
