"""Diagnostics computed from the state at every output time (compiled, one pass over the rows).

Per row: total linear momentum P, angular momentum H about the central body's centre, kinetic
energy, potential energy of the conservative effects named by the scene (the same quadrature as
the forces, so it is the exact potential of the discretised model), elastic energy of the rods
(1/2 EA L_u eps^2 per rod: the energy of the elastic bar the TMED stands for), and per rod the
strain, the axial force of eq. 1 and the joint reactions of the solve.  Libration angles are
computed from the tether's end points in the centre of mass's orbital frame (docs/model.md, 7).

The energy the paper's model conserves, if any, is discussed with numbers in docs/model.md.
"""

from __future__ import annotations

import math

import numpy as np

from ._jit import njit
from .bodies.parts import body_share
from .kernel.layout import (
    BS_SIZE,
    BS_U,
    BT_M,
    BT_SIZE,
    H_NBODY,
    H_NQT,
    H_NRODS,
    H_NTETH,
    H_NWHEEL,
    H_OFF_BODY,
    H_OFF_BSCR,
    H_OFF_SCR,
    H_OFF_TETH,
    H_MUTANT,
    MUT_NO_ELASTIC_E,
    SJ_J,
    SJ_SIZE,
    SR_EPS,
    SR_FE,
    SR_SIZE,
    TS_A,
    TS_SIZE,
    TT_NRODS,
    TT_ROD0,
    TT_SIZE,
    WS_SAT,
    WS_SIZE,
    WS_TAU,
)
from .kernel.shares import SH_E, SH_KE, SH_SIZE, SH_VE, SH_VG
from .tether.parts import tether_share
from .tether.solve import system_accelerations

# columns of the global diagnostics array: the parts' share vector (kernel/shares.py)
G_PX, G_PY, G_PZ, G_HX, G_HY, G_HZ, G_KE, G_VG, G_VE, G_E, G_KROT = range(11)
G_NCOL = SH_SIZE


@njit(cache=True)
def row_shares(t, q, qd, att, p, sh, elastic):
    """Add every part's energy and momentum share at one state (the scratch filled by a
    right-hand side evaluation) to ``sh`` (kernel/shares.py): the bodies in kernel order, then the
    tethers; then SH_E = KE + VG + VE."""
    nbody = int(p[H_NBODY])
    tscr = int(p[H_OFF_BSCR]) + nbody * BS_SIZE
    for b in range(nbody):
        body_share(t, att, p, b, sh)
    for k in range(int(p[H_NTETH])):
        ts_ = tscr + k * TS_SIZE
        tether_share(
            t, q, qd, p, k, elastic,
            p[ts_ + TS_A], p[ts_ + TS_A + 1], p[ts_ + TS_A + 2], p[ts_ + TS_A + 3], p[ts_ + TS_A + 4], p[ts_ + TS_A + 5],
            sh,
        )
    sh[SH_E] = sh[SH_KE] + sh[SH_VG] + sh[SH_VE]


@njit(cache=True)
def part_shares(t, q, qd, att, p, out, elastic):
    """Each part's share on its own: out[b] for body b, out[nbody + k] for tether k (rows of
    SH_SIZE, zeroed here).  The diagnostics add the same shares in this order."""
    nbody = int(p[H_NBODY])
    tscr = int(p[H_OFF_BSCR]) + nbody * BS_SIZE
    for i in range(out.shape[0]):
        for j in range(SH_SIZE):
            out[i, j] = 0.0
    for b in range(nbody):
        body_share(t, att, p, b, out[b])
    for k in range(int(p[H_NTETH])):
        ts_ = tscr + k * TS_SIZE
        tether_share(
            t, q, qd, p, k, elastic,
            p[ts_ + TS_A], p[ts_ + TS_A + 1], p[ts_ + TS_A + 2], p[ts_ + TS_A + 3], p[ts_ + TS_A + 4], p[ts_ + TS_A + 5],
            out[nbody + k],
        )


