"""Steady states of a tether between a fixed root (the "nail") and a held end mass (paper 4.2).

Paper section 4.2: "cancel the derivatives of the model, and compute the value R_f of the external
force on the ending mass m_f so that its position is the one required by the user."  Here that is
done on the compiled model itself (:func:`tetherlab.tether.solve.accelerations`), not on a second
copy of the physics:

    unknowns   d_1 ... d_n (3n) and R_f (3), velocities all zero;
    equations  m_i d''_i(d, R_f) = 0                      (3n: every rod at rest)
               sum_i 2 sqrt3 d_i = r_f - r_0              (3: the end mass where it is required)

With the root fixed (a_0 = 0) and every d''_i = 0, the end mass's acceleration
sum 2 sqrt3 d''_i vanishes too, so every mass of the model is at rest: a static equilibrium.
R_f enters the kernel as the ``applied_force`` effect on the tip body, so the reaction solve of
the dynamics gives the joint reactions J_k (the tension along the tether) and the end reactions.
The equations are solved by Newton's method with a finite-difference Jacobian (the residual is
affine in R_f, so those columns are exact).  Derivation and notation: docs/catenary.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .forces import applied_force
from .model.params import MUT_HOLD_1PC, ParamView
from .system import Model, TetherSpec, build_model
from .tether.solve import accelerations

SQ3 = math.sqrt(3.0)


@dataclass(frozen=True)
class Equilibrium:
    """A static equilibrium of one tether held at both ends (SI units, scene frame)."""

    y: np.ndarray  # Cowell state [r0, d_1..d_n, 0 ... 0] (zero velocities)
    joints_m: np.ndarray  # (n + 1, 3) joint positions A_1, B_1, ..., B_n
    centres_m: np.ndarray  # (n, 3) rod centres G_i
    holding_force_N: np.ndarray  # R_f: external force on the end mass that holds it in place
    joint_reactions_N: np.ndarray  # (n + 1, 3) J_k: force of the root-side element on the tip side
    axial_force_N: np.ndarray  # (n,) F_e = EA eps of every rod (eq. 1 at rest)
    strain: np.ndarray  # (n,)
    residual_N: float  # max |m_i d''_i| at the solution
    constraint_m: float  # distance of the end mass from its required position
    iterations: int

    @property
    def tension_N(self) -> np.ndarray:
        """Tension at every joint, |J_k| (k = 0 at the nail, k = n at the end mass)."""
        return np.linalg.norm(self.joint_reactions_N, axis=1)

    @property
    def nail_force_N(self) -> np.ndarray:
        """Force the fixed root exerts on the tether (J_0); the tether pulls the nail with -J_0."""
        return self.joint_reactions_N[0]

    @property
    def tip_pull_N(self) -> np.ndarray:
        """Force the tether exerts on the end mass (J_n)."""
        return self.joint_reactions_N[-1]


def held_model(
    tether: TetherSpec,
    effects: list,
    central: dict | None = None,
    *,
    quadrature: int = 2,
    root_name: str = "nail",
) -> Model:
    """A model with a fixed root, ``tether`` and an ``applied_force`` slot on its end mass."""
    if not tether.tip_mass_kg > 0.0:
        raise ValueError(f"tether.tip_mass_kg: expected > 0 (an end mass to hold), got {tether.tip_mass_kg!r}")
    central = central or {"mu_m3_s2": 0.0, "radius_m": 0.0}
    hold = (applied_force.SPEC, {"body": 1.0, "fx": 0.0, "fy": 0.0, "fz": 0.0})
    return build_model(
        root_mass_kg=0.0,
        tethers=[tether],
        effects=[*effects, hold],
        central=central,
        quadrature=quadrature,
        root_fixed=True,
        root_name=root_name,
    )


def _force_slot(model: Model) -> int:
    """Index in p of the (fx, fy, fz) of the applied_force acting on the end mass (body 1)."""
    p = model.p
    for par in ParamView(p).effects_with_code(applied_force.CODE):
        if int(p[par + applied_force.PAR_BODY]) == 1:
            return par + applied_force.PAR_F
    raise ValueError(
        "model: expected an applied_force effect on body 1 (the end mass) to carry the holding "
        "force R_f; got none (build the model with tetherlab.statics.held_model)"
    )


def sagging_guess(root_m, tip_m, length_m: float, n: int, down=(0.0, 0.0, -1.0)) -> np.ndarray:
    """Joints (n + 1, 3) on a parabola of arc length ``length_m`` sagging along ``down``.

    Only a starting point for Newton: it picks the hanging branch (an arch pointing up is an
    equilibrium too, an unstable one).  Straight when the ends are at least ``length_m`` apart.
    """
    r0 = np.asarray(root_m, float)
    span = np.asarray(tip_m, float) - r0
    chord = float(np.linalg.norm(span))
    t = np.linspace(0.0, 1.0, 4001)
    e1 = span / chord
    v = np.asarray(down, float) - (np.asarray(down, float) @ e1) * e1
    if chord >= length_m or np.linalg.norm(v) < 1e-9:
        return r0 + np.linspace(0.0, 1.0, n + 1)[:, None] * span
    v /= np.linalg.norm(v)

    def curve(sag):
        return r0 + t[:, None] * span + (4.0 * sag * t * (1.0 - t))[:, None] * v

    def arc(sag):
        return float(np.linalg.norm(np.diff(curve(sag), axis=0), axis=1).sum())

    lo, hi = 0.0, length_m
    for _ in range(100):  # bisection: arc length grows with the sag
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if arc(mid) < length_m else (lo, mid)
    pts = curve(0.5 * (lo + hi))
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
    targets = np.linspace(0.0, s[-1], n + 1)
    return np.column_stack([np.interp(targets, s, pts[:, c]) for c in range(3)])


def solve(
    model: Model,
    root_m,
    tip_m,
    *,
    down=(0.0, 0.0, -1.0),
    guess_joints: np.ndarray | None = None,
    force_tol_N: float | None = None,
    max_iter: int = 60,
) -> Equilibrium:
    """Static equilibrium with the root at ``root_m`` and the end mass held at ``tip_m``.

    ``model`` must have a fixed root, one tether with an end mass and an ``applied_force`` on
    it (see :func:`held_model`).  ``force_tol_N``: the largest rod force imbalance accepted
    (default 1e-12 EA, about ten times the round-off of the forces).
    """
    if not model.root_fixed:
        raise ValueError("model.root_fixed: expected True (a fixed root, the nail), got False")
    if len(model.tethers) != 1:
        raise ValueError(f"model.tethers: expected exactly one tether, got {len(model.tethers)}")
    tether = model.tethers[0]
    if not tether.tip_mass_kg > 0.0:
        raise ValueError(f"model.tethers[0].tip_mass_kg: expected > 0 (an end mass), got {tether.tip_mass_kg!r}")
    slot = _force_slot(model)
    r0 = np.asarray(root_m, float).reshape(3)
    rf = np.asarray(tip_m, float).reshape(3)
    span = rf - r0
    if not np.linalg.norm(span) > 0.0:
        raise ValueError(f"tip_m: expected a position other than the root's {r0.tolist()}, got {rf.tolist()}")
    n = tether.rods
    masses = model.rod_masses()
    total = tether.length_m
    d_scale = total / (2.0 * SQ3 * n)  # |d_i| of an unstretched rod, eq. 3
    f_scale = 1e-3 * tether.ea_n  # the force of a 0.1 % strain
    tol = 1e-12 * tether.ea_n if force_tol_N is None else float(force_tol_N)

    p = model.fresh_params()
    h = 3 * (1 + n)
    q = np.zeros(h)
    qd = np.zeros(h)
    acc = np.zeros(h)
    q[:3] = r0
    m3 = np.repeat(masses, 3)

    def evaluate(x):
        q[3:] = x[: 3 * n] * d_scale
        p[slot : slot + 3] = x[3 * n :] * f_scale
        if accelerations(0.0, q, qd, p, acc) != 0:
            return None
        res = np.empty(3 * n + 3)
        res[: 3 * n] = m3 * acc[3:] / f_scale
        res[3 * n :] = (2.0 * SQ3 * q[3:].reshape(n, 3).sum(axis=0) - span) / total
        return res

    joints = sagging_guess(r0, rf, total, n, down) if guess_joints is None else np.asarray(guess_joints, float)
    if joints.shape != (n + 1, 3):
        raise ValueError(f"guess_joints: expected shape {(n + 1, 3)}, got {joints.shape}")
    x = np.zeros(3 * n + 3)
    x[: 3 * n] = (np.diff(joints, axis=0) / (2.0 * SQ3)).ravel() / d_scale
    f = evaluate(x)
    if f is None:
        raise ValueError("guess_joints: the starting shape is outside the model (a rod collapsed)")
    it = 0
    for it in range(1, max_iter + 1):
        jac = np.empty((x.size, x.size))
        for j in range(x.size):
            step = 1e-7  # scaled units: 1e-7 of a rod's size, or of the 0.1 %-strain force
            xp = x.copy()
            xp[j] += step
            fp = evaluate(xp)
            if fp is None:  # the forward point leaves the model: difference backwards
                xp[j] -= 2 * step
                fp = 2 * f - evaluate(xp)
            jac[:, j] = (fp - f) / step
        dx = np.linalg.solve(jac, -f)
        norm0 = np.linalg.norm(f)
        lam = 1.0
        while True:  # backtracking: take the largest step that lowers the residual
            xn = x + lam * dx
            fn = evaluate(xn)
            if fn is not None and (np.linalg.norm(fn) < norm0 or lam < 1e-3):
                break
            lam *= 0.5
            if lam < 1e-6:
                raise ValueError("statics.solve: Newton stalled (no step lowers the residual)")
        x, f = xn, fn
        force_res = float(np.max(np.abs(f[: 3 * n]))) * f_scale
        miss = float(np.max(np.abs(f[3 * n :]))) * total
        if force_res < tol and miss < 1e-14 * total and lam == 1.0 and np.max(np.abs(dx)) < 1e-6:
            break
    else:
        raise ValueError(
            f"statics.solve: no convergence in {max_iter} Newton iterations "
            f"(force residual {force_res:.3g} N, tolerance {tol:.3g} N)"
        )
    evaluate(x)  # leaves the reactions of the solution in the scratch area of p
    hold = p[slot : slot + 3].copy()
    v = ParamView(p)
    if v.defect == MUT_HOLD_1PC:  # tetherlab.mutants' negative control only, never a user's
        hold *= 1.01
    reactions = v.joint_scratch.j_N[: n + 1].copy()
    fe = v.rod_scratch.fe[:n].copy()
    eps = v.rod_scratch.eps[:n].copy()
    d = q[3:].reshape(n, 3).copy()
    joints = r0 + np.concatenate([np.zeros((1, 3)), np.cumsum(2.0 * SQ3 * d, axis=0)])
    y = np.concatenate([q.copy(), np.zeros(h)])
    return Equilibrium(
        y=y,
        joints_m=joints,
        centres_m=joints[:-1] + SQ3 * d,
        holding_force_N=hold,
        joint_reactions_N=reactions,
        axial_force_N=fe,
        strain=eps,
        residual_N=float(np.max(np.abs(m3 * acc[3:]))),
        constraint_m=float(np.linalg.norm(joints[-1] - rf)),
        iterations=it,
    )
