"""Vern9's coefficients against every order condition, in 60-digit decimal arithmetic.

A Runge-Kutta method has order p iff sum_i b_i Phi_i(t) = 1/gamma(t) for every rooted tree t
with at most p vertices (Butcher; Hairer, Norsett & Wanner, "Solving ODEs I", section II.2,
Theorem 2.13): 1, 1, 2, 4, 9, 20, 48, 115, 286 trees of orders 1..9, 486 in all.  An interpolant
b(theta) has order q iff sum_i b_i(theta) Phi_i(t) = theta^rho(t) / gamma(t) for the trees up to
order q (ibid., II.6).  The 40-digit decimals of :mod:`tetherlab.integrators.vern9_coefficients`
must satisfy these to ~1e-38; float64 rounding (checked at import) is a separate matter.
"""

from __future__ import annotations

import decimal
from decimal import Decimal
from functools import lru_cache

import numpy as np
import pytest

from tetherlab.integrators import tableau
from tetherlab.integrators import vern9_coefficients as V

CTX = decimal.Context(prec=60)
N = 21


@lru_cache(maxsize=None)
def trees(order: int) -> tuple:
    """Rooted trees with ``order`` vertices, each a sorted tuple of its (order, child) pairs."""
    if order == 1:
        return ((),)
    out = set()

    def forests(m, cap):
        if m == 0:
            yield ()
            return
        for k in range(1, m + 1):
            for t in trees(k):
                if cap is not None and (k, t) > cap:
                    continue
                for rest in forests(m - k, (k, t)):
                    yield ((k, t),) + rest

    for f in forests(order - 1, None):
        out.add(tuple(sorted(f, reverse=True)))
    return tuple(sorted(out))


def gamma(t) -> int:
    g = 1 + sum(k for k, _ in t)
    for _, child in t:
        g *= gamma(child)
    return g


def _dec(table, shape):
    if len(shape) == 1:
        out = [Decimal(0)] * shape[0]
        for i, v in table.items():
            out[i] = Decimal(v)
        return out
    out = [[Decimal(0)] * shape[1] for _ in range(shape[0])]
    for i, row in table.items():
        for j, v in row.items():
            out[i][j] = Decimal(v)
    return out


A = _dec(V.A, (N, N))
B = _dec(V.B, (N,))
E = _dec(V.E, (N,))
P = _dec(V.P, (N, 8))


@lru_cache(maxsize=None)
def phi(t) -> tuple:
    """Phi_i(t) for every stage i: the product over the root's children of A @ Phi(child)."""
    v = [Decimal(1)] * N
    for _, child in t:
        pc = phi(child)
        with decimal.localcontext(CTX):
            w = [sum((A[i][j] * pc[j] for j in range(i)), Decimal(0)) for i in range(N)]
            v = [v[i] * w[i] for i in range(N)]
    return tuple(v)


def _residual(weights, t, theta=Decimal(1)) -> Decimal:
    """gamma(t) * (sum_i w_i Phi_i(t) - theta^rho / gamma(t)), in units of the condition."""
    with decimal.localcontext(CTX):
        ph = phi(t)
        s = sum((weights[i] * ph[i] for i in range(N)), Decimal(0))
        rho = 1 + sum(k for k, _ in t)
        return abs(gamma(t) * s - theta**rho)


def _interp_weights(theta: Decimal):
    with decimal.localcontext(CTX):
        return [sum((P[i][k] * theta ** (k + 1) for k in range(8)), Decimal(0)) for i in range(N)]


def test_tree_counts_are_butchers():
    # OEIS A000081: rooted trees with n nodes
    assert [len(trees(n)) for n in range(1, 10)] == [1, 1, 2, 4, 9, 20, 48, 115, 286]


def test_vern9_weights_have_order_9_and_not_10():
    worst = max(_residual(B, t) for n in range(1, 10) for t in trees(n))
    assert worst < Decimal("1e-35"), worst  # 40-digit inputs
    # order 10 is not claimed, and the check can tell: the worst order-10 condition is off by 3e-2
    assert max(_residual(B, t) for t in trees(10)) > Decimal("1e-3")


def test_embedded_weights_have_order_8_and_not_9():
    with decimal.localcontext(CTX):
        low = [B[i] + E[i] for i in range(N)]
    worst = max(_residual(low, t) for n in range(1, 9) for t in trees(n))
    assert worst < Decimal("1e-35"), worst
    # an error estimator needs the embedded solution to differ at order 9
    assert max(_residual(low, t) for t in trees(9)) > Decimal("1e-4")


@pytest.mark.parametrize("theta", ["0.25", "0.5", "0.8", "1"])
def test_interpolant_has_order_8(theta):
    th = Decimal(theta)
    w = _interp_weights(th)
    worst = max(_residual(w, t, th) for n in range(1, 9) for t in trees(n))
    assert worst < Decimal("1e-33"), worst


def test_interpolant_ends_on_the_step_solution():
    w = _interp_weights(Decimal(1))
    dev = max(abs(w[i] - (B[i] if i < 16 else 0)) for i in range(N))
    assert dev < Decimal("1e-35"), dev


def test_float64_tables_are_the_decimals_rounded():
    # the kernel's arrays are the nearest doubles of the decimals (no digit lost on the way)
    for i in range(N):
        for j in range(N):
            assert tableau.V9_A[i, j] == float(A[i][j])
    assert np.array_equal(tableau.V9_B, [float(x) for x in B[:16]])
    assert np.array_equal(tableau.V9_E, [float(x) for x in E[:16]])
    assert np.array_equal(tableau.V9_P, [[float(x) for x in row] for row in P])
