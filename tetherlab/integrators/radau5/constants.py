"""RADAU5's constants: the Radau IIA tableau as scalars, Hairer's defaults, the values tuned here
(each with its measurement), and the slots of the workspace arrays that carry a run between calls."""

from __future__ import annotations

import numpy as np

from ..common import EPS
from ..tableau import (
    ALPH,
    BETA,
    C1,
    C1M1,
    C1MC2,
    C2,
    C2M1,
    DD1,
    DD2,
    DD3,
    RADAU_T,
    RADAU_TI,
    U1,
)

# Transformation matrices as scalars (numba folds them into the arithmetic).
T11, T12, T13 = (float(v) for v in RADAU_T[0])
T21, T22, T23 = (float(v) for v in RADAU_T[1])
T31 = float(RADAU_T[2, 0])  # T32 = 1, T33 = 0 (used implicitly below)
TI11, TI12, TI13 = (float(v) for v in RADAU_TI[0])
TI21, TI22, TI23 = (float(v) for v in RADAU_TI[1])
TI31, TI32, TI33 = (float(v) for v in RADAU_TI[2])

# RADAU5 defaults (Hairer's IWORK/WORK defaults).
NIT = 7  # max Newton iterations per step
THET = 0.01  # Jacobian is recomputed when the Newton rate exceeds this
SAFE = 0.9
QUOT1 = 1.0  # keep h (and the LU) when hnew/h is in [QUOT1, QUOT2]
QUOT2 = 1.2
FACL = 5.0  # hnew/h >= 1/FACL
FACR = 0.125  # hnew/h <= 1/FACR
MAX_SINGULAR = 5  # consecutive singular matrices before giving up
#: Target contraction rate of the simplified Newton iteration for the step-size cap (docs/
#: integrators.md, section 7): the rate grows like h^2 on a rotating stiff tether, so after an
#: accepted step with a fresh Jacobian and a measured rate theta the next step is at most
#: h sqrt(THETA_STEP / theta).  Without the cap Hairer's error-based controller proposes steps the
#: iteration cannot converge on, and nearly every accepted step followed a Newton failure.
#: Tried on the structured path (docs/integrators.md section 11): on an undamped tether theta grows
#: like h^4 rather than h^2, and a cap h (0.15 / theta)^(1/4) saved 13-16 % of the rhs calls
#: (de-orbit n = 16: 855k -> 741k); but at rtol 1e-11 theta has a round-off floor near 0.2, above
#: that target, so the cap shrank every step (libration n = 128, 2 orbits: > 20 min against 5.6 s).
THETA_STEP = 0.3
#: Structured Jacobian (O(n), cheaper than one rhs call): 0 Hairer's reuse rule, 1 refreshed on
#: every step at its start, 2 refreshed on every step at the middle of the coming step (on the
#: extrapolated collocation polynomial), which halves the rotation of the stiff axial direction
#: between the Jacobian and the stages (docs/integrators.md, section 7; measured best).
STRUCT_JAC_EVERY_STEP = 2
#: Newton iterations allowed with the structured matrix (an iteration costs 3 rhs calls and two
#: O(n) solves; docs/integrators.md section 7: 7, 10, 14 measured, 10 kept).
NIT_STRUCT = 10
#: A stalled Newton iteration (rate >= 0.99, or a predicted miss of the iteration limit) whose
#: increment is within this factor of the round-off floor (:func:`_increment_noise`) is taken as
#: converged: the three stages' noise enters each transformed increment through rows of T^-1 of
#: norm ~4.4, and the floor is one realisation of it (docs/integrators.md section 12).
FLOOR_GAIN = 10.0

# Workspace scalar slots (float fs[], int is_[]).
_F_HOLD = 0
_F_THETA = 1
_F_FACCON = 2
_F_HACC = 3
_F_ERRACC = 4
_F_HLU = 5
_F_THSTEP = 6  # Newton-rate step cap target (0: off, Hairer's controller alone); set by the workspace
_F_JACEVERY = 7  # > 0: a fresh Jacobian on every step (set by the workspace; structured default)
_F_NIT = 8  # max Newton iterations (0: NIT); set by the workspace
_F_FLOOR = 9  # FLOOR_GAIN (0: a stalled Newton iteration is always a failure); set by the workspace
_I_FIRST = 0
_I_NEED_JAC = 1
_I_LU_VALID = 2
_I_NACCPT = 3
_I_NSING = 4
_I_STARTED = 5
_I_M1 = 6  # second-order structure: y'_i = y_{i+M1} for i < M1 (0 = none), set by the workspace
_I_STRUCT = 7  # 1: a structured Newton matrix handed in by the model (linear_solver.py), O(n) per step
_I_NBORDER = 8  # structured: number of first-order unknowns w bordering it (n - 2 m1; section 13)
_F_TBASE = 10  # structured with a border: time of the border's base state
#: rows of the border's float work array: base state y_J, f(t_J, y_J), then scratch
_B_Y, _B_F, _B_YT, _B_FT, _B_XR, _B_XI, _B_OR, _B_OI = 0, 1, 2, 3, 4, 5, 6, 7
_B_ROWS = 8
#: relative increment of the border's directional differences (forward: sqrt(eps))
_SQRT_EPS = float(np.sqrt(EPS))
