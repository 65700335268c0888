"""Layout of the float64 parameter block ``p`` that every compiled right-hand side reads.

The block is built once per run by :func:`tetherlab.system.build_model` and never re-validated by
the kernel.  Its slots, tables and records are DECLARED in :mod:`tetherlab.kernel.schema` (name,
unit, meaning, region); the integer constants the kernels index with (``H_*`` header slots,
``TT_*`` tether, ``BT_*`` body, ``WT_*`` wheel, ``RT_*`` rod and ``ET_*`` effect record fields,
``BS_*``/``TS_*``/``WS_*``/``SR_*``/``SJ_*`` scratch records, each table's ``<prefix>SIZE``) are
generated from it below as plain module-level ints, so numba folds them into the kernels.  Python
code outside the kernels reads the block through :class:`tetherlab.model.params.ParamView`
(tests/test_param_schema.py enforces it).

The codes stored in the block (formulations, tether models, failures, defects, controls, wheel
modes) are declared here.
"""

from .schema import CONSTANTS as _CONSTANTS
from .schema import N_EFFECT_CODES  # noqa: F401  (size of the counter array)

globals().update(_CONSTANTS)
H_MUTANT = _CONSTANTS["H_DEFECT"]  # the name tetherlab.mutants uses

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
DEFECT_REEL_RESCALED = 23         # a reel's tether as the peers pay it out: n fixed rods of L(t)/n, no flux (tether/reel.py)
DEFECT_REEL_NO_LDOT = 24          # the strain rate of the rod at a reel without its l' term (tether/reel.py)
DEFECT_REEL_FROZEN = 25           # the kernel ignores the reel's law: L stays L0 (tether/reel.py)
DEFECT_REEL_NO_EXIT_TORQUE = 26   # a reel on a rigid body without the torque of the exit's momentum flux (tether/reel_hub.py)
DEFECT_REEL_NO_RING = 27          # a reel on a rigid body without the ring's angular momentum left in the body (tether/reel_hub.py)
DEFECT_SPOOL_UNCOUPLED = 28       # the spool's L'' solved with the exit tension at L'' = 0 (tether/reel_spool.py)
DEFECT_TENSION_K2_SIGN = 29       # the tension law with the sign of its rate gain k2 flipped (tether/reel_spool.py)
DEFECT_SPOOL_TORQUE_UNLIMITED = 30  # the spool's balance with the motor's unlimited torque, its outputs with the limited one (tether/reel_spool.py)
DEFECT_SPOOL_NO_SPEED_BRAKE = 31    # the spool's balance without the regulating brake, its outputs with it (tether/reel_spool.py)
DEFECT_SPOOL_TORQUE_ONE_SIDED = 45  # the motor's torque limit with its upper corner dropped: bent above -tau_max only (tether/reel_spool.py)
DEFECT_TENSION_3L = 46             # the tension law's 3 l_c read as 3 L: T_c = m* Omega^2 [3 L + k1 (L - l_c) + ...] (tether/reel_spool.py)
DEFECT_INEXT_NO_VSQ = 41          # the inextensible rod's constraint without |d'|^2 in kappa (tether/inextensible.py)
DEFECT_WHEELS_NO_GYRO = 42        # a rigid body's gyroscopic torque without its wheels' momentum: omega x J_s omega only (bodies/rigid_body.py)
DEFECT_REEL_RING_FULL = 43        # a reel on a rigid body whose stored ring keeps the full line's inertia as it pays out (tether/reel_hub.py)
DEFECT_REEL_ONE_STORED = 44       # a body with several reels whose mass counts only the last reel's stored tether (tether/reel.py)
DEFECT_CANISTER_AS_DRUM = 52      # a canister's exit jump taken as a drum's, rho L'^2 eps in place of rho L'^2 (1 + eps) (tether/reel_spool.py)
DEFECT_HUB_DRUM_NO_SPIN = 50      # a drum under a spool law on a rigid hub without its own spin J L'/R in the hub's balance nor the hub's alpha in the spool's (tether/reel_hub.py, tether/reel_spool.py)
DEFECT_STAGE_FIRST_ROD = 61       # a tension law's stage switched on its first rod's length instead of the deployed length (kernel/events.py)
DEFECT_DRUM_NO_TURNS = 62         # a drum's spool mass without its turns: J/R^2 in place of J/R^2 + rho (line - L) (tether/reel_spool.py)
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
MODEL_INEXT = 3    # inextensible rods: lengths held by constraints, tensions multipliers (docs/inextensible.md)

# -- failure codes (returned by the right-hand side, details in the header) ----------------------
FAIL_NONE = 0
FAIL_ROD_COLLAPSE = 11   # a rod shortened below H_MIN_STRAIN (length -> 0: the model breaks)
FAIL_NONFINITE = 12      # a non-finite force or acceleration
FAIL_SINGULAR = 13       # the reaction system could not be solved
FAIL_REEL_EMPTY = 14     # the variable rod at a reel reached zero length (retrieved past its end)
FAIL_REEL_SPENT = 15     # a spool law paid out so far beyond the whole line that its body's mass is gone

FAIL_TEXT = {
    FAIL_ROD_COLLAPSE: "rod collapsed (its length went to zero or below the minimum strain)",
    FAIL_NONFINITE: "non-finite force or acceleration",
    FAIL_SINGULAR: "singular reaction system",
    FAIL_REEL_EMPTY: "the rod at the reel was retrieved to zero length",
    FAIL_REEL_SPENT: "a reel paid out beyond its whole line (its body's mass with the stored tether at or below zero)",
}

# part kind of each body (bodies/parts.py dispatches every part function on it); the code lives in
# the BT_RIGID slot, written once by build_model from the part table bodies/registry.py
BT_PART = BT_RIGID

# -- reels (tether/reel.py, docs/deployment.md) ---------------------------------------------------
REEL_LAW_CONSTANT = 1     # L = L0 + v t
REEL_LAW_EXPONENTIAL = 2  # L = L0 exp(r t)
REEL_LAW_TABLE = 3        # L(t) a natural cubic spline through a table (C2: L'' continuous)
REEL_LAW_SPOOL = 4        # L, L' state: the spool's balance with a torque and friction (tether/reel_spool.py)
REEL_LAW_TENSION = 5      # L, L' state: the spool's torque sets the commanded tension (tether/reel_spool.py)
REEL_EXIT_CANISTER = 1    # material at rest in the body: a jump of rho L'^2 and the Carnot loss
REEL_EXIT_DRUM = 2        # material already at rim speed: no jump at the exit

# -- body controls ---------------------------------------------------------------------------------
CTRL_NONE = 0
CTRL_ORBIT = 1     # hold the body's own orbit frame
CTRL_INERTIAL = 2  # hold a fixed inertial attitude

# -- wheel modes -----------------------------------------------------------------------------------
WMODE_CONST = 0
WMODE_TABLE = 1
WMODE_CONTROL = 2

