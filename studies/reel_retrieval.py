"""Retrieval of a 5 km tether to 100 m, at constant speed and under the tension law
(docs/deployment.md 14): the instability of uniform retrieval shown, then held.

* the constant-speed retrieval's in-plane angle against the rigid-rod variable-length pendulum
  of tetherlab/oracles/reeled_pendulum.py, within a budget derived term by term
  (`pendulum_measure`, docs/deployment.md 14.1; make verify deployment part N; negative control: a
  kernel that ignores the law, DEFECT_REEL_FROZEN);
* the same line hauled in by the tension law (k1 = 4, k2 = 1) with its commanded length halved
  every 0.75 orbit, 2.5 km -> 100 m (`stages`, docs/deployment.md 10.6): the libration stays
  bounded and decays.  One step straight to l_c = 100 m is far outside the linear law's range
  (k1 (L - l_c) is 50 l_c at the start) and tumbles the line (measured: the angle passes 170 deg).

The tests (tests/test_reel_stages.py) and make verify import these scenes and measures: one definition.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from tetherlab.deployment import simulate_reel
from tetherlab.oracles.reeled_pendulum import libration
from tetherlab.scene import Scene

MU = 3.986004418e14  # m^3/s^2, the scene preset "earth" (tetherlab/scene/data.py)
RETRIEVAL = dict(a=7000e3, M=1e4, m=100.0, rho=2e-4, L0=5000.0, Lf=100.0, v=1.0, EA=1e4, damping=3e4, rod=1000.0,
                 retire=50.0, lc=100.0, k1=4.0, k2=1.0, J=1e-3, R=0.1)  # fmt: skip


STAGE_ORBITS = 0.75  # the time between two halvings of the commanded length (the slow mode's e-fold is 0.85 orbit)


def stage_lengths() -> list:
    """The commanded lengths of the controlled retrieval: L0/2, L0/4, ... while above l_c, then l_c."""
    c = RETRIEVAL
    out, l = [], c["L0"]
    while l / 2.0 > c["lc"]:
        l /= 2.0
        out.append(l)
    return out + [c["lc"]]


def omega() -> float:
    return math.sqrt(MU / RETRIEVAL["a"] ** 3)


def reduced_mass() -> float:
    c = RETRIEVAL
    return c["M"] * c["m"] / (c["M"] + c["m"])


def retrieval_scene(*, controlled: bool = False, count: int = 401, orbits: float | None = None):
    """A 10 t station on a 7000 km circular orbit hauls in a 100 kg subsatellite on 5 km of line
    (0.2 g/m: 1 kg against m* = 99 kg; EA 10 kN, damping 30 kN s), rods of 1 km, along the local
    vertical at rest in the orbiting frame at the static strain.  Uncontrolled: the law `constant`
    at -1 m/s to 100 m (4900 s).  Controlled: the tension law about l_c = 100 m from a drum
    (J/R^2 = 0.1 kg), from rest."""
    c = RETRIEVAL
    om = omega()
    mred = reduced_mass()
    strain = 3.0 * mred * om**2 * c["L0"] / c["EA"]
    if controlled:
        lcs = stage_lengths()
        period = 2.0 * math.pi / om
        reel = {"law": "tension", "exit": "drum", "spool_inertia": f"{c['J']} kg m2", "drum_radius": f"{c['R']} m",
                "reduced_mass": f"{mred!r} kg", "orbit_rate": f"{om!r} rad/s", "commanded_length": f"{lcs[0]!r} m",
                "k1": c["k1"], "k2": c["k2"],
                "stages": [{"start": f"{(j + 1) * STAGE_ORBITS * period!r} s", "commanded_length": f"{x!r} m"}
                           for j, x in enumerate(lcs[1:])]}  # fmt: skip
        duration = f"{orbits if orbits is not None else 5.0} orbits"
    else:
        reel = {"law": "constant", "speed": f"{-c['v']} m/s"}
        duration = f"{(c['L0'] - c['Lf']) / c['v']!r} s"
    reel.update({"rod_length": f"{c['rod']} m", "retire_length": f"{c['retire']} m", "stored_length": "1 km"})
    return Scene.from_dict({
        "name": "retrieval-" + ("tension" if controlled else "constant"), "duration": duration,
        "effects": {"central_gravity": {}},
        "bodies": {"m0": {"mass": f"{c['M']} kg"}, "mf": {"mass": f"{c['m']} kg"}},
        "orbit": {"reference": "center_of_mass", "motion": "corotating", "elements": {
            "a": f"{c['a'] / 1e3} km", "e": 0.0, "i": "0 deg", "raan": "0 deg", "argp": "0 deg", "nu": "0 deg"}},
        "tethers": {"main": {
            "from": "m0", "to": "mf", "length": f"{c['L0']} m", "EA": f"{c['EA']} N", "linear_density": f"{c['rho']} kg/m",
            "damping": f"{c['damping']} N s", "model": "energy",
            "initial": {"shape": "straight", "theta": "0 deg", "strain": strain}, "reel": reel}},
        "integrator": {"method": "radau5", "rtol": 1e-9, "atol": 1e-9},
        "output": {"count": count},
    })  # fmt: skip


def fine_scene():
    """The constant-speed retrieval at a tenth of its rtol: the integrator's error of part N."""
    data = retrieval_scene().to_dict()
    data["integrator"].update(rtol=1e-10, atol=1e-10)
    return Scene.from_dict(data)


