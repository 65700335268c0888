"""studies/convergence.py: the cost table (trend over the rod count and its fitted exponent) and the
study's grid (n = 256 for the three quantities).  The study itself runs in make verify."""

from __future__ import annotations

import math

import pytest

from tests.helpers import ROOT, forget_study, import_study
from tetherlab.sweep import RunRecord, load_study


@pytest.fixture(scope="module")
def conv():
    yield import_study("convergence")
    forget_study("convergence")


def test_grid_reaches_256():
    # n = 256 for the three quantities inside a 15-minute make verify (the libration at
    # n = 256 took > 330 s before the RADAU5 round-off fix, 9 s after: studies/convergence.toml)
    study = load_study(ROOT / "studies" / "convergence.toml")
    assert int(study.options["max_rods"]) == 256
    top = {case.id: max(case.grid["tethers.main.rods"]) for case in study.cases}
    assert top == {"tension": 256, "libration": 256, "lateral": 256, "lateral_equilibrium": 256}
    lateral = next(c for c in study.cases if c.id == "lateral")
    assert "orbit.motion" not in lateral.set  # the scene's own (corotating) start: no special start


def test_fit_exponent_of_a_power_law(conv):
    ns = [8, 16, 32, 64]
    assert conv.fit_exponent(ns, [2.0 * n**1.3 for n in ns]) == pytest.approx(1.3, abs=1e-12)
    assert math.isnan(conv.fit_exponent([8], [1.0]))
    assert conv.fit_exponent(ns, [1.0, None, math.nan, 8.0]) == pytest.approx(1.0)  # 8x from n = 8 to 64


def test_cost_table_gives_the_exponent_over_the_larger_counts(conv):
    class Case:
        def __init__(self, cid):
            self.id = cid

    class Study:
        cases = [Case("a")]

    class Res:  # wall = n s for n >= 8 (exponent 1); n = 1 and 2 cost 5 s (set-up), left out of the fit
        records = [RunRecord("h", f"n={n}", {"tethers.main.rods": n}, True, {"n_steps": 10.0 * n}, None,
                             5.0 if n < 8 else float(n)) for n in (1, 2, 8, 16, 32)]
        records.append(RunRecord("h", "n=64", {"tethers.main.rods": 64}, False, {}, "SimulationError: x", 1.0))

    md = conv.cost_table(Study, {"a": Res})
    row = next(ln for ln in md if ln.startswith("| a |"))
    cells = [c.strip() for c in row.strip("|").split("|")]
    assert cells[-1] == "1.00" and cells[-2] == "failed" and cells[1] == "5 (10)"
