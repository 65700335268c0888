"""The declared schema of the float64 parameter block ``p``: every slot, table and record, once.

The compiled kernels take one pointer (``p``) and index it with the integer constants of
:mod:`tetherlab.kernel.layout`; those constants are GENERATED here, so a slot is declared in one
place with its unit and meaning, and its index follows from the declaration order.  Python code
outside the kernels reads the block through :class:`tetherlab.model.params.ParamView`.

The block is a sequence of REGIONS, each contiguous, in this order:

* ``report``  what the kernel writes for the caller: the failure record (code, rod, time, value),
  the record of the last non-finite effect, and the effect evaluation counters;
* ``defect``  the deliberate defect of the verification's negative controls (0 in every user run);
* ``params``  the model: the header scalars, then the model-sized tables (effects, tethers, rods,
  quadrature, bodies, order, roots, wheels, the other effects' pairs);
* ``scratch`` the kernels' workspace (per rod and joint, per body, tether and wheel, a 6x6 area),
  so the right-hand side allocates nothing.

A formulation that needs parameters of its own appends them after the block (``formulation_offset``
points at them; formulations/dromo.py, formulations/cowell_orbit.py).

A region is a list of items: a :class:`Field` (a fixed slot, or ``count`` consecutive slots) or a
:class:`Table` (an area whose length depends on the model, located by an offset field in the
header).  Fixed fields come first: a field's index is a compile-time constant only while every item
before it has a size known without the model, and :func:`layout_constants` refuses a declaration
where that is not so.  Integers are stored as floats (exact below 2**53).

To add a field: declare it in its region (a header scalar in ``BLOCK``, a record field in its
``Record``) with a unit-suffixed name; the layout constant and the view attribute follow.  A new
model-sized table: a ``Table`` with its parts and an int offset field in the params header, and its
dimension in :func:`dims_of`.
"""

from __future__ import annotations

from dataclasses import dataclass

#: Size of the effect evaluation counters (indexed by effect code).
N_EFFECT_CODES = 64

REGIONS = ("report", "defect", "params", "scratch")


@dataclass(frozen=True)
class Field:
    """``count`` consecutive slots.  ``const``: the layout constant the kernels index with (its
    index in the block, or in the record for a record field); ``name``: the unit-suffixed name the
    typed view uses; ``kind``: "int" (counts, indices, codes, offsets) or "real"."""

    name: str
    const: str
    count: int = 1
    unit: str = ""
    doc: str = ""
    kind: str = "real"


@dataclass(frozen=True)
class Record:
    """One row of a table (a tether, a body, a rod, ...).  The fields follow one another from 0;
    ``size`` (the ``<prefix>SIZE`` constant) may leave spare slots after them."""

    name: str
    prefix: str
    size: int
    fields: tuple


@dataclass(frozen=True)
class Part:
    """A run of ``count`` rows of ``record`` (or of ``width`` plain floats) inside a table;
    ``count`` names a model dimension (:func:`dims_of`) or is an int."""

    name: str
    count: object
    record: Record | None = None
    width: int = 1


@dataclass(frozen=True)
class Table:
    """A model-sized area: its parts one after the other; its offset is stored in the header field
    ``offset`` (None: the table has a constant size and a constant offset, ``const``)."""

    name: str
    parts: tuple
    offset: str | None = None
    const: str | None = None
    doc: str = ""


def _f(name, const, count=1, unit="", doc="", kind="real"):
    return Field(name, const, count, unit, doc, kind)


def _i(name, const, doc="", count=1):
    return Field(name, const, count, "", doc, "int")


# -- records ---------------------------------------------------------------------------------------
TETHER = Record("tether", "TT_", 13, (
    _i("n_rods", "TT_NRODS", "rods in this tether"),
    _i("rod0", "TT_ROD0", "global index of its first rod"),
    _f("tip_inv_mass_1_kg", "TT_TIP_INV_M", unit="1/kg", doc="1/mf of the tip body"),
    _f("tip_mass_kg", "TT_TIP_M", unit="kg", doc="mf"),
    _i("model", "TT_MODEL", "MODEL_*"),
    _i("tension_only", "TT_TENSION_ONLY", "1: no axial force in compression (slack allowed), kinks located as events"),
    _i("parent", "TT_PARENT", "body index at end A_1 (the root side; kernel order, after any reversal)"),
    _i("child", "TT_CHILD", "body index at end B_n (-1: free end)"),
    _f("parent_point_m", "TT_PA", 3, "m", "attachment point of A_1 on the parent, body axes (zero on a point mass)"),
    _i("part", "TT_PART", "its part kind (tether/registry.py; the dispatcher tether/parts.py reads it)"),
    _i("reel", "TT_REEL", "1 + index of the reel paying it out at A_1 (0: none; tether/reel.py)"),
))

