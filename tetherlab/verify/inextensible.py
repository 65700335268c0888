"""The inextensible tether model's measurements and gates (docs/inextensible.md section 6).

* lateral modes of the hanging chain with a tip mass (studies/scenes/hanging-chain.toml, model
  "inextensible") against the rigid-link chain's generalized eigenproblem of uniform bars
  (tetherlab.oracles.hanging_chain.uniform_chain_modes: an independent assembly; the inextensible
  rods linearised about the vertical hang are exactly those bars) and against the Bessel solution
  (observed order);
* energy and constraint drift over a long conservative run, and the same run with the
  stabilisation off (the negative control);
* the elastic model converging to the inextensible one as EA grows (slope in 1/EA);
* libration, sqrt3 w in plane and 2 w out of plane, with the inextensible model.

The tests (tests/test_inextensible.py) and ``verify --only inextensible`` call these.
"""

from __future__ import annotations

import math

import numpy as np

from .checkout import SCENES

L_M, MASS_KG, TIP_KG, G = 10.0, 1.0, 0.5, 9.80665  # studies/scenes/hanging-chain.toml
SQ3 = math.sqrt(3.0)
#: amplitudes of the release (end mass aside, m): mode 1, mode 2; the frequency is extrapolated to
#: zero from A, 2A and 4A, which removes the A^2 and A^4 terms of the amplitude shift
AMPLITUDE_M = {1: 0.01, 2: 0.0025}


def chain_scene(n: int, *, model: str = "inextensible", mode: int = 1, amplitude_m: float = 0.001,
                rtol: float = 1e-12, method: str = "vern9", rate=None, ea=None, duration=None, count=None):
    """The hanging chain released in a lateral mode, with these changes."""
    from ..scene import load_scene

    ch = {"tethers.main.rods": n, "tethers.main.model": model, "integrator.method": method,
          "integrator.rtol": rtol, "integrator.atol": rtol,
          "tethers.main.initial.release": {"mode": mode, "amplitude": f"{amplitude_m!r} m"}}  # fmt: skip
    if rate is not None:
        ch["tethers.main.constraint_rate"] = f"{rate!r} 1/s"
    if ea is not None:
        ch["tethers.main.EA"] = f"{ea!r} N"
    if duration is not None:
        ch["duration"] = duration
    if count is not None:
        ch["output.count"] = count
    return load_scene(SCENES / "hanging-chain.toml").replace(**ch)


def chain_frequency(n: int, mode: int, amplitude_m: float, **kw) -> tuple[float, dict]:
    """The lateral frequency of the end mass's sideways motion (a least-squares fit over the run)
    and the run's statistics."""
    from ..oracles.continuum import fit_frequencies
    from ..oracles.hanging_chain import continuum_frequencies
    from ..pipeline import simulate

    res = simulate(chain_scene(n, mode=mode, amplitude_m=amplitude_m, **kw), progress=False)
    if not res.ok:
        raise RuntimeError(f"hanging chain n = {n}, mode {mode}: {res.message}")
    ts = res.timeseries
    # the release lays the continuum's mode shape on the rods, which is not exactly the chain's:
    # the neighbouring modes ring at a small amplitude, independent of A, and are fitted too
    guesses = continuum_frequencies(L_M, MASS_KG, TIP_KG, G, count=min(n, 3))
    w, _, _ = fit_frequencies(ts["t_s"].to_numpy(), ts["tip.x_m"].to_numpy(), guesses)
    return float(w[mode - 1]), res.stats


def zero_amplitude_frequency(n: int, mode: int, **kw) -> float:
    """The small-oscillation frequency: w(A) = w0 + c2 A^2 + c4 A^4 + O(A^6) fitted through A, 2A,
    4A (docs/hanging-chain.md 4 measures the shift: quadratic, with an A^4 remainder of 4e-8 for
    mode 2 from 1 and 2 cm at 8 rods)."""
    a = AMPLITUDE_M[mode]
    amps = np.array([a, 2 * a, 4 * a])
    ws = np.array([chain_frequency(n, mode, float(x), **kw)[0] for x in amps])
    V = np.stack([np.ones(3), amps**2, amps**4], axis=1)
    return float(np.linalg.solve(V, ws)[0])


def rigid_chain_error(n: int, mode: int, **kw) -> float:
    """w0 / w_bars - 1 against n uniform bars of the unstretched lengths."""
    from ..oracles.hanging_chain import uniform_chain_modes

    w_bars = uniform_chain_modes(n, L_M, MASS_KG, TIP_KG, G)[0][mode - 1]
    return zero_amplitude_frequency(n, mode, **kw) / w_bars - 1.0


