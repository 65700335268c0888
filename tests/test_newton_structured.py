"""The structured Newton matrix of RADAU5 (tetherlab/tether/newton.py, docs/integrators.md 6-7).

* The block-Thomas solve agrees to round-off with a dense LU solve of the same Newton matrix
  E = g I - [[0, I], [A_q, A_v]], A = T^-1 M_x^-1 (K_x or C_x) T, assembled here in numpy from
  the rod blocks (hub of two tethers, one with a tip body and one with a free end; free and fixed
  root; real and complex g).
* The rod blocks are the derivation's: for the energy model without distributed forces M_x is
  constant and the equations are exactly M_x x'' = F_el(x, x'), so A_q and A_v equal the
  central-difference Jacobian of the compiled rhs (to the difference error, ~1e-6 relative).
* Whole runs with the structured and the dense Newton matrix agree within the tolerance.
"""

from __future__ import annotations

import numpy as np
import pytest

from tetherlab.forces import EFFECTS
from tetherlab.formulations.cowell import cowell_rhs, cowell_rhs_py
from tetherlab.integrators.driver import integrate
from tetherlab.system import TetherSpec, build_model, chain_state
from tetherlab.tether import newton as nw
from tetherlab.tether.newton_solver import choose

from tests.helpers import dense_newton_A as _dense_A, structured_vs_dense_lu

SQ3 = np.sqrt(3.0)