BODY = Record("body", "BT_", 40, (
    _f("mass_kg", "BT_M", unit="kg", doc="mass (0 for a fixed body)"),
    _f("inv_mass_1_kg", "BT_INV_M", unit="1/kg", doc="1/m (0: fixed)"),
    _i("rigid", "BT_RIGID", "1: rigid body"),
    _i("qtrans_index", "BT_QOFF", "index in q_trans of its position (roots), -1 otherwise"),
    _i("parent", "BT_PARENT", "tether joining it to its parent (-1: a root)"),
    _i("attitude_index", "BT_AOFF", "state index of its attitude block (rigid), -1 otherwise"),
    _i("wheel0", "BT_W0", "index of its first wheel"),
    _i("n_wheels", "BT_NW", "number of wheels"),
    _i("n_children", "BT_NCHILD", "number of tethers hanging from it (towards the leaves)"),
    _i("control", "BT_CTRL", "CTRL_*"),
    _f("kp_N_m", "BT_KP", unit="N m/rad", doc="PD gain"),
    _f("kd_N_m_s", "BT_KD", unit="N m s", doc="PD gain"),
    _f("target_quaternion", "BT_QT", 4, doc="target quaternion (w x y z), inertial target"),
    _f("child_point_m", "BT_PT", 3, "m", "its attachment point at the end of its parent tether, body axes"),
    _f("js_kg_m2", "BT_JS", 9, "kg m^2", "J_s = J_B - sum I_k a_k a_k^T, body axes: the body with its wheels free"),
    _f("jb_kg_m2", "BT_JB", 9, "kg m^2", "J_B, wheels locked, body axes: the mass distribution (gravity gradient)"),
))

WHEEL = Record("wheel", "WT_", 16, (
    _i("body", "WT_BODY", "body index"),
    _f("axis", "WT_AX", 3, doc="axis (body axes, unit)"),
    _f("inertia_kg_m2", "WT_I", unit="kg m^2", doc="axial inertia"),
    _i("mode", "WT_MODE", "WMODE_*"),
    _f("torque_N_m", "WT_TAU", unit="N m", doc="constant torque"),
    _f("max_speed_rad_s", "WT_MAXW", unit="rad/s", doc="speed limit (0: none)"),
    _f("max_torque_N_m", "WT_MAXT", unit="N m", doc="torque limit (0: none)"),
    _i("table_offset", "WT_TOFF", "offset of its time table (times then values)"),
    _i("table_points", "WT_TN", "points in the table"),
    _f("pinv_row", "WT_PINV", 3, doc="row k of the pseudo-inverse A^+ of the control wheels' axes"),
    _f("torque_limit_lock", "WT_LOCKT", doc="the torque limit's branch: -1 decided per evaluation, 0 off, 1 on "
       "(locked between located events: bodies/wheels.py)"),
    _f("speed_limit_lock", "WT_LOCKW", doc="the speed cut-off's branch: -1 decided per evaluation, 0 off, 1 on"),
))

ROD = Record("rod", "RT_", 8, (
    _f("mass_kg", "RT_M", unit="kg", doc="rod mass m_i"),
    _f("length_m", "RT_LU", unit="m", doc="unstretched length L_u,i"),
    _f("ea_N", "RT_EA", unit="N", doc="axial stiffness EA"),
    _f("damping_N_s", "RT_D", unit="N s", doc="damping D of T = EA*eps + D*deps/dt, paper eq. 1"),
    _i("tether", "RT_TETH", "tether index"),
    _f("constraint_rate_1_s", "RT_CRATE", unit="1/s",
       doc="inextensible tethers: Baumgarte rate a of its length constraint, phi'' + 2a phi' + a^2 phi = 0"),
))