@njit(cache=True)
def evaluate_rows(ts, Y, p, glob, rods, joints, acc, datt, ctrl, wheels):
    """Fill ``glob`` (rows x G_NCOL), ``rods`` (rows x nrods x 2: strain, axial force),
    ``joints`` (rows x njoints x 3: reaction vectors J_k), ``ctrl`` (rows x nbody x 3: commanded
    control torque, body axes) and ``wheels`` (rows x nwheel x 2: motor torque, saturation flag)
    for every state row of Y.  The global columns are the sum of every part's share
    (bodies/point.py, bodies/rigid_body.py with its wheels, tether/rod.py per rod): rigid bodies
    add J omega + R h_w to the angular momentum and 1/2 w.J_s w + sum h_k^2/(2 I_k) to the kinetic
    energy (docs/model.md 12; also in G_KROT), the gravity-gradient (MacCullagh) term to the
    potential.

    Returns the index of the first row whose right-hand side failed, or -1.
    """
    nrows = Y.shape[0]
    h = int(p[H_NQT])
    nrods = int(p[H_NRODS])
    nteth = int(p[H_NTETH])
    nbody = int(p[H_NBODY])
    offt = int(p[H_OFF_TETH])
    offb = int(p[H_OFF_BODY])
    bscr = int(p[H_OFF_BSCR])
    wscr = bscr + nbody * BS_SIZE + nteth * TS_SIZE
    nwh = int(p[H_NWHEEL])
    scr = int(p[H_OFF_SCR])
    jscr = scr + nrods * SR_SIZE
    elastic = p[H_MUTANT] != MUT_NO_ELASTIC_E  # always true but in tetherlab.mutants' control
    for row in range(nrows):
        t = ts[row]
        q = Y[row, :h]
        qd = Y[row, h : 2 * h]
        att = Y[row, 2 * h :]
        code = system_accelerations(t, q, qd, att, p, acc, datt)
        if code != 0:
            return row
        sh = glob[row]
        for j in range(G_NCOL):
            sh[j] = 0.0
        row_shares(t, q, qd, att, p, sh, elastic)
        for b in range(nbody):
            if p[offb + b * BT_SIZE + BT_M] > 0.0:
                for j in range(3):
                    ctrl[row, b, j] = p[bscr + b * BS_SIZE + BS_U + j]
        for k in range(nwh):
            wheels[row, k, 0] = p[wscr + k * WS_SIZE + WS_TAU]
            wheels[row, k, 1] = p[wscr + k * WS_SIZE + WS_SAT]
        for k in range(nteth):
            tb = offt + k * TT_SIZE
            nk = int(p[tb + TT_NRODS])
            g0 = int(p[tb + TT_ROD0])
            for g in range(g0, g0 + nk):
                rods[row, g, 0] = p[scr + g * SR_SIZE + SR_EPS]
                rods[row, g, 1] = p[scr + g * SR_SIZE + SR_FE]
            for j in range(nk + 1):
                jb = jscr + (g0 + k + j) * SJ_SIZE + SJ_J
                joints[row, g0 + k + j, 0] = p[jb]
                joints[row, g0 + k + j, 1] = p[jb + 1]
                joints[row, g0 + k + j, 2] = p[jb + 2]
    return -1


def compute(model, ts: np.ndarray, Y: np.ndarray, spans=None) -> dict:
    """Diagnostics for every row of Y (outputs of a run).  Returns numpy arrays in a dict.

    ``spans`` (pipeline.branch_spans): the wheel limits' branches the run held between its located
    events, [(t_from, [(wheel, field, value), ...]), ...]; each row is evaluated with the branches
    of the last span starting before it, so the diagnostics show the torques that were integrated
    (None: each limit decided at each row)."""
    from .model.params import ParamView

    p = model.fresh_params()
    nrows = Y.shape[0]
    nr = model.n_rods
    nj = nr + len(model.tethers)
    nb = len(model.bodies)
    nw = int(p[H_NWHEEL])
    glob = np.full((nrows, G_NCOL), np.nan)
    rods = np.full((nrows, nr, 2), np.nan)
    joints = np.full((nrows, nj, 3), np.nan)
    ctrl = np.full((nrows, nb, 3), np.nan)
    wheels = np.full((nrows, nw, 2), np.nan)
    lay = model.state
    acc = np.zeros(lay.n_qt)
    datt = np.zeros(lay.first_order.stop - lay.first_order.start)
    ts = np.ascontiguousarray(ts, float)
    Y = np.ascontiguousarray(Y, float)
    if nrows and spans is None:
        evaluate_rows(ts, Y, p, glob, rods, joints, acc, datt, ctrl, wheels)
    elif nrows:
        view = ParamView(p)
        for i, (t_from, locks) in enumerate(spans):
            lo = 0 if i == 0 else int(np.searchsorted(ts, t_from, side="right"))
            hi = nrows if i + 1 == len(spans) else int(np.searchsorted(ts, spans[i + 1][0], side="right"))
            if hi <= lo:
                continue
            for j, field, value in locks:
                setattr(view.wheel(j), field, value)
            evaluate_rows(ts[lo:hi], Y[lo:hi], p, glob[lo:hi], rods[lo:hi], joints[lo:hi], acc, datt, ctrl[lo:hi],
                          wheels[lo:hi])  # fmt: skip
    return {"global": glob, "rods": rods, "joints": joints, "control": ctrl, "wheels": wheels}


