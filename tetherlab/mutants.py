"""Deliberate defects for the verification's negative controls (mutation testing of the gates).

A gate that cannot fail proves nothing.  Each entry of :data:`MUTANTS` is one realistic defect of
the simulator -- a misprint of the paper copied into the code, a dropped term, a typo in a
coefficient -- that ``make verify`` switches on, one at a time, and runs against the gates it
concerns (``tetherlab.verify``, section "Negative controls").  The report's matrix says which gate
caught which defect; the mutation score (defects no gate caught) is itself a gate.

How a defect is switched on, and why it can never reach a user's run:

* ``param`` defects live in the compiled kernels as one branch on the header slot
  ``p[H_MUTANT]`` of the parameter block (or on a value the effect's ``pack`` always writes as 1,
  or on the tether-model code), which :func:`tetherlab.system.build_model` writes as 0 and no
  scene key reaches.  :func:`active` patches ``Model.fresh_params`` -- the one place every run,
  diagnostic and static solve takes its copy of the block from -- so the copy carries the
  defect; the model's own block is untouched.  The flag is read at run time, so the kernels'
  on-disk cache is the normal one: a defect never compiles into it.
* ``patch`` defects are in pure Python (the DE421 fit degree) or recompile a private, uncached
  copy of a kernel (DOP853's error coefficient), installed for the duration of :func:`active`
  only.

The rigid-body defects (attachment vector not rotated, omega x (omega x r) dropped)
are run by studies/rigid_bodies.py itself (no cheap probe exercises a rigid body); verify credits
them from that study's control gate, as it credits eq. 20 from the hard cases' control.  The reel's
defects (fixed-segment scaling, strain rate without l', law ignored, the spool's and its limits')
are run likewise by studies/deployment.py and credited from its control gates.

Use (verification only)::

    with mutants.active("ftp_dropped"):
        value = some_gate_measurement()
"""

from __future__ import annotations

import contextlib
import math
import types
from dataclasses import dataclass, field
from typing import Callable


from .model import params as L
from .model.params import ParamView


@dataclass(frozen=True)
class Mutant:
    name: str
    defect: str  # what is wrong, in the words of the paper / the code
    where: str  # the code that carries the switch
    source: str  # what the correct version rests on
    gates: tuple  # gates expected to catch it (the harness runs these, plus the cheap others)
    path: str = ""  # the code path it sits on: verify runs the probes that exercise that path
    mutate: Callable | None = None  # param defects: p -> None, edits the copy in place
    patch: Callable | None = None  # patch defects: a context manager factory
    status: str = "active"  # "pending": slot for a defect whose code has not landed
    skip: dict = field(default_factory=dict)  # probe -> why it is not run under this defect


# -- param defects: edits of the copy of the parameter block -------------------------------------
def _effects(p, codes):
    return ParamView(p).effects_with_code(*codes)


def _printed(p):
    for t in ParamView(p).tethers:  # eq. 20 enters the paper model only (the energy model has no J_2)
        if t.model == L.MODEL_PAPER:
            t.model = L.MODEL_PRINTED


def _flag(code):
    def mutate(p):
        ParamView(p).defect = code

    return mutate


def _one_node(p):
    # the quadrature table [nodes (2 nq), weights (2 nq)] rewritten for nq = 1: xi = -1/2, +1/2
    from .system import gauss_legendre_halves

    nodes, weights = gauss_legendre_halves(1)
    v = ParamView(p)
    v.n_quadrature = 1
    v.quadrature_nodes[:] = nodes
    v.quadrature_weights[:] = weights


def _unstabilised(p):
    # the Baumgarte rate of every inextensible rod's length constraint set to 0 (tether/inextensible.py)
    rods = ParamView(p).rods
    rods.constraint_rate_1_s[:] = 0.0


def _rod_mass_off_by_one(p):
    # every rod of a tether given m / (n + 1) in place of m / n: nodes counted for rods
    v = ParamView(p)
    masses = v.rods.mass_kg
    for t in v.tethers:
        n, g0 = int(t.n_rods), int(t.rod0)
        masses[g0 : g0 + n] *= n / (n + 1.0)


def _j2_sign(p):
    from .forces import zonal

    for par in _effects(p, (zonal.CODE_J2, zonal.CODE_ZONAL)):
        p[par + 2] = -p[par + 2]  # J2 = +sqrt5 C20bar instead of -sqrt5 C20bar (forces/zonal.py)


