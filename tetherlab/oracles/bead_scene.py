"""Initial state of the bead model from the physical inputs of a TMED scene.

:func:`bead_from_scene` reads a :class:`tetherlab.scene.Scene` (central body, the two bodies, the
tether's length, mass, EA and damping, the reference orbit, the initial direction angles, strain
and motion) and lays out the lumped-mass model of :mod:`tetherlab.oracles.bead` with its own code:
nothing here calls the TMED layout (``tetherlab.pipeline``/``tetherlab.system``), so a layout
mistake in either cannot hide in both.  The conventions are those of docs/scenes.md and
docs/bead.md section 4:

* ``motion = "corotating"``: straight tether at the scene's strain, the whole line rotating with
  the reference orbit's rate omega = r x v/|r|^2 about the central body's centre;
* ``"translating"``: every node moves with the reference point's velocity;
* ``"equilibrium"``: the relative equilibrium of the tether on the local vertical (section 3 of
  docs/bead.md: node radii and the spin rate Omega by Newton's method), then turned rigidly to the
  scene's theta/phi about the reference point, every node moving as W x r with W = Omega z.
  For theta = phi = 0 this is the exact relative equilibrium of the discrete model.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .bead import BeadModel

CENTER_OF_MASS = "center_of_mass"


@dataclass(frozen=True)
class BeadScene:
    """A laid-out bead model: the model, its initial state and the frame it was built in."""

    model: BeadModel
    y0: np.ndarray
    side: float  # +1: tip above the root at theta = phi = 0
    r_ref_m: np.ndarray  # reference point's initial inertial position
    v_ref_m_s: np.ndarray
    spin_rad_s: float  # rotation rate of the initial state about the orbit normal (0: translating)
    t_out_s: np.ndarray  # output times from the scene's [output] and duration
    normal: np.ndarray  # unit orbit normal of the reference orbit


def _frame(r, v):
    x = r / np.linalg.norm(r)
    z = np.cross(r, v)
    z = z / np.linalg.norm(z)
    return x, np.cross(z, x), z


def _output_times(scene, duration_s: float) -> np.ndarray:
    out = scene.output
    if out.times_s is not None:
        t = np.asarray(out.times_s, float)
        return np.concatenate([[0.0], t]) if t[0] > 0 else t
    if out.count is not None:
        return np.linspace(0.0, duration_s, int(out.count))
    n = int(math.floor(duration_s / out.step_s + 1e-9))
    t = out.step_s * np.arange(n + 1)
    return np.concatenate([t, [duration_s]]) if duration_s - t[-1] > 1e-9 * max(duration_s, 1.0) else t


def vertical_equilibrium(model: BeadModel, r_c_m: float, ref_weights: np.ndarray, side: float = 1.0):
    """Relative equilibrium of the bead chain on the local vertical (docs/bead.md, section 3).

    Unknowns: the radial offsets xi_k of the nodes from the reference radius ``r_c_m`` and
    delta = Omega^2/omega_c^2 - 1 (omega_c^2 = mu/r_c^3).  Equations: for every node, in the frame
    rotating at Omega, M_k (Omega^2 r_k - mu/r_k^2) + side (T_k - T_{k-1}) = 0, and
    sum(ref_weights * xi) = 0 (the reference point stays at r_c).  Returns (xi, Omega).
    Newton with the analytic Jacobian; the centrifugal-minus-gravity term is written without
    cancellation: Omega^2 r - mu/r^2 = omega_c^2 [delta (r_c + xi) + xi] + mu xi (2 r_c + xi)/(r_c^2 r^2).
    """
    mu = model.mu_m3_s2
    m = model.node_masses()
    nn = model.n_nodes
    ell = model.segment_m
    k_ax = model.EA_N / ell
    w2 = mu / r_c_m**3
    w = np.asarray(ref_weights, float)
    s_hill = model.node_arclength_m()
    x = np.empty(nn + 1)
    x[:nn] = side * (s_hill - (w @ s_hill) / w.sum())
    x[nn] = 0.0

    def residual_and_jacobian(x):
        xi = x[:nn]
        delta = x[nn]
        r = r_c_m + xi
        g = w2 * (delta * r + xi) + mu * xi * (2 * r_c_m + xi) / (r_c_m**2 * r**2)
        dg = w2 * (delta + 1.0) + mu * 2.0 / r**3  # d/dxi of Omega^2 r - mu/r^2
        stretch = side * np.diff(xi)  # segment lengths
        T = model.EA_N * (stretch / ell - 1.0)
        F = m * g
        F[:-1] += side * T
        F[1:] -= side * T
        J = np.zeros((nn + 1, nn + 1))
        J[np.arange(nn), np.arange(nn)] = m * dg
        # side * T_j depends on xi_{j+1} - xi_j through side^2 = 1
        for j in range(nn - 1):
            J[j, j] -= k_ax
            J[j, j + 1] += k_ax
            J[j + 1, j] += k_ax
            J[j + 1, j + 1] -= k_ax
        J[:nn, nn] = m * w2 * r
        res = np.empty(nn + 1)
        res[:nn] = F
        res[nn] = w @ xi / w.sum()
        J[nn, :nn] = w / w.sum()
        return res, J

    for _ in range(50):
        res, J = residual_and_jacobian(x)
        step = np.linalg.solve(J, res)
        x = x - step
        if np.max(np.abs(step[:nn])) < 1e-12 * model.length_m and abs(step[nn]) < 1e-15:
            break
    else:
        raise RuntimeError(f"bead vertical equilibrium: Newton did not converge (last step {np.max(np.abs(step)):.3g})")
    return x[:nn], math.sqrt(w2 * (1.0 + x[nn]))


def bead_from_scene(scene, beads: int, tether: str | None = None) -> BeadScene:
    """The bead model with ``beads`` interior beads for a scene's tether, and its initial state."""
    if tether is None:
        if len(scene.tethers) != 1:
            raise ValueError(
                f"tether: expected a name when the scene has {len(scene.tethers)} tethers "
                f"({[t.name for t in scene.tethers]}); got None"
            )
        teth = scene.tethers[0]
    else:
        teth = scene.tether(tether)
    root = scene.body(teth.from_body)
    tip = scene.body(teth.to_body)
    for b in (root, tip):
        if b.fixed or b.has_state:
            raise ValueError(
                f"bodies.{b.name}: expected a free body laid out from the orbit and the tether's "
                f"initial shape (the bead builder supports that layout only); got an explicit state"
            )
    ini = teth.initial
    if ini is None or ini.shape != "straight":
        raise ValueError(
            f"tethers.{teth.name}.initial.shape: expected 'straight' (the bead builder lays out a "
            f"straight tether; add lateral shapes with with_lateral_displacement); got "
            f"{None if ini is None else ini.shape!r}"
        )
    orbit = scene.orbit
    if orbit is None:
        raise ValueError("orbit: expected an [orbit] block for the bead builder; got none")
    mu = scene.central_body.mu_m3_s2
    model = BeadModel(
        beads=beads,
        m0_kg=root.mass_kg,
        mf_kg=tip.mass_kg,
        length_m=teth.length_m,
        tether_mass_kg=teth.mass_kg,
        EA_N=teth.EA_N,
        damping_N_s=teth.damping_N_s,
        mu_m3_s2=mu,
    )
    r_ref, v_ref = (np.asarray(a, float) for a in scene.reference_state())
    xhat, yhat, zhat = _frame(r_ref, v_ref)
    side = 1.0 if ini.side == "up" else -1.0
    th, ph = float(ini.theta_rad), float(ini.phi_rad)
    e = side * (math.cos(ph) * math.cos(th) * xhat + math.cos(ph) * math.sin(th) * yhat + math.sin(ph) * zhat)

    nn = model.n_nodes
    m = model.node_masses()
    if orbit.reference == CENTER_OF_MASS:
        weights = m.copy()
    elif orbit.reference == teth.from_body:
        weights = np.eye(nn)[0]
    elif orbit.reference == teth.to_body:
        weights = np.eye(nn)[-1]
    else:
        raise ValueError(f"orbit.reference: expected center_of_mass, {teth.from_body!r} or {teth.to_body!r}; got {orbit.reference!r}")

    if orbit.motion == "equilibrium":
        xi, spin = vertical_equilibrium(model, float(np.linalg.norm(r_ref)), weights, side)
        eta = side * xi  # distances along the tether direction, reference point at 0
    else:
        eta = model.node_arclength_m() * (1.0 + ini.strain)
        eta = eta - (weights @ eta) / weights.sum()
        spin = float(np.linalg.norm(np.cross(r_ref, v_ref))) / float(r_ref @ r_ref) if orbit.motion == "corotating" else 0.0
    W = spin * zhat
    rel = (eta[1:] - eta[0])[:, None] * e[None, :]  # nodes relative to the root node
    r0 = r_ref + eta[0] * e
    if orbit.motion == "equilibrium":
        v0 = np.cross(W, r0)  # rigid rotation about the central body's centre (as TMED's)
    else:
        v0 = v_ref + np.cross(W, r0 - r_ref)
    rel_v = np.cross(W[None, :], rel)
    y0 = model.state_from_relative(r0, v0, rel, rel_v)
    t_out = _output_times(scene, scene.duration_seconds())
    return BeadScene(model, y0, side, r_ref, v_ref, spin, t_out, zhat)


def with_lateral_displacement(bs: BeadScene, z_m: np.ndarray) -> BeadScene:
    """A copy whose nodes are displaced by z_m[k] (m) along the orbit normal, velocities unchanged
    (a displacement along the spin axis leaves W x r as it was)."""
    model = bs.model
    z_m = np.asarray(z_m, float)
    if z_m.shape != (model.n_nodes,):
        raise ValueError(f"z_m: expected {model.n_nodes} displacements (one per node); got shape {z_m.shape}")
    y = bs.y0.copy()
    y[:3] += z_m[0] * bs.normal
    for k in range(1, model.n_nodes):
        y[3 * k : 3 * k + 3] += (z_m[k] - z_m[0]) * bs.normal
    return BeadScene(model, y, bs.side, bs.r_ref_m, bs.v_ref_m_s, bs.spin_rad_s, bs.t_out_s, bs.normal)
