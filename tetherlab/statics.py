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
affine in R_f, so those columns are exact).  Where that fails (a stiff tether that must sag has no
tension in the sagging guess, hence no transverse stiffness), the discrete elastic catenary found
by shooting on the end pull (uniform gravity) starts a trust-region Newton on the same equations
(docs/catenary.md section 3.1).  :func:`hang_joints` is the tether hanging free, the start of
``initial.release`` (docs/hanging-chain.md).  Derivation and notation: docs/catenary.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .forces import applied_force, uniform_gravity
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
    iterations: int  # Newton iterations, over every stage
    method: str = "newton"  # "newton" from the sagging guess, "shooting" (the discrete catenary, polished), "trust-region" (from the caller's guess) or "chord" (one rod)

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
    # an inextensible tether's static shape is the elastic one of its EA; the start then restores
    # its rods' lengths (tetherlab/initial/inextensible.py)
    from .initial.inextensible import elastic_stand_in

    tether = elastic_stand_in(tether)
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


def _uniform_loads(p, slot):
    """(g vector, constant force on the end mass) when every load of the model is uniform gravity
    or a constant force on the end mass; None otherwise (loads that depend on where a rod is)."""
    v = ParamView(p)
    g = np.zeros(3)
    tip_force = np.zeros(3)
    for e in v.effects:
        if e.code == uniform_gravity.CODE:
            g[2] -= p[e.par_offset]
        elif e.code == applied_force.CODE and int(p[e.par_offset + applied_force.PAR_BODY]) == 1:
            if e.par_offset + applied_force.PAR_F != slot:
                tip_force += p[e.par_offset + applied_force.PAR_F : e.par_offset + applied_force.PAR_F + 3]
        else:
            return None
    return g, tip_force


def shot_joints(root_m, tip_m, lengths_m, masses_kg, ea_N, g_m_s2, tip_load_N, *, max_iter: int = 60):
    """Joints (n + 1, 3) of the chain of straight elastic rods hanging between ``root_m`` and
    ``tip_m`` under uniform gravity, by shooting on the tether's pull on the end mass J_n.

    Marching from the end mass to the root, rod i balances its weight with its end reactions,
    J_{i-1} = J_i - m_i g, lies along -(J_{i-1} + J_i) and is stretched by F_e = |J_{i-1} + J_i| / 2
    (docs/catenary.md section 3: the equilibrium of every TMED rod under a uniform load); three
    equations put the last joint on the root.  Newton on those three unknowns, damped, from a pull
    along the chord of the weight of the whole system.  This is the discrete elastic catenary, so
    it is exact for the model under uniform gravity; the caller still polishes the answer with the
    model's own equations.  Returns (joints, J_n), or None if the shooting does not converge (a tether with a slack point)."""
    weights = np.asarray(masses_kg, float)[:, None] * np.asarray(g_m_s2, float)[None, :]
    g_hat = np.asarray(g_m_s2, float) / max(float(np.linalg.norm(g_m_s2)), 1e-300)
    return shot_under_loads(root_m, tip_m, lengths_m, weights, ea_N, tip_load_N, g_hat, max_iter=max_iter)


