"""An end mass placed where no static equilibrium can hold it is refused naming its position key
(docs/statics-map.md section 3), not with a Newton failure message."""

from __future__ import annotations

from pathlib import Path

import pytest

import tetherlab
from tetherlab.errors import SceneError
from tetherlab.pipeline import prepare

SCENES = Path(__file__).resolve().parent.parent / "studies" / "scenes"


def _placed(**changes):
    return tetherlab.load_scene(SCENES / "hanging-chain-placed.toml").replace(**changes)


def test_tension_only_hold_on_the_vertical_names_the_position():
    # 10 m below the nail: the line stretched by its weight is longer than the span; a tether that
    # cannot push has no taut equilibrium there
    with pytest.raises(SceneError) as err:
        prepare(_placed(**{"tethers.main.tension_only": True, "bodies.tip.position": ["0 m", "0 m", "-10 m"]}))
    assert err.value.key == "bodies.tip.position", str(err.value)


def test_inextensible_hold_beyond_its_length_names_the_position():
    with pytest.raises(SceneError) as err:
        prepare(_placed(**{"tethers.main.model": "inextensible", "bodies.tip.position": ["0 m", "0 m", "-10.01 m"]}))
    assert err.value.key == "bodies.tip.position", str(err.value)
    assert "10.01" in str(err.value)