REEL = Record("reel", "RL_", 41, (
    _i("tether", "RL_TETH", "tether it pays out (at its end A_1)"),
    _i("body", "RL_BODY", "body carrying it (kernel order): the tether's parent"),
    _i("rod", "RL_ROD", "global index of the variable rod next to the reel (the tether's first)"),
    _i("law", "RL_LAW", "REEL_LAW_*: how the deployed length L(t) is prescribed"),
    _i("exit", "RL_EXIT", "REEL_EXIT_*: drum (no jump) or canister (material at rest, Carnot loss)"),
    _f("length0_m", "RL_L0", unit="m", doc="deployed unstretched length L at t = 0 (the law's origin)"),
    _f("speed_m_s", "RL_SPEED", unit="m/s", doc="constant law: dL/dt"),
    _f("rate_1_s", "RL_RATE", unit="1/s", doc="exponential law: L = L0 exp(rate t)"),
    _f("fixed_length_m", "RL_FIXED", unit="m", doc="unstretched length of the tether's other rods"),
    _f("density_kg_m", "RL_RHO", unit="kg/m", doc="line density rho of the tether"),
    _f("body_mass_kg", "RL_MBODY", unit="kg", doc="mass of the carrying body without the stored tether"),
    _f("line_length_m", "RL_LINE", unit="m", doc="whole line: deployed plus stored (stored = line - L)"),
    _i("table_offset", "RL_TOFF", "table law: offset of its intervals (t_k, then L's cubic coefficients)"),
    _i("table_intervals", "RL_TN", "table law: number of intervals"),
    _f("spool_radius_m", "RL_SPR", unit="m", doc="rigid body: radius of the spool (a thin ring at the reel point)"),
    _f("spool_axis", "RL_AX", 3, doc="rigid body: the spool's axis, body axes, unit (a drum turns +L'/radius about it)"),
    # the spool laws (L and L' in the state; tether/reel_spool.py, docs/deployment.md 10)
    _i("state_offset", "RL_SOFF", "spool laws: offset of [L, L'] in the first-order block (-1: a prescribed law)"),
    _f("spool_mass_kg", "RL_MEFF", unit="kg", doc="J/R^2 of the drum (0 on a canister)"),
    _f("radius_m", "RL_R", unit="m", doc="drum radius R (the torque's arm)"),
    _f("torque_N_m", "RL_TAU", unit="N m", doc="constant torque on the spool, positive hauling in"),
    _f("viscous_N_s_m", "RL_CV", unit="N s/m", doc="viscous friction c: force c L' against the pay-out"),
    _f("coulomb_N", "RL_FC", unit="N", doc="Coulomb friction F_c tanh(L'/v_s) against the pay-out"),
    _f("friction_speed_m_s", "RL_VS", unit="m/s", doc="v_s of the Coulomb friction's smooth sign"),
    _f("mstar_kg", "RL_MSTAR", unit="kg", doc="tension law: the reduced mass m*"),
    _f("omega_rad_s", "RL_OMEGA", unit="rad/s", doc="tension law: the orbit rate Omega"),
    _f("lc_m", "RL_LC", unit="m", doc="tension law: the commanded length l_c"),
    _f("k1", "RL_K1", doc="tension law: gain on l - l_c"),
    _f("k2", "RL_K2", doc="tension law: gain on l'/Omega"),
    _f("tmin_N", "RL_TMIN", unit="N", doc="tension law: the smooth lower limit of the commanded tension"),
    _f("tmax_N", "RL_TMAX", unit="N", doc="tension law: the smooth upper limit (0: none)"),
    _f("twidth_N", "RL_TW", unit="N", doc="tension law: the width of the limits' smooth corner"),
    _f("birth_m", "RL_LBIRTH", unit="m", doc="spool laws: the first rod's birth bound (a located event)"),
    _f("retire_m", "RL_LRETIRE", unit="m", doc="spool laws: the first rod's retirement bound (a located event)"),
    # the spool laws' smooth limits (docs/deployment.md 10.4)
    _f("max_torque_N_m", "RL_QMAX", unit="N m", doc="spool laws: the motor's torque limit |tau| <= tau_max (0: none)"),
    _f("torque_width_N_m", "RL_QW", unit="N m", doc="spool laws: the width of the torque limit's smooth corner"),
    _f("max_speed_m_s", "RL_VMAX", unit="m/s", doc="spool laws: the speed above which the regulating brake engages"),
    _f("speed_gain_N_s_m", "RL_VGAIN", unit="N s/m", doc="spool laws: the regulating brake's force per m/s beyond it"),
    _f("speed_width_m_s", "RL_VW", unit="m/s", doc="spool laws: the width of the speed limit's smooth corner (0: none)"),
    _f("stage_m", "RL_LSTAGE", unit="m",
       doc="tension law: the deployed length whose reaching starts the next stage (a located event; 0: none pending)"),
))

