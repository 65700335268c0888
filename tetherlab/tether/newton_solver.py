"""The tether model's Newton solver for RADAU5: which matrix a run uses, and its compiled entry points.

RADAU5 (tetherlab/integrators) knows nothing of tethers: it is handed a
:class:`tetherlab.integrators.linear_solver.NewtonSolver` by the caller (pipeline.py for every
scene run), as scipy's ``OdeSolver`` is handed a ``jac``.  :func:`choose` makes that choice for a
tether model's parameter block and state: the structured O(n) matrix of :mod:`.newton` (analytic
rod blocks, block-Thomas factorisation and solve; RADAU5 borders it with the rigid bodies'
attitude and wheel unknowns, docs/integrators.md sections 6 and 13) where
:func:`.newton.structure_supported` accepts the state, else RADAU5's own dense matrix with the
reason.  The five cfuncs below adapt :mod:`.newton`'s functions to the fixed signatures of
linear_solver.py (pointers in, the arrays rebuilt from the shapes the parameter block gives).
"""

from __future__ import annotations

import contextlib
import functools

from numba import carray, cfunc

from ..integrators.linear_solver import (
    FACTOR_COMPLEX_SIG,
    FACTOR_REAL_SIG,
    FORM_SIG,
    SOLVE_COMPLEX_SIG,
    SOLVE_REAL_SIG,
    NewtonSolver,
    dense,
)
from ..kernel.layout import H_LEN, H_NRIGID, H_NRODS, H_NROOT
from . import newton as _nw
from . import newton_inextensible as _ni

#: "auto" takes the structured Newton matrix from this many rods on
AUTO_STRUCTURED_MIN_RODS = 4
#: ... and with rigid bodies (the bordered matrix) from this many rods on
AUTO_BORDERED_MIN_RODS = 32
#: When RADAU5 forms the inextensible chain's matrix again (linear_solver.NewtonSolver.refresh):
#: Hairer's reuse rule.  Its stiffness is the lateral modes', which do not turn within a step as
#: an elastic tether's axial direction does (docs/integrators.md section 7), so a Jacobian holds
#: for many steps: on the hanging chain (mode start, 16 and 64 rods, rtol 1e-7 and 1e-8) 1 Jacobian
#: and 8-9 factorisations per run instead of 44-65 of each, the same steps, rhs calls (+0-3 %)
#: and no Newton failure (docs/inextensible.md section 8).
INEXTENSIBLE_REFRESH = 0

#: the request every :func:`choose` call takes while :func:`_forcing` is active (None: its own)
_FORCED: list = [None]


@contextlib.contextmanager
def _forcing(request):
    """Every run inside takes ``request`` ("dense", "structured", "auto") as its Newton matrix: the
    switch a test or bench uses to run one scene both ways (no scene key chooses the matrix)."""
    if request not in ("auto", "dense", "structured"):
        raise ValueError(f"newton: expected 'auto', 'dense' or 'structured'; got {request!r}")
    before = _FORCED[0]
    _FORCED[0] = request
    try:
        yield
    finally:
        _FORCED[0] = before


@cfunc(FORM_SIG, cache=True)
def _form(t, y_ptr, p_ptr, m1, blk_ptr):
    p = carray(p_ptr, (int(p_ptr[H_LEN]),))
    return _nw.form_blocks(t, carray(y_ptr, (2 * m1,)), p, m1, carray(blk_ptr, (int(p[H_NRODS]), _nw.BLK_SIZE)))


@cfunc(FACTOR_REAL_SIG, cache=True)
def _factor_real(g_re, g_im, p_ptr, blk_ptr, fac_ptr):
    p = carray(p_ptr, (int(p_ptr[H_LEN]),))
    nrods = int(p[H_NRODS])
    return _nw.factor(p, carray(blk_ptr, (nrods, _nw.BLK_SIZE)), g_re,
                      carray(fac_ptr, (nrods + int(p[H_NROOT]), _nw.FAC_SIZE)))  # fmt: skip