def _moon_indirect(p):
    from .forces import stiefel_moon

    for par in _effects(p, (stiefel_moon.CODE,)):
        p[par + 3] = 0.0  # the factor of the indirect term a/rho^3 (forces/stiefel_moon.py)


# -- patch defects ---------------------------------------------------------------------------------
@contextlib.contextmanager
def _de421_degree():
    from . import ephemeris

    old = ephemeris.DEGREE
    ephemeris.DEGREE = 5
    try:
        yield
    finally:
        ephemeris.DEGREE = old


_DOP_CACHE: dict = {}
#: relative change of DOP853's first 5th-order error coefficient (a typo in its 8th digit)
DOP_E5_CHANGE = 1e-7


def _dop853_kernel():
    """erk_core recompiled (uncached, private) with E5[0] of DOP853 changed by DOP_E5_CHANGE."""
    if "core" in _DOP_CACHE:
        return _DOP_CACHE["core"]
    import numba

    from .integrators import dop853, erk

    def copy(fn, g):
        f = fn.py_func
        return types.FunctionType(f.__code__, g, f.__name__, f.__defaults__, f.__closure__)

    e5 = dop853._E5.copy()
    e5[0] *= 1.0 + DOP_E5_CHANGE
    g_dop = dict(vars(dop853))
    g_dop["_E5"] = e5
    g_erk = dict(vars(erk))
    g_erk["_dop_error"] = numba.njit(cache=False)(copy(dop853._dop_error, g_dop))
    g_erk["_solution"] = numba.njit(cache=False)(copy(erk._solution, g_erk))
    core = numba.njit(cache=False)(copy(erk.erk_core, g_erk))
    g_erk["erk_core"] = core
    _DOP_CACHE["core"] = core
    return core


@contextlib.contextmanager
def _dop853_e5():
    from .integrators import driver
    from .propagation import dromo  # DROMO's driving (the sigma-form clock) calls erk_core itself

    core = _dop853_kernel()
    old = driver.erk_core, dromo.erk_core
    driver.erk_core = core
    dromo.erk_core = core
    try:
        yield
    finally:
        driver.erk_core, dromo.erk_core = old


