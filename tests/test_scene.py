"""The scene boundary: TOML file or Python dict in, validated SI dataclasses out.

Every validation rule has a case here that checks the dotted key named by the SceneError and a
fragment of its message.
"""

from __future__ import annotations

import copy
import math
import pickle

import astropy.units as u
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tetherlab.errors import SceneError
from tetherlab.forces import EFFECTS, EffectSpec, ParamSpec
from tetherlab.orbits import elements_to_cartesian, period
from tetherlab.scene import (
    MAX_SANE_STRAIN,
    Body,
    InitialShape,
    LayoutStep,
    Scene,
    load_scene,
)
from tetherlab.units import ANGLE, DAMPING, FORCE, GRAVITATIONAL_PARAMETER, LENGTH, MASS, TIME, format_si, to_si

MU = 3.986004418e14
DEG = math.pi / 180.0

EXAMPLE_TOML = """\
description = "in-plane libration of a dumbbell"
epoch = "2026-01-01T00:00:00"
duration = "10 orbits"

[central_body]
name = "earth"

[effects]
central_gravity = {}

[bodies.m0]
mass = "1000 kg"

[bodies.mf]
mass = "392.2 kg"

[tethers.main]
from = "m0"
to = "mf"
rods = 2
length = "5 km"
EA = "5e4 N"
mass = "10 kg"
damping = "1e-3 N s"

[tethers.main.initial]
shape = "straight"
theta = "30 deg"
phi = "0 deg"

[orbit]
reference = "center_of_mass"
elements = { a = "7400 km", e = 0.0, i = "35 deg", raan = "0 deg", argp = "0 deg", nu = "0 deg" }
motion = "corotating"

[integrator]
method = "dop853"
rtol = 1e-10
atol = 1e-10
max_step = "60 s"

[output]
step = "60 s"
"""


def base() -> dict:
    """A minimal valid scene: two bodies, one tether, an orbit."""
    return {
        "duration": "6000 s",
        "effects": {"central_gravity": {}},
        "bodies": {"m0": {"mass": "1000 kg"}, "mf": {"mass": "10 kg"}},
        "tethers": {
            "main": {"from": "m0", "to": "mf", "rods": 2, "length": "5 km", "EA": "5e4 N", "mass": "10 kg"}
        },
        "orbit": {"elements": {"a": "7400 km", "e": 0.0, "i": "35 deg", "raan": "0 deg", "argp": "0 deg", "nu": "0 deg"}},
        "output": {"step": "60 s"},
    }


def explicit_base(separation_m: float = 5000.0) -> dict:
    """Both bodies with explicit states, no [orbit]."""
    d = base()
    del d["orbit"]
    v = math.sqrt(MU / 7.4e6)
    d["bodies"]["m0"].update(position=["7400 km", "0 km", "0 km"], velocity=["0 m/s", f"{v} m/s", "0 m/s"])
    d["bodies"]["mf"].update(
        position=[f"{7.4e6 + separation_m} m", "0 km", "0 km"], velocity=["0 m/s", f"{v} m/s", "0 m/s"]
    )
    return d


def variant(changes: dict, data: dict | None = None) -> dict:
    """``data`` (default :func:`base`) with dotted keys set; a value of None deletes the key."""
    d = copy.deepcopy(base() if data is None else data)
    for path, value in changes.items():
        *parents, last = path.split(".")
        node = d
        for part in parents:
            node = node.setdefault(part, {})
        if value is None:
            del node[last]
        else:
            node[last] = value
    return d


def fails(data: dict, key: str, *fragments: str) -> SceneError:
    with pytest.raises(SceneError) as info:
        Scene.from_dict(data)
    err = info.value
    assert err.key == key, str(err)
    for fragment in fragments:
        assert fragment in str(err), str(err)
    assert str(err).startswith(f"scene key {key!r}: expected ")
    return err


# -- units --------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "text, kind, si",
    [
        ("5 km", LENGTH, 5000.0),
        ("392.2 kg", MASS, 392.2),
        ("35 d", TIME, 35 * 86400.0),
        ("60 s", TIME, 60.0),
        ("30 deg", ANGLE, math.pi / 6),
        ("5e4 N", FORCE, 5e4),
        ("1e-3 N s", DAMPING, 1e-3),
        ("3.986004418e14 m3 / s2", GRAVITATIONAL_PARAMETER, 3.986004418e14),
        ("2 g/m", "kg / m", 2e-3),
        ("70 GPa", "Pa", 7e10),
    ],
)
def test_quantity_strings_convert_to_si(text, kind, si):
    assert to_si(text, kind, key="k") == pytest.approx(si, rel=1e-15)


def test_quantities_from_python_are_accepted():
    assert to_si(5 * u.km, LENGTH, key="k") == 5000.0
    assert to_si(30 * u.deg, ANGLE, key="k") == pytest.approx(math.pi / 6)


