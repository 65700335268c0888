"""Coefficients of the compiled integrators, checked when this module is imported.

A wrong digit in a Butcher tableau does not crash anything: the method silently loses order, and
the only symptom is a convergence study that comes out one or two orders short.  So every tableau
used by a kernel is verified here, at import, against conditions it must satisfy exactly (to
rounding), as scipy's and diffrax's tableau classes do.  A failure raises :class:`TableauError`
(a RuntimeError), which makes ``import tetherlab.integrators`` fail loudly instead of producing
wrong trajectories.

DOP853 (Hairer, Norsett & Wanner, "Solving ODEs I", 2nd ed., section II.10; Fortran code DOP853)
    Taken from ``scipy.integrate._ivp.dop853_coefficients`` (the numbers of Hairer's DOP853, which
    scipy's ``DOP853`` uses).  Copying 300 twenty-digit constants by hand is a worse risk than
    depending on a module scipy has shipped unchanged since 1.4; the checks below would catch a
    change.  Stages 0..11 are the method, row 12 is f(t+h, y_new) (first same as last), rows
    13..15 are the three extra stages of the 7th-order dense output.

Vern9: Verner's "most efficient" 9(8) pair with an order-8 interpolant (J.H. Verner, Numer.
    Algorithms 53 (2010) 383-396)
    The 40-digit decimals live in :mod:`.vern9_coefficients`; here they are rounded to float64 and
    checked (row sums, weights, quadrature orders, the first-same-as-last row, the interpolant's
    end values).  tests/test_vern9.py checks every rooted-tree order condition in rational
    arithmetic.

Radau IIA, 3 stages, order 5 (Hairer & Wanner, "Solving ODEs II", 2nd ed., section IV.8, Table 5.6
    and the code RADAU5)
    The collocation coefficients are written in closed form in sqrt(6).  The transformation T that
    block-diagonalises A^-1 into one real eigenvalue and one complex pair is the one printed in
    RADAU5 (20 significant digits); it is checked here against the closed-form eigenvalues.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate._ivp import dop853_coefficients as _dop

from . import vern9_coefficients as _v9

#: Tolerance of the import-time checks.  Sums of O(1) coefficients in double precision are exact
#: to a few ulps; 1e-14 leaves room for that and nothing else.
CHECK_TOL = 1e-14


class TableauError(RuntimeError):
    """A coefficient set failed its consistency check (the integrators must not be used)."""


def check_tableau(name, a, b, c, order=None, tol=CHECK_TOL):
    """Verify an explicit or implicit Runge-Kutta tableau; raise TableauError when it is wrong.

    Checks the row-sum condition ``sum_j a_ij = c_i`` (every row, extended stages included), the
    consistency condition ``sum_i b_i = 1`` and, when ``order`` is given, the quadrature conditions
    ``sum_i b_i c_i^(k-1) = 1/k`` for k = 1..order (necessary for order ``order``; a single wrong
    digit in b or c breaks one of them).  ``b`` may be shorter than ``c`` (extended stages that only
    the dense output uses).
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    c = np.asarray(c, dtype=float)
    if a.ndim != 2 or a.shape[0] != a.shape[1] or a.shape[0] != c.shape[0]:
        raise TableauError(f"{name}: A must be square and match c; got A {a.shape}, c {c.shape}")
    if b.ndim != 1 or b.shape[0] > c.shape[0]:
        raise TableauError(f"{name}: b must be 1-D and not longer than c; got {b.shape}")
    row_err = np.abs(a.sum(axis=1) - c)
    if not np.all(row_err <= tol):
        i = int(np.argmax(row_err))
        raise TableauError(f"{name}: row {i} of A sums to {a[i].sum()!r}, expected c[{i}]={c[i]!r}")
    if not abs(b.sum() - 1.0) <= tol:
        raise TableauError(f"{name}: sum(b) = {b.sum()!r}, expected 1")
    if order is not None:
        cb = c[: b.shape[0]]
        for k in range(1, order + 1):
            q = float(np.sum(b * cb ** (k - 1)))
            if not abs(q - 1.0 / k) <= tol:
                raise TableauError(f"{name}: sum(b c^{k - 1}) = {q!r}, expected 1/{k}")