@cfunc(FACTOR_COMPLEX_SIG, cache=True)
def _factor_complex(g_re, g_im, p_ptr, blk_ptr, fac_ptr):
    p = carray(p_ptr, (int(p_ptr[H_LEN]),))
    nrods = int(p[H_NRODS])
    return _nw.factor(p, carray(blk_ptr, (nrods, _nw.BLK_SIZE)), complex(g_re, g_im),
                      carray(fac_ptr, (nrods + int(p[H_NROOT]), _nw.FAC_SIZE)))  # fmt: skip


@cfunc(SOLVE_REAL_SIG, cache=True)
def _solve_real(g_re, g_im, p_ptr, blk_ptr, fac_ptr, m1, b_ptr):
    p = carray(p_ptr, (int(p_ptr[H_LEN]),))
    nrods = int(p[H_NRODS])
    _nw.solve(p, carray(blk_ptr, (nrods, _nw.BLK_SIZE)), g_re,
              carray(fac_ptr, (nrods + int(p[H_NROOT]), _nw.FAC_SIZE)), m1, carray(b_ptr, (2 * m1,)))  # fmt: skip
    return 0


@cfunc(SOLVE_COMPLEX_SIG, cache=True)
def _solve_complex(g_re, g_im, p_ptr, blk_ptr, fac_ptr, m1, b_ptr):
    p = carray(p_ptr, (int(p_ptr[H_LEN]),))
    nrods = int(p[H_NRODS])
    _nw.solve(p, carray(blk_ptr, (nrods, _nw.BLK_SIZE)), complex(g_re, g_im),
              carray(fac_ptr, (nrods + int(p[H_NROOT]), _nw.FAC_SIZE)), m1, carray(b_ptr, (2 * m1,)))  # fmt: skip
    return 0


#: the structured solver's functions in linear_solver.py's order
KERNELS = (_form, _factor_real, _factor_complex, _solve_real, _solve_complex)


# the inextensible chain's (docs/inextensible.md section 8): the same signatures, its own arrays
@cfunc(FORM_SIG, cache=True)
def _form_inext(t, y_ptr, p_ptr, m1, blk_ptr):
    p = carray(p_ptr, (int(p_ptr[H_LEN]),))
    return _ni.form_blocks(t, carray(y_ptr, (2 * m1,)), p, m1, carray(blk_ptr, (int(p[H_NRODS]), _ni.BLK_SIZE)))


@cfunc(FACTOR_REAL_SIG, cache=True)
def _factor_real_inext(g_re, g_im, p_ptr, blk_ptr, fac_ptr):
    p = carray(p_ptr, (int(p_ptr[H_LEN]),))
    nrods = int(p[H_NRODS])
    return _ni.factor(p, carray(blk_ptr, (nrods, _ni.BLK_SIZE)), g_re, carray(fac_ptr, (nrods + 1, _ni.FAC_SIZE)))


@cfunc(FACTOR_COMPLEX_SIG, cache=True)
def _factor_complex_inext(g_re, g_im, p_ptr, blk_ptr, fac_ptr):
    p = carray(p_ptr, (int(p_ptr[H_LEN]),))
    nrods = int(p[H_NRODS])
    return _ni.factor(p, carray(blk_ptr, (nrods, _ni.BLK_SIZE)), complex(g_re, g_im),
                      carray(fac_ptr, (nrods + 1, _ni.FAC_SIZE)))  # fmt: skip


@cfunc(SOLVE_REAL_SIG, cache=True)
def _solve_real_inext(g_re, g_im, p_ptr, blk_ptr, fac_ptr, m1, b_ptr):
    p = carray(p_ptr, (int(p_ptr[H_LEN]),))
    nrods = int(p[H_NRODS])
    _ni.solve(p, carray(blk_ptr, (nrods, _ni.BLK_SIZE)), g_re, carray(fac_ptr, (nrods + 1, _ni.FAC_SIZE)), m1,
              carray(b_ptr, (2 * m1,)))  # fmt: skip
    return 0


