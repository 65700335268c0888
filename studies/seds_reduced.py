"""An independent reduced model of the SEDS-like deployment (docs/deployment.md 12.1): a straight,
inextensible, massive line of length l at the in-plane angle theta from the local vertical, with
the end mass at its end and the stage (with the stored line) at its start, in the Hill frame of the
system's centre of mass; the canister's jump rho l'^2 and Carnot loss and the Coulomb brake with
the scene's smooth sign. Integrated with scipy, nothing of the simulator imported.

The comparison of the TMED run with it is a gate (docs/deployment.md 12.2, `make verify`
deployment part J): every term the reduced model leaves out is bounded as a perturbation of its
l'' and theta'' and carried to (l, theta) at each output by the model's own linearisation.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp

from studies.reel_laws import MU, SEDS

R_EARTH_M = 6378.137e3  # the scene's "earth" preset radius (tetherlab/scene/data.py)
VS = 0.01  # m/s, the scene's friction_speed (the brake's smooth sign)
FIELD_P3 = 2.1  # max |dP3(cos x)/dx| = 2.07 (docs/deployment.md 14.1 (a))
BOW_MAX = 0.05  # the window: the bow's bound at most this fraction of l (12.2 (b): first order in it)
GRID = 1001  # the quadrature grid of the budget's integrals over [0, t]


def constants() -> dict:
    c = SEDS
    a_m = R_EARTH_M + c["h"]
    return {"a": a_m, "om": math.sqrt(MU / a_m**3), "rho": c["rho"], "m": c["m"], "line": c["line"],
            "fc": c["brake"], "m_tot": c["M"] + c["m"] + c["rho"] * c["line"], "EA": c["EA"]}  # fmt: skip


def parts(y) -> dict:
    """Everything the reduced model knows at the state y = [l, l', theta, theta']: its accelerations
    ((12.1)-(12.2)), the mass properties and the exit's tension (10.2 with m_s = 0, eps = 0)."""
    k = constants()
    rho, m, m_tot, om = k["rho"], k["m"], k["m_tot"], k["om"]
    l, ld, th, thd = y
    q = rho * l + m  # deployed mass
    s1 = rho * l * l / 2 + m * l  # its first moment about the stage
    mu_l = q * (1 - q / m_tot)
    dmu = rho * (1 - 2 * q / m_tot)
    inertia = rho * l**3 / 3 + m * l * l - s1 * s1 / m_tot  # about the centre of mass
    d_inertia = rho * l * l + 2 * m * l - 2 * s1 * q / m_tot
    brake = k["fc"] * math.tanh(ld / VS)
    w = thd + om
    l_terms = (-0.5 * dmu * ld * ld, -brake, -0.5 * rho * ld * ld,
               d_inertia * (thd * w - thd * thd / 2 + 1.5 * om**2 * math.cos(th) ** 2))
    ldd = sum(l_terms) / mu_l
    th_terms = (-d_inertia * ld * w / inertia, -3 * om**2 * math.sin(th) * math.cos(th))
    thdd = sum(th_terms)
    return {"l": l, "ld": ld, "th": th, "w": w, "ldd": ldd, "thdd": thdd, "q": q, "s1": s1, "mu": mu_l,
            "inertia": inertia, "brake": brake, "exit_tension": rho * ld * ld + brake,
            "l_scale": sum(abs(x) for x in l_terms) / mu_l, "th_scale": sum(abs(x) for x in th_terms)}  # fmt: skip


def rhs(_t, y):
    p = parts(y)
    return [y[1], p["ldd"], y[3], p["thdd"]]


def seds_reduced(*, rtol: float = 1e-10):
    """(t_end s, final state [l, l', theta, theta'], dense solution) of the reduced model from the
    scene's start (200 m out at 1.6 m/s along the local vertical, at rest in the Hill frame) to the
    end of the line; equations (12.1)-(12.2) of docs/deployment.md."""
    c = SEDS

    def spent(_t, y):
        return y[0] - c["line"]

    spent.terminal = True
    sol = solve_ivp(rhs, (0.0, 2e4), [c["L0"], c["v0"], 0.0, 0.0], method="Radau", rtol=rtol, atol=rtol,
                    events=spent, dense_output=True)  # fmt: skip
    if not sol.t_events[0].size:
        raise RuntimeError("reduced SEDS model: the line was not paid out within 2e4 s")
    return float(sol.t_events[0][0]), np.asarray(sol.y_events[0][0]), sol.sol