def drift_run(scene) -> dict:
    """Integrate a scene with inextensible tethers; its constraint drift and energy error.

    drift_length: max over rods and outputs of | |D| - l | / l, D = 2 sqrt3 d the rod vector;
    drift_rate_1_s: max of |D . D'| / l^2 (the constraint's derivative, per second);
    energy: max |E - E0| / max(|KE0|, |V0|)  (the diagnostics' own scale); steps."""
    from .. import diagnostics as D
    from ..model.params import ParamView
    from ..pipeline import integrate_prepared, prepare

    prep = prepare(scene)
    res, _ = integrate_prepared(prep, prep.model.fresh_params())
    if res.status != 0:
        raise RuntimeError(f"{scene.name}: {res.message}")
    lay = prep.model.state
    lengths = ParamView(prep.model.p).rods.length_m
    Y = np.asarray(res.y)
    worst_l = worst_r = 0.0
    for t, sl in zip(prep.model.tethers, prep.model.rod_slices):
        if t.model != "inextensible":
            continue
        for g in range(sl.start, sl.stop):
            d = Y[:, lay.rod(g)]
            dd = Y[:, lay.rod_rate(g)]
            ell = lengths[g]
            worst_l = max(worst_l, float(np.max(np.abs(2 * SQ3 * np.linalg.norm(d, axis=1) - ell))) / ell)
            worst_r = max(worst_r, float(np.max(np.abs(12.0 * np.sum(d * dd, axis=1)))) / ell**2)
    glob = D.compute(prep.model, np.asarray(res.t), Y)["global"]
    e = glob[:, D.G_E]
    scale = max(abs(glob[0, D.G_KE]), abs(glob[0, D.G_VG]))
    return {"drift_length": worst_l, "drift_rate_1_s": worst_r, "energy": float(np.max(np.abs(e - e[0]))) / scale,
            "steps": int(res.stats["n_accepted"]), "rtol": scene.integrator.rtol, "t_end_s": float(res.t[-1])}


def bessel_errors(ns, mode: int, **kw) -> np.ndarray:
    """w0 / w_Bessel - 1 for each rod count (tetherlab.oracles.hanging_chain.continuum_frequencies)."""
    from ..oracles.hanging_chain import continuum_frequencies

    wc = continuum_frequencies(L_M, MASS_KG, TIP_KG, G, count=2)[mode - 1]
    return np.array([zero_amplitude_frequency(n, mode, **kw) / wc - 1.0 for n in ns])


def observed_order(ns, errors) -> float:
    """-slope of log|error| against log n (least squares)."""
    return float(-np.polyfit(np.log(np.asarray(ns, float)), np.log(np.abs(errors)), 1)[0])


def ea_convergence(eas=(1e5, 1e6, 1e7, 1e8), n: int = 8) -> tuple[float, np.ndarray]:
    """The elastic model's first lateral frequency against the inextensible one's as EA grows:
    (slope of log|w_EA / w_inext - 1| against log(1/EA), the differences).  The elastic rods hang
    stretched by T/EA, so the difference is O(1/EA); RADAU5 for the elastic rods (their axial
    modes are stiff), Vern9 for the inextensible ones, rtol 1e-12 both."""
    w_in = zero_amplitude_frequency(n, 1)
    diffs = np.array([zero_amplitude_frequency(n, 1, model="paper", method="radau5", ea=ea) / w_in - 1.0 for ea in eas])
    slope = float(np.polyfit(np.log(1.0 / np.asarray(eas)), np.log(np.abs(diffs)), 1)[0])
    return slope, diffs


def libration_errors(ns=(1, 2, 4)) -> dict:
    """{(plane, n): f / f_theory - 1} for the inextensible tether of studies/scenes/libration-inplane.toml
    released 0.05 rad from its relative equilibrium, 3 orbits (rigid dumbbell: sqrt3 w in plane, 2 w out
    of plane; verify/checks.py does the same for the elastic models)."""
    from ..diagnostics import zero_crossing_frequency
    from ..pipeline import simulate
    from ..scene import load_scene

    mu = 3.986004418e14  # the scene's central body, Earth (EGM2008 / WGS 84 GM)
    out = {}
    for plane in ("in", "out"):
        for n in ns:
            sc = load_scene(SCENES / "libration-inplane.toml").replace(**{
                "tethers.main.rods": n, "tethers.main.model": "inextensible",
                "tethers.main.initial.theta": "0.05 rad" if plane == "in" else "0 rad",
                "tethers.main.initial.phi": "0.05 rad" if plane == "out" else "0 rad",
                "orbit.motion": "equilibrium", "duration": "3 orbits", "output.count": 3001})  # fmt: skip
            d = simulate(sc, progress=False).diagnostics
            w = math.sqrt(mu / d["com_radius_m"].iloc[0] ** 3)
            col = "main.theta_rad" if plane == "in" else "main.phi_rad"
            expected = math.sqrt(3.0) * w if plane == "in" else 2.0 * w
            out[plane, n] = zero_crossing_frequency(d["t_s"].to_numpy(), d[col].to_numpy()) / expected - 1.0
    return out


def long_run_scene(rate=None):
    """The conservative long run of the drift and energy gates: the hanging chain, 8 rods, released
    in its first mode at 1 cm, 3500 s (600 periods), DOP853 at rtol 1e-10."""
    return chain_scene(8, amplitude_m=0.01, rtol=1e-10, method="dop853", rate=rate, duration="3500 s", count=3501)


#: drift bound: a rod's length error, relative (docs/inextensible.md 6.3)
DRIFT_BOUND = 1e-9

