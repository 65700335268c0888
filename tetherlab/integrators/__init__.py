"""Compiled ODE integrators over the cfunc right-hand-side ABI of :mod:`tetherlab._jit`.

Kernels (numba, ``cache=True``; one call runs the whole step loop and every rhs call)::

    status, t_end, h_next, n_done = dop853_run(rhs, t, y, t_out, p, rtol, atol, h, h_max,
                                               max_steps, y_out, stats, fixed_step)
    status, t_end, h_next, n_done = vern9_run(...same...)
    status, t_end, h_next, n_done = radau5_run(...same...)

* ``y`` (float64[n]) is overwritten with the state at ``t_end``; rows 0..n_done-1 of ``y_out``
  (float64[m, n]) hold the solution at ``t_out[:n_done]`` (dense output; t_out non-decreasing,
  >= t); the run stops exactly at ``t_out[-1]``.  Rows already written survive a later failure.
* ``atol`` float64[n]; error norm RMS of err_i / (atol_i + rtol*max(|y_i|, |y_new_i|)).
* ``h <= 0``: initial step by Hairer's HINIT; ``h_max <= 0``: unlimited; ``max_steps``: accepted
  steps allowed in this call (the call returns right after an accepted step).
* ``stats`` int64[8], accumulated: accepted, rejected, rhs calls (including those of
  finite-difference Jacobians), Jacobians, LU decompositions (the real + complex pair of RADAU5
  counts as one, as Hairer's NDEC), last nonzero rhs status, Newton failures, spare.
* status: 0 done, 1 max_steps, 2 step-size underflow / too many rejections / no Newton
  convergence, 3 the rhs kept returning a nonzero status (each such trial: h /= 4; give up after
  20 in a row or underflow), 4 non-finite values that step reduction did not remove.

RADAU5 applies Hairer's tolerance map (rtol' = 0.1 rtol^(2/3)), so at tight tolerances its
error in units of the requested tolerance is larger than DOP853's; see :mod:`.radau5`.

Use :func:`integrate` for validation, chunking, progress and scipy cross-checks.  RADAU5's Newton
matrix is its own dense one unless the caller hands it a model's :class:`NewtonSolver`
(``integrate(..., newton=solver)``; linear_solver.py): this package imports nothing of any model.
"""

from .erk import dop853_run, erk_core, vern9_run
from .driver import METHODS, IntegrationResult, integrate, warm_up
from .linear_solver import NewtonSolver
from .radau5 import radau5_core, radau5_run, radau5_workspace
from .tableau import TableauError, check_tableau

__all__ = [
    "METHODS",
    "IntegrationResult",
    "NewtonSolver",
    "TableauError",
    "check_tableau",
    "dop853_run",
    "erk_core",
    "integrate",
    "radau5_core",
    "radau5_run",
    "radau5_workspace",
    "vern9_run",
    "warm_up",
]
