"""studies/workprecision.py: heyoka's Stiefel points on the work-precision axes.

The fast tests never import heyoka (it is an oracle): they check that the study runs and says why
heyoka's points are absent when it is missing, that heyoka's rows (no rhs count) are drawn and
tabled without faking a number, and that the heyoka summary refuses a scene it cannot integrate
before heyoka is needed.  The ``oracle`` test runs heyoka itself (skipped without it) against the
rows stored in references/stiefel/reference.json (built by references/stiefel/build_reference.py).
"""

from __future__ import annotations

import importlib.util
import json
import math
import sys

import pytest

from tests.helpers import ROOT, SCENES
from tetherlab.scene import load_scene

REF = json.loads((ROOT / "references" / "stiefel" / "reference.json").read_text())


@pytest.fixture(scope="module")
def wp():
    spec = importlib.util.spec_from_file_location("tetherlab_study_workprecision", ROOT / "studies" / "workprecision.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod  # the Case dataclass looks its module up there
    spec.loader.exec_module(mod)
    yield mod
    sys.modules.pop(spec.name, None)


def _no_heyoka(monkeypatch):
    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "heyoka" else real(name, *a))


def test_heyoka_grid_reaches_the_double_floor(wp):
    # tolerances 1e-4 ... 1e-13 at least, and tighter to heyoka's accuracy floor
    assert all(t in wp.HEYOKA_TOLS for t in wp.TOLERANCES)
    assert min(wp.HEYOKA_TOLS) == sys.float_info.epsilon
    assert wp._tol_str(1e-13) == "1e-13" and wp._tol_str(sys.float_info.epsilon) == "2.22e-16"


def test_study_without_heyoka_says_why(wp, monkeypatch, tmp_path):
    _no_heyoka(monkeypatch)
    note = wp.heyoka_missing()
    assert note is not None and "heyoka is not installed" in note
    # a tiny libration case: the study runs to its report, without heyoka rows and without a crash
    case = wp.libration_cases((1,), "0.05 orbits")[0]
    rows = wp.work_precision([case], tmp_path, {"dop853": [1e-6, 1e-8]}, heyoka=True, workers=1, progress=False)
    assert rows and all(r["ok"] for r in rows)
    assert not any(r["method"] == wp.HEYOKA_METHOD for r in rows)
    md = wp.report_md(rows, note)
    assert "heyoka's points are absent" in md and "heyoka is not installed" in md
    assert (tmp_path / "work_precision_wall.png").is_file()
    assert not (tmp_path / "work_precision_stiefel.png").exists()  # nothing of heyoka's to draw


def _synthetic_rows(wp):
    rows = []
    for k, tol in enumerate((1e-6, 1e-9, 1e-12)):
        rows.append({"case": "Stiefel dromo", "method": "dop853", "tol": tol, "ok": True, "error": "", "cached": False,
                     "error_m": 10.0 ** (4 - 3 * k), "wall_s": 1e-3 * (k + 1), "n_rhs": 5000.0 * (k + 1),
                     "n_steps": 300.0 * (k + 1)})  # fmt: skip
        rows.append({"case": wp.HEYOKA_CASE, "method": wp.HEYOKA_METHOD, "tol": tol, "ok": True, "error": "",
                     "cached": False, "error_m": 10.0 ** (3 - 3 * k), "wall_s": 8e-4 * (k + 1), "n_rhs": math.nan,
                     "n_steps": 3000.0 + 100 * k})  # fmt: skip
    rows.append({"case": wp.HEYOKA_CASE, "method": wp.HEYOKA_METHOD, "tol": 1e-15, "ok": False,
                 "error": "ModuleNotFoundError: No module named 'heyoka'", "cached": False})  # fmt: skip
    return rows


def test_heyoka_rows_are_drawn_and_tabled_without_an_rhs_count(wp, tmp_path):
    rows = _synthetic_rows(wp)
    wp.figures(rows, tmp_path)
    for name in ("wall", "rhs", "stiefel"):
        assert (tmp_path / f"work_precision_{name}.png").stat().st_size > 1000
    md = wp.report_md(rows, None)
    heyoka_lines = [line for line in md.splitlines() if line.startswith(f"| {wp.HEYOKA_CASE} |")]
    assert len(heyoka_lines) == 4
    # no rhs number for a Taylor method, its Taylor steps instead; a failed oracle row is shown
    assert all("n/a (Taylor)" in line for line in heyoka_lines[:3])
    assert "FAILED: ModuleNotFoundError" in heyoka_lines[3]
    assert "![stiefel](work_precision_stiefel.png)" in md