def exit_tension(ld: float) -> float:
    """The canister's exit tension of the inextensible line, rho l'^2 + F_c tanh(l'/v_s) (10.2)."""
    return SEDS["rho"] * ld * ld + SEDS["brake"] * math.tanh(ld / VS)


def line_tension(p: dict, s: np.ndarray) -> np.ndarray:
    """The axial tension T(s) of the reduced model's straight line at the distance s from the exit
    (docs/deployment.md 12.2 (b)): T' = -rho (c x - l'' + sigma''), x = s - sigma the distance from
    the centre of mass, c = omega^2 + Omega^2 (3 cos^2 theta - 1), from T(0) = rho l'^2 + F_b."""
    k = constants()
    rho, om = k["rho"], k["om"]
    sigma = p["s1"] / k["m_tot"]
    sigma_dd = (rho * p["ld"] ** 2 + p["q"] * p["ldd"]) / k["m_tot"]
    c = p["w"] ** 2 + om**2 * (3 * math.cos(p["th"]) ** 2 - 1)
    return p["exit_tension"] - rho * (c * (s * s / 2 - sigma * s) - (p["ldd"] - sigma_dd) * s)


def tip_tension(p: dict) -> float:
    """The end mass's pull m (c x_tip - l'' + sigma''): equal to line_tension at s = l when the
    reduced model's (12.2) is the line's momentum balance (a check, tests/test_reel_spool.py)."""
    k = constants()
    sigma = p["s1"] / k["m_tot"]
    sigma_dd = (k["rho"] * p["ld"] ** 2 + p["q"] * p["ldd"]) / k["m_tot"]
    c = p["w"] ** 2 + k["om"] ** 2 * (3 * math.cos(p["th"]) ** 2 - 1)
    return k["m"] * (c * (p["l"] - sigma) - p["ldd"] + sigma_dd)


def bow(p: dict) -> dict:
    """Bounds of the line's bow from its chord (docs/deployment.md 12.2 (b)): the lateral load
    the straight line's rotation leaves unbalanced, q(x) = rho (-3 Omega^2 x sin cos - x theta''
    - 2 (l' - sigma') omega) at its largest (linear in x: at an end), on a string of the effective
    tension T - rho l'^2 (the material moving along the curve at l'); y_max <= q l^2 T_max / (8
    T_min^2), |y'| <= q l (1 + T_max/(2 T_min)) / T_min; the axial loads' resultant P = int |T'| ds."""
    k = constants()
    rho, om = k["rho"], k["om"]
    l = p["l"]
    sigma = p["s1"] / k["m_tot"]
    sigma_d = p["q"] * p["ld"] / k["m_tot"]
    sc = math.sin(p["th"]) * math.cos(p["th"])
    lateral = [rho * (-3 * om**2 * x * sc - x * p["thdd"] - 2 * (p["ld"] - sigma_d) * p["w"]) for x in (-sigma, l - sigma)]
    q = max(abs(v) for v in lateral)
    s = np.linspace(0.0, l, 65)
    T = line_tension(p, s)
    t_eff = T - rho * p["ld"] ** 2
    t_min, t_max = float(t_eff.min()), float(t_eff.max())
    load = np.abs(np.diff(T))
    if t_min <= 0.0:
        return {"y": math.inf, "slope": math.inf, "P": float(load.sum()), "t_min": t_min, "T_max": float(T.max())}
    slope = q * l * (1 + t_max / (2 * t_min)) / t_min
    return {"y": q * l * l * t_max / (8 * t_min**2), "slope": slope, "P": float(load.sum()),
            "t_min": t_min, "T_max": float(T.max()), "q": q}  # fmt: skip


