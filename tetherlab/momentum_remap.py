"""Restoring the linear and angular momentum of a remapped state by the smallest change of kinetic energy.

A retirement (tetherlab/deployment.py) replaces two rods by one and the material of the merged
rod moves differently afterwards, so its momentum P and angular momentum H change
(docs/deployment.md 6.2). Both are linear in the velocities at fixed positions, so restoring
them is six linear constraints on the velocity state. Of all velocity changes that meet them,
the one that changes the kinetic energy least (the metric of the material's mass) is a rigid
velocity increment of the whole system,

    delta v(r) = a + omega x (r - c),      c the centre of mass,

with M a = P_target - P and I_c omega = H_c,target - H_c (docs/deployment.md 6.3 derives it; I_c
the material's inertia about c). This module applies that increment through the StateLayout
(each root's velocity block takes a + omega x (r_root - c), each rod's rate omega x d), and finds
(a, omega) from the response of the system's own invariant columns to unit increments: P and H
are linear in (a, omega), so six evaluations give the map exactly (to round-off), whatever the
bodies and the reel's material corrections are, and c comes from the same columns
(dH_O/da = M c x, dP/da = M). A second pass removes the round-off of the first solve.
"""

from __future__ import annotations

import numpy as np


def momenta(model, t_s: float, Y: np.ndarray) -> np.ndarray:
    """(rows, 6): the material momentum and angular momentum about the origin of each state row
    of ``Y`` at the time ``t_s``: bodies, stored tether and rods with the reel's corrections, the
    columns the deployment invariants report (tetherlab/deployment.py)."""
    from . import diagnostics as diag
    from .deployment import _rows

    Y = np.atleast_2d(np.asarray(Y, float))
    out, d, _ = _rows(model, np.full(Y.shape[0], float(t_s)), Y)
    g = d["global"]
    corr = out[:, :, 9:15].sum(axis=1)
    P = g[:, diag.G_PX : diag.G_PX + 3] + corr[:, 0:3]
    H = g[:, diag.G_HX : diag.G_HX + 3] + corr[:, 3:6]
    return np.hstack([P, H])


def rigid_increment(model, y: np.ndarray, a: np.ndarray, omega: np.ndarray, c: np.ndarray,
                    pos: np.ndarray | None = None) -> np.ndarray:
    """y with the velocity increment a + omega x (r - c) of a rigid motion applied to every root
    body and, through the rod rates d' += omega x d, to every joint hanging from it; every rigid
    body's angular velocity takes omega too (its body-axes rate R^T omega; the wheels' rates are
    relative to their body and stay), so that the material of a rigid body, its stored tether
    included, moves with the same rigid increment as the rest (docs/deployment.md 6.3: without
    it the constraints are still met, but not by the least change of kinetic energy).  ``pos``:
    the bodies' positions of y (system.point_positions "bodies"), when the caller has them (the six
    columns of one solve share them: the increment changes velocities only)."""
    lay = model.state
    z = np.array(y, float)
    if pos is None:
        from .system import point_positions

        pos = point_positions(model, y)["bodies"]
    for b in _roots(model):
        z[lay.root_velocity(b)] += a + np.cross(omega, pos[b, :3] - c)
    # every rod at once (the same products as one rod at a time)
    z[lay.rods_dd] += np.cross(omega, y[lay.rods_d].reshape(-1, 3)).ravel()
    for b, _ in lay.rigid:
        z[lay.omega_of(b)] += _body_to_inertial(y[lay.quaternion_of(b)]).T @ omega
    return z


def _body_to_inertial(q: np.ndarray) -> np.ndarray:
    """R(q/|q|), body -> inertial, scalar first: the kernel's own rotation (bodies/rigid.rotation)."""
    from .bodies.rigid import rotation

    buf = np.empty(9)
    rotation(buf, 0, *(float(c) for c in q))
    return buf.reshape(3, 3)


def _roots(model) -> list[int]:
    """Kernel indices of the root bodies (each has its own position and velocity block)."""
    from .model.params import ParamView

    return [int(b) for b in ParamView(model.p).roots]


