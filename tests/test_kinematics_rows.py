"""The outputs' kinematics in one compiled pass over the rows (tetherlab/kinematics.py) give the
numbers of the one-state functions (system.point_positions, system.center_of_mass) bit for bit,
on a rigid hub with four spokes (several tethers, a rotation matrix) and on the hanging chain."""

from __future__ import annotations

import numpy as np
import pytest

import tetherlab
from tetherlab.kinematics import center_of_mass_rows, point_rows
from tetherlab.pipeline import prepare
from tetherlab.system import center_of_mass, point_positions
from tests.helpers import SCENES


@pytest.mark.parametrize("name", ["hub-spoke-spin", "hanging-chain"])
def test_rows_equal_one_state_functions_bit_for_bit(name):
    prep = prepare(tetherlab.load_scene(SCENES / f"{name}.toml"))
    model = prep.model
    rng = np.random.default_rng(7)
    # states around the start: every component moved by up to 1e-3 of its own size, velocities too
    Y = prep.y0[None, :] * (1.0 + 1e-3 * rng.standard_normal((5, prep.y0.size))) + 1e-3 * rng.standard_normal((5, prep.y0.size))
    pts = point_rows(model, Y)
    rc, vc = center_of_mass_rows(model, pts)
    for i, y in enumerate(Y):
        one = point_positions(model, y)
        assert np.array_equal(pts["bodies"][i], one["bodies"])
        assert np.array_equal(pts["rotations"][i], one["rotations"])
        assert np.array_equal(pts["rG"][i], one["rG"]) and np.array_equal(pts["vG"][i], one["vG"])
        for k, sl in enumerate(model.rod_slices):
            block = pts["joints"][i, sl.start + k : sl.stop + k + 1]
            assert np.array_equal(block[:, :3], one["joints"][k]) and np.array_equal(block[:, 3:], one["jvel"][k])
        r, v = center_of_mass(model, y)
        assert np.array_equal(rc[i], r) and np.array_equal(vc[i], v)


def test_rows_refuse_a_state_of_another_model():
    prep = prepare(tetherlab.load_scene(SCENES / "hanging-chain.toml"))
    with pytest.raises(ValueError, match="state components"):
        point_rows(prep.model, np.zeros((3, prep.y0.size + 1)))