MUTANTS = {
    m.name: m
    for m in (
        Mutant(
            "eq20_printed_sign",
            "eq. 20 as printed: J_2 = I - (sqrt3 - 1) J(u) (transverse coefficient 2 - sqrt3)",
            "tether/rod.py rod_force (tether model code MODEL_PRINTED)",
            "docs/model.md 2.4 (misprint 1): the moment equation eq. 10 needs sqrt3",
            ("angular_momentum_internal", "lateral_mode_two_rods", "hard_cases_negative_control",
             "hanging_chain_lateral_modes", "hanging_chain_bessel_n64"),
            mutate=_printed,
            path="tether",
        ),
        Mutant(
            "eq19_doubled_ft_star",
            "eq. 19 read with the corrected J_2: 2 F_T* and J_2 (T_B - T_A) both kept (F_T* twice)",
            "tether/rod.py rod_force (p[H_MUTANT] = MUT_EQ19_DOUBLED)",
            "docs/model.md 2.4 (misprint 2): reaction moment (2 sqrt3 - 1)/sqrt3 of eq. 10",
            ("angular_momentum_internal", "lateral_mode_two_rods", "hanging_chain_bessel_n64"),
            mutate=_flag(L.MUT_EQ19_DOUBLED),
            path="tether",
        ),
        Mutant(
            "ftp_dropped",
            "F_TP of eq. 13 dropped from the d equation: (R_2 - R_1) in place of u u^T (R_2 - R_1) + J(u) Q_lag",
            "tether/rod.py rod_force (p[H_MUTANT] = MUT_FTP_DROPPED)",
            "paper eqs. 11-13, 26; docs/model.md 3 (F_TP in closed form)",
            ("libration_inplane_frequency", "libration_outofplane_frequency"),
            mutate=_flag(L.MUT_FTP_DROPPED),
            path="tether",
        ),
        Mutant(
            "one_node_per_half_rod",
            "one Gauss-Legendre node per half rod (xi = -1/2, +1/2) for the distributed forces",
            "the quadrature table of the parameter block (H_NQ), as built by system.build_model",
            "docs/model.md 3 (quadrature): 2 nodes a half are exact for the linear gravity gradient's moment",
            ("libration_inplane_frequency", "libration_outofplane_frequency"),
            mutate=_one_node,
            path="tether",
        ),
        Mutant(
            "rod_mass_off_by_one",
            "each rod of an n-rod tether given m / (n + 1) in place of m / n (the tether short of one rod's mass: "
            "an O(1/n) error)",
            "the rod records' mass_kg (RT_M), as system.build_model writes them",
            "docs/hanging-chain.md 5-7: the rods' frequencies converge to the continuum's as n^-2",
            ("hanging_chain_bessel_order", "hanging_chain_bessel_n64"),
            mutate=_rod_mass_off_by_one,
            path="tether",
        ),
        Mutant(
            "j2_sign",
            "J2 with the wrong sign (J2 = +sqrt5 C20bar), in acceleration and potential alike",
            "the j2 / zonal effect's packed coefficient (forces/zonal.py)",
            "EGM2008 (Pavlis et al. 2012): J_n = -sqrt(2n+1) C_n0bar; references/heyoka_orbits",
            ("heyoka_orbits_position", "stiefel_cowell_best_error", "stiefel_example1_te_error"),
            mutate=_j2_sign,
            path="gravity",
        ),
        Mutant(
            "moon_indirect_dropped",
            "the Stiefel Moon without its indirect term -mu' a/rho^3 (the Moon's pull on the Earth)",
            "forces/stiefel_moon.py accel (the packed factor of the indirect term, always 1)",
            "Stiefel & Scheifele 1971 sect. 23; docs/dromo.md 6; references/stiefel",
            ("stiefel_cowell_best_error",),
            mutate=_moon_indirect,
            path="moon",
        ),
        Mutant(
            "time_element_secular_dropped",
            "the linear time element's rate without Phi d(1/n)/dsigma, the mean motion's drift "
            "(dtau_l/dsigma = 1/n + grad(Phi/n).q' with Phi's own gradient only)",
            "formulations/dromo.py _linear_element_rate (p[H_MUTANT] = MUT_TE_SECULAR)",
            "docs/dromo.md section 11 (the rate derived from tau_l = tau + Phi/n); shared/references/dromo.md s6(b)",
            ("stiefel_example1_te_error",),
            mutate=_flag(L.MUT_TE_SECULAR),
            path="dromo",
        ),
        Mutant(
            "de421_low_degree",
            "DE421 positions fitted by Chebyshev polynomials of degree 5 (not 14) on 4-day segments",
            "ephemeris.DEGREE (read by fit_block at call time)",
            "ephemeris.py: DE421 stores the Moon in 4-day segments of degree 12",
            ("de421_fit_error",),
            patch=_de421_degree,
            path="de421",
        ),
        Mutant(
            "dop853_error_coefficient",
            f"DOP853's error coefficient E5[0] changed by a relative {DOP_E5_CHANGE:g} (the estimator's "
            "coefficients no longer sum to 0: an O(h) term in the error estimate)",
            "a private uncached recompile of integrators/erk.erk_core with the changed E5 (driver, DROMO)",
            "Hairer, Norsett & Wanner, Solving ODEs I, II.10 (DOP853 coefficients); integrators/tableau.py",
            ("dop853_work_exponent",),
            patch=_dop853_e5,
            path="integrator",
            skip={"stiefel": "the O(h) term of the error estimate at rtol 1e-13 over 288 days needs ~1e8 steps "
                             "(cost); the work-exponent gate sees it on a Kepler orbit in seconds"},
        ),
        Mutant(
            "damping_sign",
            "the damping term of eq. 1 with the wrong sign: T = EA eps - D eps'",
            "tether/rod.py rod_force (p[H_MUTANT] = MUT_DAMPING_SIGN)",
            "paper eq. 1; docs/model.md 6.2 (the power balance: damping dissipates D L_u eps'^2)",
            ("energy_model_power_balance",),
            mutate=_flag(L.MUT_DAMPING_SIGN),
            path="tether",
        ),
        Mutant(
            "statics_holding_force_1pc",
            "the static solver reports a holding force R_f 1 % too large",
            "statics.py solve (p[H_MUTANT] = MUT_HOLD_1PC)",
            "paper section 4.2; Irvine's elastic catenary (references/catenary)",
            ("catenary_tension_n64",),
            mutate=_flag(L.MUT_HOLD_1PC),
            path="statics",
        ),
        Mutant(
            "energy_without_elastic_term",
            "the energy diagnostic without the rods' elastic energy (1/2) EA L_u eps^2",
            "diagnostics.py evaluate_rows (p[H_MUTANT] = MUT_NO_ELASTIC_E)",
            "docs/model.md 5: the energy model's Lagrangian includes the bar's elastic energy",
            ("energy_model_energy",),
            mutate=_flag(L.MUT_NO_ELASTIC_E),
            path="diagnostics",
        ),
        # -- the rigid-body defects: the kernel's DEFECT_* codes in the same header slot.
        # No cheap probe of the harness runs a rigid body; studies/rigid_bodies.py runs both itself
        # (part B, rigid hub at a radius) and verify credits them from its control gate.
        Mutant(
            "rigid_attachment_not_rotated",
            "a tether's attachment vector on a rigid body used in body axes, not rotated to inertial",
            "bodies/rigid_body.py rigid_offset (p[H_MUTANT] = MUT_UNROTATED_ATTACHMENT)",
            "paper eq. 47 as corrected in docs/model.md section 12 (rho = R rho_b)",
            ("hub_spoke_radius_tip_over_bound", "hub_spoke_radius_defects_negative_control"),
            mutate=_flag(L.MUT_UNROTATED_ATTACHMENT),
            path="rigid",
        ),
        Mutant(
            "rigid_centripetal_dropped",
            "omega x (omega x r) dropped from the attachment point's acceleration",
            "bodies/rigid_body.py rigid_offset (p[H_MUTANT] = MUT_NO_CENTRIPETAL)",
            "paper eq. 47 (the rigid-body acceleration of a body-fixed point)",
            ("hub_spoke_radius_tip_over_bound", "hub_spoke_radius_defects_negative_control"),
            mutate=_flag(L.MUT_NO_CENTRIPETAL),
            path="rigid",
        ),
        # -- the reel's defects: the kernel's DEFECT_REEL_* codes in the same header slot.  No
        # cheap probe pays tether out of a reel; studies/deployment.py runs each beside the run it
        # must spoil and verify credits it from that study's control gate.
        Mutant(
            "reel_rescaled",
            "a reel's tether paid out as the peers do: n fixed rods of L(t)/n, mass appearing in place "
            "(no flux through the exit)",
            "tether/reel.py (p[H_MUTANT] = DEFECT_REEL_RESCALED)",
            "docs/deployment.md 1 and 4 (Reynolds' transport theorem at the exit)",
            ("deployment_momentum_over_bound", "deployment_energy_over_bound", "deployment_rescaled_negative_control"),
            mutate=_flag(L.DEFECT_REEL_RESCALED),
            path="reel",
        ),
        Mutant(
            "reel_strain_rate_without_ldot",
            "the strain rate of the rod at the reel without its l' term (the damping brakes a steady deployment)",
            "tether/reel.py (p[H_MUTANT] = DEFECT_REEL_NO_LDOT)",
            "docs/deployment.md 3.3, eq. (3.7)",
            ("deployment_exponential_tension_over_budget", "deployment_no_ldot_negative_control",
             "deployment_continuum_limit_over_budget", "deployment_continuum_no_ldot_negative_control"),
            mutate=_flag(L.DEFECT_REEL_NO_LDOT),
            path="reel",
        ),
        Mutant(
            "reel_law_frozen",
            "the kernel ignores the reel's law: the rod at the reel keeps its length",
            "tether/reel.py (p[H_MUTANT] = DEFECT_REEL_FROZEN)",
            "docs/deployment.md 7c (the libration's action, an adiabatic invariant)",
            ("deployment_retrieval_invariant", "deployment_frozen_negative_control",
             "deployment_retrieval_pendulum_over_budget", "deployment_retrieval_pendulum_frozen_negative_control"),
            mutate=_flag(L.DEFECT_REEL_FROZEN),
            path="reel",
        ),
        Mutant(
            "inextensible_unstabilised",
            "the inextensible rods' length constraints held at the acceleration level only (Baumgarte rate 0)",
            "the rod records' constraint_rate_1_s (RT_CRATE), as build_model and prepare write them",
            "docs/inextensible.md 4 (the drift of an unstabilised index-reduced constraint grows with time)",
            ("inextensible_drift", "inextensible_drift_orbit"),
            mutate=_unstabilised,
            path="inextensible",
        ),
        Mutant(
            "inextensible_centripetal_dropped",
            "the inextensible rods' constraint at the acceleration level without its |d'|^2 term: "
            "u.d'' = -(2 a d.d' + a^2 phi)/|d| in place of -(|d'|^2 + 2 a d.d' + a^2 phi)/|d|",
            "tether/inextensible.py _constrain (p[H_MUTANT] = DEFECT_INEXT_NO_VSQ)",
            "docs/inextensible.md 1 (C2: phi'' = d.d'' + |d'|^2) and 4 (B)",
            ("inextensible_rigid_chain", "inextensible_drift", "inextensible_drift_orbit", "inextensible_libration"),
            mutate=_flag(L.DEFECT_INEXT_NO_VSQ),
            path="inextensible",
        ),
        Mutant(
            "reel_hub_exit_torque_dropped",
            "a reel on a rigid body without the moment e x rho L'^2 (1 + eps) u of the exit's momentum flux",
            "tether/reel_hub.py (p[H_MUTANT] = DEFECT_REEL_NO_EXIT_TORQUE)",
            "docs/deployment.md 9.2 (the angular momentum balance of the hub with its stored tether)",
            ("deployment_hub_angular_momentum_over_bound", "deployment_hub_exit_torque_negative_control"),
            mutate=_flag(L.DEFECT_REEL_NO_EXIT_TORQUE),
            path="reel",
        ),
        Mutant(
            "reel_hub_ring_dropped",
            "a reel on a rigid body without the ring's angular momentum m' (R_s^2/2)(omega + a (a.omega)) that the "
            "material leaves in the body on its way from the spool's rim to the exit",
            "tether/reel_hub.py (p[H_MUTANT] = DEFECT_REEL_NO_RING)",
            "docs/deployment.md 9.2, eq. 9.3 (the on-axis spin-up's closed form)",
            ("deployment_hub_axis_spin_over_bound", "deployment_hub_ring_negative_control"),
            mutate=_flag(L.DEFECT_REEL_NO_RING),
            path="reel",
        ),
        Mutant(
            "wheels_gyro_dropped",
            "a rigid body's gyroscopic torque without its wheels' momentum: omega x J_s omega in place of "
            "omega x (J_s omega + h_w)",
            "bodies/rigid_body.py rigid_setup (p[H_MUTANT] = DEFECT_WHEELS_NO_GYRO)",
            "paper eq. 46; docs/deployment.md 9.5 (the spinning hub's angular momentum with its wheels)",
            ("deployment_spoke_angular_momentum_over_bound", "deployment_spoke_wheels_negative_control"),
            mutate=_flag(L.DEFECT_WHEELS_NO_GYRO),
            path="reel",
        ),
        Mutant(
            "reel_hub_ring_full",
            "a reel on a rigid body whose stored ring keeps the inertia of the full line, m_s K with "
            "m_s = rho line, as the line pays out (its first moment and the ring's term still shrink)",
            "tether/reel_hub.py reel_hub_terms (p[H_MUTANT] = DEFECT_REEL_RING_FULL)",
            "docs/deployment.md 9.5 (the spokes' spin-up along the axis, closed form)",
            ("deployment_spoke_axis_spin_over_bound", "deployment_spoke_ring_full_negative_control"),
            mutate=_flag(L.DEFECT_REEL_RING_FULL),
            path="reel",
        ),
        Mutant(
            "reel_one_stored",
            "a body carrying several reels whose mass counts only one reel's stored tether (each reel "
            "overwriting the body's mass with its dry mass plus its own stored line)",
            "tether/reel.py reel_update (p[H_MUTANT] = DEFECT_REEL_ONE_STORED)",
            "docs/deployment.md 9.5 (the hub's mass is its own plus every reel's stored tether)",
            ("deployment_spoke_momentum_over_bound", "deployment_spoke_one_stored_negative_control"),
            mutate=_flag(L.DEFECT_REEL_ONE_STORED),
            path="reel",
        ),
        Mutant(
            "spool_uncoupled",
            "the spool's L'' solved with the exit tension taken at L'' = 0 (its coupling through the first "
            "rod's apparent load dropped)",
            "tether/reel_spool.py (p[H_MUTANT] = DEFECT_SPOOL_UNCOUPLED)",
            "docs/deployment.md 10.2 (the exit tension is affine in L'')",
            ("deployment_spool_drum_over_budget", "deployment_spool_uncoupled_negative_control"),
            mutate=_flag(L.DEFECT_SPOOL_UNCOUPLED),
            path="reel",
        ),
        Mutant(
            "tension_k2_flipped",
            "the tension law with the sign of its rate gain k2 flipped",
            "tether/reel_spool.py (p[H_MUTANT] = DEFECT_TENSION_K2_SIGN)",
            "docs/deployment.md 11.3 (the characteristic polynomial)",
            ("deployment_tension_roots_over_budget", "deployment_tension_k2_negative_control"),
            mutate=_flag(L.DEFECT_TENSION_K2_SIGN),
            path="reel",
        ),
        # -- the spool limits' defects (docs/deployment.md 10.4): run by studies/deployment.py part M
        # beside the limited drum of studies/reel_limits.py and credited from its control gates.
        Mutant(
            "spool_torque_unlimited",
            "the spool's balance with the motor's unlimited command while its outputs report the limited torque",
            "tether/reel_spool.py spool_forces (p[H_MUTANT] = DEFECT_SPOOL_TORQUE_UNLIMITED)",
            "docs/deployment.md 10.4 (the limited torque is in F_b, so (10.2) and (10.3) hold with it)",
            ("deployment_limits_balance_over_bound", "deployment_limits_energy_over_bound",
             "deployment_limits_torque_unlimited_negative_control"),
            mutate=_flag(L.DEFECT_SPOOL_TORQUE_UNLIMITED),
            path="reel",
        ),
        Mutant(
            "spool_no_speed_brake",
            "the spool's balance without the regulating brake's force F_v while its outputs report it",
            "tether/reel_spool.py spool_forces (p[H_MUTANT] = DEFECT_SPOOL_NO_SPEED_BRAKE)",
            "docs/deployment.md 10.4 (the speed bound from the balance at the largest |L'|)",
            ("deployment_limits_speed_over_budget", "deployment_limits_balance_over_bound",
             "deployment_limits_energy_over_bound", "deployment_limits_no_speed_brake_negative_control"),
            mutate=_flag(L.DEFECT_SPOOL_NO_SPEED_BRAKE),
            path="reel",
        ),
        Mutant(
            "spool_torque_one_sided",
            "the motor's torque limit with its upper corner dropped: the command bent above -tau_max only",
            "tether/reel_spool.py spool_forces (p[H_MUTANT] = DEFECT_SPOOL_TORQUE_ONE_SIDED)",
            "docs/deployment.md 10.4 (|tau| <= tau_max + w e^(-2 tau_max/w) from both corners)",
            ("deployment_limits_torque_over_budget", "deployment_limits_one_sided_negative_control"),
            mutate=_flag(L.DEFECT_SPOOL_TORQUE_ONE_SIDED),
            path="reel",
        ),
        # -- the tension law's hold (docs/deployment.md 11.4, 14.2): run by studies/deployment.py parts K
        # and L beside the held YES2-like first stage and the staged retrieval, credited from their
        # control gates.
        Mutant(
            "tension_3l",
            "the tension law's 3 l_c read as 3 L: T_c = m* Omega^2 [3 L + k1 (L - l_c) + k2 L'/Omega] (the "
            "massless rest length is still l_c; the massive line's offset is divided by k1, not k1 - 3)",
            "tether/reel_spool.py tension_command (p[H_MUTANT] = DEFECT_TENSION_3L)",
            "docs/deployment.md 11.4 (the rest length with a massive line, l - l_c ~ 3 rho l^2/(2 m* (k1 - 3)))",
            ("deployment_yes2_hold_over_budget", "deployment_yes2_hold_3l_negative_control",
             "deployment_retrieval_settle_over_budget", "deployment_retrieval_settle_3l_negative_control"),
            mutate=_flag(L.DEFECT_TENSION_3L),
            path="reel",
        ),
        # -- run by studies/deployment.py part K beside the YES2-like two-stage run, credited from its control gates
        Mutant(
            "drum_no_turns",
            "a drum's spool mass without its turns: m_s = J/R^2 in place of J/R^2 + rho (line - L) (the kinetic "
            "energy the leaving turns carry through the exit, (1/2) rho L'^3, dropped from the spool's balance)",
            "tether/reel_spool.py spool_forces (p[H_MUTANT] = DEFECT_DRUM_NO_TURNS)",
            "docs/deployment.md 10.1 and 10.3 (the spool's balance with m_s' = -rho L'), 15.1",
            ("deployment_yes2_energy_over_bound", "deployment_yes2_turns_negative_control"),
            mutate=_flag(L.DEFECT_DRUM_NO_TURNS),
            path="reel",
        ),
        Mutant(
            "stage_first_rod",
            "a tension law's stage switched on its first rod's length l = L - (n - 1) l_rod instead of the "
            "deployed length L",
            "kernel/events.py event_values (p[H_MUTANT] = DEFECT_STAGE_FIRST_ROD)",
            "docs/deployment.md 10.7 (the event g = L - at_length)",
            ("deployment_yes2_switch_over_tolerance", "deployment_yes2_first_rod_negative_control"),
            mutate=_flag(L.DEFECT_STAGE_FIRST_ROD),
            path="reel",
        ),
        # -- run by studies/deployment.py part J beside the SEDS-like deployment, credited from its control gate
        Mutant(
            "canister_as_drum",
            "a canister's exit jump taken as a drum's: the spool balance with j = rho L'^2 eps in place of "
            "rho L'^2 (1 + eps) (the stored line treated as already moving at the line's speed)",
            "tether/reel_spool.py spool_forces (p[H_MUTANT] = DEFECT_CANISTER_AS_DRUM)",
            "docs/deployment.md 4 and 10.1 (the canister's material is at rest in the body and is jerked to the "
            "line's speed in the exit); 12.2 (the reduced model's exit tension rho l'^2 + F_b), 12.3 (the energy)",
            ("deployment_seds_reduced_over_budget", "deployment_seds_energy_over_bound",
             "deployment_seds_canister_negative_control"),
            mutate=_flag(L.DEFECT_CANISTER_AS_DRUM),
            path="reel",
        ),
        # -- a drum under a spool law on a rigid hub (docs/deployment.md 9.7): run by studies/deployment.py
        # part R beside the hub's drum and credited from its control gate.
        Mutant(
            "hub_drum_no_spin",
            "a drum under a spool law on a rigid hub without its own spin J (L'/R) a in the hub's balance and "
            "without the hub's angular acceleration along the axle in the spool's balance (the model before 9.7)",
            "tether/reel_hub.py reel_hub_terms, drum_axle_force (p[H_MUTANT] = DEFECT_HUB_DRUM_NO_SPIN)",
            "docs/deployment.md 9.7 (the drum's spin in the total angular momentum; the spool's balance about "
            "an axle turning with the hub)",
            ("deployment_hub_drum_angular_momentum_over_bound", "deployment_hub_drum_energy_over_bound",
             "deployment_hub_drum_negative_control"),
            mutate=_flag(L.DEFECT_HUB_DRUM_NO_SPIN),
            path="reel",
        ),
    )
}


def names(status: str = "active") -> list[str]:
    return [k for k, m in MUTANTS.items() if m.status == status]


@contextlib.contextmanager
def active(name: str | None):
    """Switch defect ``name`` on for the body of the ``with`` (None: no defect, a plain run)."""
    if name is None:
        yield None
        return
    m = MUTANTS[name]
    if m.status != "active":
        raise ValueError(f"mutant {name!r}: status {m.status!r}, its code has not landed")
    from .system import Model

    with contextlib.ExitStack() as stack:
        if m.mutate is not None:
            original = Model.fresh_params

            def fresh_params(self, _orig=original, _mut=m.mutate):
                p = _orig(self)
                _mut(p)
                return p

            Model.fresh_params = fresh_params
            stack.callback(setattr, Model, "fresh_params", original)
        if m.patch is not None:
            stack.enter_context(m.patch())
        yield m


def caught(value, threshold) -> bool:
    """A gate catches a defect when its measurement fails: over the threshold, not finite, or
    the measurement itself refused to run (None)."""
    return value is None or not (isinstance(value, (int, float)) and math.isfinite(value)) or value > threshold


__all__ = ["MUTANTS", "Mutant", "active", "caught", "names"]
