"""The shipped reel scenes (studies/scenes/reel-*.toml) through the command line: each file reads
back as the scene of the study it comes from, and ``tetherlab run``, ``--resume`` across a birth,
``validate --probe`` and ``sweep`` over a reel parameter work on it.

Runs are shortened (a duration and an output count written over the file's, in a copy) so the
file stays fast.  Expected values: the study functions' scenes (studies/*.py, each named below),
identities between an interrupted-and-resumed run and an uninterrupted one (np.array_equal: the
run store continues the phase loop and the driver from their exact state, tests/test_reel_run.py),
and rod counts of the constant-speed retrieval worked out by hand in the test that uses them.
"""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pandas as pd
import pytest

from tests.helpers import interrupt_at_birth
from tetherlab import deployment, reelstore
from tetherlab.cli import main
from tetherlab.scene import Scene, load_scene
from tetherlab.units import parse_quantity

from .helpers import SCENES, import_study

# file -> (study module, function, keyword arguments): the scene each file was made from
SOURCES = {
    "reel-exponential": ("deployment", "exponential_scene", {}),
    "reel-seds-like": ("reel_laws", "seds_scene", {}),
    "reel-retrieval": ("reel_retrieval", "retrieval_scene", {}),
    "reel-retrieval-tension": ("reel_retrieval", "retrieval_scene", {"controlled": True}),
    "reel-yes2-like": ("reel_yes2", "yes2_scene", {}),
    "reel-hub-spoke": ("deployment_spoke", "spoke_scene", {}),
}
# a short stretch of each for the command-line runs: (duration, births and retirements, phases)
# exponential: L = 2 km exp(c Omega t) reaches the birth bound 3 km at ln(1.5)/(c Omega) = 27.8 ks;
# retrieval: the first rod of 1 km reaches retire_length 50 m after 950 s at 1 m/s;
# hub: the four first rods reach 15 m (1.5 x 10 m) together at 6.0 s (docs/deployment.md 9.5's run);
# the staged laws must keep every stage within the run (deployment.check_law): the tension-law
# retrieval's last stage starts at 3.75 orbits (its 4 retirements, docs/deployment.md 14, and 5
# stage switches: 10 phases); the YES2-like's second stage starts on reaching 3.4 km at 2232 s (a
# located event, in the changes): half an orbit (2704 s) has a birth, the switch and a birth,
# 4 phases (measured: a few seconds of wall time; marked slow as the whole run was).
SHORT = {
    "reel-exponential": ("30000 s", 1, 2),
    "reel-seds-like": ("10 min", 0, 1),
    "reel-retrieval": ("1000 s", 1, 2),
    "reel-retrieval-tension": ("3.8 orbits", 4, 10),
    "reel-yes2-like": ("0.5 orbits", 3, 4),
    # the hub: t2's birth at 6.0002191886 s ends the first phase; the three others' rods are then
    # below the bound by more than the event's bracket, so a phase of 9e-12 s ends at theirs, all
    # three taken together (docs/deployment.md 17.1)
    "reel-hub-spoke": ("8 s", 4, 3),
}


def _study_scene(stem: str) -> Scene:
    module, func, kw = SOURCES[stem]
    made = getattr(import_study(module), func)(**kw)
    return made[0] if isinstance(made, tuple) else made


def _close(a, b, path: str) -> None:
    """Equal, numbers (and 'number unit' strings of one unit) within 1e-12 relative or 1e-9 in
    their SI unit: the hub's file writes 0 where the study's cos(pi/2) leaves 1e-15 m."""
    if isinstance(a, dict) and isinstance(b, dict):
        assert set(a) == set(b), (path, set(a) ^ set(b))
        for k in a:
            _close(a[k], b[k], f"{path}.{k}")
    elif isinstance(a, list) and isinstance(b, list):
        assert len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b)):
            _close(x, y, f"{path}[{i}]")
    elif isinstance(a, str) and isinstance(b, str) and a != b:
        qa, qb = parse_quantity(a, key=path), parse_quantity(b, key=path)
        assert qa.unit == qb.unit, (path, a, b)
        assert math.isclose(qa.value, qb.value, rel_tol=1e-12, abs_tol=1e-9), (path, a, b)
    elif isinstance(a, float | int) and isinstance(b, float | int):
        assert math.isclose(a, b, rel_tol=1e-12, abs_tol=1e-9), (path, a, b)
    else:
        assert a == b, (path, a, b)