def shot_under_loads(root_m, tip_m, lengths_m, rod_loads_N, ea_N, tip_load_N, down, *, max_iter: int = 60):
    """The march of :func:`shot_joints` with a given external force on every rod (``rod_loads_N``,
    (n, 3): J_{i-1} = J_i - R_i) and ``down`` the direction the loads pull (the starts' "down").
    Exact for loads that do not depend on where the rods are; for loads that do (an orbit), the
    caller repeats it with the loads of the shape found (docs/catenary.md section 3.1)."""
    r0 = np.asarray(root_m, float)
    rf = np.asarray(tip_m, float)
    lengths = np.asarray(lengths_m, float)
    weights = np.asarray(rod_loads_N, float)
    ea = np.asarray(ea_N, float)
    n = lengths.size
    total = float(lengths.sum())
    # J_{i-1} = J_n - (weights of rods i..n): suffix sums
    below = np.cumsum(weights[::-1], axis=0)[::-1]  # below[i] = sum_{k >= i} W_k (0-based)

    def joints_of(jn):
        j_prev = jn[None, :] - below  # J_{i-1} for rods i = 1..n (0-based row i-1)
        j_next = np.vstack([j_prev[1:], jn[None, :]])  # J_i
        s = j_prev + j_next
        mag = np.linalg.norm(s, axis=1)
        if not np.all(mag > 0.0):
            return None
        u = -s / mag[:, None]
        rods = (lengths * (1.0 + 0.5 * mag / ea))[:, None] * u
        return np.vstack([rf[None, :] - np.cumsum(rods[::-1], axis=0)[::-1], rf[None, :]])

    def miss(jn):
        jts = joints_of(jn)
        return None if jts is None else (jts[0] - r0) / total

    weight = float(np.linalg.norm(below[0])) + float(np.linalg.norm(np.asarray(tip_load_N, float)))
    force = max(weight, 1e-300)
    chord = (r0 - rf) / max(float(np.linalg.norm(r0 - rf)), 1e-300)
    g_hat = np.asarray(down, float)
    # starts: pulls along the chord (a taut tether), down (the tether reaching the end mass from
    # below: a loop hanging under it), up, and half-way between, each at multiples of the weight
    # from 0.003 (a loop whose bottom carries almost nothing) to 30 (a taut, stretched tether)
    def unit(vec):
        return vec / max(float(np.linalg.norm(vec)), 1e-300)

    dirs = (chord, g_hat, -g_hat, unit(g_hat + chord), unit(chord - g_hat))
    starts = [s * force * dvec for s in (1.0, 0.3, 3.0, 30.0, 0.03, 0.003) for dvec in dirs]
    for jn in starts:
        found = _shoot_from(jn, miss, joints_of, force, max_iter)
        if found is not None:
            return found
    return None


def _shoot_from(jn, miss, joints_of, force, max_iter):
    """Damped Newton on the three components of J_n from one start (see :func:`shot_joints`)."""
    f = miss(jn)
    if f is None:
        return None
    for _ in range(max_iter):
        if float(np.max(np.abs(f))) < 1e-15:
            return joints_of(jn), jn
        jac = np.empty((3, 3))
        for c in range(3):
            step = 1e-7 * max(force, float(np.linalg.norm(jn)))
            jp = jn.copy()
            jp[c] += step
            fp = miss(jp)
            if fp is None:
                return None
            jac[:, c] = (fp - f) / step
        try:
            dj = np.linalg.solve(jac, -f)
        except np.linalg.LinAlgError:
            return None
        lam = 1.0
        norm0 = float(np.linalg.norm(f))
        while lam > 1e-10:
            fn = miss(jn + lam * dj)
            if fn is not None and float(np.linalg.norm(fn)) < norm0:
                break
            lam *= 0.5
        else:
            # the round-off floor of the miss (1e-16 of the length) ends the march too
            return (joints_of(jn), jn) if norm0 < 1e-13 else None
        jn, f = jn + lam * dj, fn
    return None


def _field_shot(joints, root_m, tip_m, lengths_m, ea_N, loads_at, rounds: int = 30):
    """The shooting under loads that depend on where the rods are (central gravity, its harmonics):
    the loads of the shape ``joints`` are frozen, the chain shot under them
    (:func:`shot_under_loads`), and the loads taken again at the new shape, until the joints move
    by less than 1e-13 of the length (a fixed point: over a tether much shorter than its distance
    to the attracting centre the loads change by ~length/radius of themselves, so each round gains
    that factor).  Returns (joints, J_n, the end mass's load), or None."""
    total = float(np.sum(lengths_m))
    found = None
    for _ in range(rounds):
        loads = loads_at(joints)
        if loads is None:
            return None
        rod_loads, tip_load = loads
        pull = rod_loads.sum(axis=0) + tip_load
        if not np.linalg.norm(pull) > 0.0:
            return None
        shot = shot_under_loads(root_m, tip_m, lengths_m, rod_loads, ea_N, tip_load, pull / np.linalg.norm(pull))
        if shot is None:
            return None
        moved = float(np.max(np.abs(shot[0] - joints)))
        joints = shot[0]
        found = (shot[0], shot[1], tip_load)
        if moved < 1e-13 * total:
            break
    return found


