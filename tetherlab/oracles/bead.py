"""Lumped-mass ("bead") tether model: an oracle for TMED that shares no tether code with it.

The standard discretisation of the tether literature (e.g. Beletsky & Levin 1993, ch. 1):
a tether of unstretched length L, mass m_t = rho L and axial stiffness EA between two point
masses m0 (root) and mf (tip) becomes N interior beads joined by N + 1 massless linear springs of
unstretched length l = L/(N+1).  Each segment's mass rho l is lumped half on each of its two
end nodes, so the nodes carry

    M_0 = m0 + rho l/2,   M_j = rho l (j = 1..N),   M_{N+1} = mf + rho l/2,

which keeps the total mass and the centre of mass of the straight tether exact.  A segment from
node j to node j+1 with separation D = r_{j+1} - r_j has the tension (positive in tension,
negative in compression, as TMED's eq. 1)

    T_j = EA eps_j + c eps_j',   eps_j = |D|/l - 1,   eps_j' = (D . D')/(|D| l),

and pulls node j by +T_j D/|D| and node j+1 by -T_j D/|D|.  Every node feels point gravity
-mu r/|r|^3 of the central body.  Derivation, references and the comparison with TMED:
docs/bead.md.

State (SI), chosen like TMED's Cowell state so the tether's shape keeps full precision on a
7000 km orbit: y = [r_0, rho_1, ..., rho_{N+1}, r_0', rho_1', ..., rho_{N+1}'] with r_0 the
inertial position of the root node and rho_j = r_j - r_0.  The relative accelerations use a
cancellation-free form of g(r_0 + rho) - g(r_0) (docs/bead.md, section 2).

Parameter block p (float64): header below, then the node masses.  The right-hand side
:data:`bead_rhs` is a cfunc with tetherlab's RHS_SIG, so the compiled integrators of
``tetherlab.integrators.driver`` run it unchanged.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import carray

from .._jit import njit, rhs_cfunc

# -- parameter block header ------------------------------------------------------------------------
P_LEN = 0  # total length of p
P_NSTATE = 1  # length of the state vector, 6 (N + 2)
P_NNODES = 2  # N + 2 (root, N beads, tip)
P_MU = 3  # gravitational parameter of the central body, m^3/s^2
P_EA = 4  # axial stiffness, N
P_DAMP = 5  # damping c of T = EA eps + c eps', N s
P_SEG = 6  # unstretched segment length l = L/(N+1), m
P_FAIL = 7  # written by the kernel: 1 when a segment collapsed to zero length
P_FAIL_T = 8  # time of that failure
P_HEADER = 9  # node masses follow: p[P_HEADER + k], k = 0..N+1

FAIL_COLLAPSED = 1


@njit(cache=True)
def _gravity_difference(rx, ry, rz, qx, qy, qz, mu, out):
    """out = g(r + q) - g(r) for g(r) = -mu r/|r|^3, without cancellation when |q| << |r|.

    g(R) - g(r) = -mu [q/|R|^3 + r (1/|R|^3 - 1/|r|^3)], with
    1/|R|^3 - 1/|r|^3 = (|r|^3 - |R|^3)/(|R|^3 |r|^3),
    |r|^3 - |R|^3 = (|r| - |R|)(|r|^2 + |r||R| + |R|^2),  |r| - |R| = -(2 r.q + q.q)/(|r| + |R|).
    """
    Rx = rx + qx
    Ry = ry + qy
    Rz = rz + qz
    r = math.sqrt(rx * rx + ry * ry + rz * rz)
    R = math.sqrt(Rx * Rx + Ry * Ry + Rz * Rz)
    dr = -(2.0 * (rx * qx + ry * qy + rz * qz) + qx * qx + qy * qy + qz * qz) / (r + R)
    dinv3 = dr * (r * r + r * R + R * R) / (R**3 * r**3)
    a = mu / R**3
    b = mu * dinv3
    out[0] = -a * qx - b * rx
    out[1] = -a * qy - b * ry
    out[2] = -a * qz - b * rz


@njit(cache=True)
def bead_accelerations(t, q, v, p, acc):
    """Fill acc (same layout as q) with [r_0'', rho_1'', ..., rho_{N+1}'']; returns a status."""
    nn = int(p[P_NNODES])
    mu = p[P_MU]
    ea = p[P_EA]
    c = p[P_DAMP]
    seg = p[P_SEG]
    for i in range(3 * nn):
        acc[i] = 0.0
    # 1. spring forces, accumulated per node in acc
    for j in range(nn - 1):
        # node j's relative position (node 0 is the origin of the relative coordinates)
        if j == 0:
            ax = 0.0
            ay = 0.0
            az = 0.0
            avx = 0.0
            avy = 0.0
            avz = 0.0
        else:
            ax = q[3 * j]
            ay = q[3 * j + 1]
            az = q[3 * j + 2]
            avx = v[3 * j]
            avy = v[3 * j + 1]
            avz = v[3 * j + 2]
        dx = q[3 * j + 3] - ax
        dy = q[3 * j + 4] - ay
        dz = q[3 * j + 5] - az
        dvx = v[3 * j + 3] - avx
        dvy = v[3 * j + 4] - avy
        dvz = v[3 * j + 5] - avz
        ln = math.sqrt(dx * dx + dy * dy + dz * dz)
        if not ln > 0.0:
            p[P_FAIL] = FAIL_COLLAPSED
            p[P_FAIL_T] = t
            return FAIL_COLLAPSED
        eps = ln / seg - 1.0
        deps = (dx * dvx + dy * dvy + dz * dvz) / (ln * seg)
        ten = ea * eps + c * deps
        fx = ten * dx / ln
        fy = ten * dy / ln
        fz = ten * dz / ln
        acc[3 * j] += fx
        acc[3 * j + 1] += fy
        acc[3 * j + 2] += fz
        acc[3 * j + 3] -= fx
        acc[3 * j + 4] -= fy
        acc[3 * j + 5] -= fz
    # 2. forces -> accelerations; relative ones subtract the root node's spring acceleration
    inv0 = 1.0 / p[P_HEADER]
    s0x = acc[0] * inv0
    s0y = acc[1] * inv0
    s0z = acc[2] * inv0
    rx = q[0]
    ry = q[1]
    rz = q[2]
    g = np.empty(3)
    for k in range(1, nn):
        inv = 1.0 / p[P_HEADER + k]
        _gravity_difference(rx, ry, rz, q[3 * k], q[3 * k + 1], q[3 * k + 2], mu, g)
        acc[3 * k] = acc[3 * k] * inv - s0x + g[0]
        acc[3 * k + 1] = acc[3 * k + 1] * inv - s0y + g[1]
        acc[3 * k + 2] = acc[3 * k + 2] * inv - s0z + g[2]
    r = math.sqrt(rx * rx + ry * ry + rz * rz)
    gm = -mu / (r * r * r)
    acc[0] = s0x + gm * rx
    acc[1] = s0y + gm * ry
    acc[2] = s0z + gm * rz
    return 0


@rhs_cfunc
def bead_rhs(t, y_ptr, dy_ptr, p_ptr):
    p = carray(p_ptr, (int(p_ptr[P_LEN]),))
    n = int(p[P_NSTATE])
    y = carray(y_ptr, (n,))
    dy = carray(dy_ptr, (n,))
    h = n // 2
    for i in range(h):
        dy[i] = y[h + i]
    return bead_accelerations(t, y[:h], y[h:], p, dy[h:])


# ----------------------------------------------------------------------------------------------
# The model object (Python side)
# ----------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class BeadModel:
    """N interior beads between a root of mass ``m0_kg`` and a tip of mass ``mf_kg``."""

    beads: int
    m0_kg: float
    mf_kg: float
    length_m: float  # unstretched tether length L
    tether_mass_kg: float
    EA_N: float
    damping_N_s: float
    mu_m3_s2: float

    def __post_init__(self):
        if isinstance(self.beads, bool) or not isinstance(self.beads, (int, np.integer)) or self.beads < 1:
            raise ValueError(f"beads: expected an integer >= 1; got {self.beads!r}")
        for name in ("m0_kg", "mf_kg", "length_m", "EA_N", "mu_m3_s2"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"{name}: expected a finite value > 0; got {value!r}")
        for name in ("tether_mass_kg", "damping_N_s"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"{name}: expected a finite value >= 0; got {value!r}")

    @property
    def n_nodes(self) -> int:
        return self.beads + 2

    @property
    def segment_m(self) -> float:
        return self.length_m / (self.beads + 1)

    def node_masses(self) -> np.ndarray:
        """Half of every segment's mass lumped on each of its end nodes."""
        ms = self.tether_mass_kg / (self.beads + 1)
        m = np.full(self.n_nodes, ms)
        m[0] = self.m0_kg + 0.5 * ms
        m[-1] = self.mf_kg + 0.5 * ms
        return m

    def node_arclength_m(self) -> np.ndarray:
        """Unstretched arc length of every node from the root (0 ... L)."""
        return self.segment_m * np.arange(self.n_nodes)

    def params(self) -> np.ndarray:
        """A fresh parameter block (the kernel writes failure details into it)."""
        m = self.node_masses()
        p = np.zeros(P_HEADER + m.size)
        p[P_LEN] = p.size
        p[P_NSTATE] = 6 * self.n_nodes
        p[P_NNODES] = self.n_nodes
        p[P_MU] = self.mu_m3_s2
        p[P_EA] = self.EA_N
        p[P_DAMP] = self.damping_N_s
        p[P_SEG] = self.segment_m
        p[P_HEADER:] = m
        return p

    # -- state <-> node positions ---------------------------------------------------------------
    def state_from_nodes(self, r: np.ndarray, v: np.ndarray) -> np.ndarray:
        """The state vector from inertial node positions/velocities (n_nodes x 3 each)."""
        r = np.asarray(r, float)
        v = np.asarray(v, float)
        q = np.concatenate([r[0], (r[1:] - r[0]).ravel()])
        qd = np.concatenate([v[0], (v[1:] - v[0]).ravel()])
        return np.concatenate([q, qd])

    def state_from_relative(self, r0, v0, rel_r, rel_v) -> np.ndarray:
        """The state from the root's (r, v) and the other nodes relative to it (full precision)."""
        return np.concatenate([r0, np.asarray(rel_r, float).ravel(), v0, np.asarray(rel_v, float).ravel()])

    def nodes(self, Y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Inertial positions and velocities, arrays (rows, n_nodes, 3), of states Y (rows, n)."""
        Y = np.atleast_2d(Y)
        nn = self.n_nodes
        h = 3 * nn
        q = Y[:, :h].reshape(-1, nn, 3).copy()
        qd = Y[:, h:].reshape(-1, nn, 3).copy()
        q[:, 1:] += q[:, :1]
        qd[:, 1:] += qd[:, :1]
        return q, qd

    def relative_nodes(self, Y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Node positions/velocities relative to the root node (full precision), (rows, n_nodes, 3)."""
        Y = np.atleast_2d(Y)
        nn = self.n_nodes
        h = 3 * nn
        q = Y[:, :h].reshape(-1, nn, 3).copy()
        qd = Y[:, h:].reshape(-1, nn, 3).copy()
        q[:, 0] = 0.0
        qd[:, 0] = 0.0
        return q, qd

    def tolerance_scales(self, ref_radius_m: float, ref_time_s: float) -> np.ndarray:
        """Natural scale of each state component (as TMED's): root r0 by the orbit radius, the
        relative positions by the segment length, velocities by those over the time unit."""
        s = np.full(3 * self.n_nodes, self.segment_m)
        s[:3] = ref_radius_m
        return np.concatenate([s, s / ref_time_s])


# ----------------------------------------------------------------------------------------------
# Diagnostics
# ----------------------------------------------------------------------------------------------
def center_of_mass(model: BeadModel, Y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Inertial centre of mass position and velocity, (rows, 3) each."""
    r, v = model.nodes(Y)
    m = model.node_masses()
    M = m.sum()
    return np.einsum("k,nkj->nj", m, r) / M, np.einsum("k,nkj->nj", m, v) / M


def orbital_frame(r: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rows x (radial, outward), y = z x x, z (along r x v): array (rows, 3, 3)."""
    r = np.atleast_2d(r)
    v = np.atleast_2d(v)
    x = r / np.linalg.norm(r, axis=1, keepdims=True)
    z = np.cross(r, v)
    z = z / np.linalg.norm(z, axis=1, keepdims=True)
    y = np.cross(z, x)
    return np.stack([x, y, z], axis=1)


def libration_angles(model: BeadModel, Y: np.ndarray, side: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """In-plane theta and out-of-plane phi (rad) of the line root -> tip in the centre of mass's
    orbital frame: side (r_f - r_0)/|r_f - r_0| = (cos phi cos theta, cos phi sin theta, sin phi),
    side = +1 when the tip is above the root at theta = phi = 0 (docs/bead.md, section 4)."""
    rc, vc = center_of_mass(model, Y)
    rel, _ = model.relative_nodes(Y)
    e = side * rel[:, -1]
    e = e / np.linalg.norm(e, axis=1, keepdims=True)
    ex = np.einsum("nij,nj->ni", orbital_frame(rc, vc), e)
    return np.arctan2(ex[:, 1], ex[:, 0]), np.arcsin(np.clip(ex[:, 2], -1.0, 1.0))


def segment_tensions(model: BeadModel, Y: np.ndarray) -> np.ndarray:
    """Tension T_j = EA eps_j + c eps_j' of every segment, (rows, N+1), N (negative: compression)."""
    q, qd = model.relative_nodes(Y)
    D = np.diff(q, axis=1)
    Dv = np.diff(qd, axis=1)
    ln = np.linalg.norm(D, axis=2)
    eps = ln / model.segment_m - 1.0
    deps = np.einsum("nkj,nkj->nk", D, Dv) / (ln * model.segment_m)
    return model.EA_N * eps + model.damping_N_s * deps


def attachment_forces(model: BeadModel, Y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Force (N) the tether exerts on the root body m0 and on the tip body mf, for every row.

    The end node carries the body and half a segment of tether; the spring force F on that node
    accelerates both, so the share acting on the body itself is (m_body / M_node) F (docs/bead.md,
    section 3).  This is the bead model's counterpart of TMED's joint reaction at A_1 and B_n.
    """
    T = segment_tensions(model, Y)
    m = model.node_masses()
    return model.m0_kg / m[0] * np.abs(T[:, 0]), model.mf_kg / m[-1] * np.abs(T[:, -1])


def energy(model: BeadModel, Y: np.ndarray) -> np.ndarray:
    """Kinetic + gravitational + elastic energy (J) of every row (conserved without damping)."""
    r, v = model.nodes(Y)
    m = model.node_masses()
    ke = 0.5 * np.einsum("k,nkj,nkj->n", m, v, v)
    vg = -model.mu_m3_s2 * np.einsum("k,nk->n", m, 1.0 / np.linalg.norm(r, axis=2))
    q, _ = model.relative_nodes(Y)
    ln = np.linalg.norm(np.diff(q, axis=1), axis=2)
    ve = 0.5 * model.EA_N / model.segment_m * np.sum((ln - model.segment_m) ** 2, axis=1)
    return ke + vg + ve


def integrate(model: BeadModel, y0: np.ndarray, t_out: np.ndarray, *, method: str = "dop853",
              rtol: float = 1e-10, atol_scaled: float = 1e-10, ref_radius_m: float | None = None):  # fmt: skip
    """Integrate the bead model with tetherlab's integrators; returns the IntegrationResult.

    ``atol_scaled`` is in units of each component's natural scale (:meth:`BeadModel.tolerance_scales`),
    as a scene's atol.  Raises RuntimeError (with the integrator's message) on failure.
    """
    from ..integrators.driver import integrate as _integrate

    r0 = float(np.linalg.norm(y0[:3])) if ref_radius_m is None else float(ref_radius_m)
    t_unit = math.sqrt(r0**3 / model.mu_m3_s2)
    atol = atol_scaled * model.tolerance_scales(r0, t_unit)
    p = model.params()
    res = _integrate(method, bead_rhs, 0.0, y0, t_out, p, rtol, atol, second_order=True)
    if res.status != 0:
        why = " (a segment collapsed to zero length)" if p[P_FAIL] == FAIL_COLLAPSED else ""
        raise RuntimeError(f"bead model integration failed: {res.message}{why}")
    return res
