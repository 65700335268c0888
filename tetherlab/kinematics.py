"""Every point of the model at every output row, in one compiled pass.

:func:`tetherlab.system.point_positions` walks the forest for one state (eq. 23, the compiled
``tether.solve.joint_states``).  A run's outputs need that walk at every row: called from Python
once per row it cost more than the integration of a short run (about 0.1 ms a row in dispatch,
a fresh parameter block and the dictionary it returns).  Here the same kernel runs over all rows
inside one compiled loop, each row from a fresh copy of the parameter block exactly as the
one-state function does, so every number is the one ``point_positions`` gives, bit for bit.
"""

from __future__ import annotations

import math

import numpy as np

from ._jit import njit
from .tether.solve import joint_states

SQ3 = math.sqrt(3.0)


@njit(cache=True)
def _walk_rows(Q, QD, ATT, p0, out, bodies, rot):
    p = p0.copy()
    for i in range(Q.shape[0]):
        p[:] = p0  # every row from the block as built, as point_positions' fresh copy
        joint_states(Q[i], QD[i], ATT[i], p, out[i], bodies[i], rot[i])


def point_rows(model, Y: np.ndarray) -> dict:
    """For every row of Y (Cowell states): ``joints`` (rows, joints, 6: position and velocity of
    A_1, B_1 ... B_n of every tether, in the joint scratch order), ``bodies`` (rows, bodies, 6),
    ``rotations`` (rows, bodies, 3, 3), ``rG``/``vG`` (rows, rods, 3: the rod centres, eq. 23)."""
    lay = model.state
    Y = np.asarray(Y, float)
    if Y.ndim != 2 or Y.shape[1] != lay.size:
        raise ValueError(f"Y: expected rows of {lay.size} state components, got shape {Y.shape}")
    nrows = Y.shape[0]
    nr = model.n_rods
    nj = nr + len(model.tethers)
    nb = len(model.bodies)
    Q = np.ascontiguousarray(Y[:, lay.q])
    QD = np.ascontiguousarray(Y[:, lay.qd])
    ATT = np.ascontiguousarray(Y[:, lay.first_order])
    joints = np.zeros((nrows, nj, 6))
    bodies = np.zeros((nrows, nb, 6))
    rot = np.zeros((nrows, nb, 9))
    if nrows:
        _walk_rows(Q, QD, ATT, np.ascontiguousarray(model.p), joints, bodies, rot)
    # q and q' start where y and its q' half start, so the rods' block slices them both
    d = Q[:, lay.rods_d].reshape(nrows, nr, 3)
    dd = QD[:, lay.rods_d].reshape(nrows, nr, 3)
    rG = np.zeros((nrows, nr, 3))
    vG = np.zeros((nrows, nr, 3))
    for k, sl in enumerate(model.rod_slices):
        block = joints[:, sl.start + k : sl.stop + k + 1]
        rG[:, sl.start : sl.stop] = block[:, :-1, :3] + SQ3 * d[:, sl.start : sl.stop]
        vG[:, sl.start : sl.stop] = block[:, :-1, 3:] + SQ3 * dd[:, sl.start : sl.stop]
    return {"joints": joints, "bodies": bodies, "rotations": rot.reshape(nrows, nb, 3, 3), "rG": rG, "vG": vG}


def center_of_mass_rows(model, pts: dict) -> tuple[np.ndarray, np.ndarray]:
    """(r, v) of the centre of mass at every row of :func:`point_rows`' ``pts``: the sums of
    :func:`tetherlab.system.center_of_mass`, term for term in its order (so bit for bit)."""
    m = model.rod_masses()
    bodies = pts["bodies"]
    nrows = bodies.shape[0]
    M = 0.0
    r = np.zeros((nrows, 3))
    v = np.zeros((nrows, 3))
    for b, body in enumerate(model.bodies):
        if body.fixed or not body.mass_kg > 0 or not body.name:
            continue
        M += body.mass_kg
        r += body.mass_kg * bodies[:, b, :3]
        v += body.mass_kg * bodies[:, b, 3:]
    M += m.sum()
    rG, vG = pts["rG"], pts["vG"]
    for i in range(nrows):  # one product a row: the same reduction as the one-state function's
        r[i] += m @ rG[i]
        v[i] += m @ vG[i]
    return r / M, v / M
