"""The Newton-matrix solver a model hands to RADAU5 (scipy's ``OdeSolver(fun, jac=...)`` shape).

RADAU5 knows one Newton matrix of its own: the forward-difference Jacobian with a dense LU
(:mod:`.radau5.dense`), which works for any rhs and costs O(n^2) rhs work and O(n^3) algebra per
factorisation.  A model whose Jacobian has structure supplies a :class:`NewtonSolver` instead,
and the caller passes it to :func:`tetherlab.integrators.integrate` as ``newton=``; the
integrators import nothing of any model.  A structured solver covers the second-order block
y[:2 m1] = [q, v] (Hairer's M1 reduction: (g I - J) z = b with z_q = (b_q + z_v)/g); any
first-order rest w of the state is bordered onto it by RADAU5 itself, by finite differences and a
Schur complement (:mod:`.radau5.border`, docs/integrators.md section 13).

The solver's five functions are numba cfuncs with the fixed signatures below, for the same
reason as the rhs (tetherlab/_jit.py): a cfunc is a first-class function of a fixed type, so the
compiled step loop calls it through a plain pointer (measured: no slower than a direct call) and
the loop stays in the disk cache, one compilation for every model and for the dense path.  Each
takes the model's parameter block ``p`` and the solver's own work arrays (allocated in Python by
``NewtonSolver.arrays``: the matrix data ``blk`` and the real and complex factors), as pointers;
the model reads their shapes from its own ``p``.  A shift g enters as (real, imaginary) parts
(the imaginary one 0 for the real system, whose arithmetic stays real).  Status 0 is success; a
nonzero status from ``form`` is treated as a failed Jacobian, from a factorisation as a singular
matrix (the step is halved, as Hairer's code does).

    form(t, y, p, m1, blk)                     the matrix data at the state y (the "Jacobian")
    factor_real(g_re, g_im, p, blk, fac)       factorise g I - J for the real shift
    factor_complex(g_re, g_im, p, blk, fac_c)  ... for the complex shift (complex128 factors)
    solve_real(g_re, g_im, p, blk, fac, m1, b)      b[:2 m1] <- (g I - J)^-1 b[:2 m1], in place
    solve_complex(g_re, g_im, p, blk, fac_c, m1, b) ... complex128 b
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numba
import numpy as np
from numba import types
from numba.core.ccallback import CFunc
from numba.extending import intrinsic

import tetherlab._jit  # noqa: F401  (the cache directory is set before any cfunc below)

_F = types.float64
_PF = types.CPointer(types.float64)
_PC = types.CPointer(types.complex128)
FORM_SIG = types.int64(_F, _PF, _PF, types.int64, _PF)
FACTOR_REAL_SIG = types.int64(_F, _F, _PF, _PF, _PF)
FACTOR_COMPLEX_SIG = types.int64(_F, _F, _PF, _PF, _PC)
SOLVE_REAL_SIG = types.int64(_F, _F, _PF, _PF, _PF, types.int64, _PF)
SOLVE_COMPLEX_SIG = types.int64(_F, _F, _PF, _PF, _PC, types.int64, _PC)
SIGNATURES = (FORM_SIG, FACTOR_REAL_SIG, FACTOR_COMPLEX_SIG, SOLVE_REAL_SIG, SOLVE_COMPLEX_SIG)


@intrinsic
def data_ptr(typingctx, arr):
    """Pointer to the first element of a C-contiguous float64 or complex128 array of any rank (no
    reference counting: the caller keeps the array alive, as for :func:`tetherlab._jit.ptr`)."""
    if not (isinstance(arr, types.Array) and arr.layout == "C"
            and arr.dtype in (types.float64, types.complex128)):  # fmt: skip
        return None
    sig = types.CPointer(arr.dtype)(arr)

    def codegen(context, builder, signature, args):
        return context.make_array(signature.args[0])(context, builder, value=args[0]).data

    return sig, codegen


@dataclass(frozen=True)
class NewtonSolver:
    """The Newton matrix of one run: its name (``stats["newton_matrix"]``), and for a structured
    one the five cfuncs of the module docstring and ``arrays()``, which returns fresh work arrays
    (blk, real factors, complex factors: 2-D, C-contiguous, float64/float64/complex128).

    ``refresh``: when a structured matrix is formed again, as RADAU5's ``_F_JACEVERY`` slot
    (radau5/constants.py): 0 Hairer's reuse rule (kept while the Newton rate stays <= THET), 1 on
    every step at its start, 2 on every step at the middle of the coming step; None RADAU5's
    default for structured matrices (``STRUCT_JAC_EVERY_STEP``).  A model whose matrix turns
    little within a step (no stiff direction rotating with the motion) keeps it for many steps."""

    name: str
    kernels: tuple | None = None
    arrays: Callable[[], tuple] | None = None
    refresh: int | None = None

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"NewtonSolver.name: expected a non-empty string; got {self.name!r}")
        if self.kernels is None:
            return
        ks = tuple(self.kernels)
        if len(ks) != 5 or not all(isinstance(k, CFunc) and k._sig == s for k, s in zip(ks, SIGNATURES)):
            got = [getattr(k, "_sig", type(k).__name__) for k in ks]
            raise ValueError(f"NewtonSolver.kernels: expected cfuncs (form, factor_real, factor_complex, "
                             f"solve_real, solve_complex) with the signatures {SIGNATURES}; got {got}")  # fmt: skip
        if not callable(self.arrays):
            raise ValueError("NewtonSolver.arrays: expected a callable returning (blk, fac_real, fac_complex)")
        if self.refresh is not None and self.refresh not in (0, 1, 2):
            raise ValueError(f"NewtonSolver.refresh: expected None, 0, 1 or 2; got {self.refresh!r}")

    @property
    def structured(self) -> bool:
        return self.kernels is not None


def dense(reason: str) -> NewtonSolver:
    """RADAU5's own Newton matrix; ``reason`` says why (shown as ``dense (reason)``)."""
    return NewtonSolver(f"dense ({reason})")


# The dense path still passes five functions of these types (the loop is compiled once for both
# paths); they are never called, since the workspace's structured flag is off.
@numba.cfunc(FORM_SIG, cache=True)
def _no_form(t, y, p, m1, blk):
    return 1


@numba.cfunc(FACTOR_REAL_SIG, cache=True)
def _no_factor_real(g_re, g_im, p, blk, fac):
    return 1


@numba.cfunc(FACTOR_COMPLEX_SIG, cache=True)
def _no_factor_complex(g_re, g_im, p, blk, fac):
    return 1


@numba.cfunc(SOLVE_REAL_SIG, cache=True)
def _no_solve_real(g_re, g_im, p, blk, fac, m1, b):
    return 1


@numba.cfunc(SOLVE_COMPLEX_SIG, cache=True)
def _no_solve_complex(g_re, g_im, p, blk, fac, m1, b):
    return 1


DENSE_KERNELS = (_no_form, _no_factor_real, _no_factor_complex, _no_solve_real, _no_solve_complex)


def dense_arrays():
    """Placeholder work arrays of the dense path (the structured ones are never touched)."""
    return (np.zeros((1, 1)), np.zeros((1, 1)), np.zeros((1, 1), dtype=np.complex128))
