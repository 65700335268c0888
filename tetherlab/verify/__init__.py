"""``make verify``: run every oracle comparison and study, write reports/, enforce the gates.

Gates live in references/gates.toml (quantity, threshold, unit, source).  Each check
measures one gate's value; the report lists every measurement with pass/fail, the figures of the
paper's section 4.3 cases, and a footer with commit, versions, machine and date.  The exit status
is non-zero when any gate fails.

Files: ``checkout`` (where the studies, scenes and references are: a source checkout only),
``checks`` (the physics checks and the section 4.3 figures), ``studies`` (the studies of the
checkout's ``studies`` package and their gate readers), ``controls`` (the negative controls and
the mutation matrix), ``sections`` (which check measures which gates, where each gate's evidence
is), ``runner`` (the sections as tasks on worker processes, longest first, with their timings),
``cli`` (``python -m tetherlab.verify``: the report's assembly and the exit status).
"""

from __future__ import annotations

from .checkout import ROOT, SCENES, load_study, require_checkout
from .checks import (
    DOP_TOLS,
    ENERGY_RTOL,
    EXAMPLE1_TE_RUN,
    HEYOKA_ORBITS,
    MU_EARTH,
    POWER_DAMPING_N_S,
    U_ROUND,
    _angular_momentum_internal,
    _energy_free_space,
    _integrate_diag,
    _libration_frequency_errors,
    _power_balance,
    _stiefel_error,
    check_de421,
    check_dop853,
    check_hanging_chain,
    check_heyoka_orbits,
    check_invariants,
    check_lateral_mode,
    check_libration,
    check_reproducible,
    check_stiefel_probe,
    check_stiefel_reference,
    check_vertical,
    free_space_case,
    section_43_figures,
)
from .cli import main
from .controls import (
    _PROBE_GATES,
    FAST_PAIRS,
    PROBES,
    TOOTHLESS,
    _probe_gates,
    matrix_md,
    mutation_summary,
    run_negative_controls,
)
from .runner import SECTION_COST_S, _cores, idle_machine_wall_s, run_task, run_tasks, section_tasks
from .sections import _GATES_OF, CHECKS, FIGURE_SECTION, RETIRED, gate_section
from .studies import (
    STUDIES,
    SWEEPING_STUDIES,
    _catenary_gates,
    _deorbit_gates,
    _hard_cases_gates,
    _inverse,
    _nest_headings,
    _rigid_bodies_gates,
    _stiefel_gates,
    _summary_md,
    catenary_values,
    check_catenary_probe,
    run_studies,
)