def _model(kind, gravity, root_fixed, seed=1):
    rng = np.random.default_rng(seed)
    tets = [TetherSpec(f"t{k}", 3 + k, 1000.0, 5e4, 10.0, 300.0, kind, 50.0 if k == 0 else 0.0,
                       "mf") for k in range(2)]  # fmt: skip
    effects = [(EFFECTS["central_gravity"], {})] if gravity else []
    model = build_model(root_mass_kg=500.0, tethers=tets, effects=effects,
                        central={"mu_m3_s2": 3.986004418e14}, root_fixed=root_fixed)  # fmt: skip
    dirs = []
    for k, tet in enumerate(tets):
        v = rng.normal(size=(tet.rods, 3)) * 0.2 + np.array([1.0, 0.3 * k, 0.1])
        dirs.append(v / np.linalg.norm(v, axis=1)[:, None])
    y = chain_state(model, np.array([7e6, 0, 0.0]), np.array([0, 7500.0, 0]), dirs, [1e-3, 1e-3],
                    np.array([0, 0, 1e-3]))  # fmt: skip
    y[y.size // 2 :] += rng.normal(size=y.size // 2) * 0.01  # velocities off the rigid motion
    return model, y


def _check_solve_equals_dense_lu(p, y, seed, bound, omega=None):
    """The block-Thomas solve against a dense LU of the same Newton matrix, for the two RADAU5
    shifts at h = 0.5 s (tests/helpers.structured_vs_dense_lu; ``omega``: a frame turning with it)."""
    for rel in structured_vs_dense_lu(p, y, seed=seed, omega=omega):
        assert rel <= bound


@pytest.mark.parametrize("root_fixed", [False, True])
@pytest.mark.parametrize("kind", ["paper", "energy"])
def test_structured_solve_equals_dense_lu(kind, root_fixed):
    model, y = _model(kind, True, root_fixed)
    # round-off: cond(E) ~ 1e3 here, so 1e-12 relative leaves a factor ~10 of margin
    _check_solve_equals_dense_lu(model.fresh_params(), y, 7, 1e-12)


@pytest.mark.parametrize("root_fixed", [False, True])
def test_rod_blocks_are_the_jacobian_for_the_energy_model(root_fixed):
    model, y = _model("energy", False, root_fixed)
    p = model.fresh_params()
    m1 = y.size // 2
    blk, _, _ = nw.workspace(p)
    nw.rod_blocks(y, p, m1, blk)
    aq, av = _dense_A(p, blk, m1)
    J = np.empty((2 * m1, 2 * m1))
    for j in range(2 * m1):
        d = 1e-7 * max(1.0, abs(y[j])) if j < m1 else 1e-6
        yp, ym = y.copy(), y.copy()
        yp[j] += d
        ym[j] -= d
        J[:, j] = (cowell_rhs_py(model, yp) - cowell_rhs_py(model, ym)) / (2 * d)
    # central differences: truncation ~ d^2 f''' and rounding ~ eps |f| / d, both << 1e-5
    assert np.max(np.abs(J[m1:, :m1] - aq)) <= 1e-5 * np.max(np.abs(aq))
    assert np.max(np.abs(J[m1:, m1:] - av)) <= 1e-5 * np.max(np.abs(av))


def test_structured_and_dense_runs_agree():
    model, y0 = _model("paper", True, False)
    p = model.fresh_params()
    t_out = np.linspace(0.0, 200.0, 21)
    rtol = 1e-8
    out = {}
    for kind in ("structured", "dense"):
        p = model.fresh_params()
        res = integrate("radau5", cowell_rhs, 0.0, y0, t_out, p, rtol, rtol, second_order=True,
                        newton=choose(p, y0.size, True, kind))  # fmt: skip
        assert res.success, res.message
        out[kind] = res
    assert out["structured"].stats["newton_matrix"] == "structured"
    assert out["dense"].stats["newton_matrix"] == "dense (requested)"
    m1 = y0.size // 2
    # joint positions of both runs within 100 tolerance units of the 1000 m rods (RADAU5's
    # tolerance map loosens rtol to 0.1 rtol^(2/3); two runs of the same error estimate differ by
    # about their error)
    qa, qb = out["structured"].y[:, 3:m1], out["dense"].y[:, 3:m1]
    assert np.max(np.abs(qa - qb)) * 2 * SQ3 <= 100 * rtol * 1000.0


def test_fallback_names_the_reason():
    # a first-order state (not declared second order) keeps the dense path and says why
    model, y0 = _model("paper", False, False)
    p = model.fresh_params()
    res = integrate("radau5", cowell_rhs, 0.0, y0, np.array([0.0, 1.0]), p, 1e-6, 1e-6, second_order=False,
                    newton=choose(p, y0.size, False))  # fmt: skip
    assert res.success
    assert res.stats["newton_matrix"].startswith("dense (the state is not declared second order")
    with pytest.raises(ValueError, match="newton"):
        choose(p, y0.size, False, "structured")
    # the integrators cannot make that choice themselves: a bare "structured" is refused with a
    # pointer to the model's, and no solver at all is the dense matrix, named so
    with pytest.raises(ValueError, match="model's to give"):
        integrate("radau5", cowell_rhs, 0.0, y0, np.array([0.0, 1.0]), p, 1e-6, 1e-6, second_order=True,
                  newton="structured")  # fmt: skip
    res = integrate("radau5", cowell_rhs, 0.0, y0, np.array([0.0, 1.0]), p, 1e-6, 1e-6, second_order=True)
    assert res.stats["newton_matrix"] == "dense (no structured solver handed in)"


# --------------------------------------------------------------------------------------------
# Trees of point masses (a tether hanging from another tether's tip body): leaves-first
# elimination with the children's Schur terms collected at their parent's joint.
# --------------------------------------------------------------------------------------------

TREE = """
name = "tree"
duration = "300 s"
[effects]
central_gravity = {}
[bodies.hub]
mass = "500 kg"
[bodies.mid]
mass = "80 kg"
[bodies.a]
mass = "30 kg"
[bodies.b]
mass = "20 kg"
[tethers.t1]
from = "hub"
to = "mid"
rods = 3
length = "1 km"
EA = "3e4 N"
mass = "5 kg"
damping = "%s"
[tethers.t1.initial]
theta = "10 deg"
[tethers.t2]
from = "mid"
to = "a"
rods = 4
length = "600 m"
EA = "2e4 N"
mass = "3 kg"
[tethers.t2.initial]
theta = "25 deg"
[tethers.t3]
from = "mid"
to = "b"
rods = 2
length = "400 m"
EA = "2e4 N"
mass = "2 kg"
[tethers.t3.initial]
theta = "-20 deg"
phi = "30 deg"
[tethers.t4]
from = "hub"
to = "c"
rods = 3
length = "500 m"
EA = "1e4 N"
mass = "2 kg"
[tethers.t4.initial]
theta = "-15 deg"
[bodies.c]
mass = "10 kg"
[orbit]
reference = "center_of_mass"
elements = { a = "7000 km", e = 0.0, i = "50 deg" }
motion = "corotating"
[integrator]
method = "radau5"
rtol = 1e-8
atol = 1e-8
[output]
step = "30 s"
"""


def _tree(tmp_path, damping="0 N s"):
    from tetherlab.pipeline import prepare
    from tetherlab.scene import load_scene

    f = tmp_path / "tree.toml"
    f.write_text(TREE % damping)
    return prepare(load_scene(f))


@pytest.mark.parametrize("damping", ["0 N s", "500 N s"])
def test_structured_solve_of_a_tree_equals_dense_lu(tmp_path, damping):
    prep = _tree(tmp_path, damping)
    p = prep.model.fresh_params()
    y = prep.y0.copy()
    y[y.size // 2 :] += np.random.default_rng(5).normal(size=y.size // 2) * 0.01
    assert nw.structure_supported(p, y.size, True) == ""
    # as for the star: round-off of a matrix with cond ~ 1e3-1e4
    _check_solve_equals_dense_lu(p, y, 11, 1e-11)


def test_structured_and_dense_runs_of_a_tree_agree(tmp_path):
    prep = _tree(tmp_path)
    out = {}
    for kind in ("structured", "dense"):
        p = prep.model.fresh_params()
        res = integrate("radau5", cowell_rhs, 0.0, prep.y0, prep.t_out, p, 1e-8, prep.atol, second_order=True,
                        newton=choose(p, prep.y0.size, True, kind))  # fmt: skip
        assert res.success, res.message
        out[kind] = res
    assert out["structured"].stats["newton_matrix"] == "structured"
    m1 = prep.y0.size // 2
    # rod vectors of both runs within 100 tolerance units of the longest (333 m) rods, as above
    qa, qb = out["structured"].y[:, 3:m1], out["dense"].y[:, 3:m1]
    assert np.max(np.abs(qa - qb)) * 2 * SQ3 <= 100 * 1e-8 * 1000.0 / 3


def test_structured_solve_in_the_turning_frame_equals_dense_lu():
    """cowell-orbit: the Newton matrix carries the frame's Coriolis and centrifugal terms as
    M_x (g + 2 W + W^2/g) (docs/integrators.md section 11).  A frame rate of 0.05 rad/s (50x the
    orbit's) makes them large enough to matter at h = 0.5 s; de-orbit tether, 4 rods."""
    import tetherlab
    from tetherlab.formulations import cowell_orbit as co
    from tetherlab.pipeline import prepare

    from .helpers import SCENES

    assert nw.FRAME_OP_W == co.OP_W
    prep = prepare(tetherlab.load_scene(SCENES / "deorbit-ed.toml").replace(**{"tethers.main.rods": 4}))
    omega = np.array([0.01, -0.03, 0.04])
    pe = co.attach(prep.model.fresh_params(), omega)
    y = co.to_frame(0.0, prep.y0, omega, prep.model.state)
    assert nw.structure_supported(pe, y.size, True) == ""
    _check_solve_equals_dense_lu(pe, y, 13, 1e-11, omega)
    # negative control: the same matrix without the frame terms is not what the solve inverts
    with pytest.raises(AssertionError):
        _check_solve_equals_dense_lu(pe, y, 13, 1e-11, None)
