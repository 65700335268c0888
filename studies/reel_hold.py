"""The tension law's hold with a massive line (docs/deployment.md 11.4): where a line at rest
along the local vertical, with its own mass, the end mass and a drum, has the law's command as its
exit tension, and how fast the closed loop settles there.

* `hold_equilibrium`: the static balance in the frame turning with the orbit, the whole central
  field (not only its gradient), the line's own load and its strain, solved for the length at which
  the exit tension equals the law's command (its smooth lower limit included);
* `hold_linear_model`: the closed loop linearised about that rest state, with the line's mass and
  the drum's (the reduced model of 12.1 with the spool's inertia): its matrix and roots;
* `settling_bound`: the linear model's response from a measured state at t0, the budget of the
  gates of parts K and L (docs/deployment.md 11.4, 14.2, 15).

Plain numpy and scipy: independent of the TMED kernels it checks.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm
from scipy.optimize import brentq


@dataclass(frozen=True)
class Hold:
    """A line of density rho between a station M (the body without its stored line) and an end mass
    m on a circular orbit of radius a (rate Omega = sqrt(mu/a^3)), paid from a drum with J/R^2 = j_r
    holding `line` in all; the tension law (m*, l_c, k1, k2; T_min with its corner width w).  `up`:
    +1 when the end mass is radially outward of the station (the scenes' side "up"), -1 inward."""

    mu: float
    a: float
    M: float
    m: float
    rho: float
    EA: float
    line: float
    j_r: float
    mstar: float
    lc: float
    k1: float
    k2: float
    tmin: float = 0.0
    width: float = 0.0
    up: float = 1.0

    @property
    def omega(self) -> float:
        return math.sqrt(self.mu / self.a**3)

    def command(self, l_m: float) -> float:
        """The law at rest, T_c = m* Omega^2 [3 l_c + k1 (l - l_c)], bent above T_min as the kernel's
        softplus corner does (docs/deployment.md 10.4)."""
        tc = self.mstar * self.omega**2 * (3.0 * self.lc + self.k1 * (l_m - self.lc))
        if self.width > 0.0:
            z = (tc - self.tmin) / self.width
            tc = self.tmin + (tc - self.tmin if z > 30.0 else self.width * math.log1p(math.exp(z)))
        return tc


def _field(h: Hold, x):
    """The outward specific force along the radial line in the frame turning at Omega about the
    planet's centre, x above the orbit's radius: Omega^2 (a + x) - mu/(a + x)^2 (= 3 Omega^2 x
    - 3 Omega^2 x^2/a + ...)."""
    return h.omega**2 * (h.a + x) - h.mu / (h.a + x) ** 2


def exit_tension(h: Hold, l_m: float, *, strain: bool = True, full_field: bool = True, n: int = 4001) -> float:
    """The exit tension of the line at rest along the local vertical with l_m unstretched out
    (docs/deployment.md 11.4): the system's balance fixes the station's place x0, the station's own
    balance then gives T = |M_s g(x0)|, M_s = M + rho (line - l).  The strain eps(s) = T(s)/EA places
    the line's material (fixed-point iteration: eps ~ 1e-5 here, two passes converge)."""
    g = (lambda x: _field(h, x)) if full_field else (lambda x: 3.0 * h.omega**2 * x)
    s = np.linspace(0.0, l_m, n)
    ms = h.M + h.rho * (h.line - l_m)
    eps = np.zeros(n)
    for _ in range(4 if strain else 1):
        z = h.up * np.concatenate([[0.0], np.cumsum(0.5 * (2.0 + eps[1:] + eps[:-1]) * np.diff(s))])

        def balance(x0, z=z):
            f = g(x0 + z)
            return ms * g(x0) + h.rho * np.trapezoid(f, s) + h.m * f[-1]

        x0 = brentq(balance, -1.5 * l_m, 1.5 * l_m, xtol=1e-12)
        f = g(x0 + z)
        below = np.concatenate([[0.0], np.cumsum(0.5 * (f[1:] + f[:-1]) * np.diff(s))])
        eps = h.up * (h.rho * (below[-1] - below) + h.m * f[-1]) / h.EA
    return abs(ms * g(x0))


def hold_equilibrium(h: Hold, **kw) -> float:
    """The length at which the exit tension at rest equals the law's command (docs/deployment.md
    11.4): a root of T(l) - T_c(l), bracketed about l_c (the slope is -(k1 - 3 - 3 rho l/m*) m* Omega^2)."""
    lo, hi = 0.5 * h.lc, 2.0 * h.lc
    return brentq(lambda l: exit_tension(h, l, **kw) - h.command(l), lo, hi, xtol=1e-9)


def first_order_offset(h: Hold, l_m: float) -> float:
    """l - l_c from the gradient alone, no strain (docs/deployment.md (11.5)): 3 (f(l) - m* l) / (m* (k1 - 3))
    with f = M_s S / M_t, S = m l + rho l^2/2; ~ 3 rho l^2 / (2 m* (k1 - 3)) for a heavy station."""
    mt = h.M + h.m + h.rho * h.line
    f = (h.M + h.rho * (h.line - l_m)) * (h.m * l_m + 0.5 * h.rho * l_m**2) / mt
    return 3.0 * (f - h.mstar * l_m) / (h.mstar * (h.k1 - 3.0))


def hold_linear_model(h: Hold, l_m: float):
    """The closed loop about rest at l_m, theta = 0, state (xi, xi', theta, theta') with
    xi = (L - l)/l and ' = d/d(Omega t) (docs/deployment.md 11.4 (11.6)):

        (mu + m_s) xi'' = -m* (k1 xi + k2 xi') + (I_l/l) theta' + (3/2) I_ll xi,
        theta'' + (I_l l / I) xi' + 3 theta = 0,

    mu = q (1 - q/M_t), q = m + rho l, I = J - S^2/M_t, I_l = 2 S M_s/M_t, I_ll = 2 (q M_s - rho S)/M_t,
    m_s = J/R^2 + rho (line - l).  Returns (A, roots)."""
    mt = h.M + h.m + h.rho * h.line
    ms_body = h.M + h.rho * (h.line - l_m)
    q = h.m + h.rho * l_m
    S = h.m * l_m + 0.5 * h.rho * l_m**2
    J = h.m * l_m**2 + h.rho * l_m**3 / 3.0
    inertia = J - S * S / mt
    i_l = 2.0 * S * ms_body / mt
    i_ll = 2.0 * (q * ms_body - h.rho * S) / mt
    radial = q * (1.0 - q / mt) + h.j_r + h.rho * (h.line - l_m)
    A = np.array([[0.0, 1.0, 0.0, 0.0],
                  [(1.5 * i_ll - h.mstar * h.k1) / radial, -h.mstar * h.k2 / radial, 0.0, i_l / (l_m * radial)],
                  [0.0, 0.0, 0.0, 1.0],
                  [0.0, -i_l * l_m / inertia, -3.0, 0.0]])  # fmt: skip
    return A, np.linalg.eigvals(A)


def root_shift(A: np.ndarray, delta: float) -> float:
    """First-order bound of how far right a relative error delta of the entries of A's dynamic rows
    (1 and 3: the accelerations; rows 0 and 2 say xi' = xi', theta' = theta', exactly) moves its
    roots: ds_k = sum_ij w_ki a_ij v_jk delta_ij / (w_k . v_k) with W V = 1, so |ds_k| <= delta
    sum_(i in 1,3) sum_j |w_ki a_ij v_jk|; the largest over the roots."""
    vals, V = np.linalg.eig(A)
    W = np.linalg.inv(V)  # rows: left eigenvectors with W V = 1
    dyn = np.zeros_like(A)
    dyn[[1, 3], :] = A[[1, 3], :]
    return float(max(delta * np.sum(np.abs(np.outer(W[k], V[:, k]) * dyn)) for k in range(len(vals))))


def settling_bound(A: np.ndarray, z0: np.ndarray, dtau: float, delta: float) -> float:
    """A bound of |xi(tau0 + dtau)| from the state z0 at tau0 (units of Omega t): the linear model's
    |e1^T e^(A dtau)| |z0|, widened for a relative error delta of its coefficients, which moves the
    roots right by at most `root_shift` (first order): x (1 + delta) e^(shift dtau)."""
    row = expm(A * dtau)[0]
    grow = root_shift(A, delta) * dtau
    if grow > 700.0:  # beyond a float: the model bounds nothing
        return math.inf
    return float(np.linalg.norm(row) * np.linalg.norm(z0) * (1.0 + delta) * math.exp(grow))


def static_slope(h: Hold, l_m: float, dl: float = 1.0) -> float:
    """d(T_c - T)/dl at rest (N/m), by central differences: how far a relative error of the tension
    moves the equilibrium (dl = T err / slope)."""
    return (h.command(l_m + dl) - exit_tension(h, l_m + dl) - h.command(l_m - dl) + exit_tension(h, l_m - dl)) / (2 * dl)


def settling_measure(prof: dict, h: Hold, t0_s: float, *, rtol: float, ecc_max: float = 0.0,
                     window: bool = False) -> dict:
    """The hold's settled length against its derived equilibrium (docs/deployment.md 11.4):
    |L(t_end) - l_eq| over the budget B = B_tr + B_model.

    B_tr bounds how far the last output can still be from the rest state R the run goes to, from
    its swing at t0_s: with k = |e1^T e^(A dtau)| (1 + delta) e^(shift dtau) the linear closed loop's
    gain from t0 to t_end (`settling_bound`), |L_end - R| <= k l |z0 - z_R|, and z_R is known only
    through L_end: |z0 - z_R| <= |z0 - z_end| + |L_end - R|/l, so |L_end - R| <= k l |z0 - z_end|/(1 - k)
    (k < 1 required: the loop must have decayed over the window; otherwise the ratio is infinite,
    a failure: a run that swings too much to be bounded has not shown that it settles).  B_model,
    the terms the equilibrium leaves out:

    * the strain's representation by the rods' strains: the whole strain's share of l_eq;
    * the CoM's orbit off the circle (eccentricity e): Omega^2 changes by 3 e, the tension with it;
    * the integrator: 10 rtol l_eq.

    delta = 2 max(|L - L_end|/l + |theta|) after t0 (the quadratic terms, of the swing about the run's
    own rest state) + 4 l/a (the field beyond its gradient in the dynamics) + 2 (Omega/omega_1)^2 (the
    line's first lateral mode, omega_1 = (pi/l) (T/rho)^(1/2), and the drum's axial one,
    (EA/(l m_s))^(1/2), both far above Omega: their quasi-static share) + eps.
    ``prof``: t (s), L (m), v (m/s), theta (rad) at the outputs.  ``window``: the worst ratio over
    every output from t0 on, each against the loop's gain from t0 to it (the settling, not only its
    end: a loop that decays slower than its roots fails between t0 and t_end whatever its phase)."""
    om = h.omega
    l_eq = hold_equilibrium(h)
    l_ns = hold_equilibrium(h, strain=False)
    T_eq = h.command(l_eq)
    slope = abs(static_slope(h, l_eq))
    A, roots = hold_linear_model(h, l_eq)
    t, L = np.asarray(prof["t"]), np.asarray(prof["L"])
    theta = np.asarray(prof["theta"])
    dtheta = np.gradient(theta, t) / om
    z = np.stack([L / l_eq, np.asarray(prof["v"]) / (l_eq * om), theta, dtheta], axis=1)
    i0 = int(np.searchsorted(t, t0_s))
    if i0 >= len(t) - 1:
        return {"ratio": math.inf, "l_eq": l_eq, "why": "the run ends before t0"}
    amp = float(np.max(np.abs(L[i0:] - L[-1]) / l_eq + np.abs(theta[i0:])))
    eps = T_eq / h.EA
    w_lat = (math.pi / l_eq) * math.sqrt(T_eq / h.rho) if h.rho > 0 else math.inf
    w_ax = math.sqrt(h.EA / (l_eq * (h.j_r + h.rho * (h.line - l_eq))))
    delta = 2.0 * amp + 4.0 * l_eq / h.a + 2.0 * (om / min(w_lat, w_ax)) ** 2 + eps
    dz = z[i0] - np.array([L[-1] / l_eq, 0.0, 0.0, 0.0])
    k = settling_bound(A, np.array([1.0, 0.0, 0.0, 0.0]), (t[-1] - t[i0]) * om, delta)
    b_tr = l_eq * k * float(np.linalg.norm(dz)) / (1.0 - k) if k < 1.0 else math.inf
    model = {"strain": abs(l_eq - l_ns), "orbit": T_eq * 3.0 * ecc_max / slope, "integrator": 10.0 * rtol * l_eq}
    budget = b_tr + sum(model.values())
    err = abs(L[-1] - l_eq)
    # k >= 1: the swing is too large, or the window too short, for the linear loop to bound what is
    # left of it; the settling is then not shown, and the gate fails (an infinite ratio), never passes
    out = {"ratio": err / budget if math.isfinite(budget) else math.inf, "err": err, "budget": budget,
           "b_tr": b_tr, "gain": k, "model": model, "delta": delta, "l_eq": l_eq, "l_eq_no_strain": l_ns,
           "T_eq": T_eq, "roots": roots, "L_end": float(L[-1]), "slope": slope}
    if window and math.isfinite(b_tr):
        # along the window: |L(t) - R| <= k(t) (l |z0 - z_end| + |L_end - R|) <= k(t) (l |dz| + B_tr), so
        # B(t) = k(t) (l |dz| + B_tr) + B_model, which is the end's budget at t_end
        tw = t[i0:]
        kt = np.array([settling_bound(A, np.array([1.0, 0.0, 0.0, 0.0]), (x - t[i0]) * om, delta) for x in tw])
        bt = kt * (l_eq * float(np.linalg.norm(dz)) + b_tr) + sum(model.values())
        et = np.abs(L[i0:] - l_eq)
        j = int(np.argmax(et / bt))
        out.update({"ratio": float(et[j] / bt[j]), "t_worst": float(tw[j]), "err_t": et, "budget_t": bt, "t_window": tw})
    return out
