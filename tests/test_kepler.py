"""Classical elements <-> Cartesian state: textbook values, conventions, round trips, refusals."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tetherlab.orbits import cartesian_to_elements, elements_to_cartesian, period

MU_EARTH = 3.986004418e14
MU_CURTIS = 398600e9  # Curtis uses mu = 398600 km^3/s^2
DEG = math.pi / 180.0


def angle_diff(a: float, b: float) -> float:
    """Smallest signed difference of two angles, so 359.9 deg and 0.1 deg are close."""
    return math.remainder(a - b, 2.0 * math.pi)


# -- textbook values ---------------------------------------------------------------------------


def test_curtis_example_4_3_state_to_elements():
    # Curtis, Orbital Mechanics for Engineering Students (3rd ed.), Example 4.3:
    # r = [-6045, -3490, 2500] km, v = [-3.457, 6.618, 2.533] km/s gives
    # h = 58 310 km^2/s, i = 153.2 deg, RAAN = 255.3 deg, e = 0.1712, argp = 20.07 deg,
    # theta = 28.45 deg, a = 8788 km, T = 2.278 h.
    el = cartesian_to_elements(MU_CURTIS, [-6045e3, -3490e3, 2500e3], [-3457.0, 6618.0, 2533.0])
    assert el.a == pytest.approx(8788e3, abs=1e3)
    assert el.e == pytest.approx(0.1712, abs=1e-4)
    assert el.i / DEG == pytest.approx(153.2, abs=0.05)
    assert el.raan / DEG == pytest.approx(255.3, abs=0.05)
    assert el.argp / DEG == pytest.approx(20.07, abs=0.005)
    assert el.nu / DEG == pytest.approx(28.45, abs=0.005)
    # The book rounds its intermediates (2.2775 h from a = 8788 km); 1e-3 h covers that.
    assert period(MU_CURTIS, el.a) / 3600.0 == pytest.approx(2.278, abs=1e-3)
    h = np.linalg.norm(np.cross([-6045.0, -3490.0, 2500.0], [-3.457, 6.618, 2.533]))
    assert h == pytest.approx(58310, abs=5)  # printed to 4 significant figures


def test_curtis_example_4_7_elements_to_state_hyperbolic():
    # Curtis Example 4.7: h = 80 000 km^2/s, e = 1.4, i = 30 deg, RAAN = 40 deg, argp = 60 deg,
    # theta = 30 deg gives r = [-4040, 4815, 3629] km, v = [-10.39, -4.772, 1.744] km/s.
    h, e = 80000e6, 1.4
    a = h * h / MU_CURTIS / (1.0 - e * e)  # a < 0: hyperbola
    r, v = elements_to_cartesian(MU_CURTIS, a, e, 30 * DEG, 40 * DEG, 60 * DEG, 30 * DEG)
    np.testing.assert_allclose(r / 1e3, [-4040, 4815, 3629], atol=1.0)
    np.testing.assert_allclose(v / 1e3, [-10.39, -4.772, 1.744], atol=5e-3)
    back = cartesian_to_elements(MU_CURTIS, r, v)
    assert back.a == pytest.approx(a, rel=1e-12)
    assert back.e == pytest.approx(e, rel=1e-12)
    assert back.nu == pytest.approx(30 * DEG, abs=1e-12)


def test_period_of_geostationary_orbit_is_a_sidereal_day():
    # a_GEO = 42 164.17 km; sidereal day 86 164.09 s.
    assert period(MU_EARTH, 42164.1696e3) == pytest.approx(86164.09, abs=0.01)


# -- conventions for undefined angles --------------------------------------------------------


def test_circular_orbit_has_argp_zero_and_nu_the_argument_of_latitude():
    r, v = elements_to_cartesian(MU_EARTH, 7e6, 0.0, 0.5, 1.0, 0.7, 0.4)
    el = cartesian_to_elements(MU_EARTH, r, v)
    assert el.e < 1e-12
    assert el.argp == 0.0
    assert el.raan == pytest.approx(1.0, abs=1e-12)
    assert el.nu == pytest.approx(0.7 + 0.4, abs=1e-12)


def test_equatorial_orbit_has_raan_zero_and_argp_the_longitude_of_periapsis():
    r, v = elements_to_cartesian(MU_EARTH, 8e6, 0.1, 0.0, 1.0, 0.5, 0.3)
    el = cartesian_to_elements(MU_EARTH, r, v)
    assert el.i == 0.0
    assert el.raan == 0.0
    assert el.argp == pytest.approx(1.5, abs=1e-12)
    assert el.nu == pytest.approx(0.3, abs=1e-12)


def test_circular_equatorial_orbit_has_nu_the_true_longitude():
    r, v = elements_to_cartesian(MU_EARTH, 7e6, 0.0, 0.0, 0.0, 0.0, 2.0)
    np.testing.assert_allclose(r, 7e6 * np.array([math.cos(2.0), math.sin(2.0), 0.0]), atol=1e-6)
    el = cartesian_to_elements(MU_EARTH, r, v)
    assert (el.raan, el.argp) == (0.0, 0.0)
    assert el.nu == pytest.approx(2.0, abs=1e-12)


def test_retrograde_equatorial_orbit_round_trips():
    r, v = elements_to_cartesian(MU_EARTH, 8e6, 0.2, math.pi, 0.0, 0.8, 1.1)
    el = cartesian_to_elements(MU_EARTH, r, v)
    assert el.i == pytest.approx(math.pi, abs=1e-15)
    assert (el.raan, el.argp, el.nu) == pytest.approx((0.0, 0.8, 1.1), abs=1e-12)


def test_hyperbolic_true_anomaly_is_signed():
    r, v = elements_to_cartesian(MU_EARTH, -2e7, 1.5, 0.3, 0.2, 0.1, -0.5)
    assert cartesian_to_elements(MU_EARTH, r, v).nu == pytest.approx(-0.5, abs=1e-12)


# -- round trips ----------------------------------------------------------------------------

angles = st.floats(0.0, 2.0 * math.pi - 1e-9)
settled = settings(max_examples=300, deadline=None)


@st.composite
def elliptic(draw, e_min=0.0):
    a = draw(st.floats(6.6e6, 5e7))
    e = draw(st.floats(e_min, 0.95))
    i = draw(st.floats(0.0, math.pi))
    return a, e, i, draw(angles), draw(angles), draw(angles)


@st.composite
def hyperbolic(draw):
    e = draw(st.floats(1.05, 5.0))
    a = -draw(st.floats(6.6e6, 5e7))
    limit = math.acos(-1.0 / e)
    nu = draw(st.floats(-0.95 * limit, 0.95 * limit))
    i = draw(st.floats(0.0, math.pi))
    return a, e, i, draw(angles), draw(angles), nu


def assert_same_state(state, back, scale_r, scale_v):
    np.testing.assert_allclose(back[0], state[0], rtol=0, atol=1e-9 * scale_r)
    np.testing.assert_allclose(back[1], state[1], rtol=0, atol=1e-9 * scale_v)


@settled
@given(st.one_of(elliptic(), hyperbolic()))
def test_state_round_trip_through_elements(el):
    # Cartesian -> elements -> Cartesian holds for every orbit, near-circular and
    # near-equatorial ones included (the angle conventions make the undefined angles harmless).
    state = elements_to_cartesian(MU_EARTH, *el)
    back = elements_to_cartesian(MU_EARTH, *cartesian_to_elements(MU_EARTH, *state))
    assert_same_state(state, back, np.linalg.norm(state[0]), np.linalg.norm(state[1]))


@settled
@given(elliptic(e_min=1e-3).filter(lambda el: 1e-3 < el[2] < math.pi - 1e-3))
def test_elliptic_elements_round_trip(el):
    # Away from the circular and equatorial singularities every element comes back.
    a, e, i, raan, argp, nu = el
    back = cartesian_to_elements(MU_EARTH, *elements_to_cartesian(MU_EARTH, *el))
    assert back.a == pytest.approx(a, rel=1e-9)
    assert back.e == pytest.approx(e, rel=1e-7, abs=1e-9)
    assert back.i == pytest.approx(i, abs=1e-9)
    # argp and nu are individually ill-conditioned as e -> 0 (their sum is not).
    tol = 1e-9 / e
    for got, want in ((back.raan, raan), (back.argp, argp), (back.nu, nu)):
        assert abs(angle_diff(got, want)) < tol
    assert 0.0 <= back.raan < 2 * math.pi and 0.0 <= back.argp < 2 * math.pi and 0.0 <= back.nu < 2 * math.pi


@settled
@given(hyperbolic().filter(lambda el: 1e-3 < el[2] < math.pi - 1e-3))
def test_hyperbolic_elements_round_trip(el):
    a, e, i, raan, argp, nu = el
    back = cartesian_to_elements(MU_EARTH, *elements_to_cartesian(MU_EARTH, *el))
    assert back.a == pytest.approx(a, rel=1e-9)
    assert back.e == pytest.approx(e, rel=1e-9)
    assert back.i == pytest.approx(i, abs=1e-9)
    for got, want in ((back.raan, raan), (back.argp, argp), (back.nu, nu)):
        assert abs(angle_diff(got, want)) < 1e-8
    assert -math.pi < back.nu <= math.pi


@settled
@given(elliptic())
def test_energy_and_angular_momentum_match_the_elements(el):
    a, e = el[0], el[1]
    r, v = elements_to_cartesian(MU_EARTH, *el)
    energy = 0.5 * v @ v - MU_EARTH / np.linalg.norm(r)
    assert energy == pytest.approx(-MU_EARTH / (2 * a), rel=1e-12)
    h = np.linalg.norm(np.cross(r, v))
    assert h == pytest.approx(math.sqrt(MU_EARTH * a * (1 - e * e)), rel=1e-12)


# -- refusals --------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "args, message",
    [
        ((7e6, 1.0, 0, 0, 0, 0), "parabolic"),
        ((-7e6, 0.5, 0, 0, 0, 0), "needs a > 0"),
        ((7e6, 1.5, 0, 0, 0, 0), "needs a < 0"),
        ((7e6, -0.1, 0, 0, 0, 0), ">= 0"),
        ((-7e6, 2.0, 0, 0, 0, 2.2), "asymptotes"),
        ((float("nan"), 0.1, 0, 0, 0, 0), "finite"),
    ],
)
def test_inconsistent_elements_are_refused(args, message):
    with pytest.raises(ValueError, match=message):
        elements_to_cartesian(MU_EARTH, *args)


def test_bad_states_and_parameters_are_refused():
    with pytest.raises(ValueError, match="rectilinear"):
        cartesian_to_elements(MU_EARTH, [7e6, 0, 0], [100.0, 0, 0])
    with pytest.raises(ValueError, match="centre"):
        cartesian_to_elements(MU_EARTH, [0, 0, 0], [0, 7e3, 0])
    with pytest.raises(ValueError, match="parabolic"):
        # mu = 2, r = 1, v = 2: energy 0.5 * 4 - 2 / 1 is exactly zero in floats.
        cartesian_to_elements(2.0, [1.0, 0, 0], [0, 2.0, 0])
    with pytest.raises(ValueError, match="mu"):
        elements_to_cartesian(0.0, 7e6, 0.0, 0, 0, 0, 0)
    with pytest.raises(ValueError, match="elliptic"):
        period(MU_EARTH, -7e6)