@cfunc(SOLVE_COMPLEX_SIG, cache=True)
def _solve_complex_inext(g_re, g_im, p_ptr, blk_ptr, fac_ptr, m1, b_ptr):
    p = carray(p_ptr, (int(p_ptr[H_LEN]),))
    nrods = int(p[H_NRODS])
    _ni.solve(p, carray(blk_ptr, (nrods, _ni.BLK_SIZE)), complex(g_re, g_im),
              carray(fac_ptr, (nrods + 1, _ni.FAC_SIZE)), m1, carray(b_ptr, (2 * m1,)))  # fmt: skip
    return 0


KERNELS_INEXTENSIBLE = (_form_inext, _factor_real_inext, _factor_complex_inext, _solve_real_inext, _solve_complex_inext)


def choose(p, n_state, second_order, request="auto") -> NewtonSolver:
    """The Newton matrix for RADAU5 on a tether model with parameter block ``p`` and a state of
    ``n_state`` components (``second_order`` as for :func:`tetherlab.integrators.integrate`).

    ``request``: "structured" the O(n) matrix (ValueError with the reason when the state is not
    one it understands), "dense" RADAU5's own, "auto" the structured one whenever the state is one
    it understands and it pays (from AUTO_STRUCTURED_MIN_RODS rods, with rigid bodies from
    AUTO_BORDERED_MIN_RODS), else the dense one with the reason in its name.
    """
    if request not in ("auto", "dense", "structured"):
        raise ValueError(f"newton: expected 'auto', 'dense' or 'structured'; got {request!r}")
    if _FORCED[0] is not None:
        request = _FORCED[0]
    if request == "dense":
        return dense("requested")
    if _ni.has_inextensible(p):
        why = _ni.structure_supported(p, n_state, second_order)
        if not why:
            return NewtonSolver("structured", KERNELS_INEXTENSIBLE, functools.partial(_ni.workspace, p.copy()),
                                refresh=INEXTENSIBLE_REFRESH)  # fmt: skip
        if request == "structured":
            raise ValueError(f"newton: 'structured' is not available for this inextensible chain: {why}")
        return dense(f"inextensible chain: {why}")
    why = _nw.structure_supported(p, n_state, second_order)
    if not why and request == "auto" and int(p[H_NRIGID]) > 0 and int(p[H_NRODS]) < AUTO_BORDERED_MIN_RODS:
        # The bordered matrix (rigid bodies, docs/integrators.md section 13) pays for its ~4 rhs
        # calls per border unknown and step from a few tens of rods on: measured slower at 16 rods
        # on rigid-example (1.4x), within the timing noise at 24 (1.2x faster), 2x or more faster
        # at 32, 64 and 128 on it and on deorbit-ed-rigid.
        why = (f"rigid bodies with {int(p[H_NRODS])} rods, fewer than {AUTO_BORDERED_MIN_RODS}: the dense "
               "path is as cheap (newton='structured' forces the bordered matrix)")  # fmt: skip
    if not why and request == "auto" and int(p[H_NRODS]) < AUTO_STRUCTURED_MIN_RODS:
        # Below a few rods the dense path costs no more (measured at n = 2: 3.1 s dense against
        # 2.9 s structured on bench-libration) and keeps the full finite-difference Jacobian, whose
        # error filtering stays tolerance-proportional on an undamped stiff tether: hard-stiff
        # (n = 2, EA x 1000) converges at rate 1.58 per decade dense, 0.49 structured
        # (docs/integrators.md section 7).
        why = f"{int(p[H_NRODS])} rods, fewer than {AUTO_STRUCTURED_MIN_RODS}: the dense path is as cheap"
    if not why:
        return NewtonSolver("structured", KERNELS, functools.partial(_nw.workspace, p.copy()))
    if request == "structured":
        raise ValueError(f"newton: 'structured' is not available for this state: {why}")
    return dense(why)