# --------------------------------------------------------------------------------------------
# DOP853
# --------------------------------------------------------------------------------------------
DOP_N_STAGES = _dop.N_STAGES  # 12
DOP_A = np.ascontiguousarray(_dop.A, dtype=np.float64)  # 16 x 16 (rows 13..15: dense stages)
DOP_B = np.ascontiguousarray(_dop.B, dtype=np.float64)  # 12
DOP_C = np.ascontiguousarray(_dop.C, dtype=np.float64)  # 16
# Error estimators (b - b_hat for the 5th- and 3rd-order embedded pairs), length 13.
DOP_E5 = np.ascontiguousarray(_dop.E5, dtype=np.float64)
DOP_E3 = np.ascontiguousarray(_dop.E3, dtype=np.float64)
DOP_D = np.ascontiguousarray(_dop.D, dtype=np.float64)  # 4 x 16, dense output coefficients


def _check_dop853():
    if DOP_A.shape != (16, 16) or DOP_B.shape != (12,) or DOP_D.shape != (4, 16):
        raise TableauError(f"DOP853: unexpected coefficient shapes from {_dop.__name__}")
    check_tableau("DOP853", DOP_A, DOP_B, DOP_C, order=8)
    # The error estimators are differences of two weight vectors that each sum to 1.
    for nm, e in (("E5", DOP_E5), ("E3", DOP_E3)):
        if not abs(e.sum()) <= CHECK_TOL:
            raise TableauError(f"DOP853: sum({nm}) = {e.sum()!r}, expected 0")
    # The kernel's stage loops rely on A being strictly lower triangular (explicit method).
    if np.any(np.triu(DOP_A) != 0.0):
        raise TableauError("DOP853: A is not strictly lower triangular")
    # The kernel evaluates row 12 as f(t + h, y_new) *after* the error test (so a rejected step
    # costs 11 evaluations, as in Hairer's code) and reuses it as the first stage of the next
    # step.  That is only right if row 12 is the b row at c = 1 and the error estimators ignore it.
    if not (
        np.array_equal(DOP_A[12, :12], DOP_B)
        and DOP_C[12] == 1.0
        and DOP_E5[12] == 0.0
        and DOP_E3[12] == 0.0
    ):
        raise TableauError("DOP853: stage 12 is not the first-same-as-last stage f(t+h, y_new)")


# --------------------------------------------------------------------------------------------
# Vern9 (Verner's efficient 9(8) pair, order-8 interpolant)
# --------------------------------------------------------------------------------------------
V9_N_STAGES = 16  # stages of one step (0..15); stage 16 = f(t + h, y_new); 17..20 interpolant
V9_N_ALL = 21
V9_N_DENSE = 8  # interpolant polynomial degree (b_s(theta) = sum_k P[s, k] theta^(k + 1))


def _v9_array(table, shape):
    out = np.zeros(shape)
    for i, v in table.items():
        if isinstance(v, dict):
            for j, x in v.items():
                out[i, j] = float(x)
        else:
            out[i] = float(v)
    return out


V9_A = _v9_array(_v9.A, (V9_N_ALL, V9_N_ALL))
V9_B = _v9_array(_v9.B, (V9_N_STAGES,))
V9_C = _v9_array(_v9.C, (V9_N_ALL,))
V9_E = _v9_array(_v9.E, (V9_N_STAGES,))  # b_low - b_high
V9_P = _v9_array(_v9.P, (V9_N_ALL, V9_N_DENSE))
#: The interpolant's weights at theta = 1 in float64 differ from b by up to ~1.4e-12: its
#: polynomial coefficients reach 1.3e4 and cancel (exactly, in the 40-digit decimals: 7e-36).
#: Outputs between steps carry that relative error on the step's increment h f (documented in
#: :mod:`.vern9`); the end of a step always uses b itself.
V9_DENSE_ROUNDING = 2e-12


