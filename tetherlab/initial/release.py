"""The release of shape 'equilibrium' with ``release``: a tether hanging free under uniform
gravity, perturbed sideways with every rod at the tension it carries at the release
(docs/hanging-chain.md section 3).

The hang: the end mass free (R_f = 0), so the tether's pull on it balances its own loads,
J_n = -(m_f g + constant forces on it); marching from the end mass to the root gives every rod's
direction and stretch (tetherlab.statics.shot_joints' march with J_n known), and the statics solve
polishes it on the model's own equations.  The perturbation: every rod turned by the same angle
about the root (``angle``), or each rod j by theta_j of the hanging chain's lateral mode (the
rigid-link chain of the rods' hanging lengths and masses, linearised about the vertical: the
small-oscillation eigenproblem K theta = omega^2 M theta of docs/hanging-chain.md section 2),
scaled so the end mass moves sideways by ``amplitude``.  Turning the rods keeps their lengths, but
the tensions of a tether at rest off the vertical are not those of the hang (a pendulum released
at angle a pulls with m g cos a): the rod lengths are then solved so that no rod's length
accelerates at t = 0 (u_j . d''_j = 0, n equations in n length factors), which is the tension of
the inextensible chain at the release.  Without that step the difference rings the axial modes;
``axial_energy_J`` measures it.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg import eigh

from ..errors import SceneError

SQ3 = math.sqrt(3.0)
# Up to this many rods the slowest modes come from the dense pencil (0.3-0.4 ms at 32 rods, 1-2 % of
# the whole run, docs/inextensible.md section 7), so that the shipped scenes' starts keep their
# last bits; above it from Lanczos, whose result differs from the dense one at rounding (~1e-13).
DENSE_UP_TO = 32


def lateral_modes(lengths_m, masses_kg, tip_mass_kg, g_m_s2, count=None):
    """(omega, theta) of the chain of rigid uniform bars hanging from a fixed point: the bar angles
    of each mode in a column, normalised so the end moves sideways by 1 m (docs/hanging-chain.md
    eqs. H8-H9; the oracle tetherlab.oracles.hanging_chain is written separately from this).
    ``count``: only the ``count`` slowest modes (docs/inextensible.md section 7, the start's cost):
    above DENSE_UP_TO rods, Lanczos on the O(n) products with the mass matrix instead of the dense
    O(n^3) pencil; None: all n modes, dense."""
    lengths = np.asarray(lengths_m, float)
    masses = np.asarray(masses_kg, float)
    n = lengths.size
    below = np.concatenate([np.cumsum(masses[::-1])[::-1][1:], [0.0]])
    stiffness = g_m_s2 * lengths * (0.5 * masses + below + tip_mass_kg)
    if count is not None and n > max(DENSE_UP_TO, 2 * count + 1):
        w2, vecs = _slowest_modes(lengths, masses, tip_mass_kg, stiffness, count)
    else:
        lever = np.tril(np.ones((n, n)), -1) * lengths[None, :] + np.diag(0.5 * lengths)
        mass_matrix = (lever.T * masses) @ lever + np.diag(masses * lengths**2 / 12.0) + tip_mass_kg * np.outer(lengths, lengths)
        w2, vecs = eigh(np.diag(stiffness), mass_matrix)
        if count is not None:
            w2, vecs = w2[:count], vecs[:, :count]
    tip = lengths @ vecs
    scale = np.where(np.abs(tip) > 1e-12 * np.abs(vecs).max(axis=0) * lengths.sum(), tip, 1.0)
    return np.sqrt(w2), vecs / scale[None, :]


def _mass_product(lengths, masses, tip_mass_kg, theta):
    """M theta for the rigid-bar chain's mass matrix M = A^T diag(m) A + diag(m l^2 / 12) + m_f l l^T
    in O(n): A theta, the bar centres' sideways displacement, is a running sum (sum_{j<i} l_j theta_j
    + l_i theta_i / 2), and A^T y a running sum from the end (l_j (sum_{i>j} y_i + y_j / 2))."""
    lt = lengths * theta
    centre = np.cumsum(lt) - 0.5 * lt
    y = masses * centre
    back = lengths * (np.cumsum(y[::-1])[::-1] - 0.5 * y)
    return back + masses * lengths**2 / 12.0 * theta + tip_mass_kg * lengths * lt.sum()


def _slowest_modes(lengths, masses, tip_mass_kg, stiffness, count):
    """(omega^2, theta) of the ``count`` slowest modes of K theta = omega^2 M theta, K diagonal and
    positive: the largest eigenvalues mu = 1 / omega^2 of the symmetric K^-1/2 M K^-1/2, by
    Lanczos (ARPACK) on the O(n) product; a fixed start vector so that a run repeats bit for bit.
    They are the well separated end of mu's spectrum (mu_k ~ 1 / k^2), so few iterations do."""
    from scipy.sparse.linalg import LinearOperator, eigsh

    n = lengths.size
    root = 1.0 / np.sqrt(stiffness)

    def product(v):
        return root * _mass_product(lengths, masses, tip_mass_kg, root * np.ravel(v))

    op = LinearOperator((n, n), matvec=product, dtype=float)
    mu, vecs = eigsh(op, k=count, which="LA", v0=np.full(n, 1.0 / math.sqrt(n)), tol=0.0)
    order = np.argsort(mu)[::-1]
    return 1.0 / mu[order], root[:, None] * vecs[:, order]