def jacobian(y) -> np.ndarray:
    """d rhs / d y of the reduced model by central differences (its linearisation, 12.2)."""
    y = np.asarray(y, float)
    out = np.empty((4, 4))
    for j in range(4):
        h = 1e-6 * max(abs(y[j]), 1e-3 if j in (2, 3) else 1.0)
        yp, ym = y.copy(), y.copy()
        yp[j] += h
        ym[j] -= h
        out[:, j] = (np.asarray(rhs(0.0, yp)) - np.asarray(rhs(0.0, ym))) / (2 * h)
    return out


def sensitivity(t_s: np.ndarray, *, rtol: float = 1e-8) -> dict:
    """The reduced model from the scene's start with its variational equation: the states, the
    Jacobians A and the transition matrices Phi(t) at the times t_s. A perturbation f(tau) of
    (l'', theta'') moves the state by int_0^t Phi(t) Phi(tau)^-1 [0, f_l, 0, f_th] dtau.
    Phi needs a few digits only (it weighs bounds); the reference state is seds_reduced's, at
    rtol 1e-10."""
    c = SEDS

    def rhs_var(_t, z):
        y = z[:4]
        phi = z[4:].reshape(4, 4)
        return np.concatenate((rhs(0.0, y), (jacobian(y) @ phi).ravel()))

    z0 = np.concatenate(([c["L0"], c["v0"], 0.0, 0.0], np.eye(4).ravel()))
    t_s = np.asarray(t_s, float)
    sol = solve_ivp(rhs_var, (t_s[0], t_s[-1]), z0, method="DOP853", t_eval=t_s, rtol=rtol, atol=rtol * 1e-3)

    if not sol.success:
        raise RuntimeError(f"reduced SEDS model's sensitivity: {sol.message}")
    y = sol.y[:4].T
    return {"y": y, "phi": sol.y[4:].T.reshape(-1, 4, 4), "A": np.array([jacobian(v) for v in y]),
            "parts": [parts(v) for v in y]}


def window_end(sol, t_end: float) -> float:
    """The last time of the comparison's window: the reduced model's bow bound y_max <= BOW_MAX l
    (12.2 (b)), found on a 10 s grid from the start."""
    for t in np.arange(0.0, t_end, 10.0):
        b = bow(parts(sol(t)))
        if not b["y"] <= BOW_MAX * sol(t)[0]:
            return float(t - 10.0)
    return float(t_end)