def test_heyoka_summary_refuses_other_scenes_before_needing_heyoka():
    from tetherlab.summaries import stiefel_heyoka_final_state

    with pytest.raises(ValueError, match="expected the Stiefel-Scheifele scene"):
        stiefel_heyoka_final_state(load_scene(SCENES / "libration-inplane.toml"))
    st = load_scene(SCENES / "stiefel-scheifele.toml").replace(**{"integrator.rtol": 1e-10, "integrator.atol": 1e-12})
    with pytest.raises(ValueError, match="atol == rtol"):
        stiefel_heyoka_final_state(st)


@pytest.mark.oracle
def test_heyoka_summary_matches_the_stored_heyoka_rows(wp):
    pytest.importorskip("heyoka")
    from tetherlab.summaries import stiefel_heyoka_final_state

    base = load_scene(SCENES / "stiefel-scheifele.toml").replace(**{"output.count": 2})
    stored = {row["tol"]: row for row in REF["heyoka_double"]["rows"]}
    # the same integrator at the same tolerance as references/stiefel/build_reference.py, whose
    # expression takes the constants as runtime parameters (heyoka_rows: as literals), so the
    # two round differently: equal where truncation dominates (1e-6, 1e-8), within a few per
    # cent at 1e-13 (measured 1.6 %: 3.99 against 4.05 cm)
    for tol, rel in ((1e-6, 1e-3), (1e-8, 1e-3), (1e-13, 0.1)):
        s = stiefel_heyoka_final_state(base.replace(**{"integrator.rtol": tol, "integrator.atol": tol}))
        err = wp.position_error_m(s, wp.stiefel_truth())
        assert err == pytest.approx(stored[tol]["final_position_error_m"], rel=rel)
        assert s["n_steps"] == pytest.approx(stored[tol]["n_steps"], rel=1e-2)
        assert s["wall_s"] > 0 and "n_rhs" not in s  # a Taylor method has no rhs evaluations


# -- rod count as an axis (docs/verification.md section 7) --------------------------------------
def test_rod_axis_cases_are_damped_libration_against_a_reference_of_the_same_n(wp):
    cases = wp.rod_axis_cases()
    # error against wall time at n = 4 ... 128 (studies/workprecision.py ROD_AXIS_RODS)
    assert [c.scene.tethers[0].rods for c in cases] == [4, 8, 16, 32, 64, 128]
    for c in cases:
        t = c.scene.tethers[0]
        assert t.damping_N_s == 2e4  # the damped rows of tetherlab/benchmarks/cost_vs_n.py
        assert c.reference.tethers[0].rods == t.rods  # each n is its own problem
        # the reference: radau5 tighter than every point of the axis (studies/workprecision.py)
        assert c.reference.integrator.method == "radau5"
        assert c.reference.integrator.rtol < min(c.methods["radau5"])
        assert list(c.methods) == ["radau5"] and max(c.methods["radau5"]) == 1e-5


def test_rod_axis_table_fits_the_exponent(wp):
    # synthetic rows: wall = 0.01 n^1.5 s, steps = 100 n (exponents 1.5 and 1 by construction)
    rows = []
    for n in (4, 8, 16, 32):
        for tol in (1e-6, 1e-8):
            rows.append({"case": f"{wp.ROD_AXIS_PREFIX}{n}", "method": "radau5", "tol": tol, "ok": True,
                         "error_m": tol, "wall_s": 0.01 * n**1.5, "n_steps": 100.0 * n, "n_rhs": 1000.0 * n})
    rows.append({"case": "libration n=1", "method": "dop853", "tol": 1e-6, "ok": True, "error_m": 1.0,
                 "wall_s": 1.0, "n_steps": 1.0, "n_rhs": 1.0})  # another case: not on the rod axis
    md = wp.rod_axis_tables(rows)
    body = [ln for ln in md if ln.startswith("| 1e-")]
    assert len(body) == 2
    for ln in body:
        cells = [c.strip() for c in ln.strip("|").split("|")]
        assert cells[-2] == "1.50" and cells[-1] == "1.00"
    assert wp.rod_axis_tables([rows[-1]]) == []  # no rod axis, no table
    assert math.isnan(wp.fit_exponent([4], [1.0]))