def profile(run) -> dict:
    """Time, deployed length, rate, exit tension and in-plane angle of a run (a phase's first row,
    which repeats the last one's, dropped)."""
    r = run.reel
    dg = pd.concat([ph.diagnostics[["t_s", "main.theta_rad"]] for ph in run.phases], ignore_index=True)
    keep = ~dg["t_s"].duplicated().to_numpy()
    return {"t": r["t_s"].to_numpy()[keep], "L": r["deployed_length_m"].to_numpy()[keep],
            "v": r["speed_m_s"].to_numpy()[keep], "T": r["exit_tension_N"].to_numpy()[keep],
            "theta": dg["main.theta_rad"].to_numpy()[keep]}  # fmt: skip


def oracle_angle(t_s: np.ndarray) -> np.ndarray:
    """The rigid-rod pendulum's angle under the constant-speed law from rest at the vertical."""
    c = RETRIEVAL
    return libration(t_s, lambda t: c["L0"] - c["v"] * t, lambda t: -c["v"], omega_rad_s=omega(),
                     mstar_kg=reduced_mass(), rho_kg_m=c["rho"])  # fmt: skip


# -- the gate: the constant-speed retrieval against the reeled pendulum (docs/deployment.md 14.1) --
WINDOW_M = 500.0  # the law's length down to which the two are compared (the angle reaches 87 deg there)
FIELD_P3 = 2.1  # max |dP3(cos x)/dx| = 2.07 (at cos^2 x = 3/4), and the line's share: 14.1 (a)
GRID = 3001  # the quadrature grid of the budget's integrals over [0, t]


def _law_length(t):
    c = RETRIEVAL
    return c["L0"] - c["v"] * np.asarray(t, float)


