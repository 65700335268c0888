"""Layout of the float64 parameter block ``p`` that every compiled right-hand side reads.

The block is built once per run by :func:`tetherlab.system.build_model` and never re-validated by
the kernel.  Integers are stored as floats (exact below 2**53).  The kernel also writes into it:
failure details, effect evaluation counters and scratch space (so the right-hand side allocates
nothing).

Header (indices into p):
"""

# -- header -------------------------------------------------------------------------------------
H_LEN = 0          # total length of p
H_NSTATE = 1       # length of the state vector
H_FORM = 2         # formulation code (FORM_*)
H_NRODS = 3        # total number of rods (all tethers)
H_NTETH = 4        # number of tethers (spokes) on the root body
H_ROOT_INV_M = 5   # 1/m0 of the root body (0 = fixed body, the "nail")
H_ROOT_M = 6       # m0 (0 when fixed)
H_NEFF = 7         # number of effects named by the scene
H_OFF_EFF = 8      # offset of the effect table
H_OFF_TETH = 9     # offset of the tether table
H_OFF_ROD = 10     # offset of the per-rod table
H_OFF_QUAD = 11    # offset of the quadrature table (nodes, weights) for the half-rod integrals
H_NQ = 12          # quadrature nodes per half-rod
H_OFF_SCR = 13     # offset of the scratch area
H_OFF_CNT = 14     # offset of the effect evaluation counters (indexed by effect code)
H_FAIL_CODE = 15   # failure code written by the kernel (FAIL_*)
H_FAIL_ROD = 16    # global index of the rod that failed (-1 if none)
H_FAIL_T = 17      # time of the failure
H_FAIL_VAL = 18    # a value describing the failure (e.g. the strain)
H_MIN_STRAIN = 19  # strain below which a rod counts as collapsed (FAIL_ROD_COLLAPSE)
H_EV_STOP_R = 20   # stop when the root body's radius falls below this (m; 0 = no such stop)
H_OFF_FORM = 21    # offset of the formulation's own parameters (DROMO: formulations/dromo.py); 0 = none
# -- state-layout descriptor (issue 10; docs/model.md section 12) ------------------------------------
# y = [q_trans (NQT), q_trans' (NQT), attitude (7 per rigid body: quaternion w x y z body->inertial,
#      omega in body axes), wheels (1 per wheel: axial angular momentum h_k)]
# q_trans = [r of root 0 (3), d of every rod (3 each), r of the other roots (3 each)]
H_NQT = 22         # length of q_trans: q_trans' starts at NQT, the attitude block at 2 NQT
H_OFF_ATT = 23     # state index of the attitude block (= 2 NQT)
H_NRIGID = 24      # number of rigid bodies
H_OFF_WHL = 25     # state index of the wheel block (= 2 NQT + 7 NRIGID)
H_NWHEEL = 26      # number of wheels
H_NBODY = 27       # number of bodies (kernel body order: docs/scenes.md)
H_OFF_BODY = 28    # offset of the body table
H_OFF_ORDER = 29   # offset of the tether order (NTETH floats): leaves first (elimination order)
H_OFF_WT = 30      # offset of the wheel table
H_OFF_BSCR = 31    # offset of the body scratch (BS_SIZE per body), then tether scratch (TS_SIZE each),
                   # then wheel scratch (WS_SIZE each), then a 6x6 work area (72)
H_MU_GG = 32       # mu of the central body for the gravity-gradient torque (0: no central_gravity)
H_DEFECT = 33      # MUT_* / DEFECT_*: a deliberate defect for the verification's negative controls;
                   # 0 in every user run: build_model writes 0 and no scene key reaches it; only
                   # tetherlab.mutants and the rigid-body tests set it, on a copy of the block
                   # (docs/verification.md)
H_MUTANT = H_DEFECT  # the name tetherlab.mutants uses
H_NROOT = 34       # number of root bodies
H_OFF_ROOTS = 35   # offset of the root list (NROOT body indices)
H_FAIL_EFFECT = 36    # code of the last effect whose force came out non-finite (0 = none): kernel/effects.py
H_FAIL_EFFECT_T = 37  # time of that evaluation
# -- body forces without the table walk (kernel/effects.py::_body_force; docs/integrators.md 8):
# the parameter offsets of the point-mass effects every orbit scene names, -1 when not named, and
# the (code, parameter offset) pairs of every other effect, for the loop over the rest
H_PAR_CG = 38      # parameter offset of central_gravity (-1: not named)
H_PAR_J2 = 39      # parameter offset of j2 (-1: not named)
H_PAR_SMOON = 40   # parameter offset of stiefel_moon (-1: not named)
H_NREST = 41       # number of the other effects
H_OFF_REST = 42    # offset of their (code, parameter offset) pairs
H_SIZE = 48