def shares(model, t: float, y: np.ndarray) -> np.ndarray:
    """Each part's own energy and momentum share at the state y: rows of G_NCOL (columns as the
    global diagnostics, G_E left 0), one per body in kernel order then one per tether.  Their sum
    is the diagnostics' global row."""
    p = model.fresh_params()
    lay = model.state
    y = np.ascontiguousarray(y, float)
    acc = np.zeros(lay.n_qt)
    datt = np.zeros(lay.first_order.stop - lay.first_order.start)
    q, qd, att = y[lay.q], y[lay.qd], y[lay.first_order]
    code = system_accelerations(float(t), q, qd, att, p, acc, datt)
    if code != 0:
        raise ValueError(f"y: the right-hand side failed at this state (failure code {code})")
    out = np.zeros((len(model.bodies) + len(model.tethers), G_NCOL))
    part_shares(float(t), q, qd, att, p, out, p[H_MUTANT] != MUT_NO_ELASTIC_E)
    return out


def has_orbital_frame(model) -> bool:
    """Whether a run's outputs have an orbital frame: only about a central body (central gravity
    among the effects, as the orbital elements; docs/model.md 7).  In free space the centre of
    mass rests or drifts at an arbitrary place (often the origin, to round-off): a frame built
    from it would turn with its round-off, so the angles measured in it would be noise."""
    return "central_gravity" in getattr(model, "effect_names", ())


