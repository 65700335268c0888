"""RADAU5's workspace: the arrays that carry a run between calls of :func:`.core.radau5_core`,
and the Newton solver's functions, in the order of radau5_core's arguments after ``fixed_step``."""

from __future__ import annotations

import numpy as np

from ..linear_solver import DENSE_KERNELS, NewtonSolver, dense_arrays
from .constants import (
    _B_ROWS,
    _F_FLOOR,
    _F_JACEVERY,
    _F_NIT,
    _F_THSTEP,
    _I_M1,
    _I_NBORDER,
    _I_STRUCT,
    FLOOR_GAIN,
    NIT,
    NIT_STRUCT,
    STRUCT_JAC_EVERY_STEP,
    THETA_STEP,
)

#: positions in the workspace tuple: the dense matrix's arrays (fjac, e1, e2, ip1, ip2), the
#: collocation polynomial, f0, the float and int scalars, the structured solver's arrays (blk,
#: real and complex factors), the border's arrays, then the solver's five cfuncs
WS_DENSE, WS_CONT, WS_F0, WS_FLOATS, WS_INTS, WS_SOLVER, WS_BORDER, WS_KERNELS = 0, 1, 2, 3, 4, 5, 6, 7


def radau5_workspace(n, m1=0, newton=None):
    """Arrays that carry RADAU5's state between calls of :func:`radau5_core`, followed by the
    Newton solver's five functions (radau5_core takes them all as positional arguments).

    ``newton``: a structured :class:`tetherlab.integrators.linear_solver.NewtonSolver` handed in by
    the model (for a tether model, tetherlab/tether/newton_solver.py: analytic rod blocks,
    block-Thomas factorisation and solve, O(n) per step); then no dense n x n array is allocated.
    With n > 2 m1 (a first-order rest w, e.g. rigid bodies' attitude and wheels) the structured
    solve is bordered by the n - 2 m1 unknowns w and completed by a Schur complement on them
    (docs/integrators.md section 13; :mod:`.border`).  None, or a dense NewtonSolver: the
    finite-difference Jacobian and dense LU.

    ``m1 > 0`` declares Hairer's special structure (RADAU5's M1 = M2): the first m1 components have
    the next m1 as their exact derivatives (y = [q, v, w], q' = v, as in Cowell's formulation; w:
    first-order components appended, e.g. attitude and wheels, n >= 2 m1).  Then
    J = [[0, I, 0], [A_q, A_v, A_w], [B_q, B_v, B_w]] and both Newton systems reduce to
    (n - m1) x (n - m1) ones (docs/integrators.md): for n = 2 m1 the LU work falls by 8x and each
    solve by about 4x.
    """
    if m1 < 0 or 2 * m1 > n:
        raise ValueError(f"m1: expected 0 <= m1 <= n/2 = {n / 2:g} (second-order structure); got {m1}")
    if newton is not None and not isinstance(newton, NewtonSolver):
        raise ValueError(f"newton: expected a NewtonSolver or None; got {type(newton).__name__}")
    structured = newton is not None and newton.structured
    if structured and m1 == 0:
        raise ValueError("m1: a structured Newton matrix needs the second-order structure (m1 > 0); got 0")
    nb = n - 2 * m1 if structured else 0  # border unknowns (docs/integrators.md section 13)
    ne = 1 if structured else n - m1
    nd = 1 if structured else n
    blk, sf1, sf2 = newton.arrays() if structured else dense_arrays()
    fs = np.zeros(12)  # float scalars
    is_ = np.zeros(10, dtype=np.int64)  # int scalars
    ws = (
        (np.zeros((nd, nd)),  # fjac
         np.zeros((ne, ne)),  # e1 (LU of U1/h - J, or of its reduced form)
         np.zeros((ne, ne), dtype=np.complex128),  # e2 (LU of (ALPH+iBETA)/h - J, or reduced)
         np.zeros(ne, dtype=np.int64),  # ip1
         np.zeros(ne, dtype=np.int64)),  # ip2
        np.zeros((4, n)),  # cont: y_new and the 3 coefficients of the collocation polynomial
        np.zeros(n),  # f0 = f(t, y)
        fs,
        is_,
        (blk, sf1, sf2),  # structured: the solver's matrix data, real and complex factors
        # the border (docs/integrators.md section 13), one tuple: a kernel call of more than 30
        # arguments is compiled by CPython as f(*args), and numba warns on the tuple of a
        # first-class function that this builds
        (np.zeros((n, max(nb, 1))),  # border: finite-difference columns of J for the w unknowns
        np.zeros((max(nb, 1), n)),  # border: z^j = S_t(0, A_w e_j), real shift
        np.zeros((max(nb, 1), n), dtype=np.complex128),  # border: the same, complex shift
        np.zeros((max(nb, 1), max(nb, 1))),  # border: LU of Sigma, real
        np.zeros((max(nb, 1), max(nb, 1)), dtype=np.complex128),  # border: LU of Sigma, complex
        np.zeros(max(nb, 1), dtype=np.int64),  # border: pivots, real
        np.zeros(max(nb, 1), dtype=np.int64),  # border: pivots, complex
        np.zeros((_B_ROWS, n))),  # border: base state, f there, scratch (rows _B_*)
    ) + tuple(newton.kernels if structured else DENSE_KERNELS)  # fmt: skip
    is_[_I_M1] = m1
    is_[_I_STRUCT] = 1 if structured else 0
    is_[_I_NBORDER] = nb
    fs[_F_THSTEP] = THETA_STEP
    fs[_F_NIT] = NIT_STRUCT if structured else NIT
    if structured:
        fs[_F_JACEVERY] = float(STRUCT_JAC_EVERY_STEP if newton.refresh is None else newton.refresh)
    fs[_F_FLOOR] = FLOOR_GAIN
    return ws