EFFECT = Record("effect", "ET_", 4, (
    _i("code", "ET_CODE", "effect code"),
    _i("par_offset", "ET_OFF_PAR", "offset of its parameters"),
    _i("n_par", "ET_NPAR", "number of its parameters"),
))

BODY_SCRATCH = Record("body_scratch", "BS_", 120, (
    _f("r_m", "BS_R", 3, "m", "centre of mass position"),
    _f("v_m_s", "BS_V", 3, "m/s", "its velocity"),
    _f("rot", "BS_ROT", 9, doc="rotation matrix body -> inertial (row-major)"),
    _f("w_rad_s", "BS_W", 3, "rad/s", "angular velocity, inertial axes"),
    _f("m_eff", "BS_M", 36, doc="effective mass matrix (3x3 or 6x6, row-major in 36)"),
    _f("f_eff", "BS_F", 6, doc="effective force (3 or 6)"),
    _f("m_eff_inv", "BS_MI", 36, doc="its inverse"),
    _f("acc", "BS_A", 6, doc="acceleration: a_G (3), alpha inertial (3)"),
    _f("control_torque_N_m", "BS_U", 3, "N m", "commanded control torque, body axes"),
    _f("gg_torque_N_m", "BS_TQ", 3, "N m", "gravity-gradient torque, body axes"),
    _f("compliance", "BS_C", 9, doc="compliance of its parent-tether attachment point (3x3): a_B = C J_n + f"),
    _f("free_acc_m_s2", "BS_CF", 3, "m/s^2", "the free acceleration f of that point"),
))

TETHER_SCRATCH = Record("tether_scratch", "TS_", 18, (
    _f("a", "TS_A", 6, doc="attachment point A_1: position (3) and velocity (3)"),
    _f("rho_m", "TS_RHO", 3, "m", "rho_A = R rho_b, inertial"),
    _f("kappa", "TS_KAP", 3, doc="kappa_A = omega x (omega x rho_A)"),
    _f("b", "TS_B", 6, doc="end B_n: position (3) and velocity (3)"),
))

WHEEL_SCRATCH = Record("wheel_scratch", "WS_", 4, (
    _f("torque_N_m", "WS_TAU", unit="N m", doc="motor torque applied"),
    _i("saturation", "WS_SAT", "0 none, 1 torque limit, 2 speed limit"),
    _f("command_N_m", "WS_CMD", unit="N m", doc="motor torque commanded, before its limits"),
    _f("speed_rad_s", "WS_SPEED", unit="rad/s", doc="speed relative to the body"),
))

ROD_SCRATCH = Record("rod_scratch", "SR_", 24, (
    _f("r1", "SR_R1", 3), _f("r2", "SR_R2", 3), _f("q", "SR_Q", 3),
    _f("c", "SR_C", 2, doc="(c1, c2) of C = c1 I + c2 u u^T (eq. 20 corrected)"),
    _f("u", "SR_U", 3), _f("fe", "SR_FE"), _f("eps", "SR_EPS", doc="strain"),
    _f("epsdot_1_s", "SR_EPSD", unit="1/s", doc="strain rate"),
    _f("m_coeffs_1_kg", "SR_M", 2, unit="1/kg",
       doc="(al, be) of M = al I + be u u^T = (sqrt3 C - I)/m, kept by the elimination for the back substitution"),
))

