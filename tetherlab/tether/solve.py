"""The reaction solve over a forest of bodies and tethers (compiled): the driver of the parts.

The system is one or more trees: root bodies (point masses or rigid bodies with wheels; fixed,
the catenary's "nail", or free) carrying tethers of TMED rods (tether/chain.py) whose far ends
hold further bodies (hub and spoke, paper section 2.4; one tether between two point masses is
section 2.3; trees: docs/model.md section 12).  Every evaluation runs, in this order:

1. :func:`forward`, roots to leaves: each body's kinematics, each tether's attachment point, its
   walk with every rod's forces, the body at its end (bodies/parts.py: body_root_state,
   body_attach, tether/chain.py: chain_walk, body_end_state);
2. every body's set-up: external forces, torques, wheels, its effective system (body_setup);
3. compliance up the tree, leaves first (the tether order H_OFF_ORDER): the tip body's compliance
   a_B = C J_n + f (body_compliance), the tether's block Thomas elimination down to
   J_0 = W (s_0 + a_A) (chain_reduce), W and s_0 into its parent's system (body_add_child);
4. each root's own 3x3 or 6x6 solve (body_root_solve);
5. back substitution, roots to leaves: a_A of each tether from its parent, every J_k and d''
   (chain_back_substitute), the tip body's accelerations (body_back_substitute);
6. every body's own derivatives (body_derivatives: attitude; the wheels' are written in 2).

Cost: linear in the total number of rods plus a constant per body.

Paper equations: the joints (eqs. 21-22) are built into the coordinates (eq. 23), so their
reactions J_k are the unknowns; the tip (eqs. 24, 29, 31) and each rod (eqs. 25-28, 30, 32-34)
form the tether's system L; a point root couples it through eqs. 35-39 (one tether) or eqs. 40-43
(hub and spoke), a rigid root through eqs. 44-49.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import njit, njit_hot
from ..bodies.parts import (
    body_add_child,
    body_attach,
    body_back_substitute,
    body_compliance,
    body_derivatives,
    body_end_state,
    body_point_acceleration,
    body_root_solve,
    body_root_state,
    body_setup,
)
from ..kernel.layout import (
    BS_A,
    BS_R,
    BS_SIZE,
    BS_ROT,
    BS_V,
    BT_AOFF,
    BT_QOFF,
    BT_SIZE,
    FAIL_NONFINITE,
    FAIL_SINGULAR,
    H_NBODY,
    H_NREEL,
    H_NROOT,
    H_NRODS,
    H_NTETH,
    H_NWHEEL,
    H_OFF_BODY,
    H_OFF_BSCR,
    H_OFF_ORDER,
    H_OFF_ROOTS,
    H_OFF_SCR,
    H_OFF_TETH,
    SJ_J,
    SJ_S,
    SJ_SINV,
    SJ_SIZE,
    SR_SIZE,
    TS_A,
    TS_B,
    TS_SIZE,
    TT_CHILD,
    TT_NRODS,
    TT_PARENT,
    TT_ROD0,
    TT_SIZE,
    WS_SIZE,
)
from .parts import tether_back_substitute, tether_reduce, tether_walk
from .reel import reel_body_forces, reel_update
from .reel_spool import n_spools, record_tensions, set_trial, spool_indices, spool_system, write_spool_derivatives
from .rod import fail, next_joint


@njit_hot(cache=True)
def forward(t, q, qd, att, p, with_forces):
    """Kinematics of the whole forest, roots to leaves: every body's centre of mass (and attitude),
    every tether's attachment point A_1 and end B_n, and (with_forces) every rod's forces.
    Returns a failure code."""
    offb = int(p[H_OFF_BODY])
    offt = int(p[H_OFF_TETH])
    bscr = int(p[H_OFF_BSCR])
    nteth = int(p[H_NTETH])
    tscr = bscr + int(p[H_NBODY]) * BS_SIZE
    order = int(p[H_OFF_ORDER])
    roots = int(p[H_OFF_ROOTS])
    for i in range(int(p[H_NROOT])):
        b = int(p[roots + i])
        qo = int(p[offb + b * BT_SIZE + BT_QOFF])
        body_root_state(att, p, b, q[qo], q[qo + 1], q[qo + 2], qd[qo], qd[qo + 1], qd[qo + 2])
    for i in range(nteth - 1, -1, -1):  # roots first
        k = int(p[order + i])
        tb = offt + k * TT_SIZE
        ts = tscr + k * TS_SIZE
        pbs = bscr + int(p[tb + TT_PARENT]) * BS_SIZE
        ax, ay, az, avx, avy, avz = body_attach(
            p, int(p[tb + TT_PARENT]), tb, ts,
            p[pbs + BS_R], p[pbs + BS_R + 1], p[pbs + BS_R + 2], p[pbs + BS_V], p[pbs + BS_V + 1], p[pbs + BS_V + 2],
        )
        p[ts + TS_A] = ax
        p[ts + TS_A + 1] = ay
        p[ts + TS_A + 2] = az
        p[ts + TS_A + 3] = avx
        p[ts + TS_A + 4] = avy
        p[ts + TS_A + 5] = avz
        code, ax, ay, az, avx, avy, avz = tether_walk(t, q, qd, p, k, with_forces, ax, ay, az, avx, avy, avz)
        if code != 0:
            return code
        p[ts + TS_B] = ax
        p[ts + TS_B + 1] = ay
        p[ts + TS_B + 2] = az
        p[ts + TS_B + 3] = avx
        p[ts + TS_B + 4] = avy
        p[ts + TS_B + 5] = avz
        c = int(p[tb + TT_CHILD])
        if c >= 0:
            body_end_state(att, p, c, ax, ay, az, avx, avy, avz)
    return 0


@njit(cache=True)  # allocates the spool solve's small arrays; the pass itself (_evaluate) is hot
def system_accelerations(t, q, qd, att, p, acc, datt):
    """Accelerations of q_trans into ``acc`` and the derivatives of the attitude, wheel and spool
    blocks into ``datt`` (empty for a point-mass scene without a spool).  Leaves in the scratch
    area, per joint, the reaction J_k (used by the diagnostics).  Returns 0 or a failure code
    (details in p's header).

    A reel whose length is state (a spool law) needs its L'' from the spool's balance, which
    holds the exit tension (and, for a drum on a rigid hub, the hub's angular acceleration along
    the axle: docs/deployment.md 9.7), both affine in L'': solved exactly by evaluating the system
    at L'' = 0 and at one unit per spool reel, then once more at the solution (tether/reel_spool.py).
    """
    reels = int(p[H_NREEL]) > 0
    if not reels:
        return _evaluate(t, q, qd, att, p, acc, datt)
    ns = n_spools(p)
    if ns == 0:
        code = reel_update(t, att, p)  # lengths and masses that vary in time, before anything reads them
        if code != 0:
            return code
        return _evaluate(t, q, qd, att, p, acc, datt)
    idx = spool_indices(p)
    trial = np.zeros(ns)
    T0 = np.zeros(ns)
    Tk = np.zeros(ns)
    S = np.zeros((ns, ns))
    set_trial(p, idx, trial)
    code = reel_update(t, att, p)
    if code != 0:
        return code
    code = _evaluate(t, q, qd, att, p, acc, datt)
    if code != 0:
        return code
    record_tensions(p, idx, T0)
    for c in range(ns):
        trial[c] = 1.0
        set_trial(p, idx, trial)
        reel_update(t, att, p)
        code = _evaluate(t, q, qd, att, p, acc, datt)
        if code != 0:
            return code
        record_tensions(p, idx, Tk)
        for a in range(ns):
            S[a, c] = Tk[a] - T0[a]
        trial[c] = 0.0
    A, b = spool_system(p, idx, att, T0, S)
    if ns == 1:
        if A[0, 0] == 0.0:
            return fail(p, FAIL_SINGULAR, -1, t, 0.0)
        ldd = b / A[0, 0]
    else:
        ldd = np.linalg.solve(A, b)
    if not np.all(np.isfinite(ldd)):
        return fail(p, FAIL_NONFINITE, -1, t, 0.0)
    set_trial(p, idx, ldd)
    reel_update(t, att, p)
    code = _evaluate(t, q, qd, att, p, acc, datt)
    if code != 0:
        return code
    record_tensions(p, idx, Tk)
    spool_system(p, idx, att, T0, S)  # the torque, friction and command of the true state into the scratch
    write_spool_derivatives(p, idx, att, datt, ldd)
    return 0


@njit_hot(cache=True)
def _evaluate(t, q, qd, att, p, acc, datt):
    """One pass of the reaction solve at the lengths and masses the reels wrote (module docstring)."""
    reels = int(p[H_NREEL]) > 0
    code = forward(t, q, qd, att, p, True)
    if code != 0:
        return code
    nteth = int(p[H_NTETH])
    offt = int(p[H_OFF_TETH])
    offb = int(p[H_OFF_BODY])
    nbody = int(p[H_NBODY])
    bscr = int(p[H_OFF_BSCR])
    tscr = bscr + nbody * BS_SIZE
    jscr = int(p[H_OFF_SCR]) + int(p[H_NRODS]) * SR_SIZE  # joint scratch follows the rod scratch
    work = tscr + nteth * TS_SIZE + WS_SIZE * int(p[H_NWHEEL])  # 6x6 work area after the wheels'
    order = int(p[H_OFF_ORDER])
    roots = int(p[H_OFF_ROOTS])

    for b in range(nbody):
        body_setup(t, att, p, b, datt)
    if reels:
        reel_body_forces(p)

    # compliance up the tree, leaves first
    for i in range(nteth):
        k = int(p[order + i])
        tb = offt + k * TT_SIZE
        c = int(p[tb + TT_CHILD])
        g0 = int(p[tb + TT_ROD0])
        if c >= 0:
            det = body_compliance(p, c, work)
            if det == 0.0 or not math.isfinite(det):
                return fail(p, FAIL_SINGULAR, g0 + int(p[tb + TT_NRODS]) - 1, t, 0.0)
        code = tether_reduce(t, p, k)
        if code != 0:
            return code
        j0 = jscr + (g0 + k) * SJ_SIZE
        body_add_child(p, int(p[tb + TT_PARENT]), k, j0 + SJ_SINV, j0 + SJ_S)

    # each root's own system
    for i in range(int(p[H_NROOT])):
        b = int(p[roots + i])
        det = body_root_solve(p, b)
        if det == 0.0 or not math.isfinite(det):
            return fail(p, FAIL_SINGULAR, -1, t, det)
        A = bscr + b * BS_SIZE + BS_A
        qo = int(p[offb + b * BT_SIZE + BT_QOFF])
        acc[qo] = p[A]
        acc[qo + 1] = p[A + 1]
        acc[qo + 2] = p[A + 2]
        if not (math.isfinite(p[A]) and math.isfinite(p[A + 1]) and math.isfinite(p[A + 2])):
            return fail(p, FAIL_NONFINITE, -1, t, 0.0)

    # back substitution, roots to leaves
    for i in range(nteth - 1, -1, -1):
        k = int(p[order + i])
        tb = offt + k * TT_SIZE
        aax, aay, aaz = body_point_acceleration(p, int(p[tb + TT_PARENT]), tscr + k * TS_SIZE)
        code = tether_back_substitute(t, p, k, aax, aay, aaz, acc)
        if code != 0:
            return code
        c = int(p[tb + TT_CHILD])
        if c >= 0:
            n = int(p[tb + TT_NRODS])
            body_back_substitute(p, c, jscr + (int(p[tb + TT_ROD0]) + k + n) * SJ_SIZE + SJ_J)

    # every body's own derivatives
    if datt.shape[0] > 0:
        for b in range(nbody):
            if not body_derivatives(att, p, b, datt):
                return fail(p, FAIL_NONFINITE, -1, t, 0.0)
    return 0


@njit(cache=True)
def rod_forces(t, q, qd, p):
    """Forces of every rod into the scratch (point-mass scenes: no attitude block).  Returns a
    failure code (0 = fine)."""
    return forward(t, q, qd, q[:0], p, True)


@njit(cache=True)
def tip_position_velocity(q, qd, p, k):
    """Position and velocity of the far end B_n of tether k (point-mass scenes), eq. 23."""
    forward(0.0, q, qd, q[:0], p, False)
    ts = int(p[H_OFF_BSCR]) + int(p[H_NBODY]) * BS_SIZE + k * TS_SIZE + TS_B
    return p[ts], p[ts + 1], p[ts + 2], p[ts + 3], p[ts + 4], p[ts + 5]


@njit(cache=True)
def accelerations(t, q, qd, p, acc):
    """Accelerations of q_trans (roots' positions, rods' d_i) into ``acc``, for a scene without an
    attitude block (point masses).  See :func:`system_accelerations`."""
    return system_accelerations(t, q, qd, q[:0], p, acc, acc[:0])


@njit(cache=True)
def joint_states(q, qd, att, p, out, bodies, rot):
    """Every joint's position and velocity (out: rows per tether A_1, B_1, ..., B_n, in the joint
    scratch order), every body's centre of mass (bodies: r, v) and rotation matrix (rot, 9 per
    body; zero for point masses), from the one forest walk (:func:`forward`, rod.next_joint)."""
    forward(0.0, q, qd, att, p, False)
    offt = int(p[H_OFF_TETH])
    bscr = int(p[H_OFF_BSCR])
    nbody = int(p[H_NBODY])
    tscr = bscr + nbody * BS_SIZE
    offb = int(p[H_OFF_BODY])
    for k in range(int(p[H_NTETH])):
        tb = offt + k * TT_SIZE
        ts = tscr + k * TS_SIZE
        n = int(p[tb + TT_NRODS])
        g0 = int(p[tb + TT_ROD0])
        ax = p[ts + TS_A]
        ay = p[ts + TS_A + 1]
        az = p[ts + TS_A + 2]
        avx = p[ts + TS_A + 3]
        avy = p[ts + TS_A + 4]
        avz = p[ts + TS_A + 5]
        row = g0 + k
        out[row, 0] = ax
        out[row, 1] = ay
        out[row, 2] = az
        out[row, 3] = avx
        out[row, 4] = avy
        out[row, 5] = avz
        for g in range(g0, g0 + n):
            ax, ay, az, avx, avy, avz = next_joint(q, qd, g, ax, ay, az, avx, avy, avz)
            row += 1
            out[row, 0] = ax
            out[row, 1] = ay
            out[row, 2] = az
            out[row, 3] = avx
            out[row, 4] = avy
            out[row, 5] = avz
    for b in range(nbody):
        bs = bscr + b * BS_SIZE
        for j in range(6):
            bodies[b, j] = p[bs + BS_R + j]
        if p[offb + b * BT_SIZE + BT_AOFF] >= 0.0:  # a body with an attitude keeps its rotation
            for j in range(9):
                rot[b, j] = p[bs + BS_ROT + j]
