"""The deploying damped elastic string on a circular orbit, solved as a continuum (docs/deployment.md 8h):
an independent limit for the rod-count convergence of a reel's deployment (part G of
studies/deployment.py).

The line is labelled by its unstretched length s from the end mass (s = 0, a material point) to the
reel's exit (s = L(t), which moves in the material as the reel pays out).  With r(s, t) its position,
v = r_t its material velocity, eps = |r_s| - 1 its strain and tau = r_s/|r_s| (from the end mass
towards the station), the balances are

    rho r_tt = (T tau)_s + rho g,          T = EA eps + D eps_t,   eps_t = tau . v_s,
    M_f r_tt(0) = T(0) tau(0) + M_f g,                                         (end mass)
    r(L(t), t) = r_A(t),   v(L) = v_A - L' r_s(L)                               (exit)
    M_A v_A' = -(T(L) - rho L'^2 (1 + eps(L))) tau(L) + M_A g,   M_A = M_0 + rho (line - L),

g the exact central field, all written in the frame turning at the reference orbit's rate about the
Earth's centre (the fictitious forces added).  They are discretised on the fixed grid xi_j = j/N of
the normalised coordinate xi = s/L(t): node j carries r and v of the material passing it, so the
moving boundary adds the advection xi L'/L d/dxi to both time derivatives.  Segments between nodes
carry the strain and the tension (a staggered grid, second order in 1/N); the end mass's node
carries half a cell of line; the exit is the station's position, its material velocity from the
exit condition with a one-sided difference.  scipy's BDF or Radau integrates the method of lines with
a banded sparsity (references/deploying_string/build_limit.py uses BDF: as accurate, fewer Jacobians).  Nothing here imports the simulator's tether code: the scene's numbers are
arguments, and the only shared thing is the problem statement.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp
from scipy.sparse import lil_matrix


@dataclass(frozen=True)
class DeployingString:
    """The problem, in SI units: the station's dry mass, the end mass, the line (density, EA, the
    damping D of T = EA eps + D eps_t), the reel (deployed length at t = 0, its constant speed, the
    stored length at t = 0), the reference circular orbit (gravitational parameter, radius) and the
    duration."""

    station_kg: float
    end_kg: float
    rho_kg_m: float
    ea_n: float
    damping_n_s: float
    length0_m: float
    speed_m_s: float
    stored0_m: float
    mu_m3_s2: float
    radius_m: float
    duration_s: float

    def __post_init__(self):
        for key in ("station_kg", "end_kg", "rho_kg_m", "ea_n", "length0_m", "mu_m3_s2", "radius_m", "duration_s"):
            val = getattr(self, key)
            if not (math.isfinite(val) and val > 0):
                raise ValueError(f"DeployingString.{key}: expected a positive finite number; got {val!r}")
        if not (self.damping_n_s >= 0 and self.stored0_m >= 0 and math.isfinite(self.speed_m_s)):
            raise ValueError("DeployingString: expected damping_n_s >= 0, stored0_m >= 0 and a finite speed_m_s; got "
                             f"{self.damping_n_s!r}, {self.stored0_m!r}, {self.speed_m_s!r}")

    @property
    def rate_rad_s(self) -> float:
        return math.sqrt(self.mu_m3_s2 / self.radius_m**3)


@dataclass
class StringSolution:
    """A run at the requested times t_s: theta_rad the in-plane angle of the station -> end mass chord in
    the centre of mass's orbital frame (positive along the orbital motion), offset_m the end mass's
    distance from the station's radial line; the nodes' positions at the last time in the turning frame
    (x radial from the reference orbit's radius, y along the motion); the run's statistics."""

    t_s: np.ndarray
    theta_rad: np.ndarray
    offset_m: np.ndarray
    positions_m: np.ndarray  # the nodes at the last requested time, end mass (row 0) to station (row grid)
    nfev: int
    njev: int
    nlu: int
    n_steps: int
    grid: int


def _sparsity(n: int):
    """Banded: a node's rates read its neighbours up to two away (the exit's one-sided difference);
    the station reads the last three nodes, and the last three nodes read the station."""
    size = 4 * (n + 1)  # nodes 0..n-1 (end mass, interior), then the station; [x, y, vx, vy] each
    S = lil_matrix((size, size), dtype=np.int8)
    for j in range(n + 1):
        for k in range(max(0, j - 3), min(n, j + 3) + 1):
            S[4 * j:4 * j + 4, 4 * k:4 * k + 4] = 1
    for j in range(max(0, n - 4), n + 1):
        S[4 * j:4 * j + 4, 4 * n:4 * n + 4] = 1
        S[4 * n:4 * n + 4, 4 * j:4 * j + 4] = 1
    return S.tocsc()


def _relative_field(X: np.ndarray, Y: np.ndarray, a: float, n2: float):
    """The central field plus the centrifugal acceleration in the frame turning at the reference orbit's
    rate n (n^2 = mu/a^3), at the points (a + X, Y): n^2 (R - a^3 R/|R|^3), with 1 - (a/|R|)^3 formed
    without cancellation (it is ~3 X/a, X ~ km against a ~ 7000 km)."""
    q = 2.0 * X / a + (X * X + Y * Y) / (a * a)  # |R|^2/a^2 - 1
    c = -np.expm1(-1.5 * np.log1p(q))  # 1 - (|R|/a)^-3
    return n2 * ((a + X) * c), n2 * (Y * c)


def solve(problem: DeployingString, grid: int, *, t_eval=None, rtol: float = 1e-10, atol_m: float = 1e-9,
          method: str = "Radau", initial_strain: float = 0.0, center_station_kg: float | None = None) -> StringSolution:
    """The method of lines on ``grid`` segments, from the straight line on the local vertical (end mass
    above the station), unstrained by ``initial_strain``, with the system's centre of mass on the
    reference orbit turning rigidly with it, the line and end mass moving out at L'(0)(1 + eps) (the
    exit condition at t = 0, so no jump); Radau at ``rtol``, position tolerance ``atol_m`` (velocity
    atol_m/s).  ``center_station_kg``: the station mass the centre of mass is formed with (the
    station's dry mass by default)."""
    p = problem
    n = int(grid)
    if n < 4:
        raise ValueError(f"deploying_string.solve: grid: expected at least 4 segments; got {grid!r}")
    a, n2 = p.radius_m, p.rate_rad_s**2
    om = p.rate_rad_s
    rho, ea, dmp, ld = p.rho_kg_m, p.ea_n, p.damping_n_s, p.speed_m_s
    dxi = 1.0 / n
    xi = np.arange(n + 1) * dxi  # node n is the exit
    line_m = p.length0_m + p.stored0_m

    def length(t):
        return p.length0_m + ld * t

    def unpack(y):
        z = y.reshape(n + 1, 4)
        return z[:, 0:2], z[:, 2:4]  # positions, velocities (the last row: the station)

    def rhs(t, y):
        L = length(t)
        pos, vel = unpack(y)
        # the exit: the station's position; its material velocity v_A - L' r_s (one-sided, second order)
        rs_exit = (3.0 * pos[n] - 4.0 * pos[n - 1] + pos[n - 2]) / (2.0 * dxi * L)
        v = vel.copy()
        v[n] = vel[n] - ld * rs_exit
        # segments j + 1/2: strain, material strain rate, tension
        dp = np.diff(pos, axis=0)
        dv = np.diff(v, axis=0)
        stretch = np.hypot(dp[:, 0], dp[:, 1]) / (L * dxi)  # 1 + eps
        tau = dp / (stretch * L * dxi)[:, None]
        eps = stretch - 1.0
        eps_t = np.einsum("ij,ij->i", tau, dv) / (L * dxi)
        T = ea * eps + dmp * eps_t
        F = T[:, None] * tau  # the force the part beyond s pulls the part below with
        gx, gy = _relative_field(pos[:, 0], pos[:, 1], a, n2)
        g = np.column_stack([gx, gy])
        cor = 2.0 * om * np.column_stack([v[:, 1], -v[:, 0]])  # -2 n z x v of the material (not the station's, row n)
        out = np.empty((n + 1, 4))
        # interior: rates at fixed xi carry the advection xi L'/L d/dxi
        adv = (xi[1:n] * ld / L)[:, None] / (2.0 * dxi)
        out[1:n, 0:2] = v[1:n] + adv * (pos[2:] - pos[:-2])
        acc = (F[1:] - F[:-1]) / (rho * L * dxi) + g[1:n] + cor[1:n]
        out[1:n, 2:4] = acc + adv * (v[2:] - v[:-2])
        # the end mass with half a cell of line (a material point: no advection)
        m0 = p.end_kg + 0.5 * rho * L * dxi
        out[0, 0:2] = v[0]
        out[0, 2:4] = F[0] / m0 + g[0] + cor[0]
        # the station: the line's pull less the momentum flux, both at the exit (linear extrapolation
        # from the last two segments), with the stored line in its mass
        Fe = 1.5 * F[-1] - 0.5 * F[-2]
        eps_e = 1.5 * eps[-1] - 0.5 * eps[-2]
        te = 1.5 * tau[-1] - 0.5 * tau[-2]
        te /= np.hypot(te[0], te[1])
        ma = p.station_kg + rho * (line_m - L)
        out[n, 0:2] = vel[n]
        out[n, 2:4] = (-Fe + rho * ld * ld * (1.0 + eps_e) * te) / ma + g[n] + 2.0 * om * np.array([vel[n, 1], -vel[n, 0]])
        return out.ravel()

    # initial state: the line straight up the local vertical, strained uniformly
    eps0 = float(initial_strain)
    L0 = p.length0_m
    m_line = rho * L0
    m_sta = p.station_kg if center_station_kg is None else float(center_station_kg)
    # centre of mass above the station: end mass at L0 (1 + eps), line's at half of it
    up = L0 * (1.0 + eps0)
    c = (p.end_kg * up + m_line * 0.5 * up) / (m_sta + p.end_kg + m_line)
    y0 = np.zeros((n + 1, 4))
    y0[:, 0] = -c + up * (1.0 - xi)  # node n (the station) at -c
    y0[:n, 2] = ld * (1.0 + eps0)
    y0 = y0.ravel()
    t_end = p.duration_s
    te = np.array([t_end]) if t_eval is None else np.asarray(t_eval, float)
    # every accepted step is kept (t_eval None) so that the step count is known; the requested times
    # are read from the dense output, the end exactly from the last step
    sol = solve_ivp(rhs, (0.0, t_end), y0, method=method, rtol=rtol, atol=atol_m,
                    jac_sparsity=_sparsity(n), dense_output=True)
    if not sol.success:
        raise RuntimeError(f"deploying_string.solve: Radau failed: {sol.message}")
    th, off, pos = [], [], None
    for tk in te:
        yk = sol.y[:, -1] if tk == t_end else sol.sol(tk)
        pos, _ = unpack(yk)
        pos = pos.copy()
        th_k, off_k = _end_quantities(pos, length(tk), n, p, m_sta)
        th.append(th_k)
        off.append(off_k)
    return StringSolution(te, np.array(th), np.array(off), pos, int(sol.nfev), int(sol.njev), int(sol.nlu),
                          len(sol.t) - 1, n)


def _end_quantities(pos: np.ndarray, L: float, n: int, p: DeployingString, m_sta: float):
    """(theta, offset) of a state: theta of the station -> end mass chord in the orbital frame of the
    system's centre of mass (station with ``m_sta``, end mass, the line by the trapezoid rule on the
    nodes), offset the end mass's distance from the station's radial line."""
    a = p.radius_m
    R = pos + np.array([a, 0.0])
    w = np.full(n + 1, p.rho_kg_m * L / n)
    w[0] *= 0.5
    w[n] *= 0.5
    w[0] += p.end_kg
    w[n] += m_sta
    rc = (w[:, None] * R).sum(axis=0) / w.sum()
    e = R[0] - R[n]
    e = e / np.hypot(e[0], e[1])
    rhat = rc / np.hypot(rc[0], rc[1])
    that = np.array([-rhat[1], rhat[0]])  # along the motion (the frame turns counter-clockwise)
    theta = math.atan2(float(e @ that), float(e @ rhat))
    rel = R[0] - R[n]
    rs = R[n] / np.hypot(R[n][0], R[n][1])
    off = float(np.linalg.norm(rel - (rel @ rs) * rs))
    return theta, off
