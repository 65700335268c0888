"""make verify's section runner (tetherlab/verify/runner.py: section_tasks, run_task, run_tasks).

The sections run in worker processes, longest first; the report must not depend on which worker
ran a section or when, and a section that fails must be reported with what it computed before
failing while the others still run.  The whole verify is make verify's job; here: the task list,
a failing section, and (slow) the same cheap sections on 1 and 2 workers giving identical values.
"""

from __future__ import annotations

import math

import pytest

from tetherlab import verify


def test_section_tasks_canonical_order():
    tasks = verify.section_tasks()
    checks = [f"check:{sid}" for sid, _t, _fn in verify.CHECKS]
    studies = [f"study:{name}" for _t, name, *_ in verify.STUDIES]
    # the report's order: checks, the section 4.3 figures, the studies, the negative controls
    assert tasks == checks + ["figures"] + studies + ["controls"]
    assert verify.section_tasks(only=["convergence"], no_controls=True) == checks + ["figures", "study:convergence"]
    # every section has a cost estimate or the default (only the start order depends on them)
    assert set(verify.SECTION_COST_S) <= set(tasks)


def test_failing_section_is_reported_with_its_rows(monkeypatch):
    def broken(rows):
        rows.append({"case": "first row, computed before the failure", "value": 1.0})
        raise RuntimeError("deliberate failure")

    def fine(rows):
        rows.append({"case": "ok"})
        return {"vertical_equilibrium": 0.0}

    monkeypatch.setattr(verify.runner, "CHECKS", [("a", "A", broken), ("b", "B", fine)])  # the runner's table
    res = verify.run_tasks(["check:a", "check:b"], "unused-out-dir", jobs=1, log=lambda *a, **k: None)
    assert res["check:a"]["error"] == "RuntimeError: deliberate failure"
    assert res["check:a"]["rows"] == [{"case": "first row, computed before the failure", "value": 1.0}]
    assert res["check:a"]["values"] == {}  # its gates are then "not measured": they fail
    assert res["check:b"]["error"] is None and res["check:b"]["values"] == {"vertical_equilibrium": 0.0}


def test_unknown_task_is_an_error_not_a_crash():
    r = verify.run_task("nonsense", "unused-out-dir")
    assert r["error"].startswith("ValueError: task: expected")


@pytest.mark.slow
def test_two_workers_give_the_serial_values(tmp_path):
    # three cheap deterministic checks (DE421 fit, DOP853 step counts, a data check): the values
    # must be bit-identical whether they run here one after the other or on two spawned workers
    tasks = ["check:de421", "check:dop853", "check:stiefel-data"]
    serial = verify.run_tasks(tasks, tmp_path / "a", jobs=1, log=lambda *a, **k: None)
    pooled = verify.run_tasks(tasks, tmp_path / "b", jobs=2, log=lambda *a, **k: None)
    for t in tasks:
        assert serial[t]["error"] is None and pooled[t]["error"] is None
        assert serial[t]["values"] == pooled[t]["values"]
        for a, b in zip(serial[t]["rows"], pooled[t]["rows"]):
            assert {k: v for k, v in a.items() if not (isinstance(v, float) and math.isnan(v))} == {
                k: v for k, v in b.items() if not (isinstance(v, float) and math.isnan(v))}


def test_idle_machine_estimate_hands_out_longest_first():
    # costs 5 (fidelity), 4 (hard cases), 3 (work-precision) by SECTION_COST_S order; two cores:
    # worker A takes 5, worker B 4, then B (free first, at 4) takes 3 -> max(5, 7) = 7
    res = {"study:fidelity": {"cpu_s": 5.0}, "study:hard_cases": {"cpu_s": 4.0},
           "study:workprecision": {"cpu_s": 3.0}}
    assert verify.idle_machine_wall_s(res, 2) == 7.0
    assert verify.idle_machine_wall_s(res, 1) == 12.0


