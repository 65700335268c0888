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
H_FAIL_EFFECT = 22    # code of the last effect whose force came out non-finite (0 = none): kernel/effects.py
H_FAIL_EFFECT_T = 23  # time of that evaluation
H_SIZE = 24

# -- formulation codes ---------------------------------------------------------------------------
FORM_COWELL = 1
FORM_DROMO_SIGMA = 2   # DROMO, ideal anomaly sigma independent (point mass)
FORM_DROMO_TIME = 3    # DROMO elements of the root body, time independent (any scene)

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
TT_SIZE = 8

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