def _short_copy(tmp_path, stem: str, duration: str, count: int = 11):
    """The scene file with its duration and output count replaced (its text otherwise as shipped)."""
    text = (SCENES / f"{stem}.toml").read_text()
    text, n1 = re.subn(r'(?m)^duration = ".*"$', f'duration = "{duration}"', text)
    text, n2 = re.subn(r"(?m)^count = \d+$", f"count = {count}", text)
    assert n1 == 1 and n2 == 1
    f = tmp_path / f"{stem}.toml"
    f.write_text(text)
    return f


def test_every_reel_scene_is_listed_here():
    assert sorted(p.stem for p in SCENES.glob("reel-*.toml")) == sorted(SOURCES)


@pytest.mark.parametrize("stem", sorted(SOURCES))
def test_reel_scene_reads_back_as_its_studys_scene(stem):
    scene = load_scene(SCENES / f"{stem}.toml")
    d = scene.to_dict()
    assert Scene.from_dict(d).to_dict() == d  # the loader and to_dict round-trip
    assert scene.name == stem and scene.description and scene.tethers[0].reel is not None
    study = _study_scene(stem).to_dict()
    d.pop("description")
    d["name"] = study["name"]
    _close(d, study, stem)


@pytest.mark.parametrize("stem", [pytest.param(s, marks=pytest.mark.slow) if s == "reel-yes2-like" else s
                                  for s in sorted(SOURCES)])  # fmt: skip
def test_cli_runs_each_reel_scene_and_writes_its_phases(tmp_path, stem, capsys):
    duration, changes, phases = SHORT[stem]
    f = _short_copy(tmp_path, stem, duration)
    out = tmp_path / "run"
    assert main(["run", str(f), "--out", str(out)]) == 0
    said = capsys.readouterr().out
    rec = json.loads((out / "run.json").read_text())
    assert rec["reel"] and rec["state"] == "complete"
    assert len(rec["changes"]) == changes and len(rec["phases"]) == phases
    assert f"{phases} phases" in said
    run = reelstore.load(out)
    assert len(run.phases) == phases and run.ok
    assert float(run.reel["t_s"].iloc[-1]) == pytest.approx(load_scene(f).duration_seconds(), rel=1e-12)


def test_a_shortened_staged_scene_is_refused_naming_the_stage(tmp_path, capsys):
    # the tension-law retrieval's first stage starts at 0.75 orbit (4371.39 s); a stage started by a
    # length (the YES2-like's) is not refused: it is a located event, switched if it is reached
    f = _short_copy(tmp_path, "reel-retrieval-tension", "10 min")
    assert main(["run", str(f), "--out", str(tmp_path / "run")]) == 2
    err = capsys.readouterr().err
    assert "tethers.main.reel.stages[0].start" in err and "before 600 s" in err and "4371.39 s" in err


def test_cli_resumes_a_shipped_reel_scene_across_a_birth(tmp_path, monkeypatch, capsys):
    f = _short_copy(tmp_path, "reel-hub-spoke", "8 s", count=17)
    ref, out = tmp_path / "ref", tmp_path / "o"
    assert main(["run", str(f), "--out", str(ref), "--quiet"]) == 0
    interrupt_at_birth(monkeypatch, 2)
    assert main(["run", str(f), "--out", str(out), "--quiet"]) == 130
    assert f"tetherlab run --resume {out}" in capsys.readouterr().err
    rec = json.loads((out / "run.json").read_text())
    # the second birth ends the second phase (9e-12 s long, SHORT's note), with the third and
    # fourth in the same remap sequence (docs/deployment.md 17.1)
    assert rec["state"] == "interrupted" and len(rec["phases"]) == 2
    monkeypatch.undo()
    assert main(["run", "--resume", str(out), "--quiet"]) == 0
    a, b = reelstore.load(out), reelstore.load(ref)
    assert [c["t_s"] for c in a.changes] == [c["t_s"] for c in b.changes]
    for x, y in ((a.reel, b.reel), (a.invariants, b.invariants)):
        assert list(x.columns) == list(y.columns) and len(x) == len(y)
        for c in x.columns:
            u, v = x[c].to_numpy(), y[c].to_numpy()
            assert np.array_equal(u, v, equal_nan=u.dtype.kind == "f"), c


def test_validate_describes_the_reels_and_the_largest_layout(capsys):
    assert main(["validate", str(SCENES / "reel-seds-like.toml")]) == 0
    said = capsys.readouterr().out
    # 20 km of line in rods of 2 km, the birth bound 3 km: 1 + ceil((20 - 3) / 2) = 10 rods at most
    assert "reel main: law spool, exit canister; 200 m out of a 20000 m line" in said
    assert "1 rods now, up to 10 with 20000 m out" in said
    assert "with the most rods: state" in said