def _check_vern9():
    a, b, c, e, P = V9_A, V9_B, V9_C, V9_E, V9_P
    check_tableau("Vern9", a, b, c, order=9)
    check_tableau("Vern9 embedded", a[:V9_N_STAGES, :V9_N_STAGES], b + e, c[:V9_N_STAGES], order=8)
    if not abs(e.sum()) <= CHECK_TOL:
        raise TableauError(f"Vern9: sum(E) = {e.sum()!r}, expected 0")
    if np.any(np.triu(a) != 0.0):
        raise TableauError("Vern9: A is not strictly lower triangular")
    # The kernel evaluates row 16 as f(t + h, y_new) after the error test and reuses it as the
    # first stage of the next step; that needs row 16 = b at c = 1.
    if not (np.array_equal(a[16, :16], b) and c[16] == 1.0 and np.all(a[16, 16:] == 0.0)):
        raise TableauError("Vern9: stage 16 is not the first-same-as-last stage f(t+h, y_new)")
    # Interpolant: b(1) = b (with zeros for the extra stages) and b(0) = 0 by construction;
    # quadrature conditions sum_s b_s(theta) c_s^(k-1) = theta^k / k, k = 1..8, at theta = 1/2.
    end = P.sum(axis=1)
    ref = np.concatenate([b, np.zeros(V9_N_ALL - V9_N_STAGES)])
    if not np.all(np.abs(end - ref) <= V9_DENSE_ROUNDING):
        raise TableauError(f"Vern9: interpolant at theta = 1 differs from b by "
                           f"{np.abs(end - ref).max():.3e}")  # fmt: skip
    th = 0.5
    bt = P @ th ** np.arange(1, V9_N_DENSE + 1)
    for k in range(1, V9_N_DENSE + 1):
        q = float(bt @ c ** (k - 1))
        if not abs(q - th**k / k) <= V9_DENSE_ROUNDING:
            raise TableauError(f"Vern9: interpolant quadrature k={k} off by {q - th**k / k:.3e}")


# --------------------------------------------------------------------------------------------
# Radau IIA (s = 3, order 5)
# --------------------------------------------------------------------------------------------
SQ6 = math.sqrt(6.0)
RADAU_C = np.array([(4.0 - SQ6) / 10.0, (4.0 + SQ6) / 10.0, 1.0])
RADAU_A = np.array(
    [
        [(88.0 - 7.0 * SQ6) / 360.0, (296.0 - 169.0 * SQ6) / 1800.0, (-2.0 + 3.0 * SQ6) / 225.0],
        [(296.0 + 169.0 * SQ6) / 1800.0, (88.0 + 7.0 * SQ6) / 360.0, (-2.0 - 3.0 * SQ6) / 225.0],
        [(16.0 - SQ6) / 36.0, (16.0 + SQ6) / 36.0, 1.0 / 9.0],
    ]
)
RADAU_B = RADAU_A[2].copy()  # stiffly accurate: b is the last row of A

