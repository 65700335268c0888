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

from ._jit import njit
from .diagnostics import G_NCOL, G_PX, row_shares
from .kernel.layout import BT_RIGID, BT_SIZE, H_MUTANT, H_NQT, H_NREEL, H_OFF_BODY, H_OFF_REEL, MUT_NO_ELASTIC_E, RL_BODY, RL_SIZE
from .tether.reel_diagnostics import material_momentum
from .tether.reel_hub import reel_hub_share
from .tether.solve import system_accelerations


def momenta(model, t_s: float, Y: np.ndarray) -> np.ndarray:
    """(rows, 6): the material momentum and angular momentum about the origin of each state row
    of ``Y`` at the time ``t_s``: bodies, stored tether and rods with the reel's corrections, the
    columns the deployment invariants report (tetherlab/deployment.py ``_rows``).  Evaluated by
    :func:`momentum_rows`, which computes only these columns: the same products and sums as the
    whole diagnostics and reel table, so the same bits (docs/deployment.md 8g)."""
    from .model.params import ParamView

    Y = np.ascontiguousarray(np.atleast_2d(np.asarray(Y, float)))
    p = model.fresh_params()
    lay = model.state
    rows = Y.shape[0]
    glob = np.empty((rows, 6))
    corr = np.empty((rows, int(ParamView(p).n_reels), 6))
    bad = momentum_rows(np.full(rows, float(t_s)), Y, p, glob, corr, np.zeros(lay.n_qt),
                        np.zeros(lay.first_order.stop - lay.first_order.start))  # fmt: skip
    if bad >= 0:  # as the whole diagnostics leave such a row: not a number, caught by the solve
        glob[bad:] = np.nan
        corr[bad:] = np.nan
    c = corr.sum(axis=1)
    return np.hstack([glob[:, 0:3] + c[:, 0:3], glob[:, 3:6] + c[:, 3:6]])


@njit(cache=True)
def momentum_rows(ts, Y, p, glob, corr, acc, datt):
    """The momentum and angular momentum columns alone of every state row of Y: glob[row] the
    parts' shares (diagnostics.row_shares, columns G_PX .. G_HZ), corr[row, reel] the reel's material
    corrections (tether/reel_diagnostics.material_momentum and, on a rigid body, the stored
    tether's share).  One right-hand side evaluation a row, where the whole diagnostics and the
    reel table take one each.  Returns the first row whose right-hand side failed, or -1."""
    h = int(p[H_NQT])
    elastic = p[H_MUTANT] != MUT_NO_ELASTIC_E
    sh = np.empty(G_NCOL)
    for row in range(Y.shape[0]):
        t = ts[row]
        q = Y[row, :h]
        qd = Y[row, h : 2 * h]
        att = Y[row, 2 * h :]
        if system_accelerations(t, q, qd, att, p, acc, datt) != 0:
            return row
        for i in range(int(p[H_NREEL])):
            o = corr[row, i]
            material_momentum(p, q, i, o, 0)
            rb = int(p[H_OFF_REEL]) + i * RL_SIZE
            if p[int(p[H_OFF_BODY]) + int(p[rb + RL_BODY]) * BT_SIZE + BT_RIGID] != 0.0:
                s0, s1, s2, s3, s4, s5, _s6, _s7, _ring = reel_hub_share(p, i)
                o[0] += s0
                o[1] += s1
                o[2] += s2
                o[3] += s3
                o[4] += s4
                o[5] += s5
        for j in range(G_NCOL):
            sh[j] = 0.0
        row_shares(t, q, qd, att, p, sh, elastic)
        for j in range(6):
            glob[row, j] = sh[G_PX + j]
    return -1


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
    return rigid_increments(model, y, np.asarray(a, float)[None, :], np.asarray(omega, float)[None, :], c, pos)[0]