def restore(model, t_s: float, y: np.ndarray, target: np.ndarray, c_target: np.ndarray,
            passes: int = 2, translate: bool = True) -> tuple[np.ndarray, dict]:
    """The state y (of ``model`` at ``t_s``) with its centre of mass put back at ``c_target`` (a
    translation of every position: the remap moved material, not the system) and the rigid
    velocity increment that brings its momentum to target[:3] and its angular momentum to
    target[3:] (about the origin; with the centre of mass and the momentum both restored, the
    angular momentum about the centre of mass is restored too).  Returns (state, {"a", "omega",
    "shift_m", "c", "mass_kg"}).  ValueError on non-finite momenta or a rigid increment that
    changes nothing (no mass).  ``translate=False``: the caller has put the centre of mass back
    itself (exactly, from the masses) and ``c_target`` is only the centre of the rotation: on an
    orbit the centre of mass found from the momentum columns carries ~1e-5 m of round-off (H ~ r x P
    ~ 1e13), which each translation would turn into ~0.1 J of potential energy."""
    from .system import point_positions

    target = np.asarray(target, float)
    c_target = np.asarray(c_target, float)
    z = np.array(y, float)
    info = {"a": np.zeros(3), "omega": np.zeros(3), "shift_m": np.zeros(3)}
    lay = model.state
    for _ in range(passes):
        if translate:
            c, mass = centre_of_mass(model, t_s, z)
            for b in _roots(model):  # every position hangs from a root's through the rods' d
                z[lay.root_position(b)] += c_target - c
            info["shift_m"] = info["shift_m"] + (c_target - c)
        else:
            c, mass = c_target, float("nan")
        base = momenta(model, t_s, z[None, :])[0]
        pos = point_positions(model, z)["bodies"]
        cols = [rigid_increment(model, z, e, np.zeros(3), c_target, pos) for e in np.eye(3)]
        cols += [rigid_increment(model, z, np.zeros(3), e, c_target, pos) for e in np.eye(3)]
        A = (momenta(model, t_s, np.array(cols)) - base).T
        x = _solve(A, target - base)
        z = rigid_increment(model, z, x[:3], x[3:], c_target, pos)
        info["a"] = info["a"] + x[:3]
        info["omega"] = info["omega"] + x[3:]
        info["c"] = c
        info["mass_kg"] = mass
    return z, info


def _solve(A: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """The least-norm solution of A x = rhs with the columns scaled to unit norm.  A straight line
    of material has no inertia about itself (one singular value at round-off): no velocity change
    can alter the angular momentum along it, which is zero for any velocities, so that direction
    is dropped (singular values below 1e-11 of the largest, or a column exactly zero) instead of
    taking a huge rotation about the line from round-off."""
    if not np.all(np.isfinite(A)) or not np.all(np.isfinite(rhs)):
        raise ValueError("momentum restore: expected finite momenta and responses; got a non-finite value")
    scale = np.linalg.norm(A, axis=0)
    scale[scale == 0.0] = 1.0  # (a rotation about an exactly straight line: a zero column, dropped)
    x, *_ = np.linalg.lstsq(A / scale, rhs, rcond=1e-11)
    return x / scale


def centre_of_mass(model, t_s: float, y: np.ndarray) -> tuple[np.ndarray, float]:
    """(c, M) of the state's material from the response of its momenta to a translation of its
    velocity: dP/da = M I and dH/da = M [c x] (H about the origin), so c is the centre of mass
    of exactly the material the momenta count (bodies, stored tether, rods)."""
    from .system import point_positions

    base = momenta(model, t_s, np.asarray(y, float)[None, :])[0]
    pos = point_positions(model, np.asarray(y, float))["bodies"]
    units = [rigid_increment(model, y, e, np.zeros(3), np.zeros(3), pos) for e in np.eye(3)]
    rt = momenta(model, t_s, np.array(units)) - base
    if not (np.all(np.isfinite(base)) and np.all(np.isfinite(rt))):
        raise ValueError("momentum restore: expected a state with finite momenta; got a non-finite value")
    mass = float(np.trace(rt[:, :3])) / 3.0
    if not mass > 0.0:
        raise ValueError(f"momentum restore: expected a positive total mass; got {mass!r} kg")
    Cx = rt[:, 3:].T / mass  # column j: c x e_j
    return np.array([Cx[2, 1], Cx[0, 2], Cx[1, 0]]), mass