JOINT_SCRATCH = Record("joint_scratch", "SJ_", 15, (
    _f("sinv", "SJ_SINV", 9), _f("s", "SJ_S", 3), _f("j_N", "SJ_J", 3, "N", "joint reaction"),
))

REEL_SCRATCH = Record("reel_scratch", "RS_", 16, (
    _f("length_m", "RS_L", unit="m", doc="deployed unstretched length L(t)"),
    _f("speed_m_s", "RS_LD", unit="m/s", doc="dL/dt"),
    _f("accel_m_s2", "RS_LDD", unit="m/s^2", doc="d2L/dt2"),
    _f("rod_length_m", "RS_LROD", unit="m", doc="unstretched length l of the variable rod"),
    _f("lambda_1_s", "RS_LAM", unit="1/s", doc="dl/dt / l"),
    _f("kappa_1_s2", "RS_KAP", unit="1/s^2", doc="d(lambda)/dt - lambda^2 = l''/l - 2 (l'/l)^2"),
    _f("jump_N", "RS_JUMP", unit="N", doc="momentum flux through the exit, rho L'^2 (1 + eps)"),
    _f("torque_N_m", "RS_TAU", unit="N m", doc="spool laws: torque of the brake or motor, positive hauling in"),
    _f("friction_N", "RS_FR", unit="N", doc="spool laws: friction force against the pay-out"),
    _f("brake_force_N", "RS_FB", unit="N", doc="spool laws: torque/R + friction, the force holding the line back"),
    _f("command_N", "RS_TCMD", unit="N", doc="tension law: the commanded exit tension"),
    _f("spool_mass_kg", "RS_MEFF", unit="kg", doc="spool laws: J/R^2 + rho (stored) on a drum, 0 on a canister"),
    _f("exit_tension_N", "RS_TEX", unit="N", doc="spool laws: the line's tension at the exit, -J_0.u"),
    _f("torque_command_N_m", "RS_QCMD", unit="N m", doc="spool laws: the motor's torque before its limit"),
    _f("speed_brake_N", "RS_FV", unit="N", doc="spool laws: the speed-regulating brake's force against the pay-out"),
))

RECORDS = (TETHER, BODY, WHEEL, ROD, EFFECT, REEL, BODY_SCRATCH, TETHER_SCRATCH, WHEEL_SCRATCH, ROD_SCRATCH,
           JOINT_SCRATCH, REEL_SCRATCH)