def seds_measure(prof: dict, fine: dict | None = None, coarse: dict | None = None) -> dict:
    """The TMED run's in-plane angle and deployed length (``prof``: studies/reel_laws.seds_profile)
    against the reduced model at every output of the window, and their budgets term by term
    (docs/deployment.md 12.2): the field's P3 term, the line's bow, its strain, each as a bound of a
    perturbation of (l'', theta'') carried by the reduced model's linearisation; the rods'
    discretisation (``coarse``: the run with rods twice as long, Richardson at order 2) and the
    integrator's error (``fine``: the run at a tenth of its rtol, twice the difference). The worst
    ratio error / budget over the outputs, of the angle and of the length."""
    k = constants()
    om = k["om"]
    t_end, _y_end, sol = seds_reduced()
    t_w = window_end(sol, t_end)
    # a birth ends a phase: its time is reported twice (same state), keep the first
    t_all, first = np.unique(prof["t"], return_index=True)
    sel = first[t_all <= t_w]
    t = prof["t"][sel]
    tau = np.linspace(0.0, t_w, GRID)
    both, back = np.unique(np.concatenate((tau, t)), return_inverse=True)
    sv = sensitivity(both)  # one integration for the grid and the outputs
    s = {key: (v[back[:GRID]] if key != "parts" else [v[j] for j in back[:GRID]]) for key, v in sv.items()}
    at = {"phi": sv["phi"][back[GRID:]], "y": np.array([sol(x) for x in t])}
    ps = s["parts"]
    keys = ("l", "ld", "w", "thdd", "inertia", "mu", "l_scale", "th_scale")
    arr = {key: np.array([p[key] for p in ps]) for key in keys}
    bows = [bow(p) for p in ps]
    l = arr["l"]
    # (a) the field beyond the gravity gradient
    f_th_a = FIELD_P3 * om**2 * l / k["a"]
    f_l_a = 3.0 * om**2 * l * l / k["a"]
    # (b) the bow: the axial loads' moment on the sag and the transport along the curve (first
    # order, x2 for the lateral modes as in 14.1 (c)); its radial effect is second order
    yb = np.array([b["y"] for b in bows])
    slope = np.array([b["slope"] for b in bows])
    load = np.array([b["P"] for b in bows])
    t_line = np.array([b["T_max"] for b in bows])
    f_th_b = 2.0 * (yb * load + k["rho"] * arr["ld"] ** 2 * l * slope) / arr["inertia"]
    f_l_b = t_line * slope**2 / arr["mu"]
    # (c) the strain: |eps| <= the running maximum of the line's tension over EA (T = EA eps + D eps'
    # is a low-pass of T/EA with unit gain); its relative change of the geometry perturbs every term
    # by 2 eps; its rate enters theta'' as -2 eps' omega, integrated by parts
    e_b = np.maximum.accumulate(t_line) / k["EA"]
    f_th_c = 2.0 * e_b * arr["th_scale"]
    f_l_c = 2.0 * e_b * arr["l_scale"]
    inv = np.linalg.inv(s["phi"])  # Phi(tau)^-1
    dinv = -inv @ s["A"]  # its derivative in tau
    wq = np.full(GRID, tau[1] - tau[0])
    wq[0] = wq[-1] = 0.5 * wq[0]
    names = ("field", "bow", "strain", "rods", "integration")
    terms = {q: {n: np.zeros(len(t)) for n in names} for q in ("theta", "L")}
    for i in range(len(t)):
        kk = tau <= t[i] + 1e-9
        gm = at["phi"][i] @ inv[kk]  # Phi(t) Phi(tau)^-1 on the grid up to t
        dgm = at["phi"][i] @ dinv[kk]
        for q, row in (("theta", 2), ("L", 0)):
            g_l, g_th = np.abs(gm[:, row, 1]), np.abs(gm[:, row, 3])
            terms[q]["field"][i] = np.sum((g_l * f_l_a[kk] + g_th * f_th_a[kk]) * wq[kk])
            terms[q]["bow"][i] = np.sum((g_l * f_l_b[kk] + g_th * f_th_b[kk]) * wq[kk])
            by_parts = np.abs(dgm[:, row, 3] * arr["w"][kk] + gm[:, row, 3] * arr["thdd"][kk])
            terms[q]["strain"][i] = np.sum((g_l * f_l_c[kk] + g_th * f_th_c[kk] + 2.0 * e_b[kk] * by_parts) * wq[kk])
    ref = {"theta": at["y"][:, 2], "L": at["y"][:, 0]}
    run = {"theta": prof["theta"][sel], "L": prof["L"][sel]}
    for q in ("theta", "L"):
        if coarse is not None:
            d = np.abs(run[q] - np.interp(t, coarse["t"], coarse[q]))
            terms[q]["rods"] = np.maximum.accumulate(d) / 3.0  # Richardson, order 2: e(h) = |x(2h) - x(h)| / (2^2 - 1)
        if fine is not None:
            d = np.abs(run[q] - np.interp(t, fine["t"], fine[q]))
            terms[q]["integration"] = 2.0 * np.maximum.accumulate(d)
    # the run reports the unstretched length, the reduced model the chord: L (1 + eps) = l, and
    # released unstretched the axial transient at most doubles the static stretch (11.1's argument)
    e_out = np.interp(t, tau, e_b)
    terms["L"]["strain"] = terms["L"]["strain"] + 2.0 * e_out * at["y"][:, 0]
    out = {"t": t, "t_window": t_w, "t_end_reduced": t_end, "l_window": float(sol(t_w)[0]), "terms": terms}
    for q in ("theta", "L"):
        err = np.abs(run[q] - ref[q])
        budget = sum(terms[q].values())
        ratio = err / np.where(budget > 0, budget, math.inf)
        worst = int(np.argmax(ratio))
        out[q] = {"err": err, "budget": budget, "ratio": float(ratio[worst]), "worst": worst}
    out["ratio"] = max(out["theta"]["ratio"], out["L"]["ratio"])
    return out