def consistent_lengths(model, y, p, slot=None, iterations: int = 20):
    """y with every rod vector rescaled so that no rod's length accelerates at t = 0 (velocities
    zero), and the scale factors.  Newton on the n length factors, finite-difference Jacobian.
    ``slot``: the holding force's place in ``p``, zeroed (the end mass released); None: no hold."""
    from ..tether.solve import accelerations

    lay = model.state
    n = lay.n_rods
    rods = lay.rods_d  # the rod vectors, inside q as inside y (q starts the state)
    q = y[lay.q].copy()
    qd = np.zeros(lay.n_qt)
    acc = np.zeros(lay.n_qt)
    d0 = q[rods].reshape(n, 3).copy()
    u = d0 / np.linalg.norm(d0, axis=1)[:, None]
    if slot is not None:
        p[slot : slot + 3] = 0.0  # released: nothing holds the end mass

    def axial(s):
        q[rods] = (d0 * s[:, None]).ravel()
        if accelerations(0.0, q, qd, p, acc) != 0:
            raise SceneError("initial.release", "a release whose rods stay in the model", "a rod collapsed")
        return (acc[rods].reshape(n, 3) * u).sum(axis=1)

    s = np.ones(n)
    f = axial(s)
    a_ref = float(np.max(np.abs(acc))) or 1.0
    for _ in range(iterations):
        jac = np.empty((n, n))
        for j in range(n):
            sp = s.copy()
            sp[j] += 1e-9
            jac[:, j] = (axial(sp) - f) / 1e-9
        step = np.linalg.solve(jac, -f)
        s = s + step
        f = axial(s)
        if float(np.max(np.abs(step))) < 1e-14:
            break
    if not float(np.max(np.abs(step))) < 1e-12:
        raise SceneError("initial.release", "rod lengths with no axial acceleration at the release (Newton converging)",
                         f"last step {float(np.max(np.abs(step))):.3g} of the rod lengths, axial acceleration {np.max(np.abs(f)) / a_ref:.3g} of the largest")  # fmt: skip
    out = y.copy()
    out[rods] = (d0 * s[:, None]).ravel()
    return out, s


def axial_energy_J(model, y, y_consistent):
    """Elastic energy of the difference between the rods' lengths in ``y`` and in
    ``y_consistent`` (same directions): sum EA / (2 l_u) (l - l_c)^2, the energy a release from
    ``y`` puts into the axial modes that one from ``y_consistent`` does not."""
    from ..model.params import ParamView

    lay = model.state
    n = lay.n_rods
    v = ParamView(model.p)
    ell = 2.0 * SQ3 * np.linalg.norm(y[lay.rods_d].reshape(n, 3), axis=1)
    ell_c = 2.0 * SQ3 * np.linalg.norm(y_consistent[lay.rods_d].reshape(n, 3), axis=1)
    return float(np.sum(v.rods.ea_N / (2.0 * v.rods.length_m) * (ell - ell_c) ** 2))


def released_state(held, eq_y, release, g_vec, tip_mass_kg, toward, path):
    """The released state from the hang ``eq_y`` (zero velocities): the rods turned in the
    vertical plane through ``toward`` (a horizontal unit vector), their lengths made consistent."""
    lay = held.state
    n = lay.n_rods
    d = eq_y[lay.rods_d].reshape(n, 3)
    down = g_vec / np.linalg.norm(g_vec)
    ell = 2.0 * SQ3 * np.linalg.norm(d, axis=1)
    if release.angle_rad is not None:
        theta = np.full(n, release.angle_rad)
    else:
        if release.mode > n:
            raise SceneError(f"{path}.mode", f"a mode from 1 to {n} (a chain of {n} rods has {n} lateral modes in a plane)",
                             str(release.mode))  # fmt: skip
        _, modes = lateral_modes(ell, held.rod_masses(), tip_mass_kg, float(np.linalg.norm(g_vec)), count=release.mode)
        theta = release.amplitude_m * modes[:, release.mode - 1]
        if not float(np.max(np.abs(theta))) < 0.5 * math.pi:
            raise SceneError(f"{path}.amplitude", f"an amplitude that turns no rod beyond 90 deg (mode {release.mode})",
                             f"{release.amplitude_m:.6g} m turns a rod by {math.degrees(float(np.max(np.abs(theta)))):.4g} deg")  # fmt: skip
    u = np.sin(theta)[:, None] * toward[None, :] + np.cos(theta)[:, None] * down[None, :]
    y = eq_y.copy()
    y[lay.rods_d] = ((ell / (2.0 * SQ3))[:, None] * u).ravel()
    y[lay.qd] = 0.0
    return y
