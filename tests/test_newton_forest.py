"""RADAU5's structured Newton matrix for forests: several root bodies (docs/integrators.md
section 13, "Forests").

The trees of a forest share no joint, so the Newton matrix is block diagonal over them and the
block-Thomas elimination of section 6 ends at each root separately (tetherlab/tether/newton.py).

* The structured solve equals a dense LU of the same matrix, assembled here in numpy from the rod
  blocks and the parameter block (every root's position block at its body's BT_QOFF in q), on a
  forest of two tethered systems (one a hub of two tethers) and a free body; real and complex
  shift; also with a fixed root that is not the first, and in the frame turning with the orbit.
  Negative controls: the second tree's root left out of the elimination; the frame terms left out
  of the dense matrix.
* Whole runs with newton="structured" and newton="dense" agree within a bound from the tolerance.
* Rigid roots in the forest (a free rigid body; the second tree's root rigid with its tether
  attached off its centre) go through the bordered matrix (section 13) the same way.
* newton="auto" takes the structured path for a point-mass forest from AUTO_STRUCTURED_MIN_RODS rods.
"""

from __future__ import annotations

import numpy as np
import pytest

from tetherlab.model.params import ParamView
from tetherlab.pipeline import prepare
from tetherlab.scene import Scene
from tetherlab.tether import newton as nw

from tests.helpers import assert_runs_agree as _assert_runs_agree
from tests.helpers import dense_and_structured_runs as _runs
from tests.helpers import newton_roots as _roots
from tests.helpers import structured_vs_dense_lu as _solve_vs_dense

SQ3 = np.sqrt(3.0)

RIGID_FREE = {
    "mass": "300 kg",
    "elements": {"a": "7050 km", "e": 0.0, "i": "31 deg", "nu": "40 deg"},
    "rigid": {
        "inertia": {"xx": "400 kg m2", "yy": "300 kg m2", "zz": "200 kg m2", "xy": "20 kg m2"},
        "attitude": {"euler": ["20 deg", "-10 deg", "35 deg"], "sequence": "ZYX", "frame": "orbit"},
        "angular_velocity": {"vector": ["0.02 rad/s", "-0.01 rad/s", "0.03 rad/s"], "frame": "body"},
    },
    "wheels": {"w1": {"axis": [1.0, 0.2, 0.0], "inertia": "0.1 kg m2", "speed": "50 rad/s"}},
}


def forest_scene(rods=(3, 4, 5), duration="60 s", free="point", damping="200 N s", h2_fixed=False, h2_rigid=False):
    """Two tethered systems and a free body: hub h1 (500 kg) carrying a1 and a2; h2 (200 kg,
    its own orbit, or ``h2_fixed``: held at rest) carrying b1; a free body f (a point mass, or a
    rigid body with a wheel); ``h2_rigid``: h2 a rigid body too, t3 attached 1.5 m off its centre."""
    def teth(frm, to, n, length, theta):
        return {"from": frm, "to": to, "rods": n, "length": length, "EA": "2e4 N", "mass": "2 kg",
                "damping": damping, "initial": {"theta": theta}}  # fmt: skip

    bodies = {
        "h1": {"mass": "500 kg"},
        "a1": {"mass": "30 kg"},
        "a2": {"mass": "20 kg"},
        "h2": {"mass": "200 kg", "elements": {"a": "7010 km", "e": 0.001, "i": "30 deg", "nu": "12 deg"}},
        "b1": {"mass": "15 kg"},
        **({"h2": {"fixed": True, "position": ["7010 km", "0 km", "0 km"]}} if h2_fixed else {}),
        **({"h2": {**RIGID_FREE, "elements": {"a": "7010 km", "e": 0.001, "i": "30 deg", "nu": "12 deg"}}}
           if h2_rigid else {}),
        "f": RIGID_FREE if free == "rigid" else {"mass": "40 kg", "elements": {"a": "7020 km", "e": 0.0, "nu": "5 deg"}},
    }
    tethers = {
        "t1": teth("h1", "a1", rods[0], "1 km", "20 deg"),
        "t2": teth("h1", "a2", rods[1], "600 m", "-30 deg"),
        "t3": teth("h2", "b1", rods[2], "800 m", "10 deg"),
    }
    if h2_rigid:
        tethers["t3"]["from_point"] = ["1 m", "0.5 m", "-1 m"]
    return Scene.from_dict({
        "duration": duration,
        "effects": {"central_gravity": {}},
        "bodies": bodies,
        "tethers": tethers,
        "orbit": {"reference": "h1", "elements": {"a": "7000 km", "e": 0.01, "i": "30 deg", "nu": "10 deg"},
                  "motion": "corotating"},
        "integrator": {"method": "radau5", "rtol": 1e-8, "atol": 1e-8},
        "output": {"count": 7},
    })  # fmt: skip


def _state(prep, seed=5):
    y = prep.y0.copy()
    m1 = prep.model.n_qt
    y[m1 : 2 * m1] += np.random.default_rng(seed).normal(size=m1) * 0.01  # velocities off the rigid motion
    return y