# Constants of RADAU5 (names as in the Fortran code, so the kernel can be read against it).
C1 = RADAU_C[0]
C2 = RADAU_C[1]
C1M1 = C1 - 1.0
C2M1 = C2 - 1.0
C1MC2 = C1 - C2
# Error-estimate weights e_i / gamma_0 (Hairer & Wanner IV.8, eq. (8.19)-(8.20)).
DD1 = -(13.0 + 7.0 * SQ6) / 3.0
DD2 = (-13.0 + 7.0 * SQ6) / 3.0
DD3 = -1.0 / 3.0
_CBRT81 = 81.0 ** (1.0 / 3.0)
_CBRT9 = 9.0 ** (1.0 / 3.0)
# Eigenvalues of A^-1: one real (U1 = gamma) and a complex pair ALPH +- i BETA, closed forms.
_u1 = (6.0 + _CBRT81 - _CBRT9) / 30.0
_alph = (12.0 - _CBRT81 + _CBRT9) / 60.0
_beta = (_CBRT81 + _CBRT9) * math.sqrt(3.0) / 60.0
_cno = _alph**2 + _beta**2
U1 = 1.0 / _u1
ALPH = _alph / _cno
BETA = _beta / _cno
# T and T^-1 of RADAU5: T^-1 A^-1 T = [[U1, 0, 0], [0, ALPH, -BETA], [0, BETA, ALPH]].
RADAU_T = np.array(
    [
        [9.1232394870892942792e-02, -0.14125529502095420843, -3.0029194105147424492e-02],
        [0.24171793270710701896, 0.20412935229379993199, 0.38294211275726193779],
        [0.96604818261509293619, 1.0, 0.0],
    ]
)
RADAU_TI = np.array(
    [
        [4.3255798900631553510, 0.33919925181580986954, 0.54177053993587487119],
        [-4.1787185915519047273, -0.32768282076106238708, 0.47662355450055045196],
        [-0.50287263494578687595, 2.5719269498556054292, -0.59603920482822492497],
    ]
)


def _check_radau():
    a, b, c = RADAU_A, RADAU_B, RADAU_C
    # B(5): the quadrature (b, c) is the 3-point Radau right formula, exact to degree 4.
    check_tableau("Radau IIA", a, b, c, order=5)
    # C(3): collocation, sum_j a_ij c_j^(k-1) = c_i^k / k for k = 1..3.  The dense output of the
    # kernel is the collocation polynomial, so this is what makes it valid.
    for k in range(1, 4):
        dev = np.abs(a @ c ** (k - 1) - c**k / k)
        if not np.all(dev <= CHECK_TOL):
            raise TableauError(
                f"Radau IIA: collocation condition C({k}) violated by {dev.max():.3e}"
            )
    # c must be the roots of the Radau polynomial: c1 + c2 = 4/5, c1 c2 = 1/10 (from
    # d^2/dx^2 [x^2 (x - 1)^3] = 0 divided out by (x - 1)).
    if not (abs(C1 + C2 - 0.8) <= CHECK_TOL and abs(C1 * C2 - 0.1) <= CHECK_TOL):
        raise TableauError("Radau IIA: c1, c2 are not the Radau nodes")
    # Transformation: T^-1 T = I, and T^-1 A^-1 T is the real + complex block form with the
    # closed-form eigenvalues.  The T digits are printed to 20 places; 1e-13 relative to the
    # eigenvalues (~3.6) is still far below anything that could hurt the Newton iteration.
    if not np.all(np.abs(RADAU_TI @ RADAU_T - np.eye(3)) <= 10 * CHECK_TOL):
        raise TableauError("Radau IIA: TI is not the inverse of T")
    lam = np.array([[U1, 0.0, 0.0], [0.0, ALPH, -BETA], [0.0, BETA, ALPH]])
    dev = np.abs(RADAU_TI @ np.linalg.inv(a) @ RADAU_T - lam).max()
    if not dev <= 1e-13 * U1:
        raise TableauError(f"Radau IIA: T does not block-diagonalise A^-1 (deviation {dev:.3e})")
    # Error estimate: the embedded weights (gamma0 * DD) must annihilate constants, i.e. the
    # estimate of a step with z_i = c_i * h * f (exact for y' = const) is zero:
    # sum_i DD_i c_i + 1 = 0  (the "+1" is the gamma0 h f0 term divided by gamma0 h).
    s = DD1 * C1 + DD2 * C2 + DD3 * 1.0 + 1.0
    if not abs(s) <= 10 * CHECK_TOL:
        raise TableauError(f"Radau IIA: error-estimate weights are inconsistent ({s!r})")


_check_dop853()
_check_vern9()
_check_radau()