def test_example1_gate_reads_its_own_row(tmp_path):
    """stiefel_example1_te_error is the dromo+te abm row at 1e-11 of the Stiefel table, not a
    neighbour (tolerances 1e-8 ... 1e-13 sit within numpy.isclose's default atol of each other),
    and a table without that row fails the gate."""
    import math

    import pandas as pd

    from tetherlab import verify

    form, method, tol = verify.EXAMPLE1_TE_RUN
    rows = [{"who": "tetherlab cowell dop853", "tol": 1e-13, "final_position_error_m": 0.04},
            {"who": "tetherlab dromo dop853", "tol": 1e-13, "final_position_error_m": 0.003}]
    # each tolerance its own error, so the row read is identified by its value
    rows += [{"who": f"ex1 tetherlab {form} {method}", "tol": 10.0**-k, "final_position_error_m": float(k)}
             for k in range(8, 14)]  # fmt: skip
    pd.DataFrame(rows).to_csv(tmp_path / "stiefel_table.csv", index=False)
    assert verify._stiefel_gates(tmp_path)["stiefel_example1_te_error"] == -math.log10(tol)
    pd.DataFrame(rows[:2]).to_csv(tmp_path / "stiefel_table.csv", index=False)
    assert verify._stiefel_gates(tmp_path)["stiefel_example1_te_error"] == math.inf


def test_studies_are_modules_of_the_checkouts_studies_package():
    import sys

    mod = verify.load_study("catenary")
    assert mod.__name__ == "studies.catenary" and sys.modules["studies.catenary"] is mod
    assert verify.load_study("catenary") is mod  # one module object (pickled dataclasses find it)


def test_outside_a_checkout_verify_says_what_is_missing(tmp_path, monkeypatch):
    # an installed tetherlab has no studies/ or references/ beside it: a clear error, not an
    # ImportError from deep inside a section
    from tetherlab.verify import checkout

    monkeypatch.setattr(checkout, "ROOT", tmp_path)
    with pytest.raises(RuntimeError, match="source checkout.*studies"):
        checkout.load_study("catenary")
    with pytest.raises(SystemExit):
        verify.main(["--out", str(tmp_path / "r")])  # argparse's error: usage and the message, status 2


def test_deployment_section_measures_every_deployment_gate(tmp_path):
    """The deployment study (studies/deployment.py, a few seconds once the kernels are compiled)
    through verify's own study runner: every deployment gate of references/gates.toml is measured
    and passes, its controls among them, and the section has its figures."""
    import tomllib

    gates = tomllib.loads((verify.ROOT / "references" / "gates.toml").read_text())
    sections, values, failures = verify.run_studies(tmp_path, ["deployment"])
    assert failures == [] and [s[0] for s in sections] == ["deployment"]
    wanted = {g for g in gates if g.startswith("deployment_")}
    assert len(wanted) == 61 and wanted <= set(values)
    for g in wanted:
        assert values[g] is not None and values[g] <= gates[g]["threshold"], (g, values[g])
        assert verify.gate_section(g) == "study-deployment"
    md = sections[0][2]
    for fig in ("deployment_length_rods", "deployment_momentum", "deployment_exponential_angle",
                "deployment_retrieval_invariant", "deployment_spool", "deployment_seds",
                "deployment_hub_attitude", "deployment_spoke_attitude"):
        assert f"(deployment/{fig}.png)" in md and (tmp_path / "deployment" / f"{fig}.png").is_file()


def test_deployment_part_that_fails_leaves_its_gates_unmeasured(tmp_path, monkeypatch):
    mod = verify.load_study("deployment")

    def broken():
        raise RuntimeError("deliberate failure")

    monkeypatch.setattr(mod, "part_exponential", broken)
    mod.main([str(tmp_path), "--quiet", "--parts", "ABE"])
    from tetherlab.verify.studies import _deployment_gates

    values = _deployment_gates(tmp_path)
    assert values["deployment_exponential_angle_over_budget"] is None  # "not measured": verify fails it
    assert values["deployment_no_ldot_negative_control"] is None
    assert values["deployment_momentum_over_bound"] is not None  # the other parts still ran
    assert "E FAILED: RuntimeError: deliberate failure" in (tmp_path / "deployment.md").read_text()
