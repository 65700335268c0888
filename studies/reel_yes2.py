"""A YES2-like two-stage deployment under the tension law in stages (docs/deployment.md 10.6, 15).

YES2 (Foton-M3, 25 September 2007; ESA's technical facts and the mission's reconstruction): a
22 kg deployer on the Foton capsule ejected MASS (8 kg) with the Fotino capsule (6 kg) towards
the Earth at ~3 m/s on a 0.5 mm Dyneema line of ~31.7 km, from a 260-300 km orbit; the first stage
went out to ~3.4 km, where the brake held it, and the second stage deployed fast to ~30 km.  The
scene keeps that outline, not the flight's data: a 6.5 t spacecraft on a 280 km circular orbit, a
14 kg end mass ejected radially outwards at 3 m/s with 200 m out (the scene's side "up"; the
flight's went towards the Earth, which changes the sign of the field's P3 term in the hold's rest
length, docs/deployment.md 11.4), 0.19 g/m (the 0.5 mm line's section at 970 kg/m^3: 6 kg over
31.7 km), EA 10 kN, damping 50 N s, rods of 2 km, paid from a drum under the
tension law (k1 = 4, k2 = 1) about l_c = 3.4 km, then 30 km from the moment the deployed length
reaches 3.4 km (the second stage's `at_length`, a located event: docs/deployment.md 10.7), the
command kept above 5 mN (a brake cannot push).  Not a reproduction: the flight used a barber-pole
brake on a spool with its own control, not this law.

The two-stage run is gated (docs/deployment.md 15.1): J = E + K_s + W_b + W_loss - Omega_0 H_z
conserved across the switch and the births (:func:`yes2_energy`), and the switch located at the
commanded length within the event locator's tolerance (:func:`yes2_switch`).
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from tetherlab.scene import Scene

MU = 3.986004418e14  # m^3/s^2, the scene preset "earth" (tetherlab/scene/data.py)
YES2 = dict(h=280e3, M=6500.0, m=14.0, line=31.7e3, L0=200.0, rho=1.9e-4, EA=1e4, v0=3.0, lc1=3400.0, lc2=30e3,
            k1=4.0, k2=1.0, J=1e-3, R=0.1, orbits=4.0, tmin=0.005)  # fmt: skip


def yes2_scene(*, count: int = 801, rtol: float = 1e-8, orbits: float | None = None):
    c = dict(YES2, orbits=YES2["orbits"] if orbits is None else orbits)
    a_m = 6378.137e3 + c["h"]
    om = math.sqrt(MU / a_m**3)
    mred = c["M"] * c["m"] / (c["M"] + c["m"])
    return Scene.from_dict({
        "name": "yes2-like", "duration": f"{c['orbits']} orbits", "effects": {"central_gravity": {}},
        "bodies": {"m0": {"mass": f"{c['M']} kg"}, "mf": {"mass": f"{c['m']} kg"}},
        "orbit": {"reference": "center_of_mass", "motion": "corotating", "elements": {
            "a": f"{a_m / 1e3} km", "e": 0.0, "i": "0 deg", "raan": "0 deg", "argp": "0 deg", "nu": "0 deg"}},
        "tethers": {"main": {
            "from": "m0", "to": "mf", "length": f"{c['L0']} m", "EA": f"{c['EA']} N", "linear_density": f"{c['rho']} kg/m",
            "damping": "50 N s", "model": "energy", "initial": {"shape": "straight", "theta": "0 deg"},
            "reel": {"law": "tension", "exit": "drum", "speed": f"{c['v0']} m/s", "rod_length": "2 km",
                     "retire_length": "100 m", "stored_length": f"{c['line'] - c['L0']} m",
                     "spool_inertia": f"{c['J']} kg m2", "drum_radius": f"{c['R']} m",
                     "reduced_mass": f"{mred!r} kg", "orbit_rate": f"{om!r} rad/s", "commanded_length": f"{c['lc1']} m",
                     "k1": c["k1"], "k2": c["k2"], "min_tension": f"{c['tmin']} N",
                     "stages": [{"at_length": f"{c['lc1']} m", "commanded_length": f"{c['lc2']} m"}]}}},
        "integrator": {"method": "radau5", "rtol": rtol, "atol": rtol},
        "output": {"count": count},
    })  # fmt: skip


def yes2_hold() -> "Hold":
    """The first stage's hold as studies/reel_hold.py's balance sees it (the scene's own numbers)."""
    from studies.reel_hold import Hold

    c = YES2
    a_m = 6378.137e3 + c["h"]
    om = math.sqrt(MU / a_m**3)
    mred = c["M"] * c["m"] / (c["M"] + c["m"])
    width = 0.01 * mred * om**2 * 3.0 * c["lc1"]  # the scene's default corner (tetherlab/scene/reels.py)
    return Hold(MU, a_m, c["M"], c["m"], c["rho"], c["EA"], c["line"], c["J"] / c["R"] ** 2, mred, c["lc1"], c["k1"],
                c["k2"], c["tmin"], width, up=1.0)  # fmt: skip


#: the two-stage run's outputs for its energy gate (docs/deployment.md 15.1): J's drift is the works'
#: trapezoid on the outputs (2.4 J at the scene's 801, 0.15 J at 3201), which this count makes 16
#: times smaller than the scene's for 6 s more of diagnostics
GATE_COUNT = 3201

HOLD_ORBITS = 8.0  # the first stage held alone: ~8 e-folds of the slowest closed-loop root (0.163 Omega)
HOLD_FROM_ORBITS = 6.0  # the state the settling bound starts from: two orbits before the end (the swing down to ~1e-3 of l)


def yes2_hold_scene(*, orbits: float = HOLD_ORBITS, count: int = 401, rod_length: str = "6 km"):
    """The YES2-like scene with its first stage held (no second stage) for ``orbits``.  One rod of
    the whole line by default (no birth up to 9 km): at rest the line is straight, which one rod
    represents with its load integrated, and the run costs 20 times fewer steps than with the
    scene's 2 km rods, whose two-rod phase RADAU5 steps through with 82 % of its steps rejected
    (docs/deployment.md 11.4: both settle within 0.03 m of each other)."""
    data = yes2_scene(count=count).to_dict()
    reel = data["tethers"]["main"]["reel"]
    reel.pop("stages")
    if rod_length != reel["rod_length"]:
        reel["rod_length"] = rod_length
        reel["birth_length"] = "9 km"
    data["duration"] = f"{orbits} orbits"
    return Scene.from_dict(data)


def yes2_profile(run) -> dict:
    """Time, deployed length, rate, exit tension, in-plane angle and commanded length."""
    from tetherlab.deployment import stage_length

    r = run.reel
    dg = pd.concat([ph.diagnostics[["t_s", "main.theta_rad"]] for ph in run.phases], ignore_index=True)
    keep = ~dg["t_s"].duplicated().to_numpy()
    sp = yes2_scene(count=3).tethers[0].reel.spool
    t = r["t_s"].to_numpy()[keep]
    # the second stage from its located switch (run.changes), the first's before
    switch = [c["t_s"] for c in run.changes if c["change"] == "stage"]
    lc = [sp.stages[0].commanded_length_m if switch and x >= switch[0] else stage_length(sp, float(x)) for x in t]
    return {"t": t, "L": r["deployed_length_m"].to_numpy()[keep], "v": r["speed_m_s"].to_numpy()[keep],
            "T": r["exit_tension_N"].to_numpy()[keep], "theta": dg["main.theta_rad"].to_numpy()[keep],
            "lc": lc}  # fmt: skip


def yes2_energy(run) -> dict:
    """The energy balance of the two-stage run without the orbit's share (docs/deployment.md 12.3,
    15.1): J = E + K_s + W_b + W_loss - Omega_0 H_z per output, Omega_0 the circular orbit's rate.
    Exactly constant for the model across the switch (state and works continuous, 10.7) and the
    births (6.1); returns the times (each once), J - J(0), the works' Richardson estimate on the
    outputs (studies/reel_laws.spool_energy), the round-off scale max |E| + Omega_0 |H_z| and the
    drift of E + K_s + W_b + W_loss alone."""
    from studies.reel_laws import spool_energy

    c = YES2
    om = math.sqrt(MU / (6378.137e3 + c["h"]) ** 3)
    total, est = spool_energy(run)
    inv = run.invariants.reset_index(drop=True)
    e, hz = inv["energy_J"].to_numpy(), inv["angmom_z_kg_m2_s"].to_numpy()
    j = total - om * hz
    t, first = np.unique(inv["t_s"].to_numpy(), return_index=True)  # a phase's first time repeats the last
    return {"t": t, "drift": (j - j[0])[first], "quadrature": est, "orbit_drift": float(np.abs(total - total[0]).max()),
            "scale": float(np.max(np.abs(e) + om * np.abs(hz)))}  # fmt: skip


def yes2_switch(run, rtol: float = 1e-8) -> dict:
    """The located switch to the second stage against its at_length (docs/deployment.md 10.7a,
    15.1): the deployed length where the run switched, the error, and the tolerance of the located
    stop in length by term (tetherlab.deployment.located_length_tolerance; the state's size at the
    switch, 6 (1 + rods) + 2: the root's position and one chord a rod, their rates, L and L').  No
    switch in the run: an infinite ratio."""
    from tetherlab.deployment import located_length_tolerance

    at = yes2_scene(count=3).tethers[0].reel.spool.stages[0].at_length_m
    sw = [c for c in run.changes if c["change"] == "stage"]
    if not sw:
        return {"at_m": at, "L_m": math.nan, "err_m": math.inf, "tol_m": math.nan, "ratio": math.inf, "t_s": math.nan,
                "terms": {}}  # fmt: skip
    t_b = sw[0]["t_s"]
    r = run.reel
    speed = float(np.abs(r.loc[r["t_s"] == t_b, "speed_m_s"].to_numpy()).max())
    before = [c for c in run.changes if c["t_s"] < t_b and c["change"] in ("birth", "retire")]
    ph_start = before[-1]["t_s"] if before else 0.0
    rods = before[-1]["rods"] if before else 1
    terms = located_length_tolerance(speed, t_b, t_b - ph_start, at, 6 * (1 + rods) + 2, rtol, rtol)
    err = abs(sw[0]["length_m"] - at)
    return {"at_m": at, "L_m": sw[0]["length_m"], "err_m": err, "tol_m": terms["total"], "ratio": err / terms["total"],
            "t_s": t_b, "terms": terms}  # fmt: skip


def hold_profile(run) -> dict:
    """t, L, v and the in-plane angle of a run (a phase's repeated first row dropped)."""
    r = run.reel
    dg = pd.concat([ph.diagnostics[["t_s", "main.theta_rad", "eccentricity"]] for ph in run.phases], ignore_index=True)
    keep = ~dg["t_s"].duplicated().to_numpy()
    return {"t": r["t_s"].to_numpy()[keep], "L": r["deployed_length_m"].to_numpy()[keep],
            "v": r["speed_m_s"].to_numpy()[keep], "theta": dg["main.theta_rad"].to_numpy()[keep],
            "ecc": dg["eccentricity"].to_numpy()[keep]}  # fmt: skip


def hold_measure(run) -> dict:
    """The held first stage against its derived equilibrium and the closed loop's settling from the
    state at HOLD_FROM_ORBITS (docs/deployment.md 11.4, 15): studies/reel_hold.settling_measure."""
    from studies.reel_hold import settling_measure

    h = yes2_hold()
    pr = hold_profile(run)
    t0 = HOLD_FROM_ORBITS * 2.0 * math.pi / h.omega
    m = settling_measure(pr, h, t0, rtol=1e-8, ecc_max=float(pr["ecc"][pr["t"] >= t0].max()))
    m["profile"] = pr
    return m
