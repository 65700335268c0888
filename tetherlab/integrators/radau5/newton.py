"""The linear solves of RADAU5's simplified Newton iteration, and the iteration's round-off floor.

:func:`_lin` solves (g I - J) x = b with whichever Newton matrix the run was handed: the dense one
of :mod:`.dense`, or a model's structured solver (:mod:`tetherlab.integrators.linear_solver`)
bordered by :mod:`.border`.  :func:`_increment_noise` measures the floor below which the
iteration's increments are round-off (docs/integrators.md section 12; used by the step loop with
FLOOR_GAIN).
"""

from __future__ import annotations

import numpy as np

from tetherlab._jit import njit, ptr

from ..common import EPS, ST_NRHS, scaled_sq
from ..linear_solver import data_ptr
from .border import _border_solve
from .dense import _solve


@njit(cache=True)
def _lin(struct, e, ip, fjac, g, m1, b, p, blk, sfac, solve, rhs, nb, bz, bs, bp, bw, tb, iu, stats):
    """(g I - J) x = b in place: the handed-in structured solve ``solve`` (the real or the complex
    cfunc of linear_solver.py, matching b; bordered when nb > 0), or the dense factors' one.
    ``iu``: 0.0 for the real system, 1j for the complex one (typed like b)."""
    if struct:
        solve(g.real, g.imag, ptr(p), data_ptr(blk), data_ptr(sfac), m1, data_ptr(b))
        if nb > 0:
            _border_solve(rhs, tb, p, m1, nb, b, bz, bs, bp, bw, iu, stats)
    else:
        _solve(e, ip, fjac, g, m1, b)


@njit(cache=True)
def _increment_noise(rhs, t, y, f0, p, scal, tmp, out, struct, e1, ip1, fjac, fac1, m1, blk, sfac1, solve_r, nb,
                     bz1, bs1, bp1, bw, tb, stats):  # fmt: skip
    """RMS (tolerance units) of the change of the real Newton system's solution when y moves by
    one rounding unit: the floor below which the increments of the simplified Newton iteration
    are round-off (docs/integrators.md section 12).  One rhs call and one linear solve."""
    n = y.size
    for i in range(n):
        # a fixed +-1 pattern, so the floor is reproducible (restarts stay bit for bit)
        sgn = 1.0 if (i * 40503) % 7 < 4 else -1.0
        tmp[i] = y[i] + sgn * EPS * abs(y[i])
    st = rhs(t, ptr(tmp), ptr(out), ptr(p))
    stats[ST_NRHS] += 1
    if st != 0:
        return 0.0
    for i in range(n):
        out[i] -= f0[i]
    _lin(struct, e1, ip1, fjac, fac1, m1, out, p, blk, sfac1, solve_r, rhs, nb, bz1, bs1, bp1, bw, tb, 0.0, stats)
    acc = 0.0
    for i in range(n):
        acc += scaled_sq(out[i], scal[i])
    r = np.sqrt(acc / n)
    return r if np.isfinite(r) else 0.0