def orbital_frame(r: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rows: x radial (outward), y = z x x (along-track for a circular orbit), z along r x v.
    Where (r, v) has no frame (r = 0, or r x v = 0: at the origin, or moving radially) its rows
    are NaN, by design and without a floating-point warning; elsewhere the same bits as the plain
    quotients (numpy's ``divide`` with ``where`` divides the same numbers)."""
    r = np.asarray(r, float)
    v = np.asarray(v, float)
    rn = np.linalg.norm(r, axis=-1, keepdims=True)
    hvec = np.cross(r, v)
    hn = np.linalg.norm(hvec, axis=-1, keepdims=True)
    ok = (rn > 0) & (hn > 0)
    x = np.divide(r, rn, out=np.full(r.shape, np.nan), where=ok)
    z = np.divide(hvec, hn, out=np.full(hvec.shape, np.nan), where=ok)
    y = np.cross(z, x)
    return np.stack([x, y, z], axis=-2)


def libration_angles(r_cm, v_cm, r_from, r_to, side: float = 1.0):
    """In-plane theta and out-of-plane phi (rad) of the line from `from` to `to` (docs/model.md 7).

    With e = (r_to - r_from)/|.| in the orbital frame (x radial, y along-track, z normal):
    e = side * (cos phi cos theta, cos phi sin theta, sin phi); side = +1 when the `to` body
    is above (radially outward of) the `from` body at theta = phi = 0, -1 when below.
    """
    frame = orbital_frame(np.atleast_2d(r_cm), np.atleast_2d(v_cm))
    e = np.atleast_2d(r_to - r_from)
    e = side * e / np.linalg.norm(e, axis=-1, keepdims=True)
    ex = np.einsum("nij,nj->ni", frame, e)
    theta = np.arctan2(ex[:, 1], ex[:, 0])
    phi = np.arcsin(np.clip(ex[:, 2], -1.0, 1.0))
    return theta, phi


def direction_from_angles(r, v, theta, phi, side: float = 1.0) -> np.ndarray:
    """Unit vector (inertial) for in-plane theta, out-of-plane phi in the orbital frame of (r, v)."""
    frame = orbital_frame(np.atleast_2d(r), np.atleast_2d(v))[0]
    e = side * np.array([math.cos(phi) * math.cos(theta), math.cos(phi) * math.sin(theta), math.sin(phi)])
    return frame.T @ e


def zero_crossing_frequency(t: np.ndarray, x: np.ndarray, smooth_s: float = 0.0) -> float:
    """Angular frequency (rad/s) from the mean spacing of the zero crossings of x(t).

    ``smooth_s > 0``: x is first convolved with a Gaussian of standard deviation ``smooth_s``
    seconds (t must be uniformly spaced; the 4 sigma at either end, where the kernel would run off
    the data, are dropped).  That removes oscillations much faster than the one measured, which
    otherwise shift every crossing a little and, through the first and last crossings, the mean
    spacing.  A symmetric kernel moves no crossing of a signal that is odd about its crossings
    (a libration: conservative and time-reversible), so the frequency is not biased by it; the
    libration period of studies/convergence.toml needs it (the lateral modes riding on theta shift
    crossings by ~1e-5 s, more than the period changes from n = 8 on).
    """
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    if smooth_s < 0 or not math.isfinite(smooth_s):
        raise ValueError(f"smooth_s: expected a non-negative number of seconds, got {smooth_s!r}")
    if smooth_s > 0:
        dt = (t[-1] - t[0]) / (len(t) - 1)
        if not np.allclose(np.diff(t), dt, rtol=1e-9, atol=0.0):
            raise ValueError("t: smoothing needs uniformly spaced samples (an [output] count or step)")
        half = int(math.ceil(4.0 * smooth_s / dt))
        if 2 * half + 1 > len(t):
            raise ValueError(f"smooth_s: {smooth_s:g} s needs a record longer than 8 sigma, got {t[-1] - t[0]:g} s")
        kernel = np.exp(-0.5 * (np.arange(-half, half + 1) * dt / smooth_s) ** 2)
        x = np.convolve(x, kernel / kernel.sum(), mode="valid")
        t = t[half : len(t) - half]
    s = np.sign(x)
    idx = np.where(s[:-1] * s[1:] < 0)[0]
    if len(idx) < 3:
        raise ValueError(f"only {len(idx)} zero crossings: run longer")
    tz = t[idx] - x[idx] * (t[idx + 1] - t[idx]) / (x[idx + 1] - x[idx])
    return math.pi / ((tz[-1] - tz[0]) / (len(tz) - 1))


def internal_angular_momentum_scale(model, y) -> float:
    """sum m |(r - r_cm) x (v - v_cm)| over the root, the tips and every TMED mass (m/2 at
    r_G -/+ d): the size of the system's own angular momentum about its centre of mass.

    The total angular momentum about the attracting centre is almost all orbital, so a relative
    change of it cannot see an error in the tether's own rotation; this is the scale to measure
    that against (references/gates.toml [angular_momentum_internal]).
    """
    from .system import center_of_mass, point_positions

    pts = point_positions(model, y)
    rc, vc = center_of_mass(model, y)
    mr = model.rod_masses()
    items = [
        (b.mass_kg, pts["bodies"][i, :3], pts["bodies"][i, 3:])
        for i, b in enumerate(model.bodies)
        if b.name and b.mass_kg > 0 and not b.fixed
    ]
    spin = 0.0  # rigid bodies: |J_s omega + h_w| (their own angular momentum about G)
    for b, off in model.rigid_index.items():
        rs = model.bodies[b].rigid
        w = np.asarray(y[off + 4 : off + 7], float)
        js = np.asarray(rs.inertia_kg_m2, float) - sum(
            (wh.inertia_kg_m2 * np.outer(wh.axis, wh.axis) for wh in rs.wheels), np.zeros((3, 3))
        )
        hw = sum((np.asarray(wh.axis) * y[model.wheel_index[(b, wh.name)]] for wh in rs.wheels), np.zeros(3))
        spin += float(np.linalg.norm(js @ w + hw))
    # the two TMED masses of every rod, in the order rod 1 (-, +), rod 2 (-, +), ...: the cross
    # products in one call (elementwise, so the same numbers), then each norm and the sum in order
    sign = np.tile([-1.0, 1.0], model.n_rods)[:, None]
    r_all = np.vstack([np.zeros((0, 3))] + [r for _, r, _ in items] + [np.repeat(pts["rG"], 2, axis=0) + sign * np.repeat(pts["d"], 2, axis=0)])
    v_all = np.vstack([np.zeros((0, 3))] + [v for _, _, v in items] + [np.repeat(pts["vG"], 2, axis=0) + sign * np.repeat(pts["dd"], 2, axis=0)])
    masses = [m for m, _, _ in items] + list(np.repeat(0.5 * mr, 2))
    arms = np.cross(r_all - rc, v_all - vc)
    return spin + float(sum(m * np.linalg.norm(a) for m, a in zip(masses, arms)))