# -- deliberate defects: one registry of codes (tetherlab/mutants.py; like MODEL_PRINTED) -----------
MUT_NONE = 0
MUT_EQ19_DOUBLED = 1     # eq. 19 read with the corrected J_2: F_T* counted twice (chain.py)
MUT_FTP_DROPPED = 2      # F_TP of eq. 13 left out of the d equation (chain.py)
MUT_DAMPING_SIGN = 3     # T = EA eps - D eps' (chain.py)
MUT_MOON_INDIRECT = 4    # the Stiefel Moon without its indirect term (kernel/effects.py)
MUT_NO_ELASTIC_E = 5     # the elastic energy left out of the energy diagnostic (diagnostics.py)
MUT_HOLD_1PC = 6         # the static solver's holding force 1 % off (statics.py)
MUT_TE_SECULAR = 7       # the linear time element's rate without Phi d(1/n)/dsigma (formulations/dromo.py)
DEFECT_NONE = MUT_NONE
DEFECT_UNROTATED_ATTACHMENT = 21  # the attachment vector used in body axes as if inertial (chain.py)
DEFECT_NO_CENTRIPETAL = 22        # omega x (omega x rho) dropped from the attachment acceleration
MUT_UNROTATED_ATTACHMENT = DEFECT_UNROTATED_ATTACHMENT
MUT_NO_CENTRIPETAL = DEFECT_NO_CENTRIPETAL

# -- formulation codes ---------------------------------------------------------------------------
FORM_COWELL = 1
FORM_DROMO_SIGMA = 2   # DROMO, ideal anomaly sigma independent (point mass)
FORM_DROMO_TIME = 3    # DROMO elements of the root body, time independent (any scene)
FORM_COWELL_ORBIT = 4  # Cowell in a frame turning uniformly with the orbit (formulations/cowell_orbit.py)

# -- tether models ---------------------------------------------------------------------------------
MODEL_PAPER = 0    # published TMED equations (eq. 26 with the eq. 20 sign corrected)
MODEL_ENERGY = 1   # energy-consistent variant (ideal joints, Lagrangian), docs/model.md
MODEL_PRINTED = 2  # eq. 20 exactly as printed (wrong sign); for the evidence in docs/model.md only

# -- failure codes (returned by the right-hand side, details in the header) ----------------------
FAIL_NONE = 0
FAIL_ROD_COLLAPSE = 11   # a rod shortened below H_MIN_STRAIN (length -> 0: the model breaks)
FAIL_NONFINITE = 12      # a non-finite force or acceleration
FAIL_SINGULAR = 13       # the reaction system could not be solved

FAIL_TEXT = {
    FAIL_ROD_COLLAPSE: "rod collapsed (its length went to zero or below the minimum strain)",
    FAIL_NONFINITE: "non-finite force or acceleration",
    FAIL_SINGULAR: "singular reaction system",
}

# -- tether table: TT_SIZE floats per tether ----------------------------------------------------------
TT_NRODS = 0       # rods in this tether
TT_ROD0 = 1        # global index of its first rod
TT_TIP_INV_M = 2   # 1/mf of the tip body
TT_TIP_M = 3       # mf
TT_MODEL = 4       # MODEL_*
TT_TENSION_ONLY = 5  # 1: no axial force in compression (slack allowed), kinks located as events
TT_PARENT = 6      # body index at end A_1 (the root side; kernel order, after any reversal)
TT_CHILD = 7       # body index at end B_n (-1: free end)
TT_PA = 8          # attachment point of A_1 on the parent, body axes (3; zero on a point mass)
TT_SIZE = 12