MU_EARTH = 3.986004418e14  # m^3/s^2, the libration scene's central body (EGM2008 / WGS 84 GM)
ORBIT_R0_M = 7.4e6  # studies/scenes/libration-inplane.toml: circular orbit of the centre of mass


def orbit_drift_scene(rate=None, days: float = 35.0):
    """The long orbital run of the drift gate: the in-plane libration scene (5 km, 10 kg between
    1000 kg and 100 kg at 7400 km), 4 inextensible rods, 30 deg, DOP853 rtol 1e-10, 3501 outputs."""
    from ..scene import load_scene

    ch = {"tethers.main.rods": 4, "tethers.main.model": "inextensible", "duration": f"{days!r} d", "output.count": 3501}
    if rate is not None:
        ch["tethers.main.constraint_rate"] = f"{rate!r} 1/s"
    return load_scene(SCENES / "libration-inplane.toml").replace(**ch)


def orbit_drift_bound(run: dict) -> float:
    """Baumgarte's critically damped constraint forgets a violation in about 1/a; over that time
    the integrator adds one local error per step, each below rtol (relative): the length error
    stays below 2 rtol x (steps per 1/a), a = the default rate, the mean motion (docs/inextensible.md
    6.3).  The rate is the scene's default, not the run's, so a run with the rate zeroed is held to
    the same bound."""
    a = math.sqrt(MU_EARTH / ORBIT_R0_M**3)
    return 2.0 * run["rtol"] * run["steps"] / (a * run["t_end_s"])


def check_inextensible(rows_out, quick: bool = False):
    """The gates of the inextensible model (references/gates.toml, inextensible_*)."""
    ns = (4, 8) if quick else (4, 8, 16)
    worst = 0.0
    for n in ns:
        for mode in (1, 2):
            e = rigid_chain_error(n, mode)
            rows_out.append({"case": f"hanging chain, n = {n}, mode {mode}: w0 / w_bars - 1", "value": e})
            worst = max(worst, abs(e))
    gates = {"inextensible_rigid_chain": worst}
    if quick:
        gates["inextensible_drift"] = drift_run(long_run_scene())["drift_length"]
        orb = drift_run(orbit_drift_scene())
        gates["inextensible_drift_orbit"] = orb["drift_length"] / orbit_drift_bound(orb)
        gates["inextensible_libration"] = max(abs(e) for e in libration_errors(ns=(1, 2)).values())
        return gates
    order_ns = (8, 16, 32, 64)
    dev = 0.0
    for mode in (1, 2):
        err = bessel_errors(order_ns, mode)
        p = observed_order(order_ns, err)
        rows_out.append({"case": f"mode {mode} against Bessel, n = {order_ns}: errors {np.array2string(err, precision=3)}",
                         "value": p})  # fmt: skip
        dev = max(dev, abs(p - 2.0))
    gates["inextensible_bessel_order"] = dev
    on = drift_run(long_run_scene())
    off = drift_run(long_run_scene(rate=0.0))
    for name, r in (("stabilised", on), ("stabilisation off (control)", off)):
        rows_out.append({"case": f"3500 s, {name}: max | |D| - l | / l", "value": r["drift_length"]})
        rows_out.append({"case": f"3500 s, {name}: max |D.D'| / l^2 (1/s)", "value": r["drift_rate_1_s"]})
        rows_out.append({"case": f"3500 s, {name}: energy error / (sqrt(steps) rtol)",
                         "value": r["energy"] / (math.sqrt(r["steps"]) * r["rtol"])})  # fmt: skip
    gates["inextensible_drift"] = on["drift_length"]
    gates["inextensible_drift_control"] = DRIFT_BOUND / off["drift_length"]
    gates["inextensible_energy"] = on["energy"] / (math.sqrt(on["steps"]) * on["rtol"])
    orb_on = drift_run(orbit_drift_scene())
    orb_off = drift_run(orbit_drift_scene(rate=0.0))
    for name, r in (("stabilised", orb_on), ("stabilisation off (control)", orb_off)):
        rows_out.append({"case": f"35 d on orbit, 4 rods, {name}: max | |D| - l | / l (bound {orbit_drift_bound(r):.3g})",
                         "value": r["drift_length"]})  # fmt: skip
    gates["inextensible_drift_orbit"] = orb_on["drift_length"] / orbit_drift_bound(orb_on)
    gates["inextensible_drift_orbit_control"] = orbit_drift_bound(orb_off) / orb_off["drift_length"]
    slope, diffs = ea_convergence()
    rows_out.append({"case": f"elastic against inextensible, EA = 1e5 ... 1e8: {np.array2string(diffs, precision=3)}",
                     "value": slope})  # fmt: skip
    gates["inextensible_ea_slope"] = abs(slope - 1.0)
    lib = libration_errors()
    for (plane, n), e in lib.items():
        rows_out.append({"case": f"{plane}-plane libration, n = {n}: f / f_theory - 1", "value": e})
    gates["inextensible_libration"] = max(abs(e) for e in lib.values())
    return gates