def hang_joints(root_m, lengths_m, masses_kg, p, g_m_s2, tip_load_N) -> np.ndarray:
    """Joints (n + 1, 3) of the tether hanging free from ``root_m`` under uniform gravity: the
    march of :func:`shot_joints` with the pull on the end mass known, J_n = -tip_load_N."""
    lengths = np.asarray(lengths_m, float)
    weights = np.asarray(masses_kg, float)[:, None] * np.asarray(g_m_s2, float)[None, :]
    ea = ParamView(p).rods.ea_N
    jn = -np.asarray(tip_load_N, float)
    below = np.cumsum(weights[::-1], axis=0)[::-1]
    j_prev = jn[None, :] - below
    s = j_prev + np.vstack([j_prev[1:], jn[None, :]])
    mag = np.linalg.norm(s, axis=1)
    if not np.all(mag > 0.0):
        raise ValueError("hang_joints: a rod with no tension (nothing hangs from it)")
    rods = (lengths * (1.0 + 0.5 * mag / ea))[:, None] * (-s / mag[:, None])
    return np.asarray(root_m, float)[None, :] + np.vstack([np.zeros((1, 3)), np.cumsum(rods, axis=0)])


class _NoConvergence(Exception):
    """A Newton run that ended without meeting its tolerances (message: why)."""


class NoTautEquilibrium(ValueError):
    """The end mass is held where no equilibrium with every rod in tension was found (n > 1).

    ``span_m``: the hold distance asked; ``hang_m``: the length the tether takes hanging along the
    load under its own weight with nothing pulling its end, ``free_hang_m``: with the end mass
    hanging free from it (both None when the loads are not uniform); ``proven``: True when no taut
    equilibrium exists (a hold on the line of a uniform load shorter than ``hang_m``), False when
    the solver found none (docs/catenary.md 3.2)."""

    def __init__(self, message, span_m, hang_m=None, free_hang_m=None, proven=False):
        super().__init__(message)
        self.span_m = span_m
        self.hang_m = hang_m
        self.free_hang_m = free_hang_m
        self.proven = proven


def hang_lengths(lengths_m, masses_kg, ea_N, g_m_s2: float, tip_pull_N: float):
    """(length hanging with nothing pulling its end, length with ``tip_pull_N`` pulling it) of a
    chain of rods hanging straight along a uniform load ``g_m_s2``: rod i carries the weight below
    its centre, T_i = g (sum_{k>i} m_k + m_i / 2), and is stretched by T_i / EA_i (eq. 1)."""
    lengths = np.asarray(lengths_m, float)
    m = np.asarray(masses_kg, float)
    ea = np.asarray(ea_N, float)
    below = np.cumsum(m[::-1])[::-1] - 0.5 * m  # mass below each rod's centre
    t = g_m_s2 * below
    return float(np.sum(lengths * (1.0 + t / ea))), float(np.sum(lengths * (1.0 + (t + tip_pull_N) / ea)))


def _rotation(axis, angle):
    """Rodrigues' rotation matrix by ``angle`` about the unit vector ``axis``."""
    k = np.asarray(axis, float)
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + math.sin(angle) * kx + (1.0 - math.cos(angle)) * (kx @ kx)


#: The continuation in the hold angle (docs/catenary.md 3.2): the first step is this fraction of
#: the way from the horizontal hold to the one asked; a step that fails is halved, down to
#: CONTINUATION_MIN_STEP of the way, after which the branch is taken to end there (a fold: measured
#: at 8-16 rods, EA 1e3 N, the taut branch from the horizontal turns back 2-6 deg off the vertical,
#: the steps shrinking there); each step's Newton
#: gets CONTINUATION_ITERATIONS iterations (from the neighbouring solution it needs 2-6).
CONTINUATION_FIRST_STEP = 0.25
CONTINUATION_MIN_STEP = 1e-3
CONTINUATION_ITERATIONS = 8
#: ... and the whole continuation at most this many attempted steps (each an O(n^2) Jacobian or more)
CONTINUATION_MAX_ATTEMPTS = 40
#: Off switch of the continuation: the negative control of the range tests (tests/test_statics_range.py)
CONTINUATION = True