# -- the block, region by region ---------------------------------------------------------------------
BLOCK = {
    "report": (
        _i("fail_code", "H_FAIL_CODE", "failure code written by the kernel (FAIL_*)"),
        _i("fail_rod", "H_FAIL_ROD", "global index of the rod that failed (-1 if none)"),
        _f("fail_time_s", "H_FAIL_T", unit="s", doc="time of the failure"),
        _f("fail_value", "H_FAIL_VAL", doc="a value describing the failure (e.g. the strain)"),
        _i("fail_effect_code", "H_FAIL_EFFECT", "code of the last effect whose force came out non-finite (0 = none)"),
        _f("fail_effect_time_s", "H_FAIL_EFFECT_T", unit="s", doc="time of that evaluation"),
        Table("counters", (Part("counts", N_EFFECT_CODES),), offset="H_OFF_CNT", const="CNT0",
              doc="effect evaluation counters, indexed by effect code (kernel/effects.py)"),
    ),
    "defect": (
        _i("defect", "H_DEFECT", "MUT_* / DEFECT_*: a deliberate defect for the negative controls; 0 in every "
           "user run (build_model writes 0, no scene key reaches it; tetherlab.mutants and the tests set it "
           "on a copy)"),
    ),
    "params": (
        _i("block_length", "H_LEN", "total length of p (with any formulation block)"),
        _i("n_state", "H_NSTATE", "length of the state vector"),
        _i("formulation", "H_FORM", "formulation code (FORM_*)"),
        _i("n_rods", "H_NRODS", "total number of rods (all tethers)"),
        _i("n_tethers", "H_NTETH", "number of tethers"),
        _f("root_inv_mass_1_kg", "H_ROOT_INV_M", unit="1/kg", doc="1/m0 of the root body (0 = fixed body)"),
        _f("root_mass_kg", "H_ROOT_M", unit="kg", doc="m0 (0 when fixed)"),
        _i("n_effects", "H_NEFF", "number of effects named by the scene"),
        _i("n_quadrature", "H_NQ", "quadrature nodes per half-rod"),
        _f("min_strain", "H_MIN_STRAIN", doc="strain below which a rod counts as collapsed (FAIL_ROD_COLLAPSE)"),
        _f("stop_radius_m", "H_EV_STOP_R", unit="m", doc="stop when the root's radius falls below this (0 = none)"),
        _i("wheel_limit_events", "H_EV_WHEELS", "1: the wheels' torque and speed limits are event components "
           "(kernel/events.py; the Cowell formulation), 0: not located"),
        _f("interval_end_s", "H_INTERVAL_END", unit="s", doc="end of the smooth interval being integrated (the next "
           "breakpoint): time tables take their left limit there, their right limit elsewhere (-1 = none)"),
        _i("formulation_offset", "H_OFF_FORM", "offset of the formulation's own parameters (0 = none)"),
        # state-layout descriptor (docs/model.md section 12): y = [q_trans, q_trans', attitude, wheels]
        _i("n_qtrans", "H_NQT", "length of q_trans: q_trans' starts at NQT, the attitude block at 2 NQT"),
        _i("attitude_index", "H_OFF_ATT", "state index of the attitude block (= 2 NQT)"),
        _i("n_rigid", "H_NRIGID", "number of rigid bodies"),
        _i("wheel_state_index", "H_OFF_WHL", "state index of the wheel block (= 2 NQT + 7 NRIGID)"),
        _i("n_wheels", "H_NWHEEL", "number of wheels"),
        _i("n_bodies", "H_NBODY", "number of bodies (kernel body order: docs/scenes.md)"),
        _i("n_roots", "H_NROOT", "number of root bodies"),
        _f("mu_gg_m3_s2", "H_MU_GG", unit="m^3/s^2", doc="mu for the gravity-gradient torque (0: no central_gravity)"),
        # body forces without the table walk (kernel/effects.py::_body_force)
        _i("central_gravity_par", "H_PAR_CG", "parameter offset of central_gravity (-1: not named)"),
        _i("j2_par", "H_PAR_J2", "parameter offset of j2 (-1: not named)"),
        _i("stiefel_moon_par", "H_PAR_SMOON", "parameter offset of stiefel_moon (-1: not named)"),
        _i("n_rest", "H_NREST", "number of the other effects"),
        # offsets of the model-sized tables (filled by build_model from block_offsets)
        _i("counters_offset", "H_OFF_CNT", "offset of the effect evaluation counters (a constant: the report region)"),
        _i("effects_offset", "H_OFF_EFF", "offset of the effect table"),
        _i("tethers_offset", "H_OFF_TETH", "offset of the tether table"),
        _i("rods_offset", "H_OFF_ROD", "offset of the rod table"),
        _i("quadrature_offset", "H_OFF_QUAD", "offset of the quadrature table (nodes, weights)"),
        _i("bodies_offset", "H_OFF_BODY", "offset of the body table"),
        _i("order_offset", "H_OFF_ORDER", "offset of the tether order: leaves first (elimination order)"),
        _i("roots_offset", "H_OFF_ROOTS", "offset of the root list (body indices)"),
        _i("wheels_offset", "H_OFF_WT", "offset of the wheel table"),
        _i("rest_offset", "H_OFF_REST", "offset of the other effects' (code, parameter offset) pairs"),
        _i("rod_scratch_offset", "H_OFF_SCR", "offset of the rod scratch, then the joint scratch"),
        _i("body_scratch_offset", "H_OFF_BSCR", "offset of the body scratch, then tether, wheel, a 6x6 area"),
        _i("n_reels", "H_NREEL", "number of reels (tethers of varying length; tether/reel.py)"),
        _i("reels_offset", "H_OFF_REEL", "offset of the reel table"),
        _i("reel_scratch_offset", "H_OFF_RSCR", "offset of the reel scratch"),
        Table("effects", (Part("rows", "n_effects", EFFECT), Part("pars", "n_effect_pars")), offset="H_OFF_EFF",
              doc="effect table, then every effect's own parameters"),
        Table("tethers", (Part("rows", "n_tethers", TETHER),), offset="H_OFF_TETH"),
        Table("rods", (Part("rows", "n_rods", ROD),), offset="H_OFF_ROD"),
        Table("quadrature", (Part("nodes", "n_quadrature", width=2), Part("weights", "n_quadrature", width=2)),
              offset="H_OFF_QUAD", doc="nodes xi then weights of the two half rods"),
        Table("bodies", (Part("rows", "n_bodies", BODY),), offset="H_OFF_BODY"),
        Table("order", (Part("tethers", "n_tethers"),), offset="H_OFF_ORDER"),
        Table("roots", (Part("bodies", "n_roots"),), offset="H_OFF_ROOTS"),
        Table("wheels", (Part("rows", "n_wheels", WHEEL), Part("tables", "n_wheel_table_floats")), offset="H_OFF_WT",
              doc="wheel table, then the time tables of the table-driven wheels"),
        Table("rest", (Part("pairs", "n_rest", width=2),), offset="H_OFF_REST"),
        Table("reels", (Part("rows", "n_reels", REEL), Part("tables", "n_reel_table_floats")), offset="H_OFF_REEL",
              doc="reel table, then the intervals of the table laws (5 floats each: t_k, a0..a3)"),
    ),
    "scratch": (
        Table("rod_scratch", (Part("rods", "n_rods", ROD_SCRATCH), Part("joints", "n_joints", JOINT_SCRATCH)),
              offset="H_OFF_SCR", doc="per rod, then per joint (n + 1 joints per tether)"),
        Table("body_scratch", (Part("bodies", "n_bodies", BODY_SCRATCH), Part("tethers", "n_tethers", TETHER_SCRATCH),
                               Part("wheels", "n_wheels", WHEEL_SCRATCH), Part("work6", 72)),
              offset="H_OFF_BSCR", doc="per body, per tether, per wheel, then a 6x6 work area"),
        Table("reel_scratch", (Part("reels", "n_reels", REEL_SCRATCH),), offset="H_OFF_RSCR",
              doc="per reel: its law's values and the exit's momentum flux at the last evaluation"),
    ),
}


