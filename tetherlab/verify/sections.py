"""The report's gate sections: which check measures which gates, and where a gate's evidence is."""

from __future__ import annotations

from .hanging_chain_modes import check_hanging_chain_modes
from .inextensible import check_inextensible
from .checks import (
    check_de421,
    check_dop853,
    check_hanging_chain,
    check_heyoka_orbits,
    check_invariants,
    check_lateral_mode,
    check_libration,
    check_reproducible,
    check_stiefel_reference,
    check_vertical,
)

#: (section id, title, check function or None for a study section)
CHECKS = [
    ("libration", "Libration in circular orbit (paper section 4.3)", check_libration),
    ("vertical", "Local vertical: relative equilibrium (paper section 4.3)", check_vertical),
    ("invariants", "Invariants: angular momentum, energy, power balance (docs/model.md 6)", check_invariants),
    ("lateral", "Two-rod lateral mode (docs/model.md 9)", check_lateral_mode),
    ("hanging-chain", "Hanging chain with a tip mass: lateral modes (docs/hanging-chain.md)", check_hanging_chain),
    ("hanging-chain-bessel", "Hanging chain against Bessel: lateral modes 1 and 2, n = 4 ... 256, both models, by the "
     "linearised eigenproblem (docs/hanging-chain.md 5-7)", check_hanging_chain_modes),
    ("inextensible", "The inextensible tether model (docs/inextensible.md)", check_inextensible),
    ("gravity", "Gravity effects against heyoka (references/heyoka_orbits)", check_heyoka_orbits),
    ("de421", "DE421 Chebyshev fit (tetherlab/ephemeris.py)", check_de421),
    ("dop853", "DOP853 step-size control (Hairer, Norsett & Wanner II.4)", check_dop853),
    ("stiefel-data", "Stiefel-Scheifele references: data check (references/stiefel)", check_stiefel_reference),
    ("reproducible", "Reproducibility", check_reproducible),
]
#: figures shown in the section of the gate they belong to: the section 4.3 scenes, and the hanging
#: chain's errors against the rod count (verify/hanging_chain_modes.py)
FIGURE_SECTION = {"libration-inplane": "libration", "libration-outofplane": "libration",
                  "lateral-two-rods": "lateral", "vertical-equilibrium": "vertical",
                  "hanging-chain": "hanging-chain-bessel"}


def gate_section(gid: str) -> str:
    """The report section that holds a gate's figure and table."""
    for sid, _t, fn in CHECKS:
        if gid in _GATES_OF.get(sid, ()):
            return sid
    for prefix, sid in (("uq_deorbit", "study-uncertainty_deorbit"), ("uq_", "study-uncertainty"),
                        ("catenary", "study-catenary"), ("stiefel_", "study-stiefel_table"),
                        ("deorbit", "study-deorbit"), ("hard_cases", "study-hard_cases"), ("mutation", "controls"),
                        # the rigid-body oracles (studies/rigid_bodies.py, docs/rigid-oracles.md)
                        ("hub_spoke", "study-rigid_bodies"), ("torque_free", "study-rigid_bodies"),
                        ("gg_libration", "study-rigid_bodies"), ("wheel", "study-rigid_bodies"),
                        ("untethered_bodies", "study-rigid_bodies"), ("conservation_tree", "study-rigid_bodies"),
                        # the reel (studies/deployment.py, docs/deployment.md 8)
                        ("deployment_", "study-deployment")):
        if gid.startswith(prefix):
            return sid
    return "gates"


_GATES_OF = {
    "libration": ("libration_inplane_frequency", "libration_outofplane_frequency", "libration_rod_count_spread"),
    "vertical": ("vertical_equilibrium",),
    "invariants": ("angular_momentum_internal", "energy_model_energy", "energy_model_power_balance"),
    "lateral": ("lateral_mode_two_rods",),
    "hanging-chain": ("hanging_chain_lateral_modes",),
    "hanging-chain-bessel": ("hanging_chain_bessel_order", "hanging_chain_bessel_n64"),
    "inextensible": ("inextensible_rigid_chain", "inextensible_bessel_order", "inextensible_drift",
                     "inextensible_drift_control", "inextensible_drift_orbit", "inextensible_drift_orbit_control", "inextensible_energy", "inextensible_ea_slope",
                     "inextensible_libration"),
    "gravity": ("heyoka_orbits_position",),
    "de421": ("de421_fit_error",),
    "dop853": ("dop853_work_exponent",),
    "stiefel-data": ("stiefel_reference_data_check",),
    "reproducible": ("reproducible_runs",),
}

#: gates retired, and why (kept in the report so a reader of an old report finds them)
RETIRED = {
    "angular_momentum": "relative change of |H| about the Earth's centre: |H| is almost all orbital, so the "
    "printed eq. 20 (which breaks the tether's own angular momentum) scored 6e-12 against its 1e-9. "
    "Replaced by angular_momentum_internal, the change of H against its round-off bound, which the "
    "printed model fails",
    "stiefel_reference_agreement": "renamed stiefel_reference_data_check: it reads a number the builder "
    "stored; nothing is measured when verify runs",
}


