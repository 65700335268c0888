"""RADAU5: implicit Runge-Kutta Radau IIA of order 5 for stiff problems, compiled.

Reference: E. Hairer, G. Wanner, "Solving Ordinary Differential Equations II", 2nd ed., Springer
1996, section IV.8, and Hairer's Fortran code RADAU5 (routine RADCOR, version of 2002), followed
closely so the kernel can be read against it; Fortran names are kept for the scalars.

* Simplified Newton iteration on the stage increments Z, transformed with T so the 3n x 3n system
  splits into one real n x n system (U1/h - J) and one complex one ((ALPH + i BETA)/h - J).
* Jacobian by forward differences of the rhs, column increment sqrt(eps*max(1e-5, |y_j|)), kept
  across steps while the Newton contraction rate theta stays <= THET (Hairer's reuse rule); the
  LU factors are kept while h changes by less than the factor QUOT1..QUOT2.
* Error estimate of Hairer (IV.8, (8.19)-(8.20)) including the extra solve with f(t, y + err) on
  the first step and after a rejection ("stiff" filtering), Gustafsson's predictive controller.
* Dense output: the collocation polynomial (CONTR5).
* Tolerances are transformed as in RADAU5's driver, rtol' = 0.1 rtol^(2/3) and
  atol' = atol rtol'/rtol: the estimate is of an embedded order-3 solution, which overstates the
  error of the order-5 result; Hairer calibrated this map so the global error tracks rtol.

The Newton matrix is the dense one (finite-difference Jacobian, LU written here because numba
offers only ``np.linalg.solve``, which refactorises every call), or a structured one handed in by
the model as a :class:`tetherlab.integrators.linear_solver.NewtonSolver` (five cfuncs; the
integrators import nothing of any model), bordered here by any first-order rest of the state.

Two entry points: :func:`radau5_run` has the common kernel ABI and starts fresh on every call.
:func:`radau5_core` additionally takes a workspace (:func:`radau5_workspace`) holding the Jacobian,
LU factors, the last collocation polynomial, the controller state and the Newton solver's
functions, and can resume from it: the driver uses that, so splitting a run into calls changes
neither the steps nor the result.

Files, one concept each: ``constants`` (tableau scalars, Hairer's defaults, tuned values,
workspace slots), ``workspace``, ``dense`` (finite-difference Jacobian, LU, reduced systems),
``border`` (the Schur complement on the first-order unknowns), ``newton`` (the Newton iteration's
linear solve and its round-off floor), ``controller`` (step ratios: error estimate, Gustafsson,
Newton-rate cap, slow Newton), ``core`` (the step loop: the Newton iteration itself, the error
estimate, events, dense output; kept in one function because its pieces share some thirty arrays
and the handed-in cfuncs, and numba warns on a tuple holding a cfunc, which a compiled call of
more than 30 arguments builds).
"""

from __future__ import annotations

from .border import _border_apply, _border_dir, _border_factor, _border_jacobian, _border_solve
from .constants import *  # noqa: F401,F403  (the public constants: NIT, THET, FLOOR_GAIN, ...)
from .constants import (  # noqa: F401  (workspace slots, read by tests and the driver's callers)
    _B_F,
    _B_FT,
    _B_OI,
    _B_OR,
    _B_ROWS,
    _B_XI,
    _B_XR,
    _B_Y,
    _B_YT,
    _F_ERRACC,
    _F_FACCON,
    _F_FLOOR,
    _F_HACC,
    _F_HLU,
    _F_HOLD,
    _F_JACEVERY,
    _F_NIT,
    _F_TBASE,
    _F_THETA,
    _F_THSTEP,
    _I_FIRST,
    _I_LU_VALID,
    _I_M1,
    _I_NACCPT,
    _I_NBORDER,
    _I_NEED_JAC,
    _I_NSING,
    _I_STARTED,
    _I_STRUCT,
)
from .controller import error_quotient, gustafsson_quotient, newton_rate_cap, newton_slow_factor
from .core import _collocation, radau5_core, radau5_run
from .dense import _decompose, _jacobian, _solve, lu_factor, lu_solve
from .newton import _increment_noise, _lin
from .workspace import (
    WS_BORDER,
    WS_CONT,
    WS_DENSE,
    WS_F0,
    WS_FLOATS,
    WS_INTS,
    WS_KERNELS,
    WS_SOLVER,
    radau5_workspace,
)

__all__ = ["lu_factor", "lu_solve", "radau5_core", "radau5_run", "radau5_workspace"]