class SchemaError(ValueError):
    """A schema declaration that cannot be laid out (overlap, gap, fixed field after a model-sized table)."""


def _part_size(part: Part, dims: dict) -> int:
    n = part.count if isinstance(part.count, int) else dims[part.count]
    return n * (part.record.size if part.record is not None else part.width)


def _check_record(rec: Record) -> dict:
    """The record's constants: fields packed from 0 in order, inside ``size``."""
    out = {}
    pos = 0
    seen = {}
    for f in rec.fields:
        if not f.const.startswith(rec.prefix):
            raise SchemaError(
                f"record {rec.name!r}: field {f.name!r} constant {f.const!r} lacks the prefix {rec.prefix!r}"
            )
        if f.name in seen or f.const in out:
            raise SchemaError(f"record {rec.name!r}: field {f.name!r} ({f.const}) declared twice")
        if f.count < 1:
            raise SchemaError(f"record {rec.name!r}: field {f.name!r} count {f.count}, expected >= 1")
        seen[f.name] = pos
        out[f.const] = pos
        pos += f.count
    if pos > rec.size:
        raise SchemaError(f"record {rec.name!r}: its fields need {pos} slots, more than its size {rec.size}")
    out[rec.prefix + "SIZE"] = rec.size
    return out


def layout_constants(block: dict = BLOCK, records: tuple = RECORDS) -> dict:
    """Every layout constant (name -> int) the declaration defines: header slots ``H_*``, the
    header size ``H_SIZE`` (slots whose index needs no model), constant-size tables' offsets, every
    record's field offsets and ``<prefix>SIZE``.  Raises SchemaError on a declaration that does
    not lay out (overlapping or repeated names, a fixed field after a model-sized table, a table
    without an offset field)."""
    out: dict[str, int] = {}

    def put(name, value, what):
        if name in out:
            raise SchemaError(
                f"{what}: the constant {name!r} is declared twice (slots {out[name]} and {value} overlap)"
            )
        out[name] = value

    for rec in records:
        for k, v in _check_record(rec).items():
            put(k, v, f"record {rec.name!r}")
    if tuple(block) != REGIONS:
        raise SchemaError(f"block regions: expected {REGIONS}, got {tuple(block)}")
    pos = 0
    fixed = True
    names = set()
    headers = {}
    for region, items in block.items():
        for it in items:
            if it.name in names:
                raise SchemaError(f"region {region!r}: the name {it.name!r} is declared twice")
            names.add(it.name)
            if isinstance(it, Field):
                if not fixed:
                    raise SchemaError(
                        f"region {region!r}: field {it.name!r} comes after a model-sized table, so its index is "
                        "not a constant; declare fixed fields before the tables"
                    )
                put(it.const, pos, f"region {region!r}")
                headers[it.const] = it
                pos += it.count
            else:
                if it.offset is None:
                    raise SchemaError(f"region {region!r}: table {it.name!r} has no offset field")
                const_size = all(isinstance(pt.count, int) for pt in it.parts)
                if fixed and const_size:
                    if it.const:
                        put(it.const, pos, f"region {region!r}")
                    pos += sum(_part_size(pt, {}) for pt in it.parts)
                else:
                    if fixed:
                        put("H_SIZE", pos, "block")
                    fixed = False
    if fixed:
        put("H_SIZE", pos, "block")
    for region, items in block.items():
        for it in items:
            if isinstance(it, Table) and (it.offset not in headers or headers[it.offset].kind != "int"):
                raise SchemaError(f"table {it.name!r}: its offset field {it.offset!r} is not an int header field")
    return out


