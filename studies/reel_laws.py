"""The reel as a dynamical system: the spool's oracles and gates (docs/deployment.md 10-11).

* D, a frictionless drum in uniform gravity paying out a hanging tether with an end mass:
  (J/R^2 + M + rho L_tot) l'' = (M + rho l) g - tau/R, in closed form for a constant torque
  (docs/deployment.md 11.1); negative control: the L'' coupling of the exit tension dropped
  (DEFECT_SPOOL_UNCOUPLED);
* W, the energy balance with a brake and friction, E + K_spool + W_brake + W_exit loss = const,
  the works integrated on the outputs and bounded by their Richardson estimate (11.2);
* K, the tension law T = m* Omega^2 [3 l_c + k1 (l - l_c) + k2 l'/Omega] on a circular orbit: the
  decay rates and frequencies of a small perturbation about l_c, measured by a Prony fit of the
  in-plane angle and of the length, against the roots of s^4 + k2 s^3 + (k1 + 4) s^2 + 3 k2 s
  + 3 (k1 - 3) (11.3); negative control: the sign of k2 flipped (DEFECT_TENSION_K2_SIGN);
* S, a SEDS-like deployment (no gate: its swing angle and tension profile, docs/deployment.md 12).

The tests (tests/test_reel_spool.py) import these scenes and measures: one definition.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from tetherlab.deployment import simulate_reel
from tetherlab.scene import Scene

G = 9.80665  # m/s^2, the scene's uniform gravity (standard gravity, forces/uniform_gravity.py)

# -- D and W: the drum in uniform gravity -------------------------------------------------------
DRUM = dict(M=10.0, rho=1.0, L0=10.0, stored=90.0, J=2.0, R=0.2, EA=1e9)


def drum_scene(*, torque="10 N m", duration="10 s", count=101, friction=None, rtol=1e-10, ea_N=None, rod_length="200 m"):
    """A fixed nail with a drum (J = 2 kg m^2, R = 0.2 m: J/R^2 = 50 kg) pays out a 1 kg/m line
    (10 m out, 90 m stored, EA 1e9 N) to a 10 kg end mass hanging straight down, released at rest
    with the line unstretched.  ``friction``: (viscous N s/m, Coulomb N) on the spool; ``ea_N``
    another stiffness (a softer line rings slower than the outputs sample it); ``rod_length``: one
    rod by default, shorter for births (located events under a spool law)."""
    d = DRUM
    reel = {"law": "spool", "exit": "drum", "rod_length": rod_length, "retire_length": "1 m",
            "stored_length": f"{d['stored']} m", "spool_inertia": f"{d['J']} kg m2", "drum_radius": f"{d['R']} m",
            "torque": torque}  # fmt: skip
    if friction is not None:
        reel["viscous_friction"] = f"{friction[0]} N s/m"
        reel["coulomb_friction"] = f"{friction[1]} N"
    return Scene.from_dict({
        "name": "drum-gravity", "duration": duration, "effects": {"uniform_gravity": {"g": f"{G} m/s2"}},
        "bodies": {"nail": {"fixed": True, "position": ["0 m", "0 m", "0 m"]},
                   "tip": {"mass": f"{d['M']} kg", "position": ["0 m", "0 m", f"-{d['L0']} m"],
                           "velocity": ["0 m/s", "0 m/s", "0 m/s"]}},
        "tethers": {"main": {"from": "nail", "to": "tip", "length": f"{d['L0']} m", "EA": f"{d['EA'] if ea_N is None else ea_N} N",
                             "linear_density": f"{d['rho']} kg/m", "model": "energy", "reel": reel}},
        "integrator": {"method": "radau5", "rtol": rtol, "atol": rtol},
        "output": {"count": count},
    })  # fmt: skip


def drum_oracle(t_s, torque_N_m: float) -> np.ndarray:
    """l(t) of the inextensible line (docs/deployment.md 11.1): l'' = a + b l with
    b = rho g / I, a = (M g - tau/R) / I, I = J/R^2 + M + rho L_tot, from l0 at rest."""
    d = DRUM
    inertia = d["J"] / d["R"] ** 2 + d["M"] + d["rho"] * (d["L0"] + d["stored"])
    b = d["rho"] * G / inertia
    a = (d["M"] * G - torque_N_m / d["R"]) / inertia
    return -a / b + (d["L0"] + a / b) * np.cosh(math.sqrt(b) * np.asarray(t_s))


def drum_error(run, torque_N_m: float) -> tuple[float, float]:
    """(max |L - l_oracle|, its budget): the oracle's line is inextensible, the run's stretches by
    eps = T/EA; released unstretched, the axial transient at most doubles the static stretch, so
    the length is within 2 eps_max L_max of the oracle's, plus the integrator's 10 rtol L_max."""
    r = run.reel
    L = r["deployed_length_m"].to_numpy()
    err = float(np.abs(L - drum_oracle(r["t_s"].to_numpy(), torque_N_m)).max())
    eps_max = float(r["exit_tension_N"].abs().max()) / DRUM["EA"]
    # the tension is largest at the end mass's side of a heavy line: bound it by the whole weight
    eps_max = max(eps_max, (DRUM["M"] + DRUM["rho"] * float(L.max())) * G / DRUM["EA"])
    return err, 2.0 * eps_max * float(L.max()) + 10.0 * 1e-10 * float(L.max())


def spool_energy(run) -> tuple[np.ndarray, float]:
    """E + K_spool + W_brake + W_loss per output row (one reel), and the Richardson estimate of
    the trapezoid error of the two works on these outputs (order 2: (W_2h - W_h)/3, at its largest
    over the run, from every other row against every row)."""
    r = run.reel.reset_index(drop=True)
    inv = run.invariants.reset_index(drop=True)
    total = inv["energy_J"].to_numpy() + r["spool_kinetic_J"].to_numpy()
    t = r["t_s"].to_numpy()
    works = np.zeros(len(r))
    est = 0.0
    for col in ("brake_power_W", "exit_loss_power_W"):
        pw = r[col].to_numpy()
        w_h = np.concatenate([[0.0], np.cumsum(0.5 * (pw[1:] + pw[:-1]) * np.diff(t))])
        w_2h = np.concatenate([[0.0], np.cumsum(0.5 * (pw[2::2] + pw[:-2:2]) * np.diff(t[::2]))])
        est += float(np.abs(w_2h - w_h[::2]).max()) / 3.0
        works += w_h
    return total + works, est


# -- K: the tension law on a circular orbit ----------------------------------------------------
MU = 3.986004418e14  # m^3/s^2, the scene preset "earth" (tetherlab/scene/data.py)
TENSION = dict(a=7000e3, M=1e4, m=100.0, rho=1e-4, lc=1000.0, k1=4.0, k2=1.0, EA=1e4, xi0=0.01, stored=1000.0,
               J=1e-3, R=0.1, damping=1000.0)  # fmt: skip


def tension_scene(*, orbits=2.0, count=401, xi0=None):
    """A 10 t station on a 7000 km circular orbit holds a 100 kg subsatellite on a light line
    (0.1 g/m, EA 10 kN, 1 kg at 1 km against m* = 99 kg), along the local vertical, paid out from
    a drum (J/R^2 = 0.1 kg, 1 km stored: 0.2 kg with the turns) under the tension law with
    k1 = 4, k2 = 1 about l_c = 1 km; released at rest in the orbiting frame with the length
    1 % long and the line at the commanded tension.  The line's damping (1 kN s) damps the reel's
    own fast mode (the spool against the line's stiffness, ~10 rad/s) and leaves the slow dynamics
    alone: the exit tension follows the command whatever splits it between elastic and damping
    forces."""
    c = TENSION
    xi0 = c["xi0"] if xi0 is None else xi0
    om = math.sqrt(MU / c["a"] ** 3)
    mst = c["M"] + c["rho"] * c["stored"]
    mred = mst * c["m"] / (mst + c["m"])
    L0 = c["lc"] * (1.0 + xi0)
    T0 = mred * om**2 * (3.0 * c["lc"] + c["k1"] * (L0 - c["lc"]))
    return Scene.from_dict({
        "name": "tension-law", "duration": f"{orbits} orbits", "effects": {"central_gravity": {}},
        "bodies": {"m0": {"mass": f"{c['M']} kg"}, "mf": {"mass": f"{c['m']} kg"}},
        "orbit": {"reference": "center_of_mass", "motion": "corotating", "elements": {
            "a": f"{c['a'] / 1e3} km", "e": 0.0, "i": "0 deg", "raan": "0 deg", "argp": "0 deg", "nu": "0 deg"}},
        "tethers": {"main": {
            "from": "m0", "to": "mf", "length": f"{L0!r} m", "EA": f"{c['EA']} N", "linear_density": f"{c['rho']} kg/m",
            "damping": f"{c['damping']} N s", "model": "energy",
            "initial": {"shape": "straight", "theta": "0 deg", "strain": T0 / c["EA"]},
            "reel": {"law": "tension", "exit": "drum", "rod_length": "5 km", "retire_length": "100 m",
                     "stored_length": f"{c['stored']} m", "spool_inertia": f"{c['J']} kg m2", "drum_radius": f"{c['R']} m",
                     "reduced_mass": f"{mred!r} kg", "orbit_rate": f"{om!r} rad/s", "commanded_length": f"{c['lc']} m",
                     "k1": c["k1"], "k2": c["k2"]}}},
        "integrator": {"method": "radau5", "rtol": 1e-10, "atol": 1e-9},
        "output": {"count": count},
    }), om, mred  # fmt: skip


def characteristic_roots(k1: float, k2: float) -> np.ndarray:
    """Roots of s^4 + k2 s^3 + (k1 + 4) s^2 + 3 k2 s + 3 (k1 - 3) (docs/deployment.md 11.3), s in
    units of Omega, sorted by imaginary part (the upper half plane: one per mode)."""
    r = np.roots([1.0, k2, k1 + 4.0, 3.0 * k2, 3.0 * (k1 - 3.0)])
    up = r[r.imag > 0]
    return up[np.argsort(-up.imag)]


def prony(x: np.ndarray, dt: float, order: int = 4) -> np.ndarray:
    """The exponents s of a sum of ``order`` damped modes and a constant fitted to equally spaced
    samples x (least squares on the recurrence x_{n+order} = -sum a_i x_{n+i} + c); the upper-half-plane ones,
    sorted by imaginary part (largest first)."""
    n = len(x) - order
    H = np.column_stack([x[i : i + n] for i in range(order)] + [np.ones(n)])
    sol = np.linalg.lstsq(H, -x[order : order + n], rcond=None)[0]
    z = np.roots(np.r_[1.0, sol[:order][::-1]])
    s = np.log(z.astype(complex)) / dt
    up = s[s.imag > 0]
    return up[np.argsort(-up.imag)] if len(up) else s


def tension_measure(run, om: float) -> dict:
    """The modes measured from the in-plane angle and from the length (Prony), against the roots,
    and the budget (docs/deployment.md 11.3) of their relative error."""
    c = TENSION
    r = run.reel
    dg = pd.concat([ph.diagnostics[["main.theta_rad"]] for ph in run.phases], ignore_index=True)
    tau = r["t_s"].to_numpy() * om
    theta = dg["main.theta_rad"].to_numpy()
    xi = r["deployed_length_m"].to_numpy() / c["lc"] - 1.0
    roots = characteristic_roots(c["k1"], c["k2"])
    dt = tau[1] - tau[0]
    out = {"roots": roots}
    worst = 0.0
    for name, x in (("theta", theta), ("xi", xi)):
        s = prony(x, dt)
        if len(s) != len(roots):
            out[name] = s
            worst = math.inf
            continue
        rel = np.abs(s - roots) / np.abs(roots)
        out[name] = s
        out[f"{name}_rel"] = rel
        worst = max(worst, float(rel.max()))
    mstar = c["M"] * c["m"] / (c["M"] + c["m"])
    ms = c["J"] / c["R"] ** 2 + c["rho"] * c["stored"]
    lmax = float(np.abs(r["deployed_length_m"]).max())
    amplitude = float(np.abs(xi).max() + np.abs(theta).max())
    eps = float(r["exit_tension_N"].abs().max()) / c["EA"]
    out["budget"] = (2.0 * amplitude + c["rho"] * lmax / mstar + ms / mstar + 4.0 * lmax / c["a"] + eps)
    out["worst"] = worst
    out["curves"] = {"tau": tau, "theta": theta, "xi": xi}
    return out


def tension_run(defect: int = 0):
    scene, om, _ = tension_scene()
    return simulate_reel(scene, defect=defect, raise_on_failure=False, progress=False), om


# -- S: a SEDS-like deployment -------------------------------------------------------------------
SEDS = dict(h=400e3, M=1000.0, m=25.0, line=20e3, L0=200.0, rho=3.5e-4, EA=2e4, v0=1.6, brake=0.05)


def seds_scene(*, count=481, rod_length="2 km", rtol=1e-8):
    """SEDS-like (Small Expendable Deployer System; SEDS-1, 1993): a 1 t stage on a 400 km circular
    orbit ejects a 25 kg end mass downwards at 1.6 m/s on a 20 km line of 0.35 g/m (7 kg; EA 20 kN,
    damping 50 N s) paid out of a canister through a passive friction brake (Coulomb 0.05 N,
    smooth over 1 cm/s), 200 m out at the start, rods of 2 km; the run ends when the whole line is
    out (the event reel.main.spent, at 68 min).  The outputs cover 80 min, every 10 s: the
    deployment's end is a located event, not known ahead, so the duration only has to pass it
    (by the reduced model's 68.3 min, docs/deployment.md 12.1, plus a margin); a brake that made it
    last longer would end the run without the event, which part J reports as a failure.
    ``rod_length`` and ``rtol`` are the comparison's other levels (docs/deployment.md 12.2: the
    rods' discretisation and the integrator's error, each from a twin run)."""
    c = SEDS
    a_m = 6378.137e3 + c["h"]
    return Scene.from_dict({
        "name": "seds-like", "duration": "80 min", "effects": {"central_gravity": {}},
        "bodies": {"m0": {"mass": f"{c['M']} kg"}, "mf": {"mass": f"{c['m']} kg"}},
        "orbit": {"reference": "center_of_mass", "motion": "corotating", "elements": {
            "a": f"{a_m / 1e3} km", "e": 0.0, "i": "0 deg", "raan": "0 deg", "argp": "0 deg", "nu": "0 deg"}},
        "tethers": {"main": {
            "from": "m0", "to": "mf", "length": f"{c['L0']} m", "EA": f"{c['EA']} N", "linear_density": f"{c['rho']} kg/m",
            "damping": "50 N s", "model": "energy", "initial": {"shape": "straight", "theta": "0 deg"},
            "reel": {"law": "spool", "exit": "canister", "speed": f"{c['v0']} m/s", "rod_length": rod_length,
                     "retire_length": "100 m", "stored_length": f"{c['line'] - c['L0']} m",
                     "coulomb_friction": f"{c['brake']} N", "friction_speed": "0.01 m/s"}}},
        "integrator": {"method": "radau5", "rtol": rtol, "atol": rtol},
        "output": {"count": count},
    })  # fmt: skip


def seds_profile(run) -> dict:
    """Time, deployed length, speed, exit tension and in-plane swing angle of a SEDS-like run."""
    r = run.reel
    dg = pd.concat([ph.diagnostics[["main.theta_rad"]] for ph in run.phases], ignore_index=True)
    return {"t": r["t_s"].to_numpy(), "L": r["deployed_length_m"].to_numpy(), "v": r["speed_m_s"].to_numpy(),
            "T": r["exit_tension_N"].to_numpy(), "theta": dg["main.theta_rad"].to_numpy()}


def seds_energy(run) -> dict:
    """The energy balance of a canister run in a central field without the orbit's share
    (docs/deployment.md 12.3): J = E + K_s + W_b + W_loss - Omega_0 H_z per output, Omega_0 the
    circular orbit's rate; exactly constant for the model (E + K_s + W_b + W_loss by (10.3), H_z
    because the field is central and the exit's forces internal), and stationary at the circular
    orbit, so the integrator's first-order error on the orbit, which E alone carries, cancels.
    Returns the times (each once), J - J(0), the Richardson estimate of the works' quadrature on the
    outputs (11.2), the round-off scale |E| + Omega_0 |H_z| and E_H = E - Omega_0 H_z + (3/2) mu M/a,
    the Hill-frame energy of the relative motion."""
    c = SEDS
    a_m = 6378.137e3 + c["h"]
    om = math.sqrt(MU / a_m**3)
    total, est = spool_energy(run)
    inv = run.invariants.reset_index(drop=True)
    e, hz = inv["energy_J"].to_numpy(), inv["angmom_z_kg_m2_s"].to_numpy()
    j = total - om * hz
    t, first = np.unique(inv["t_s"].to_numpy(), return_index=True)  # a birth's time is reported twice
    m_tot = c["M"] + c["m"] + c["rho"] * c["line"]
    return {"t": t, "drift": (j - j[0])[first], "quadrature": est, "orbit_drift": float(np.abs(total - total[0]).max()),
            "scale": float(np.max(np.abs(e) + om * np.abs(hz))), "hill": (e - om * hz + 1.5 * MU * m_tot / a_m)[first]}