def test_forest_layout_has_root_blocks_after_the_rods():
    # what the solve relies on (tetherlab/system.py): q = (r_root0, d_1..d_N, r_root1, ...)
    prep = prepare(forest_scene())
    p = prep.model.fresh_params()
    roots = _roots(p)
    nrods = ParamView(p).n_rods
    assert len(roots) == 3 and roots[0][:2] == (0, 0)
    assert sorted(qo for _, qo, _ in roots[1:]) == [3 + 3 * nrods, 6 + 3 * nrods]
    assert ParamView(p).n_qtrans == 3 * len(roots) + 3 * nrods == prep.y0.size // 2
    assert nw.structure_supported(p, prep.y0.size, True) == ""


@pytest.mark.parametrize("damping, h2_fixed", [("0 N s", False), ("200 N s", False), ("200 N s", True)])
def test_forest_solve_equals_dense_lu(damping, h2_fixed):
    # (h2_fixed: a group's fixed body is its tree's root, tetherlab/pipeline.py; the root that is
    # not the first is then held at rest, a row g z = b without tether terms)
    prep = prepare(forest_scene(damping=damping, h2_fixed=h2_fixed))
    p = prep.model.fresh_params()
    if h2_fixed:
        assert [m for _, _, m in _roots(p)] == [500.0, 0.0, 40.0]
    # round-off: the matrix has cond ~ 1e3-1e4 here (as tests/test_newton_structured.py's tree),
    # so 1e-11 relative leaves a margin of 10 or more
    for rel in _solve_vs_dense(p, _state(prep)):
        assert rel <= 1e-11


def test_forest_solve_in_the_turning_frame_equals_dense_lu():
    # cowell-orbit (docs/integrators.md section 11): every joint, each root's block included,
    # carries the frame terms; a frame rate of 0.05 rad/s makes them matter at h = 0.5 s
    from tetherlab.formulations import cowell_orbit as co

    prep = prepare(forest_scene())
    omega = np.array([0.01, -0.03, 0.04])
    pe = co.attach(prep.model.fresh_params(), omega)
    y = co.to_frame(0.0, _state(prep), omega, prep.model.state)
    assert nw.structure_supported(pe, y.size, True) == ""
    for rel in _solve_vs_dense(pe, y, omega=omega):
        assert rel <= 1e-11  # round-off, as above
    # the same matrix without the frame terms is not what the solve inverts
    for rel in _solve_vs_dense(pe, y):
        assert rel > 1e-6


def test_forest_solve_without_the_second_root_disagrees():
    # negative control: the elimination told of the first root only (the second tethered tree's
    # root row left out: H_NROOT lowered on a copy whose root list has that root last) does not
    # solve the forest's matrix
    prep = prepare(forest_scene())
    p = prep.model.fresh_params()
    names = [b.name for b in prep.model.bodies]
    roots = [b for b, _, _ in _roots(p)]
    h2 = names.index("h2")
    bad = p.copy()
    ParamView(bad).roots[:] = [b for b in roots if b != h2] + [h2]
    ParamView(bad).n_roots = len(roots) - 1
    y = _state(prep)
    with np.errstate(all="ignore"):
        rels = _solve_vs_dense(bad, y, blk_p=p)
    for rel in rels:
        assert not rel <= 1e-3  # (NaN from the never-solved rows counts as disagreement too)


def test_structured_and_dense_runs_of_a_forest_agree():
    prep = prepare(forest_scene())
    runs = _runs(prep, True)
    _assert_runs_agree(prep, runs)
    # and the rod vectors (the stiff part) within 100 tolerance units of the 200 m rods, as
    # tests/test_newton_structured.py's runs
    nrods = ParamView(prep.model.p).n_rods
    qa, qb = runs["structured"].y[:, 3 : 3 + 3 * nrods], runs["dense"].y[:, 3 : 3 + 3 * nrods]
    assert np.max(np.abs(qa - qb)) * 2 * SQ3 <= 100 * prep.rtol * 200.0


@pytest.mark.parametrize("h2_rigid", [False, True])
def test_forest_with_rigid_roots_takes_the_bordered_matrix(h2_rigid):
    # the rigid bodies' attitudes and wheels are the border's unknowns (section 13); a rigid
    # root's position is a root block of its mass like a free point mass's.  h2_rigid: the second
    # tree's root rigid too, its tether attached off its centre
    prep = prepare(forest_scene(free="rigid", duration="30 s", h2_rigid=h2_rigid))
    m1 = prep.model.n_qt
    assert prep.y0.size == 2 * m1 + (2 if h2_rigid else 1) * (7 + 1)
    assert nw.structure_supported(prep.model.fresh_params(), prep.y0.size, m1) == ""
    _assert_runs_agree(prep, _runs(prep, m1))


def test_auto_takes_the_structured_path_for_a_forest():
    # newton_solver.AUTO_STRUCTURED_MIN_RODS: the structured path from that many rods in all
    from tetherlab.tether import newton_solver

    nmin = newton_solver.AUTO_STRUCTURED_MIN_RODS
    for total, kind in ((nmin - 1, "dense"), (nmin, "structured")):
        rods = (1, 1, total - 2)
        prep = prepare(forest_scene(rods=rods))
        p = prep.model.fresh_params()
        solver = newton_solver.choose(p, prep.y0.size, True)
        assert solver.name.startswith(kind) and solver.structured == (kind == "structured"), solver.name