@pytest.mark.parametrize(
    "value, kind, fragment",
    [
        (5000, LENGTH, "missing unit"),
        (5000.0, LENGTH, "missing unit"),
        ("5000", LENGTH, "missing unit"),
        (0.5, ANGLE, "missing unit"),
        (5 * u.dimensionless_unscaled, LENGTH, "missing unit"),
        ("5e4 kg", FORCE, "(dimension mass)"),
        ("5 km", TIME, "(dimension length)"),
        ("5 m3", GRAVITATIONAL_PARAMETER, "(dimension volume)"),
        ("nan km", LENGTH, "not finite"),
        ("inf m", LENGTH, "not finite"),
        ("1e400 m", LENGTH, "not finite"),
        (float("nan") * u.m, LENGTH, "not finite"),
        ("five km", LENGTH, "does not start with a number"),
        ("5 kms", LENGTH, "did you mean km"),
        ([1, 2] * u.m, LENGTH, "an array"),
        (True, LENGTH, "bool"),
        (None, LENGTH, "NoneType"),
    ],
)
def test_bad_quantities_are_refused(value, kind, fragment):
    with pytest.raises(SceneError) as info:
        to_si(value, kind, key="a.b")
    assert info.value.key == "a.b"
    assert fragment.lower() in str(info.value).lower()


def test_wrong_dimension_message_has_the_documented_form():
    err = fails(variant({"tethers.main.EA": "5e4 kg"}), "tethers.main.EA")
    assert str(err) == "scene key 'tethers.main.EA': expected a force (e.g. '5e4 N'), got '5e4 kg' (dimension mass)"
    assert err.expected == "a force (e.g. '5e4 N')"
    assert err.got == "'5e4 kg' (dimension mass)"
    assert isinstance(err, ValueError)


@settings(max_examples=300, deadline=None)
@given(st.floats(allow_nan=False, allow_infinity=False), st.sampled_from([LENGTH, MASS, TIME, ANGLE, FORCE, DAMPING, GRAVITATIONAL_PARAMETER]))
def test_format_si_reads_back_exactly(x, kind):
    assert to_si(format_si(x, kind), kind, key="k") == x


def test_scene_error_pickles():
    err = SceneError("tethers.main.EA", "a force", "'5 kg'", hint="did you mean?", source="a.toml", line=3)
    back = pickle.loads(pickle.dumps(err))
    assert (back.key, back.expected, back.got, back.hint, back.source, back.line, str(back)) == (
        err.key, err.expected, err.got, err.hint, err.source, err.line, str(err)
    )


# -- loading -----------------------------------------------------------------------------------


def test_load_example_file(tmp_path):
    path = tmp_path / "libration-inplane.toml"
    path.write_text(EXAMPLE_TOML)
    scene = load_scene(path)
    assert scene.name == "libration-inplane"  # the file stem
    assert scene.source == str(path)
    assert scene.description.startswith("in-plane")
    assert scene.epoch == "2026-01-01T00:00:00"
    assert scene.duration_orbits == 10.0 and scene.duration_s is None
    assert scene.central_body.mu_m3_s2 == MU
    assert scene.central_body.radius_m == 6378137.0
    assert [e.name for e in scene.effects] == ["central_gravity"]
    assert scene.body("mf") == Body("mf", 392.2)
    t = scene.tether("main")
    assert (t.from_body, t.to_body, t.rods, t.length_m, t.EA_N, t.mass_kg, t.damping_N_s) == ("m0", "mf", 2, 5000.0, 5e4, 10.0, 1e-3)
    assert (t.model, t.quadrature) == ("paper", 2)
    assert t.initial == InitialShape("straight", pytest.approx(math.pi / 6), 0.0, "up", 0.0)
    assert scene.orbit.elements.a_m == 7.4e6
    assert scene.orbit.elements.i_rad == pytest.approx(35 * DEG)
    assert scene.integrator.max_step_s == 60.0
    assert scene.output.step_s == 60.0
    assert scene.duration_seconds() == pytest.approx(10 * period(MU, 7.4e6), rel=1e-12)
    assert scene.layout_plan() == (LayoutStep("main", "m0", "mf"),)
    assert Scene.from_dict(scene.to_dict()) == scene


def test_missing_file_is_a_clear_error(tmp_path):
    with pytest.raises(FileNotFoundError, match="scene file .*nope.toml.* does not exist"):
        load_scene(tmp_path / "nope.toml")