def rigid_increments(model, y: np.ndarray, a: np.ndarray, omega: np.ndarray, c: np.ndarray,
                     pos: np.ndarray | None = None, roots: list[int] | None = None) -> np.ndarray:
    """(n, len(y)): the rows of :func:`rigid_increment` for the n increments (a[i], omega[i]),
    in whole-array passes over the increments and the rods (a birth's remap applies some twenty of
    them to a state of ~250 numbers: one numpy call per root and rod block instead of one per
    increment keeps its cost off the per-call overhead; docs/deployment.md 8f).  Each number is
    the same product and sum as one increment at a time, in the same order, so the same bits."""
    lay = model.state
    a = np.asarray(a, float)
    omega = np.asarray(omega, float)
    y = np.asarray(y, float)
    z = np.repeat(y[None, :], len(a), axis=0)
    if pos is None:
        from .system import point_positions

        pos = point_positions(model, y)["bodies"]
    for b in _roots(model) if roots is None else roots:
        z[:, lay.root_velocity(b)] += a + _cross(omega, pos[b, :3] - c)
    # every rod at once: (n, 1, 3) x (1, rods, 3)
    z[:, lay.rods_dd] += _cross(omega[:, None, :], y[lay.rods_d].reshape(1, -1, 3)).reshape(len(a), -1)
    for b, _ in lay.rigid:
        R = _body_to_inertial(y[lay.quaternion_of(b)])
        for i in range(len(omega)):
            z[i, lay.omega_of(b)] += R.T @ omega[i]
    return z


def _cross(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """u x v over the last axis (broadcast), with numpy.cross's products and differences in its
    order (a1 b2 - a2 b1, a2 b0 - a0 b2, a0 b1 - a1 b0), so the same bits without its axis
    handling, which is most of its cost on 3-vectors."""
    u0, u1, u2 = u[..., 0], u[..., 1], u[..., 2]
    v0, v1, v2 = v[..., 0], v[..., 1], v[..., 2]
    out = np.empty(np.broadcast_shapes(u.shape, v.shape))
    out[..., 0] = u1 * v2 - u2 * v1
    out[..., 1] = u2 * v0 - u0 * v2
    out[..., 2] = u0 * v1 - u1 * v0
    return out


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
    roots = _roots(model)
    pos = None
    for _ in range(passes):
        if translate:
            c, mass = centre_of_mass(model, t_s, z)
            for b in roots:  # every position hangs from a root's through the rods' d
                z[lay.root_position(b)] += c_target - c
            info["shift_m"] = info["shift_m"] + (c_target - c)
        else:
            c, mass = c_target, float("nan")
        if translate or pos is None:  # a velocity increment leaves the positions: kept for the next pass
            pos = point_positions(model, z)["bodies"]
        # the state and its six unit increments in one evaluation of the columns (each row is
        # evaluated on its own, so the same numbers as seven evaluations)
        units = rigid_increments(model, z, _UNIT_A, _UNIT_W, c_target, pos, roots)
        rows = momenta(model, t_s, np.vstack([z[None, :], units]))
        base = rows[0]
        A = (rows[1:] - base).T
        x = _solve(A, target - base)
        z = rigid_increments(model, z, x[None, :3], x[None, 3:], c_target, pos, roots)[0]
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
    c, mass, _ = centre_and_momenta(model, t_s, y)
    return c, mass


def centre_and_momenta(model, t_s: float, y: np.ndarray) -> tuple[np.ndarray, float, np.ndarray]:
    """(c, M, P and H) of the state: :func:`centre_of_mass` and :func:`momenta` of its one row,
    from one evaluation of the columns on the state and its three unit translations (each row is
    evaluated on its own, so the same numbers as separate calls)."""
    from .system import point_positions

    y = np.asarray(y, float)
    pos = point_positions(model, y)["bodies"]
    units = rigid_increments(model, y, np.eye(3), np.zeros((3, 3)), np.zeros(3), pos)
    rows = momenta(model, t_s, np.vstack([y[None, :], units]))
    base = rows[0]
    rt = rows[1:] - base
    if not (np.all(np.isfinite(base)) and np.all(np.isfinite(rt))):
        raise ValueError("momentum restore: expected a state with finite momenta; got a non-finite value")
    mass = float(np.trace(rt[:, :3])) / 3.0
    if not mass > 0.0:
        raise ValueError(f"momentum restore: expected a positive total mass; got {mass!r} kg")
    Cx = rt[:, 3:].T / mass  # column j: c x e_j
    return np.array([Cx[2, 1], Cx[0, 2], Cx[1, 0]]), mass, base


_UNIT_A = np.vstack([np.eye(3), np.zeros((3, 3))])  # the six unit increments (a, omega) of a solve
_UNIT_W = np.vstack([np.zeros((3, 3)), np.eye(3)])
