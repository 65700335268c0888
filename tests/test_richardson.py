"""Richardson extrapolation and observed order against analytic sequences a_n = a + c n^-p."""

from __future__ import annotations

import math

import pytest

from tetherlab.richardson import extrapolate, observed_order, richardson


@pytest.mark.parametrize("p", [1.0, 2.0, 3.5])
@pytest.mark.parametrize("ratio", [2.0, 3.0])
def test_exact_power_law(p, ratio):
    a, c = 1.5, 0.3
    ns = [ratio**k for k in range(5)]
    vals = [a + c * n**-p for n in ns]
    out = richardson(ns, vals)
    # exact sequence: the order and the limit come back to round-off (1e-9 relative at most here)
    assert out["order"] == pytest.approx(p, rel=1e-9)
    assert out["limit"] == pytest.approx(a, rel=1e-12)
    assert out["error_estimate"] == pytest.approx(c * ns[-1] ** -p, rel=1e-6)


def test_higher_order_term_is_asymptotically_negligible():
    # a_n = a + c n^-2 + d n^-3: the observed order tends to 2 as n grows (error ~ (d/c) n^-1)
    seq = lambda n: 2.0 + 1.0 / n**2 + 0.5 / n**3  # noqa: E731
    coarse = observed_order(seq(2), seq(4), seq(8))
    fine = observed_order(seq(64), seq(128), seq(256))
    assert abs(fine - 2) < abs(coarse - 2) and abs(fine - 2) < 0.01


def test_non_monotone_or_flat_gives_nan():
    assert math.isnan(observed_order(1.0, 2.0, 1.5))  # oscillating differences
    assert math.isnan(observed_order(1.0, 1.0, 1.0))  # at round-off
    assert math.isnan(extrapolate(1.0, 1.1, math.nan))


def test_bad_arguments_raise():
    with pytest.raises(ValueError, match="refinement ratio"):
        observed_order(1, 2, 3, ratio=1.0)
    with pytest.raises(ValueError, match="constant refinement ratio"):
        richardson([1, 2, 3], [1.0, 0.5, 0.2])
    with pytest.raises(ValueError, match="at least three"):
        richardson([1, 2], [1.0, 0.5])
