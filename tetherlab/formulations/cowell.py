"""Cowell's method: the Cartesian equations of motion integrated directly (paper section 2.6).

State layout (SI): y = [q, q', attitude, wheels] with q = q_trans = (r0, d_1, ..., d_N, other
roots): the root bodies' inertial positions and the half-separation vector of every rod
(docs/model.md, section 4); the first-order attitude and wheel blocks of rigid bodies follow
(kernel/layout.py, the state-layout descriptor H_NQT, H_OFF_ATT; docs/model.md section 12).  Relative coordinates d_i
rather than the absolute positions of the TMED masses keep full precision in the tether's shape
when the orbit radius is thousands of times the rod length.
"""

from __future__ import annotations

from numba import carray

from .._jit import rhs_cfunc
from ..kernel.layout import H_LEN, H_NQT, H_NSTATE
from ..tether.solve import system_accelerations


@rhs_cfunc
def cowell_rhs(t, y_ptr, dy_ptr, p_ptr):
    p = carray(p_ptr, (int(p_ptr[H_LEN]),))
    n = int(p[H_NSTATE])
    y = carray(y_ptr, (n,))
    dy = carray(dy_ptr, (n,))
    h = int(p[H_NQT])
    for i in range(h):
        dy[i] = y[h + i]
    return system_accelerations(t, y[:h], y[h : 2 * h], y[2 * h :], p, dy[h : 2 * h], dy[2 * h :])


def cowell_rhs_py(model, y, t=0.0):
    """The same right-hand side called once from Python (set-up code only, never a loop)."""
    import ctypes

    import numpy as np

    P = ctypes.POINTER(ctypes.c_double)
    p = model.fresh_params()
    y = np.ascontiguousarray(y, dtype=float)
    dy = np.empty_like(y)
    status = cowell_rhs.ctypes(t, y.ctypes.data_as(P), dy.ctypes.data_as(P), p.ctypes.data_as(P))
    if status != 0:
        raise FloatingPointError(f"right-hand side failed with status {status}")
    return dy