def _hold_plane(span, down):
    """(unit down g, unit side e, angle of ``span`` from g in [0, pi]) of the vertical plane of a
    hold; on the line of ``down`` the side is the direction of x (or y) across it."""
    g = np.asarray(down, float) / float(np.linalg.norm(down))
    side = span - (span @ g) * g
    if np.linalg.norm(side) <= 1e-12 * np.linalg.norm(span):
        side = np.array([1.0, 0.0, 0.0]) if abs(g[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        side = side - (side @ g) * g
    side = side / np.linalg.norm(side)
    return g, side, math.atan2(float(span @ side), float(span @ g))


def _continue_hold_angle(attempt, taut, x_start, span, down, n):
    """Continuation in the hold angle at the asked distance: from a solution ``x_start`` of the
    horizontal hold, rotate the hold in its vertical plane towards the one asked, each step's rods
    rotated with it as the next start (``attempt(chord, x)`` -> x or raises _NoConvergence);
    ``taut(x)``: every rod in tension.  Returns (x, steps, iterations) at the asked hold, or raises
    _NoConvergence naming the last angle reached with every rod taut."""
    g, side, target = _hold_plane(span, down)
    s = float(np.linalg.norm(span))
    axis = np.cross(g, side)
    theta = 0.5 * math.pi
    x = x_start
    step = CONTINUATION_FIRST_STEP * (target - theta)
    steps = 0
    iterations = 0
    attempts = 0
    while theta != target:
        attempts += 1
        if attempts > CONTINUATION_MAX_ATTEMPTS:
            raise _NoConvergence(
                f"continuation in the hold angle from the horizontal reached {math.degrees(theta):.4g} deg off the line "
                f"of the load with every rod taut in {CONTINUATION_MAX_ATTEMPTS} steps, and stopped there")
        if abs(step) < CONTINUATION_MIN_STEP * abs(target - 0.5 * math.pi):
            raise _NoConvergence(
                f"continuation in the hold angle from the horizontal kept every rod taut down to "
                f"{math.degrees(theta):.4g} deg off the line of the load and no further")
        nxt = target if abs(target - theta) <= abs(step) else theta + step
        rot = _rotation(axis, nxt - theta)
        xg = x.copy()
        xg[: 3 * n] = (x[: 3 * n].reshape(n, 3) @ rot.T).ravel()
        chord = span if nxt == target else s * (math.cos(nxt) * g + math.sin(nxt) * side)
        try:
            xn, it = attempt(chord, xg)
        except (_NoConvergence, np.linalg.LinAlgError):
            step *= 0.5
            continue
        iterations += it
        if not taut(xn):  # the branch found passes through a rod without tension: not ours
            step *= 0.5
            continue
        x, theta = xn, nxt
        steps += 1
        step *= 1.5
    return x, steps, iterations


def _fd_jacobian(evaluate, x, f):
    """Forward differences in scaled units: 1e-7 of a rod's size, or of the 0.1 %-strain force."""
    jac = np.empty((x.size, x.size))
    for j in range(x.size):
        step = 1e-7
        xp = x.copy()
        xp[j] += step
        fp = evaluate(xp)
        if fp is None:  # the forward point leaves the model: difference backwards
            xp[j] -= 2 * step
            fp = 2 * f - evaluate(xp)
        jac[:, j] = (fp - f) / step
    return jac


#: The plain Newton gives up once its residual has risen in STALL_ITERATIONS iterations in a row
#: (each such step is taken only because backtracking found no step that lowers it): it is
#: wandering, and the fallback takes over at once instead of after max_iter iterations.  Where it
#: converged, over the statics grid of docs/catenary.md 3.1 (1-64 rods, EA 4e4-1e9 N, ten holds),
#: it never rose more than 11 times in a row, so those solves are bit for bit what they were.  A
#: test on the residual's progress instead (not halved in k iterations) would have to wait 52
#: iterations to spare them: solves that converge cross plateaus that long.
STALL_ITERATIONS = 15


def _plain_newton(evaluate, x, f, converged, max_iter):
    """Newton with backtracking on the residual norm: the solve of the first versions, kept
    step for step so that every equilibrium it finds stays bit for bit what it was; it stops
    early when it stalls (``STALL_ITERATIONS``)."""
    it = 0
    rises = 0
    for it in range(1, max_iter + 1):
        jac = _fd_jacobian(evaluate, x, f)
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
                raise _NoConvergence("Newton stalled (no step lowers the residual)")
        rose = not np.linalg.norm(fn) < norm0
        x, f = xn, fn
        if converged(f, dx, lam == 1.0):
            return x, f, it
        rises = rises + 1 if rose else 0
        if rises >= STALL_ITERATIONS:
            raise _NoConvergence(f"the residual rose in {STALL_ITERATIONS} Newton iterations in a row (stopped at {it})")
    raise _NoConvergence(f"no convergence in {max_iter} Newton iterations")


def _trust_newton(evaluate, x, f, converged, max_iter):
    """Newton globalised by a Levenberg-Marquardt trust region on the scaled residual.

    Each iteration tries the full Newton step first and keeps it when it lowers |f|; otherwise it
    solves the damped least-squares problem min |J dx + f|^2 + mu |D dx|^2 (D: the column norms
    of J, Marquardt's scaling) with mu raised until the residual falls.  It never accepts a step
    that raises the residual (the plain solve's last resort does), so it cannot wander off; where
    the Jacobian is singular (a straight tether with no tension has no transverse stiffness) the
    damped step is still defined.  Returns (x, f, iterations)."""
    mu = 0.0
    it = 0
    for it in range(1, max_iter + 1):
        jac = _fd_jacobian(evaluate, x, f)
        norm0 = float(np.linalg.norm(f))
        try:
            dx = np.linalg.solve(jac, -f)
        except np.linalg.LinAlgError:
            dx = None
        fn = None
        full = False
        if dx is not None and np.all(np.isfinite(dx)):
            fn = evaluate(x + dx)
            full = fn is not None and float(np.linalg.norm(fn)) < norm0
            if not full and fn is not None and converged(fn, dx, True) and converged(f, dx, True):
                return x, f, it  # at the round-off floor: the residual cannot fall any more
        if not full:
            scale = np.linalg.norm(jac, axis=0)
            scale[scale == 0.0] = max(float(scale.max()), 1.0)
            mu = max(mu, 1e-6)
            aug_rhs = np.concatenate([-f, np.zeros(x.size)])
            for _ in range(60):
                aug = np.vstack([jac, math.sqrt(mu) * np.diag(scale)])
                dx = np.linalg.lstsq(aug, aug_rhs, rcond=None)[0]
                fn = evaluate(x + dx)
                if fn is not None and float(np.linalg.norm(fn)) < norm0:
                    break
                mu *= 4.0
            else:
                raise _NoConvergence("the trust region shrank to nothing (no step lowers the residual)")
            mu /= 3.0
        else:
            mu = 0.0
        x, f = x + dx, fn
        if converged(f, dx, full):
            return x, f, it
    raise _NoConvergence(f"no convergence in {max_iter} trust-region Newton iterations")


def _refusal_lengths(uniform, tether, model, ea_rods, span, down, n):
    """(span, hang length, free-hang length, proven) of a hold under uniform loads (None
    otherwise, or for one rod, whose vector is the chord): ``proven`` when the hold is on the line
    of the load, below the root, nearer than the hang length.  On that line a taut chain is
    straight (its rods' directions -(J_{i-1} + J_i) have no component across the load) and each
    rod carries at least the weight below its centre, so it is at least ``hang`` long; a chain
    that folds back has a rod at the fold with J_{i-1} + J_i = 0, i.e. no tension (section 3.2)."""
    if uniform is None or n < 2:
        return None
    g_vec, tip_force = uniform
    g = float(np.linalg.norm(g_vec))
    if not g > 0.0:
        return None
    g_hat = g_vec / g
    pull = tether.tip_mass_kg * g + float(tip_force @ g_hat)
    hang, free = hang_lengths(model.rod_lengths(), model.rod_masses(), ea_rods, g, max(pull, 0.0))
    s = float(np.linalg.norm(span))
    across = float(np.linalg.norm(span - (span @ g_hat) * g_hat))
    proven = across <= 1e-12 * s and float(span @ g_hat) > 0.0 and s < hang
    return s, hang, free, proven


def _refusal_text(refusal, span, down, why):
    """The message of a NoTautEquilibrium: the hold asked, the hang lengths, and why."""
    s = float(np.linalg.norm(span))
    g_hat = np.asarray(down, float) / float(np.linalg.norm(down))
    off = math.degrees(math.acos(max(-1.0, min(1.0, float(span @ g_hat) / s))))
    found = "exists" if refusal is not None and refusal[3] else "was found"
    text = f"no equilibrium with every rod in tension {found}: the end mass held {s:.9g} m from the root, {off:.4g} deg off the downward vertical"
    if refusal is not None and refusal[1] is not None:
        text += (f"; hanging under its own weight with nothing pulling its end the tether is {refusal[1]:.9g} m long "
                 f"({refusal[2]:.9g} m with the end mass hanging free)")
        if refusal[3]:
            return text + ": held on the vertical, a taut tether needs at least that distance; hold the end mass at least that far, or off the vertical"
        if s < refusal[1]:
            text += ": the extra length must hang as a loop below the end mass, and none was found"
    return text + (f" ({why})" if why else "") + "; move the end mass further from the root or further off the vertical"


def _horizontal_start(attempt, taut, evaluate, converged, unknowns, span, down, r0, total, n,
                      uniform, tether, model, masses, ea_rods, f_scale, max_iter):
    """A taut equilibrium of the hold at the asked distance, horizontal in the asked hold's
    vertical plane: the continuation's start.  Newton from the sagging guess, else the shooting
    (uniform loads), polished by the trust region.  Returns (x, iterations)."""
    g, side, _ = _hold_plane(span, down)
    s = float(np.linalg.norm(span))
    chord = s * side
    span[:] = chord
    x0 = unknowns(sagging_guess(r0, r0 + chord, total, n, g))
    f0 = evaluate(x0)
    if f0 is not None:
        try:
            x, _, it = _plain_newton(evaluate, x0, f0, converged, max_iter)
            if taut(x):
                return x, it
        except (_NoConvergence, np.linalg.LinAlgError):
            pass
    if uniform is None:
        raise _NoConvergence("no taut equilibrium of the horizontal hold to start the continuation from")
    tip_load = uniform[1] + tether.tip_mass_kg * uniform[0]
    shot = shot_joints(r0, r0 + chord, model.rod_lengths(), masses, ea_rods, uniform[0], tip_load)
    if shot is None:
        raise _NoConvergence("the horizontal hold has no discrete catenary to start the continuation from")
    xs = unknowns(shot[0])
    xs[3 * n :] = -(shot[1] + tip_load) / f_scale
    x, it = attempt(chord, xs)
    if not taut(x):
        raise _NoConvergence("the horizontal hold's equilibrium has a rod in compression")
    return x, it


def solve(
    model: Model,
    root_m,
    tip_m,
    *,
    down=(0.0, 0.0, -1.0),
    guess_joints: np.ndarray | None = None,
    force_tol_N: float | None = None,
    max_iter: int = 60,
    taut_only: bool = True,
) -> Equilibrium:
    """Static equilibrium with the root at ``root_m`` and the end mass held at ``tip_m``.

    ``model`` must have a fixed root, one tether with an end mass and an ``applied_force`` on
    it (see :func:`held_model`).  ``force_tol_N``: the largest rod force imbalance accepted
    (default 1e-12 EA, about ten times the round-off of the forces).

    Newton from the sagging guess first (bit for bit the solve of the first versions).  When it
    fails, which it does for stiff tethers (EA a million times the weight) that must sag, and the
    loads are uniform gravity and constant forces on the end mass, the discrete elastic catenary
    found by shooting on three unknowns (:func:`shot_joints`) is the start of a Newton iteration
    globalised by a trust region (:func:`_trust_newton`), which meets the same tolerances on the
    model's own equations (docs/catenary.md section 3.1).

    ``taut_only`` (n > 1): refuse a hold with no equilibrium with every rod in tension
    (:class:`NoTautEquilibrium`, section 3.2), after a continuation in the hold angle; False keeps
    the strut Newton converged to (the elastic stand-in of an inextensible tether, whose start
    restores the rods' lengths: straight on the vertical at its length).
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
    v = ParamView(p)
    ea_rods = v.rods.ea_N.copy()  # the shooting's EA per rod
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

    def converged(f, dx, full):
        force_res = float(np.max(np.abs(f[: 3 * n]))) * f_scale
        miss = float(np.max(np.abs(f[3 * n :]))) * total
        return force_res < tol and miss < 1e-14 * total and full and np.max(np.abs(dx)) < 1e-6

    def unknowns(joints):
        x = np.zeros(3 * n + 3)
        x[: 3 * n] = (np.diff(joints, axis=0) / (2.0 * SQ3)).ravel() / d_scale
        return x

    def _loads_at(jts):
        """(external force on every rod (n, 3), on the end mass (3)) of the model at the shape
        ``jts`` at rest, nothing holding the end mass: the kernel's own loads (rod scratch R_1 + R_2,
        eqs. 11-18, and the end mass's force; tetherlab/tether/rod.py)."""
        xl = unknowns(jts)  # R_f = 0 in it
        if evaluate(xl) is None:
            return None
        rs = ParamView(p).rod_scratch
        return rs.r1[:n] + rs.r2[:n], ParamView(p).body_scratch.f_eff[1, :3].copy()

    uniform = _uniform_loads(p, slot)
    refusal = _refusal_lengths(uniform, tether, model, ea_rods, span, down, n) if guess_joints is None and taut_only else None
    if refusal is not None and refusal[3]:
        raise NoTautEquilibrium(_refusal_text(refusal, span, down, None), *refusal)

    joints = sagging_guess(r0, rf, total, n, down) if guess_joints is None else np.asarray(guess_joints, float)
    if joints.shape != (n + 1, 3):
        raise ValueError(f"guess_joints: expected shape {(n + 1, 3)}, got {joints.shape}")
    x0 = unknowns(joints)
    f0 = evaluate(x0)
    if f0 is None:
        raise ValueError("guess_joints: the starting shape is outside the model (a rod collapsed)")
    method = "newton"
    first_error = None
    loads = None
    newton_x = None
    x = None
    try:
        if guess_joints is not None:
            raise _NoConvergence("a guess from the caller goes to the trust region directly")
        x, f, it = _plain_newton(evaluate, x0, f0, converged, max_iter)
        evaluate(x)
        if n > 1 and float(ParamView(p).rod_scratch.fe[:n].min()) < 0.0:
            # a strut: Newton found the unstable branch that pushes on the end mass (seen for
            # stiff tethers held at their length); a hanging, tensioned one is looked for below
            raise _NoConvergence("Newton from the guess found a compressed tether")
    except (_NoConvergence, np.linalg.LinAlgError) as first:
        newton_x = x if str(first).startswith("Newton from the guess found a compressed") else None
        x = None
        loads = _uniform_loads(p, slot) if guess_joints is None else None
        if loads is not None:  # the discrete catenary by shooting, polished on the model itself
            tip_load = loads[1] + tether.tip_mass_kg * loads[0]
            shot = shot_joints(r0, rf, model.rod_lengths(), masses, ea_rods, loads[0], tip_load)
            if shot is not None:
                xs = unknowns(shot[0])
                xs[3 * n :] = -(shot[1] + tip_load) / f_scale  # the end mass at rest: R_f + J_n + loads = 0
                fs = evaluate(xs)
                if fs is not None:
                    try:
                        x, f, it = _trust_newton(evaluate, xs, fs, converged, max_iter)
                        method = "shooting"
                    except (_NoConvergence, np.linalg.LinAlgError):
                        x = None
        elif guess_joints is None:  # loads that depend on where the rods are (an orbit)
            shot = _field_shot(sagging_guess(r0, rf, total, n, down), r0, rf, model.rod_lengths(), ea_rods, _loads_at)
            if shot is not None:
                xs = unknowns(shot[0])
                xs[3 * n :] = -(shot[1] + shot[2]) / f_scale  # R_f + J_n + the end mass's loads = 0
                fs = evaluate(xs)
                if fs is not None:
                    try:
                        x, f, it = _trust_newton(evaluate, xs, fs, converged, max_iter)
                        method = "shooting"
                    except (_NoConvergence, np.linalg.LinAlgError):
                        x = None
        if x is None and guess_joints is not None:
            # a guess that is already the answer leaves the plain solve at its round-off floor,
            # where no full step lowers the residual: the trust region accepts it there
            try:
                x, f, it = _trust_newton(evaluate, x0, f0, converged, max_iter)
                method = "trust-region"
            except (_NoConvergence, np.linalg.LinAlgError):
                x = None
        if x is None and n == 1:  # one rod: its vector is the chord; only R_f is unknown
            xs = unknowns(np.vstack([r0, rf]))
            fs = evaluate(xs)
            if fs is not None:
                try:
                    x, f, it = _trust_newton(evaluate, xs, fs, converged, max_iter)
                    method = "chord"
                except (_NoConvergence, np.linalg.LinAlgError):
                    x = None
        first_error = str(first)
    if first_error is not None and x is None and guess_joints is None and n > 1 and (taut_only or newton_x is None):
        # the globalisation: continuation in the hold angle from the horizontal (section 3.2)
        why = "the continuation is switched off"
        if CONTINUATION:
            def attempt(chord, xg):
                span[:] = chord
                fg = evaluate(xg)
                if fg is None:
                    raise _NoConvergence("a rod collapsed")
                xn, _, k = _trust_newton(evaluate, xg, fg, converged, CONTINUATION_ITERATIONS)
                return xn, k

            def taut(xt):
                evaluate(xt)
                return float(ParamView(p).rod_scratch.fe[:n].min()) > 0.0

            try:
                x_h, it_h = _horizontal_start(attempt, taut, evaluate, converged, unknowns, span, down, r0, total, n,
                                              uniform, tether, model, masses, ea_rods, f_scale, max_iter)
                x, steps, it_c = _continue_hold_angle(attempt, taut, x_h, rf - r0, down, n)
                it = it_h + it_c
                method = "continuation"
            except (_NoConvergence, np.linalg.LinAlgError) as exc:
                x = None
                why = str(exc)
            finally:
                span[:] = rf - r0
        if x is None:
            refusal = refusal or (None, None, None, False)
            raise NoTautEquilibrium(_refusal_text(refusal, span, down, why), float(np.linalg.norm(span)), *refusal[1:])
    if first_error is not None and x is None and newton_x is not None:
        x = newton_x  # one rod, or a strut asked for (taut_only False)
        method = "newton"
    if first_error is not None and x is None:
        why = (
            "the shooting found no discrete catenary (a tether folded back on itself, or slack)"
            if guess_joints is None
            else "the trust region from the guess did not converge"
        )
        raise ValueError(f"statics.solve: no convergence: Newton from the sagging guess ({first_error}); {why}")
    f = evaluate(x)  # leaves the reactions of the solution in the scratch area of p
    hold = p[slot : slot + 3].copy()
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
        method=method,
    )