def test_probe_of_a_reel_scene_runs_its_births(capsys):
    # the hub's first births come at 6 s of simulated time, reached in well under the probe's 2 s
    assert main(["validate", str(SCENES / "reel-hub-spoke.toml"), "--probe", "2"]) == 0
    said = capsys.readouterr().out
    probe = said[said.index("probe:"):]
    births = int(re.search(r"within the probe (\d+) births", probe).group(1))
    assert births >= 4, probe
    assert "rods at its end" in probe and "up to about" in probe


def test_sweep_over_a_reel_rod_length_writes_a_deployment_table(tmp_path):
    from tetherlab.sweep import main as sweep_main

    study = tmp_path / "study.toml"
    study.write_text(f"""
name = "retrieval rods"
[[case]]
id = "rods"
scene = "{SCENES / 'reel-retrieval.toml'}"
summary = "tetherlab.summaries:deployment"
[case.set]
duration = "1000 s"
"output.count" = 11
[case.grid]
"tethers.main.reel.rod_length" = ["1000 m", "500 m"]
""")
    assert sweep_main([str(study), "--out", str(tmp_path / "o"), "--workers", "1", "--quiet"]) == 0
    table = pd.read_csv(tmp_path / "o" / "rods.csv")
    assert table["ok"].all()
    # L(t) = 5000 m - 1 m/s t, retire_length 50 m (given in the file, so kept):
    # rods of 1 km: 5 rods, the first 1000 m -> 50 m at 950 s: one retirement, 4 rods at 1000 s;
    # rods of 500 m: 10 rods, the first 500 m -> 50 m at 450 s, then 550 m -> 50 m at 950 s: 8 rods
    assert table["main.rods"].tolist() == [4, 8]
    assert table["main.retirements"].tolist() == [1, 2]
    assert table["main.deployed_length_m"].to_numpy() == pytest.approx([4000.0, 4000.0], abs=1e-6)


def test_a_swept_rod_length_carries_the_bounds_left_at_their_defaults():
    from tetherlab.sweep import reel_bound_changes

    base = load_scene(SCENES / "reel-seds-like.toml")  # birth bound by default (1.5 rods), retirement given
    changes = reel_bound_changes(base, {"tethers.main.reel.rod_length": "1 km"})
    r = base.replace(**changes).tethers[0].reel
    assert r.rod_length_m == 1000.0 and r.birth_length_m == 1500.0 and r.retire_length_m == 100.0
    kept = reel_bound_changes(base, {"tethers.main.reel.rod_length": "1 km", "tethers.main.reel.birth_length": "2 km"})
    assert base.replace(**kept).tethers[0].reel.birth_length_m == 2000.0


def test_a_fixed_length_summary_refuses_a_reel_scene_naming_the_key():
    from tetherlab.summaries import final_state

    scene = load_scene(SCENES / "reel-retrieval.toml")
    with pytest.raises(ValueError, match=r"tethers\.main\.reel.*tetherlab\.summaries:deployment"):
        final_state(scene)


def test_a_first_rod_past_its_birth_bound_is_warned_of():
    scene = load_scene(SCENES / "reel-hub-spoke.toml")  # rods of 10 m, birth bound 15 m
    reel = pd.DataFrame({"t_s": [0.0, 1.0, 2.0], "reel": "t0", "rods": [3, 3, 3],
                         "deployed_length_m": [30.0, 39.9, 41.0]})  # first rod 10, 19.9, 21 m
    (w,) = reelstore.missed_birth_warnings(scene, reel)
    assert w["kind"] == "missed birth" and w["t_s"] == 2.0 and "tethers.t0.reel.rod_length" in w["text"]
    assert reelstore.missed_birth_warnings(scene, reel.iloc[:2]) == []


def test_every_spoke_of_the_symmetric_hub_is_born(tmp_path):
    # by symmetry the four first rods reach 15 m together at 6.0 s and again at 16.7 s (t3's birth in
    # the run): every reel must then have 4 rods
    f = _short_copy(tmp_path, "reel-hub-spoke", "20 s")
    run = deployment.simulate_reel(load_scene(f))
    last = run.reel.groupby("reel").tail(1)
    assert last["rods"].tolist() == [4, 4, 4, 4]