def test_toml_syntax_error_names_file_and_line(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text('duration = "60 s"\n[effects]\ncentral_gravity = {\n')
    with pytest.raises(SceneError) as info:
        load_scene(path)
    assert info.value.line == 3
    assert info.value.source == str(path)
    assert f"scene file {str(path)!r} line 3: expected valid TOML" in str(info.value)


def test_validation_error_in_a_file_names_the_file(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(EXAMPLE_TOML.replace('EA = "5e4 N"', 'EA = "5e4 kg"'))
    with pytest.raises(SceneError) as info:
        load_scene(path)
    assert info.value.key == "tethers.main.EA"
    assert str(info.value).endswith(f"[in {path}]")


@pytest.mark.parametrize(
    "old, new, key",
    [
        ("rtol = 1e-10", "rtol = nan", "integrator.rtol"),
        ("atol = 1e-10", "atol = inf", "integrator.atol"),
        ('mass = "1000 kg"', 'mass = "1000 kg"\nposition = [-inf, 0.0, 0.0]', "bodies.m0.position[0]"),
    ],
)
def test_toml_nan_and_inf_literals_are_refused(tmp_path, old, new, key):
    path = tmp_path / "s.toml"
    path.write_text(EXAMPLE_TOML.replace(old, new, 1))
    with pytest.raises(SceneError) as info:
        load_scene(path)
    assert info.value.key == key
    assert "a finite number" in str(info.value)


def test_python_api_with_quantities_equals_strings():
    d = base()
    d["duration"] = 6000 * u.s
    d["bodies"]["m0"]["mass"] = 1 * u.t
    d["tethers"]["main"].update(length=5 * u.km, EA=5e4 * u.N, mass=10 * u.kg)
    d["orbit"]["elements"].update(a=7400 * u.km, i=35 * u.deg)
    assert Scene.from_dict(d) == Scene.from_dict(base())


def test_python_api_vector_quantity_for_position():
    d = explicit_base()
    v = math.sqrt(MU / 7.4e6)
    d["bodies"]["m0"].update(position=[7400, 0, 0] * u.km, velocity=[0, v, 0] * u.m / u.s)
    assert Scene.from_dict(d) == Scene.from_dict(explicit_base())


def test_name_defaults_and_source_is_not_compared():
    assert Scene.from_dict(base()).name == "scene"
    a = Scene.from_dict(base(), source="x/one.toml")
    assert a.name == "one" and a.source == "x/one.toml"
    assert Scene.from_dict(a.to_dict()) == a


def test_toml_datetime_epoch_is_accepted(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(EXAMPLE_TOML.replace('epoch = "2026-01-01T00:00:00"', "epoch = 2026-01-01T00:00:00"))
    assert load_scene(path).epoch == "2026-01-01T00:00:00"


# -- round trips and replace ------------------------------------------------------------------

ROUND_TRIP_VARIANTS = {
    "base": base(),
    "explicit states": explicit_base(),
    "E and density": variant({"tethers.main.EA": None, "tethers.main.mass": None, "tethers.main.E": "70 GPa",
                              "tethers.main.diameter": "0.5 mm", "tethers.main.density": "2700 kg/m3"}),
    "linear density": variant({"tethers.main.mass": None, "tethers.main.linear_density": "2 g/m"}),
    "rods shape": variant({"tethers.main.initial": {"shape": "rods", "theta": ["0.1 rad", "0.2 rad"],
                                                    "phi": ["0.1 rad", "-0.2 rad"], "side": "down", "strain": 0.01}}),
    "count and options": variant({"output": {"count": 11}, "integrator": {"method": "scipy:Radau", "max_steps": 10,
                                  "max_step": "1 s"}, "tethers.main.model": "energy", "tethers.main.quadrature": 8,
                                  "orbit.motion": "translating", "central_body": {"mu": "3.9e14 m3/s2", "radius": "6371 km"}}),
    "times": variant({"output": {"times": ["0 s", "1 min", "6000 s"]}}),
    "body reference with position": variant(
        {"orbit": {"reference": "m0", "position": ["7000 km", "0 km", "1 km"], "velocity": ["0 km/s", "7.5 km/s", "0.1 km/s"]}}
    ),
    "hyperbolic body reference": variant(
        {"orbit": {"reference": "m0"}, "bodies.m0.elements": {"a": "-20000 km", "e": 1.5, "nu": "-10 deg"}}
    ),
    "fixed body": variant(
        {"orbit": {"reference": "mf", "elements": {"a": "7000 km", "e": 0.01}}, "bodies.m0.fixed": True,
         "bodies.m0.position": ["7000 km", "0 km", "0 km"], "description": "nail", "epoch": "2026-01-01"}
    ),
    "no tethers": {"duration": "1 orbits", "effects": {"central_gravity": {}}, "bodies": {"sat": {"mass": "1 kg"}},
                   "orbit": {"elements": {"a": "7000 km", "e": 0.01}}, "output": {"count": 2}},
}


@pytest.mark.parametrize("data", ROUND_TRIP_VARIANTS.values(), ids=ROUND_TRIP_VARIANTS.keys())
def test_round_trip(data):
    scene = Scene.from_dict(data)
    assert Scene.from_dict(scene.to_dict()) == scene
    assert Scene.from_dict(scene.to_dict()).to_dict() == scene.to_dict()


def test_derived_tether_values():
    e_density = Scene.from_dict(ROUND_TRIP_VARIANTS["E and density"]).tether("main")
    area = math.pi * 0.5e-3**2 / 4
    assert e_density.EA_N == pytest.approx(70e9 * area, rel=1e-14)
    assert e_density.mass_kg == pytest.approx(2700 * area * 5000, rel=1e-14)
    assert e_density.diameter_m == pytest.approx(0.5e-3)
    assert Scene.from_dict(ROUND_TRIP_VARIANTS["linear density"]).tether("main").mass_kg == pytest.approx(10.0)


@settings(max_examples=50, deadline=None)
@given(
    rods=st.integers(1, 200),
    length=st.floats(1e-3, 1e6),
    ea=st.floats(1e-3, 1e12),
    theta=st.floats(-10, 10),
)
def test_round_trip_property(rods, length, ea, theta):
    d = variant({"tethers.main.rods": rods, "tethers.main.length": f"{length} m", "tethers.main.EA": f"{ea} N",
                 "tethers.main.initial": {"theta": f"{theta} rad"}})
    scene = Scene.from_dict(d)
    assert Scene.from_dict(scene.to_dict()) == scene


def test_replace_sweeps_a_dotted_key_and_revalidates():
    scene = Scene.from_dict(base())
    eight = scene.replace(**{"tethers.main.rods": 8})
    assert eight.tether("main").rods == 8 and scene.tether("main").rods == 2
    assert eight.replace(**{"tethers.main.rods": 2}) == scene
    with pytest.raises(SceneError, match="tethers.main.rods"):
        scene.replace(**{"tethers.main.rods": 0})
    swapped = scene.replace(**{"tethers.main.EA": None, "tethers.main.E": "70 GPa", "tethers.main.diameter": "1 mm"})
    assert swapped.tether("main").EA_N == pytest.approx(70e9 * math.pi * 1e-6 / 4)
    assert scene.replace(duration="3 orbits").duration_orbits == 3.0


def test_replace_fields():
    scene = Scene.from_dict(base())
    assert scene.replace(name="other").name == "other"
    orbits = scene.replace(duration_orbits=2.0)
    assert (orbits.duration_s, orbits.duration_orbits) == (None, 2.0)
    with pytest.raises(SceneError, match="tethers.main.rods"):
        scene.replace(tethers=(scene.tether("main").__class__(**{**scene.tether("main").__dict__, "rods": 0}),))


# -- validation: one case per rule -------------------------------------------------------------

CASES = {
    # unknown keys, at every level, with did-you-mean
    "unknown top key": ({"durration": "1 s"}, "durration", "did you mean 'duration'?"),
    "unknown tether key": ({"tethers.main.lenght": "5 km"}, "tethers.main.lenght", "did you mean 'length'?"),
    "unknown tether key case": ({"tethers.main.ea": "5e4 N"}, "tethers.main.ea", "did you mean 'EA'?"),
    "unknown body key": ({"bodies.m0.mas": "1 kg"}, "bodies.m0.mas", "did you mean 'mass'?"),
    "unknown element": ({"orbit.elements.ecc": 0.1}, "orbit.elements.ecc", "did you mean 'e'?"),
    "unknown initial key": ({"tethers.main.initial": {"thetta": "1 deg"}}, "tethers.main.initial.thetta", "did you mean 'theta'?"),
    "unknown orbit key": ({"orbit.refrence": "m0"}, "orbit.refrence", "did you mean 'reference'?"),
    "unknown integrator key": ({"integrator": {"rtoll": 1e-9}}, "integrator.rtoll", "did you mean 'rtol'?"),
    "unknown output key": ({"output": {"stp": "1 s"}}, "output.stp", "did you mean 'step'?"),
    "unknown central body key": ({"central_body": {"radious": "1 km"}}, "central_body.radious", "did you mean 'radius'?"),
    "unknown effect": ({"effects": {"central_gravty": {}}}, "effects.central_gravty", "did you mean 'central_gravity'?"),
    "unknown effect parameter": ({"effects": {"central_gravity": {"mu": "1 m3/s2"}}}, "effects.central_gravity.mu", "no keys"),
    "effect not a table": ({"effects": {"central_gravity": True}}, "effects.central_gravity", "a table"),
    "unknown central body": ({"central_body": {"name": "eart"}}, "central_body.name", "did you mean 'earth'?"),
    # missing required keys
    "missing duration": ({"duration": None}, "duration", "missing"),
    "missing effects": ({"effects": None}, "effects", "missing"),
    "missing bodies": ({"bodies": None}, "bodies", "missing"),
    "empty bodies": ({"bodies": {}}, "bodies", "at least one body"),
    "missing output": ({"output": None}, "output", "missing"),
    "missing body mass": ({"bodies.m0.mass": None}, "bodies.m0.mass", "expected a mass"),
    "missing tether length": ({"tethers.main.length": None}, "tethers.main.length", "expected a length"),
    "missing rods": ({"tethers.main.rods": None}, "tethers.main.rods", "missing"),
    "missing from": ({"tethers.main.from": None}, "tethers.main.from", "missing"),
    "missing to": ({"tethers.main.to": None}, "tethers.main.to", "missing"),
    "missing EA": ({"tethers.main.EA": None}, "tethers.main.EA", "or E with diameter"),
    "missing tether mass": ({"tethers.main.mass": None}, "tethers.main.mass", "linear_density"),
    "missing element a": ({"orbit.elements.a": None}, "orbit.elements.a", "missing"),
    # missing unit / wrong dimension
    "length missing unit": ({"tethers.main.length": 5000}, "tethers.main.length", "5000 (missing unit)"),
    "angle missing unit": ({"tethers.main.initial": {"theta": 0.5}}, "tethers.main.initial.theta", "missing unit"),
    "duration missing unit": ({"duration": 600}, "duration", "missing unit"),
    "position missing unit": ({"orbit": {"position": [7.4e6, 0, 0], "velocity": ["0 m/s", "7 km/s", "0 m/s"]}},
                              "orbit.position[0]", "missing unit"),
    "length wrong unit": ({"tethers.main.length": "5 kg"}, "tethers.main.length", "(dimension mass)"),
    "mass wrong unit": ({"bodies.m0.mass": "5 m"}, "bodies.m0.mass", "(dimension length)"),
    "damping wrong unit": ({"tethers.main.damping": "1 N"}, "tethers.main.damping", "(dimension force)"),
    "duration wrong unit": ({"duration": "5 m"}, "duration", "(dimension length)"),
    "velocity wrong unit": ({"orbit": {"position": ["7400 km", "0 m", "0 m"], "velocity": ["0 m/s", "7 km", "0 m/s"]}},
                            "orbit.velocity[1]", "(dimension length)"),
    "mu wrong unit": ({"central_body": {"mu": "4e14 m3/s"}}, "central_body.mu", "expected a gravitational parameter"),
    "max_step wrong unit": ({"integrator": {"max_step": "1 m"}}, "integrator.max_step", "expected a time"),
    "step wrong unit": ({"output": {"step": "1 kg"}}, "output.step", "expected a time"),
    "unparsable": ({"tethers.main.length": "five km"}, "tethers.main.length", "does not start with a number"),
    # non-positive / negative
    "zero body mass": ({"bodies.m0.mass": "0 kg"}, "bodies.m0.mass", "a mass > 0"),
    "negative body mass": ({"bodies.m0.mass": "-1 kg"}, "bodies.m0.mass", "a mass > 0"),
    "zero length": ({"tethers.main.length": "0 m"}, "tethers.main.length", "a length > 0"),
    "negative EA": ({"tethers.main.EA": "-5 N"}, "tethers.main.EA", "a force > 0"),
    "zero tether mass": ({"tethers.main.mass": "0 kg"}, "tethers.main.mass", "a mass > 0"),
    "zero diameter": ({"tethers.main.EA": None, "tethers.main.E": "70 GPa", "tethers.main.diameter": "0 mm"},
                      "tethers.main.diameter", "a length > 0"),
    "zero E": ({"tethers.main.EA": None, "tethers.main.E": "0 GPa", "tethers.main.diameter": "1 mm"},
               "tethers.main.E", "> 0"),
    "negative density": ({"tethers.main.mass": None, "tethers.main.density": "-1 kg/m3", "tethers.main.diameter": "1 mm"},
                         "tethers.main.density", "a density > 0"),
    "zero linear density": ({"tethers.main.mass": None, "tethers.main.linear_density": "0 g/m"},
                            "tethers.main.linear_density", "a linear density > 0"),
    "negative damping": ({"tethers.main.damping": "-1 N s"}, "tethers.main.damping", ">= 0"),
    "zero mu": ({"central_body": {"mu": "0 m3/s2"}}, "central_body.mu", "> 0"),
    # stiffness and mass alternatives
    "EA and E": ({"tethers.main.E": "70 GPa", "tethers.main.diameter": "1 mm"}, "tethers.main.E", "not both"),
    "E without diameter": ({"tethers.main.EA": None, "tethers.main.E": "70 GPa"}, "tethers.main.diameter", "to go with E"),
    "density without diameter": ({"tethers.main.mass": None, "tethers.main.density": "2700 kg/m3"},
                                 "tethers.main.diameter", "to go with density"),
    "mass and linear density": ({"tethers.main.linear_density": "2 g/m"}, "tethers.main.linear_density", "only one of"),
    # integers and choices
    "rods zero": ({"tethers.main.rods": 0}, "tethers.main.rods", "an integer >= 1"),
    "rods float": ({"tethers.main.rods": 2.5}, "tethers.main.rods", "an integer >= 1"),
    "rods integral float": ({"tethers.main.rods": 2.0}, "tethers.main.rods", "(float)"),
    "rods string": ({"tethers.main.rods": "2"}, "tethers.main.rods", "(str)"),
    "rods bool": ({"tethers.main.rods": True}, "tethers.main.rods", "(bool)"),
    "quadrature too big": ({"tethers.main.quadrature": 9}, "tethers.main.quadrature", "from 1 to 8"),
    "quadrature zero": ({"tethers.main.quadrature": 0}, "tethers.main.quadrature", "from 1 to 8"),
    "unknown model": ({"tethers.main.model": "papper"}, "tethers.main.model", "did you mean 'paper'?"),
    "unknown shape": ({"tethers.main.initial": {"shape": "curved"}}, "tethers.main.initial.shape", "'straight', 'rods'"),
    "unknown side": ({"tethers.main.initial": {"side": "upp"}}, "tethers.main.initial.side", "did you mean 'up'?"),
    "unknown motion": ({"orbit.motion": "rotating"}, "orbit.motion", "did you mean 'corotating'?"),
    "unknown method": ({"integrator": {"method": "dop85"}}, "integrator.method", "did you mean 'dop853'?"),
    "rtol zero": ({"integrator": {"rtol": 0.0}}, "integrator.rtol", "(0, 1)"),
    "rtol one": ({"integrator": {"rtol": 1}}, "integrator.rtol", "(0, 1)"),
    "atol negative": ({"integrator": {"atol": -1e-9}}, "integrator.atol", ">= 0"),
    "max_steps zero": ({"integrator": {"max_steps": 0}}, "integrator.max_steps", "an integer >= 1"),
    "fixed not bool": ({"bodies.m0.fixed": "yes"}, "bodies.m0.fixed", "true or false"),
    # tether ends
    "from no body": ({"tethers.main.from": "M0"}, "tethers.main.from", "'M0' (no such body)", "did you mean 'm0'?"),
    "to no body": ({"tethers.main.to": "mff"}, "tethers.main.to", "did you mean 'mf'?"),
    "same body twice": ({"tethers.main.to": "m0"}, "tethers.main.to", "same body at both ends"),
    # a body may end several tethers (trees), but a closed loop is refused naming the
    # tether that closes it (docs/scenes.md, forests)
    "loop of tethers": ({"bodies.m2": {"mass": "1 kg"},
                         "tethers.second": {"from": "m2", "to": "mf", "rods": 1, "length": "1 km", "EA": "1 N", "mass": "1 kg"},
                         "tethers.third": {"from": "m0", "to": "m2", "rods": 1, "length": "1 km", "EA": "1 N", "mass": "1 kg"}},
                        "tethers.third", "no closed loop", "tether 'third' closes a loop between 'm0' and 'm2'"),
    # names
    "body name not identifier": ({"bodies": {"m 0": {"mass": "1 kg"}}}, "bodies.m 0", "identifier"),
    "body named center_of_mass": ({"bodies.center_of_mass": {"mass": "1 kg"}}, "bodies.center_of_mass", "centre of mass"),
    "tether name not identifier": ({"tethers": {"1st": {}}}, "tethers.1st", "identifier"),
    "empty name": ({"name": " "}, "name", "non-empty"),
    # NaN and inf
    "nan float": ({"integrator": {"rtol": float("nan")}}, "integrator.rtol", "a finite number"),
    "inf eccentricity": ({"orbit.elements.e": float("inf")}, "orbit.elements.e", "a finite number"),
    "nan string": ({"tethers.main.length": "nan km"}, "tethers.main.length", "not finite"),
    "nan in a list": ({"output": {"times": ["0 s", float("nan")]}}, "output.times[1]", "a finite number"),
    "nan in an unknown key": ({"whatever": [1.0, float("inf")]}, "whatever[1]", "a finite number"),
    # states
    "elements and position": ({"orbit.position": ["7400 km", "0 km", "0 km"]}, "orbit.elements", "not both"),
    "body elements and velocity": ({"bodies.m0.elements": {"a": "7000 km", "e": 0}, "bodies.m0.velocity": ["0 m/s"] * 3,
                                    "orbit.reference": "m0", "orbit.elements": None},
                                   "bodies.m0.elements", "not both"),
    "position without velocity": ({"orbit": {"position": ["7400 km", "0 km", "0 km"]}}, "orbit.velocity", "to go with position"),
    "velocity without position": ({"orbit": {"velocity": ["0 m/s", "7 km/s", "0 m/s"]}}, "orbit.position", "to go with velocity"),
    "position wrong length": ({"orbit": {"position": ["7400 km", "0 km"], "velocity": ["0 m/s"] * 3}}, "orbit.position", "3 components"),
    "position at origin": ({"orbit": {"position": ["0 km"] * 3, "velocity": ["0 m/s", "7 km/s", "0 m/s"]}}, "orbit.position", "away from the centre"),
    "e >= 1 with a > 0": ({"orbit.elements.e": 1.5}, "orbit.elements.a", "a < 0 for a hyperbolic orbit"),
    "e < 1 with a < 0": ({"orbit.elements.a": "-7400 km"}, "orbit.elements.a", "a > 0 for an elliptic orbit"),
    "parabolic": ({"orbit.elements.e": 1}, "orbit.elements.e", "parabolic"),
    "negative e": ({"orbit.elements.e": -0.1}, "orbit.elements.e", ">= 0"),
    "e with unit": ({"orbit.elements.e": "0.1 m"}, "orbit.elements.e", "(dimension length)"),
    "inclination too big": ({"orbit.elements.i": "200 deg"}, "orbit.elements.i", "from 0 to 180 deg"),
    "beyond asymptote": ({"orbit.elements.a": "-7400 km", "orbit.elements.e": 1.5, "orbit.elements.nu": "150 deg"},
                         "orbit.elements.nu", "asymptotes"),
    "fixed without position": ({"bodies.m0.fixed": True}, "bodies.m0.position", "fixed body"),
    "fixed with velocity": ({"bodies.m0.fixed": True, "bodies.m0.position": ["7 km"] * 3, "bodies.m0.velocity": ["0 m/s"] * 3},
                            "bodies.m0.velocity", "held at rest"),
    # orbit and layout
    "reference no body": ({"orbit.reference": "m00"}, "orbit.reference", "(no such body)", "did you mean 'm0'?"),
    "no orbit no state": ({"orbit": None}, "orbit", "neither an [orbit] table nor any body"),
    "no orbit, one state": ({"orbit": None, "bodies.m0.elements": {"a": "7000 km", "e": 0}}, "bodies.mf", "without an [orbit] table"),
    "com reference with explicit body": ({"bodies.m0.elements": {"a": "7000 km", "e": 0}}, "orbit.reference", "would depend on them"),
    "com reference without state": ({"orbit.elements": None}, "orbit.elements", "the initial orbit"),
    "reference body state twice": ({"orbit.reference": "m0", "bodies.m0.elements": {"a": "7000 km", "e": 0}},
                                   "orbit.elements", "give it once"),
    "reference body without any state": ({"orbit.reference": "m0", "orbit.elements": None}, "orbit.elements", "explicit state on body 'm0'"),
    "reference fixed body": ({"orbit.reference": "m0", "orbit.elements": None, "bodies.m0.fixed": True,
                              "bodies.m0.position": ["7000 km", "0 km", "0 km"]}, "orbit.reference", "a moving body"),
    "unreachable body": ({"bodies.loose": {"mass": "1 kg"}}, "bodies.loose", "chain of tethers"),
    # duration
    "zero duration": ({"duration": "0 s"}, "duration", "> 0"),
    "negative orbits": ({"duration": "-1 orbits"}, "duration", "> 0"),
    "orbits on a hyperbola": ({"duration": "2 orbits", "orbit.elements.a": "-7400 km", "orbit.elements.e": 2.0},
                              "duration", "not closed"),
    # initial shape
    "rods wrong count": ({"tethers.main.initial": {"shape": "rods", "theta": ["0.1 rad"] * 3}}, "tethers.main.initial.theta",
                         "a list of 2 angles", "got 3 angles"),
    "rods phi wrong count": ({"tethers.main.initial": {"shape": "rods", "theta": ["0.1 rad"] * 2, "phi": ["0 rad"]}},
                             "tethers.main.initial.phi", "a list of 2 angles"),
    "rods scalar theta": ({"tethers.main.initial": {"shape": "rods", "theta": "0.1 rad"}}, "tethers.main.initial.theta", "one per rod"),
    "rods without theta": ({"tethers.main.initial": {"shape": "rods"}}, "tethers.main.initial.theta", "missing"),
    "straight list theta": ({"tethers.main.initial": {"theta": ["0.1 rad"] * 2}}, "tethers.main.initial.theta", "a single angle"),
    "strain too big": ({"tethers.main.initial": {"strain": 0.06}}, "tethers.main.initial.strain", "MAX_SANE_STRAIN"),
    "strain -1": ({"tethers.main.initial": {"strain": -1.0}}, "tethers.main.initial.strain", "(-1, 0.05]"),
    # output
    "output none": ({"output": {}}, "output", "exactly one of step, count, times", "none of them"),
    "output two": ({"output": {"step": "1 s", "count": 3}}, "output", "got step and count"),
    "count one": ({"output": {"count": 1}}, "output.count", "an integer >= 2"),
    "step zero": ({"output": {"step": "0 s"}}, "output.step", "> 0"),
    "times decreasing": ({"output": {"times": ["10 s", "5 s"]}}, "output.times[1]", "increasing"),
    "times beyond run": ({"output": {"times": ["0 s", "7000 s"]}}, "output.times[1]", "within the run"),
    "times empty": ({"output": {"times": []}}, "output.times", "non-empty"),
    # epoch
    "bad epoch": ({"epoch": "2026-13-01"}, "epoch", "ISO date"),
}


@pytest.mark.parametrize("changes, key, fragments", [(c, k, f) for c, k, *f in CASES.values()], ids=CASES.keys())
def test_validation(changes, key, fragments):
    fails(variant(changes), key, *fragments)


def test_initial_strain_at_the_limit_is_allowed():
    scene = Scene.from_dict(variant({"tethers.main.initial": {"strain": MAX_SANE_STRAIN}}))
    assert scene.tether("main").initial.strain == MAX_SANE_STRAIN


# -- tethers between explicitly placed ends ----------------------------------------------------


def test_explicit_ends_within_sane_strain_are_accepted():
    scene = Scene.from_dict(explicit_base(separation_m=5000.0 * (1 + MAX_SANE_STRAIN) * 0.999))
    assert scene.orbit is None
    assert scene.tether("main").initial is None  # straight between its ends
    assert scene.layout_plan() == (LayoutStep("main", "m0", None),)


def test_explicit_ends_too_far_apart():
    fails(explicit_base(separation_m=6000.0), "tethers.main.length", "ends farther apart than the tether can stretch",
          "strain 20.000%")


def test_explicit_ends_from_elements_too_far_apart():
    # m0 on a circular orbit at nu = 0, mf 1 deg further along: about 129 km apart for a 5 km tether.
    d = variant({"orbit": None, "bodies.m0.elements": {"a": "7400 km", "e": 0},
                 "bodies.mf.elements": {"a": "7400 km", "e": 0, "nu": "1 deg"}})
    fails(d, "tethers.main.length", "ends farther apart than the tether can stretch")


def test_explicit_ends_coincide():
    fails(explicit_base(separation_m=0.0), "tethers.main.to", "same position")


def test_explicit_ends_with_an_initial_shape():
    d = explicit_base()
    d["tethers"]["main"]["initial"] = {"theta": "1 deg"}
    fails(d, "tethers.main.initial", "starts straight between them")


def test_two_tethers_joining_the_same_pair_close_a_loop():
    # the kernel solves trees; two tethers between the same pair form a loop, refused at
    # load naming the second one (it closes the loop)
    d = variant({"tethers.back": {"from": "mf", "to": "m0", "rods": 1, "length": "5 km", "EA": "5e4 N", "mass": "1 kg"}})
    fails(d, "tethers.back", "no closed loop", "closes a loop between 'mf' and 'm0'")


def test_a_body_may_end_two_tethers():
    # a chain written towards its middle body: m0 -> mf <- m2 (trees allow any number of tethers per body)
    d = variant({"bodies.m2": {"mass": "1 kg"},
                 "tethers.second": {"from": "m2", "to": "mf", "rods": 1, "length": "1 km", "EA": "1 N", "mass": "1 kg"}})
    scene = Scene.from_dict(d)
    assert scene.layout_plan() == (LayoutStep("main", "m0", "mf"), LayoutStep("second", "mf", "m2"))
    assert Scene.from_dict(scene.to_dict()) == scene


def test_layout_from_a_reference_body_lays_tethers_in_either_direction():
    d = variant({"orbit.reference": "mf", "bodies.m2": {"mass": "1 kg"},
                 "tethers.second": {"from": "m2", "to": "m0", "rods": 1, "length": "1 km", "EA": "1 N", "mass": "1 kg"}})
    scene = Scene.from_dict(d)
    assert scene.layout_plan() == (LayoutStep("main", "mf", "m0"), LayoutStep("second", "m0", "m2"))


def test_orbit_period_from_a_body_state():
    d = variant({"orbit": {"reference": "m0"}, "bodies.m0.elements": {"a": "8000 km", "e": 0.2, "nu": "40 deg"},
                 "duration": "2.5 orbits"})
    scene = Scene.from_dict(d)
    assert scene.duration_seconds() == pytest.approx(2.5 * period(MU, 8e6), rel=1e-12)
    r, v = scene.reference_state()
    r_want, v_want = elements_to_cartesian(MU, 8e6, 0.2, 0, 0, 0, 40 * DEG)
    assert (r == r_want).all() and (v == v_want).all()


def test_orbits_duration_needs_an_orbit():
    d = explicit_base()
    d["duration"] = "3 orbits"
    fails(d, "duration", "needs an [orbit] table")


# -- effects with parameters (a temporary effect registered for the test) ----------------------


@pytest.fixture
def drag_effect(monkeypatch):
    spec = EffectSpec(
        name="test_drag",
        code=999,
        doc="test only",
        params={
            "cd": ParamSpec(unit="", required=False, default=2.2),
            "area": ParamSpec(unit="m2"),
            "rho": ParamSpec(unit="kg / m3", required=False, default="1e-12 g/cm3"),
            "scale": ParamSpec(unit="m", required=False, default=None),
        },
    )
    monkeypatch.setitem(EFFECTS, spec.name, spec)
    return spec


def test_effect_parameters_are_converted_and_defaults_filled(drag_effect):
    scene = Scene.from_dict(variant({"effects.test_drag": {"area": "2 cm2"}}))
    use = scene.effects[1]
    assert use.name == "test_drag"
    assert use.params_si == {"cd": 2.2, "area": pytest.approx(2e-4), "rho": pytest.approx(1e-9)}
    assert Scene.from_dict(scene.to_dict()) == scene


@pytest.mark.parametrize(
    "params, key, fragment",
    [
        ({}, "effects.test_drag.area", "missing"),
        ({"area": "2 m"}, "effects.test_drag.area", "(dimension length)"),
        ({"area": 2.0}, "effects.test_drag.area", "missing unit"),
        ({"area": "1 m2", "aera": "1 m2"}, "effects.test_drag.aera", "did you mean 'area'?"),
        ({"area": "1 m2", "cd": "2 kg"}, "effects.test_drag.cd", "expected a number"),
    ],
)
def test_effect_parameter_errors(drag_effect, params, key, fragment):
    fails(variant({"effects.test_drag": params}), key, fragment)
