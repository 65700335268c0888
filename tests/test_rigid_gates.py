"""The simulator against the rigid-body oracles (docs/rigid-oracles.md 7): the gates of studies/rigid_bodies.py.

Expected values: tetherlab/oracles/{spinning_spokes, torque_free, gg_attitude, wheel_exchange}.py
and references/rigid_bodies/reference.json (docs/rigid-oracles.md); bounds: the study's
docstrings and docs/rigid-oracles.md section 7, never the measured values.  Fast tests run one
small case each; the full gates (several rod counts, negative controls) are `slow` and run by
`make verify`.
"""

from __future__ import annotations

import importlib.util
import sys

import pytest

from tests.helpers import ROOT

_spec = importlib.util.spec_from_file_location("rigid_bodies_study", ROOT / "studies" / "rigid_bodies.py")
study = importlib.util.module_from_spec(_spec)
sys.modules[_spec.name] = study
_spec.loader.exec_module(study)

REF = study.load_reference()


# -- A: hub and spoke at the centre of a point-mass hub (runs on point masses) ---------------------
def test_hub_spoke_centre_two_rods_within_bound():
    r = study.hub_run(REF, "centre", 2)
    # continuum steady state (spinning_spokes.spoke_profile at the spin of the run's angular
    # momentum) within the first-order discretisation bound dx_max = (L/n)(T(0) - T(L))/EA
    assert r["tip_radius_error_m"] < r["tip_bound_m"]
    assert r["hub_tension_error_N"] < r["tension_bound_N"]
    # the settled spin is the one the conserved angular momentum implies: within 1e-4 of Omega0
    # (the start is near the steady state at Omega0, so only the stretch adjusts it)
    assert abs(r["spin_rad_s"] / REF["hub_spoke"]["omega0_rad_s"] - 1) < 1e-4
    # three symmetric tethers keep the hub's centre fixed (round-off: 4 u sqrt(N) L ~ 1e-11 m)
    assert r["hub_drift_m"] < 4 * 2.0**-53 * r["steps"] ** 0.5 * 100.0 * 10
    # internal damping keeps the angular momentum: to the integration tolerance (rtol 1e-11)
    assert r["H_drift_rel"] < 1e-9
    # relaxed: the last 10 % of the run wobbles by far less than the discretisation error
    assert r["tail_wobble_m"] < 1e-2 * r["tip_bound_m"]


@pytest.mark.slow
def test_hub_spoke_centre_gates():
    rows, g = study.part_hub(REF, "centre")
    assert g["hub_spoke_centre_tip_over_bound"] <= 1.0
    assert g["hub_spoke_centre_tension_over_bound"] <= 1.0
    assert g["hub_spoke_centre_order_deficit"] <= study.ORDER_SLACK
    assert g["hub_spoke_centre_negative_control"] <= 1.0  # the 1 % stiffer tether fails the order gate


# -- B-G: rigid bodies (docs/scenes.md [bodies.NAME.rigid]) ------------------------------------------
def test_hub_spoke_rigid_hub_two_rods_within_bound():
    # four tethers at r_h = 2 m on a rigid hub spinning with them: the continuum at the spin the
    # run's angular momentum (hub's J w included) implies, within the first-order bound
    r = study.hub_run(REF, "radius", 2)
    assert r["tip_radius_error_m"] < r["tip_bound_m"]
    assert r["hub_tension_error_N"] < r["tension_bound_N"]
    assert r["hub_drift_m"] < 1e-9  # four symmetric pulls cancel (round-off of 100 m radii)
    assert r["H_drift_rel"] < 1e-9  # damping is internal: H kept to the tolerance (rtol 1e-11)


@pytest.mark.slow
def test_hub_spoke_rigid_hub_gates_and_defects():
    rows, g = study.part_hub(REF, "radius")
    assert g["hub_spoke_radius_tip_over_bound"] <= 1.0
    assert g["hub_spoke_radius_tension_over_bound"] <= 1.0
    assert g["hub_spoke_radius_order_deficit"] <= study.ORDER_SLACK
    assert g["hub_spoke_radius_negative_control"] <= 1.0
    # the kernel's deliberate defects (unrotated attachment, omega x (omega x r) dropped) fail
    assert g["hub_spoke_radius_defects_negative_control"] <= 1.0


@pytest.mark.parametrize("case", ["major", "minor"])
def test_torque_free_one_period(case):
    # the closed form (torque_free.py, Landau & Lifshitz section 37) over one period, rtol 1e-12:
    # within N sqrt(n) tol (1 + 2 pi k) (integration_bound, docs/rigid-oracles.md 7C)
    r = study.torque_free_run(REF, case, periods=1.0, count=101)
    assert r["rate_error_rad_s"] <= r["rate_bound_rad_s"]
    assert r["H_error_rel"] <= r["H_bound_rel"]
    assert r["attitude_error_rad"] <= r["attitude_bound_rad"]


@pytest.mark.slow
def test_torque_free_gate():
    _, g = study.part_torque_free(REF)
    assert g["torque_free_over_bound"] <= 1.0
    assert g["torque_free_negative_control"] <= 1.0  # I2 x (1 + 1e-4) is seen
    assert g["torque_free_convergence"] <= 1.0  # the error falls with the tolerance


@pytest.mark.slow
def test_gravity_gradient_libration_gate():
    # pitch n sqrt(3 (Ix - Iz)/Iy) and the roll-yaw quartic's roots (gg_attitude.py, Hughes ch. 9)
    _, g = study.part_gg(REF)
    assert g["gg_libration_frequency"] <= 1e-5  # budget: docs/rigid-oracles.md 7D
    assert g["gg_libration_negative_control"] <= 1.0


def test_wheel_single_axis_exchange():
    # closed form (wheel_exchange.SingleAxis): w' = -M/(J - Iw), Omega' = J M/(Iw (J - Iw));
    # round-off bounds (docs/rigid-oracles.md 7E)
    r = study.wheel_run(REF, torque_N_m=0.3, duration_s=10.0)
    assert r["transverse_rate_rad_s"] == 0.0  # spin about a principal axis stays exact
    assert r["H_change_N_m_s"] <= r["H_bound_N_m_s"]
    assert r["exchange_error_N_m_s"] <= r["H_bound_N_m_s"]
    assert r["energy_minus_work_J"] <= r["E_bound_J"]
    _, g = study.part_wheel(REF)
    assert g["wheel_exchange_over_bound"] <= 1.0


def test_three_wheels_against_gyrostat():
    # a tumbling body with three motorised wheels on skewed axes against the gyrostat equations
    # integrated by scipy at rtol 1e-13 (wheel_exchange.integrate_gyrostat)
    r = study.wheels3_run(duration_s=10.0)
    for err, bound in (("rate_error_rad_s", "rate_bound_rad_s"), ("wheel_speed_error_rad_s", "wheel_speed_bound_rad_s"),
                       ("attitude_error_rad", "attitude_bound_rad"), ("H_change_rel", "H_bound_rel"),
                       ("energy_error_rel", "E_bound_rel")):  # fmt: skip
        assert r[err] <= r[bound], err


@pytest.mark.slow
def test_untethered_bodies_match_single_body_runs():
    _, g = study.part_formation(REF)
    assert g["untethered_bodies_over_bound"] <= 1.0


@pytest.mark.slow
def test_conservation_tree_everything_on():
    _, g = study.part_conservation()
    assert g["conservation_tree_over_bound"] <= 1.0
