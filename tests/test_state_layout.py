"""The state layout (tetherlab/model/state.py): named blocks that tile the state and agree with the
offsets the compiled kernels read from the parameter block."""

from __future__ import annotations

import numpy as np
import pytest

import tetherlab
from tetherlab.model.state import StateLayout
from tetherlab.pipeline import prepare
from tetherlab.resources import scene_layout
from tetherlab.system import BodySpec, RigidSpec, TetherSpec, WheelSpec, build_model

from .helpers import SCENES

CENTRAL = {"mu_m3_s2": 3.986004418e14, "radius_m": 6.378137e6}


def _tiles(lay: StateLayout) -> None:
    blocks = lay.blocks()
    assert blocks[0].start == 0 and blocks[-1].stop == lay.size
    for a, b in zip(blocks, blocks[1:]):
        assert a.stop == b.start, (a, b)
    assert len({b.name for b in blocks}) == len(blocks)


@pytest.mark.parametrize("name", ["rigid-example", "rigid-wheels-control", "deorbit-ed-rigid", "chain3",
                                  "hub-spoke-spin", "stiefel-scheifele", "catenary", "lateral-two-rods"])
def test_layout_agrees_with_the_parameter_block(name):
    scene = tetherlab.load_scene(SCENES / f"{name}.toml")
    prep = prepare(scene)
    lay = prep.model.state
    assert lay.agrees_with(prep.model.p) == []
    assert lay.size == prep.y0.size == prep.model.n_state and lay.n_qt == prep.model.n_qt
    _tiles(lay)
    # the resource check's layout, from the scene's counts before the model exists
    assert scene_layout(scene).size == lay.size


def _forest_model():
    """Two trees: root a -> b, and a rigid root c (two wheels) -> d: body c is an 'other root'."""
    wheels = (WheelSpec("w1", (1.0, 0.0, 0.0), 0.1), WheelSpec("w2", (0.0, 1.0, 0.0), 0.1))
    inertia = ((10.0, 0.0, 0.0), (0.0, 12.0, 0.0), (0.0, 0.0, 8.0))
    bodies = [BodySpec("a", 100.0), BodySpec("b", 10.0), BodySpec("d", 5.0),
              BodySpec("c", 50.0, rigid=RigidSpec(inertia, wheels))]  # fmt: skip
    tethers = [TetherSpec("t1", 3, 100.0, 1e4, 1.0, tip_mass_kg=10.0, tip_name="b", parent="a"),
               TetherSpec("t2", 2, 50.0, 1e4, 0.5, tip_mass_kg=5.0, tip_name="d", parent="c")]  # fmt: skip
    return build_model(root_mass_kg=100.0, tethers=tethers, effects=[], central=CENTRAL, bodies=bodies)


def test_forest_blocks_by_name():
    model = _forest_model()
    lay = model.state
    assert lay.agrees_with(model.p) == []
    _tiles(lay)
    assert [b.name for b in lay.blocks()] == [
        "root.r", "tether.t1.d", "tether.t2.d", "root.c.r", "root.v", "tether.t1.dd", "tether.t2.dd",
        "root.c.v", "attitude.c", "wheels.c",
    ]  # fmt: skip
    assert lay.n_qt == 3 * (1 + 5 + 1) and lay.size == 2 * lay.n_qt + 7 + 2
    assert lay.root_offset(3) == model.root_offset(3) == 18
    assert lay.block("tether.t2.d") == lay.tether_rods(1) == slice(12, 18)
    assert lay.rod(4) == slice(15, 18)
    assert lay.attitude_of(3) == slice(2 * lay.n_qt, 2 * lay.n_qt + 7)
    assert lay.wheels_of(3) == lay.wheels == slice(lay.size - 2, lay.size)
    with pytest.raises(KeyError, match="root.r"):
        lay.block("nope")


def test_orbit_split_is_the_pass_through_and_joins_back():
    lay = _forest_model().state
    y = np.arange(lay.size, dtype=float)
    r, v, rest = lay.orbit_split(y)
    assert r.tolist() == [0, 1, 2] and v.tolist() == [lay.n_qt, lay.n_qt + 1, lay.n_qt + 2]
    assert rest.size == lay.n_passthrough == lay.size - 6
    assert np.array_equal(lay.orbit_join(r, v, rest), y)
    assert np.array_equal(lay.passthrough_atol(y), rest)


def test_disagreeing_block_is_reported():
    """Negative control: a parameter block with one offset moved is caught."""
    from tetherlab.model.params import ParamView

    model = _forest_model()
    p = model.p.copy()
    ParamView(p).wheel_state_index += 1
    assert any("H_OFF_WHL" in s for s in model.state.agrees_with(p))


def test_formulations_declare_what_they_support():
    """Each formulation's own reason reaches the SceneError (formulations/registry.py)."""
    from tetherlab.errors import SceneError
    from tetherlab.formulations.registry import CHOICES, FORMULATIONS

    assert set(CHOICES) == set(tetherlab.scene.FORMULATIONS)
    assert all(name in FORMULATIONS for names in CHOICES.values() for name in names)
    rigid = tetherlab.load_scene(SCENES / "rigid-example.toml")
    assert prepare(rigid.replace(**{"integrator.formulation": "dromo"})).formulation == "dromo-time"
    assert prepare(rigid.replace(**{"integrator.formulation": "cowell-orbit"})).formulation == "cowell-orbit"
    with pytest.raises(SceneError, match="central_gravity"):
        prepare(rigid.replace(**{"integrator.formulation": "dromo", "effects.central_gravity": None,
                                 "effects.uniform_gravity": {}}))  # fmt: skip