def pendulum_measure(run, fine=None) -> dict:
    """The constant-speed run's in-plane angle against the reeled pendulum over l >= WINDOW_M, and
    its budget at every output derived term by term (docs/deployment.md 14.1): the linearised
    pendulum's response to a bound of each neglected term, through |G(t, tau)|, plus the
    integrator's error (twice the difference from ``fine``, the same run at a tenth of the rtol).
    Returns the worst ratio error / budget, its terms where the ratio is worst, and the curves."""
    c = RETRIEVAL
    om, ms = omega(), reduced_mass()
    pr = profile(run)
    t = pr["t"][_law_length(pr["t"]) >= WINDOW_M]
    err = np.abs(pr["theta"][: len(t)] - oracle_angle(t)) if len(t) > 1 else np.array([math.inf])
    from tetherlab.oracles.reeled_pendulum import libration_sensitivity

    tau = np.linspace(0.0, (c["L0"] - WINDOW_M) / c["v"], GRID)
    kw = dict(omega_rad_s=om, mstar_kg=ms, rho_kg_m=c["rho"])
    s = libration_sensitivity(tau, _law_length, lambda x: -c["v"], **kw)
    at = libration_sensitivity(t, _law_length, lambda x: -c["v"], **kw) if len(t) > 1 else None
    l = _law_length(tau)
    w = s["dtheta"] + om  # the line's rotation rate
    # (a) the field beyond the gravity gradient: the P3 term of the end mass's potential
    b_field = FIELD_P3 * om**2 * l / c["a"]
    # (b) the line's inertia about the system's centre of mass against (m* + rho l/3) l^2: within 2 rho l/M
    b_mass = 3.0 * (2.0 * c["rho"] * l / c["M"]) * (c["v"] / l) * np.abs(w)
    # (c) the line's lateral flexibility: the moment of the axial loads on its sag
    tension = ms * l * (w**2 - om**2 + 3.0 * om**2 * np.cos(s["theta"]) ** 2)
    q = c["rho"] * (l * np.abs(s["ddtheta"]) + 2.0 * c["v"] * np.abs(w) + 1.5 * om**2 * l)
    sag = q * l * l / (8.0 * np.maximum(tension, 1e-300))
    b_flex = 2.0 * sag * c["rho"] * l * l * (w**2 + 3.0 * om**2) / (2.0 * (ms + c["rho"] * l / 3.0) * l * l)
    # (d) the strain, through |e(tau)| = |eps - eps0| (integrated by parts: no derivative of eps)
    eps0 = 3.0 * ms * om**2 * c["L0"] / c["EA"]
    r = run.reel
    tr, T = r["t_s"].to_numpy(), np.abs(r["exit_tension_N"].to_numpy())
    tmax = np.maximum.accumulate(T) / c["EA"]
    idx = np.minimum(np.searchsorted(tr, tau), len(tr) - 1)
    e_b = eps0 + (1.0 + c["rho"] * l / ms) * np.maximum(eps0, tmax[idx])
    inv = np.linalg.inv(s["phi"])  # Phi(tau)^-1
    col1 = inv[:, :, 1]  # Phi(tau)^-1 e2
    dcol = -(inv @ np.stack([np.ones_like(tau), -s["growth"]], axis=1)[:, :, None])[:, :, 0]  # d/dtau of it
    wq = np.full(GRID, tau[1] - tau[0])
    wq[0] = wq[-1] = 0.5 * wq[0]
    terms = {k: np.zeros(len(t)) for k in ("field", "mass", "flex", "strain", "integration")}
    for i in range(len(t) if at is not None else 0):
        row = at["phi"][i, 0, :]
        k = tau <= t[i]
        G = col1[k] @ row
        dG = dcol[k] @ row
        terms["field"][i] = np.sum(np.abs(G) * b_field[k] * wq[k])
        terms["mass"][i] = np.sum(np.abs(G) * b_mass[k] * wq[k])
        terms["flex"][i] = np.sum(np.abs(G) * b_flex[k] * wq[k])
        terms["strain"][i] = 2.0 * np.sum(e_b[k] * np.abs(dG * w[k] + G * s["ddtheta"][k]) * wq[k])
    if fine is not None and at is not None:
        pf = profile(fine)
        diff = np.abs(pr["theta"][: len(t)] - np.interp(t, pf["t"], pf["theta"]))
        terms["integration"] = 2.0 * np.maximum.accumulate(diff)
    budget = sum(terms.values())
    ratio = err / np.where(budget > 0, budget, math.inf)
    worst = int(np.argmax(ratio))
    return {"ratio": float(ratio[worst]), "t": t, "err": err, "budget": budget, "terms": terms, "worst": worst,
            "max_err": float(err.max()), "oracle_max": float(np.abs(oracle_angle(t)).max()) if len(t) > 1 else 0.0}


# -- the gate on the staged retrieval's last stage (docs/deployment.md 14.2) ----------------------
SETTLE_ORBITS = 8.0  # the controlled run extended: the last stage (from 3.75 orbits) held 4.25 orbits
SETTLE_FROM_ORBITS = 6.0  # the state the settling bound starts from (the 156 -> 100 m step's swing decayed)


def retrieval_hold():
    """The last stage's hold (l_c = 100 m) as studies/reel_hold.py's balance sees it."""
    from studies.reel_hold import Hold

    c = RETRIEVAL
    line = c["L0"] + 1000.0  # the scene's 5 km out and 1 km stored
    return Hold(MU, c["a"], c["M"], c["m"], c["rho"], c["EA"], line, c["J"] / c["R"] ** 2, reduced_mass(), c["lc"],
                c["k1"], c["k2"], up=1.0)  # fmt: skip


def settle_measure(run) -> dict:
    """The staged retrieval's last stage against its rest length, at every output from
    SETTLE_FROM_ORBITS on, within the closed loop's settling from the state there
    (studies/reel_hold.settling_measure with window=True; docs/deployment.md 14.2)."""
    from studies.reel_hold import settling_measure

    h = retrieval_hold()
    pr = profile(run)
    dg = pd.concat([ph.diagnostics[["t_s", "eccentricity"]] for ph in run.phases], ignore_index=True)
    ecc = dg["eccentricity"].to_numpy()[~dg["t_s"].duplicated().to_numpy()]
    t0 = SETTLE_FROM_ORBITS * 2.0 * math.pi / omega()
    m = settling_measure(pr, h, t0, rtol=1e-9, ecc_max=float(ecc[pr["t"] >= t0].max()), window=True)
    m["profile"] = pr
    return m