# -- body table: BT_SIZE floats per body -------------------------------------------------------------
BT_M = 0           # mass (0 for a fixed body)
BT_INV_M = 1       # 1/m (0: fixed)
BT_RIGID = 2       # 1: rigid body
BT_QOFF = 3        # index in q_trans of its position (roots), -1 otherwise
BT_PARENT = 4      # tether joining it to its parent (-1: a root)
BT_AOFF = 5        # state index of its attitude block (rigid), -1 otherwise
BT_W0 = 6          # index of its first wheel
BT_NW = 7          # number of wheels
BT_NCHILD = 8      # number of tethers hanging from it (towards the leaves)
BT_CTRL = 9        # CTRL_*
BT_KP = 10         # PD gains (N m per rad, N m s)
BT_KD = 11
BT_QT = 12         # target quaternion (4), inertial target
BT_PT = 16         # its attachment point at the end of its parent tether, body axes (3)
BT_JS = 19         # J_s = J_B - sum I_k a_k a_k^T (9, body axes): the body with its wheels free
BT_JB = 28         # J_B, wheels locked (9, body axes): the mass distribution (gravity gradient)
BT_SIZE = 40
# part kind of each body (bodies/parts.py dispatches every part function on it); the code lives in
# the BT_RIGID slot, written once by build_model: PART_POINT = 0 (point mass), PART_RIGID = 1
BT_PART = BT_RIGID; PART_POINT = 0; PART_RIGID = 1  # noqa: E702

CTRL_NONE = 0
CTRL_ORBIT = 1     # hold the body's own orbit frame
CTRL_INERTIAL = 2  # hold a fixed inertial attitude

# -- wheel table: WT_SIZE floats per wheel ------------------------------------------------------------
WT_BODY = 0
WT_AX = 1          # axis (3, body axes, unit)
WT_I = 4           # axial inertia
WT_MODE = 5        # WMODE_*
WT_TAU = 6         # constant torque
WT_MAXW = 7        # speed limit (0: none)
WT_MAXT = 8        # torque limit (0: none)
WT_TOFF = 9        # offset of its time table (times then values)
WT_TN = 10         # points in the table
WT_PINV = 11       # row k of the pseudo-inverse A^+ of the control wheels' axes (3)
WT_SIZE = 16
WMODE_CONST = 0
WMODE_TABLE = 1
WMODE_CONTROL = 2

# -- body scratch (BS_SIZE per body) -----------------------------------------------------------------
BS_R = 0           # centre of mass position (3)
BS_V = 3           # its velocity (3)
BS_ROT = 6         # rotation matrix body -> inertial (9, row-major)
BS_W = 15          # angular velocity, inertial axes (3)
BS_M = 18          # effective mass matrix (3x3 or 6x6, row-major in 36)
BS_F = 54          # effective force (3 or 6)
BS_MI = 60         # its inverse (36)
BS_A = 96          # acceleration: a_G (3), alpha inertial (3)
BS_U = 102         # commanded control torque, body axes (3)
BS_TQ = 105        # gravity-gradient torque, body axes (3)
BS_C = 108         # compliance of its parent-tether attachment point (3x3): a_B = C J_n + f
BS_CF = 117        # the free acceleration f of that point (3)
BS_SIZE = 120
# tether scratch (TS_SIZE per tether)
TS_A = 0           # attachment point A_1: position (3) and velocity (3)
TS_RHO = 6         # rho_A = R rho_b, inertial (3)
TS_KAP = 9         # kappa_A = omega x (omega x rho_A) (3)
TS_B = 12          # end B_n: position (3) and velocity (3)
TS_SIZE = 18
# wheel scratch (WS_SIZE per wheel)
WS_TAU = 0         # motor torque applied
WS_SAT = 1         # 0 none, 1 torque limit, 2 speed limit
WS_SIZE = 2

# -- rod table: RT_SIZE floats per rod ---------------------------------------------------------------
RT_M = 0           # rod mass m_i
RT_LU = 1          # unstretched length L_u,i
RT_EA = 2          # axial stiffness EA (N)
RT_D = 3           # damping D of T = EA*eps + D*deps/dt (N s), paper eq. 1
RT_TETH = 4        # tether index
RT_SIZE = 8

# -- effect table: ET_SIZE floats per effect; the effect's own parameters follow at ET_OFF_PAR --------
ET_CODE = 0
ET_OFF_PAR = 1
ET_NPAR = 2
ET_SIZE = 4

N_EFFECT_CODES = 64  # size of the counter array

# -- scratch, per rod (SR_SIZE floats) and per joint (SJ_SIZE floats) ------------------------------
# per rod: R1(3) R2(3) Q(3) C(9) u(3) FE(1) eps(1) epsdot(1)
SR_R1, SR_R2, SR_Q, SR_C, SR_U, SR_FE, SR_EPS, SR_EPSD = 0, 3, 6, 9, 18, 21, 22, 23
SR_SIZE = 24
# per joint: Sinv(9) s(3) J(3)
SJ_SINV, SJ_S, SJ_J = 0, 9, 12
SJ_SIZE = 15