def dims_of(*, n_rods, n_tethers, n_bodies, n_wheels, n_effects, n_effect_pars, n_quadrature, n_roots, n_rest,
            n_wheel_table_floats, n_reels=0, n_reel_table_floats=0) -> dict:
    """The model dimensions the tables are sized by (``n_joints`` follows: n + 1 joints per tether)."""
    return {
        "n_rods": n_rods, "n_tethers": n_tethers, "n_bodies": n_bodies, "n_wheels": n_wheels,
        "n_effects": n_effects, "n_effect_pars": n_effect_pars, "n_quadrature": n_quadrature, "n_roots": n_roots,
        "n_rest": n_rest, "n_wheel_table_floats": n_wheel_table_floats, "n_joints": n_rods + n_tethers,
        "n_reels": n_reels, "n_reel_table_floats": n_reel_table_floats,
    }


def block_offsets(dims: dict, block: dict = BLOCK) -> tuple[dict, int]:
    """Offset of every table (by table name) and the block's length, for a model of ``dims``."""
    offs = {}
    pos = 0
    for items in block.values():
        for it in items:
            if isinstance(it, Field):
                pos += it.count
            else:
                offs[it.name] = pos
                pos += sum(_part_size(pt, dims) for pt in it.parts)
    return offs, pos


def part_offsets(table: Table, dims: dict) -> dict:
    """Offset of each part inside ``table`` (relative to the table's offset)."""
    out = {}
    pos = 0
    for pt in table.parts:
        out[pt.name] = pos
        pos += _part_size(pt, dims)
    return out


def table(name: str) -> Table:
    """The declared table ``name`` (KeyError naming the tables when there is none)."""
    try:
        return _TABLES[name]
    except KeyError:
        raise KeyError(f"no table {name!r} in the schema; tables: {sorted(_TABLES)}") from None


def header_fields() -> dict:
    """Every fixed field of the block by view name: (region, Field)."""
    return {it.name: (region, it) for region, items in BLOCK.items() for it in items if isinstance(it, Field)}


def region_spans(dims: dict, block: dict = BLOCK) -> dict:
    """[start, stop) of every region for a model of ``dims`` (the formulation's block, if any, follows)."""
    out = {}
    pos = 0
    for region, items in block.items():
        start = pos
        for it in items:
            pos += it.count if isinstance(it, Field) else sum(_part_size(pt, dims) for pt in it.parts)
        out[region] = (start, pos)
    return out


#: Checked at import: a declaration that does not lay out stops the package from loading.
CONSTANTS = layout_constants()
_TABLES = {it.name: it for items in BLOCK.values() for it in items if isinstance(it, Table)}
