"""[tethers]: ends, rods, stiffness and mass (directly or from material properties), model and
quadrature, the initial shape, attachment points."""

from __future__ import annotations

import math
from typing import Any

import astropy.units as u

from ..errors import SceneError
from ..units import (
    ANGLE,
    DAMPING,
    DENSITY,
    DIMENSIONLESS,
    FORCE,
    LENGTH,
    LINEAR_DENSITY,
    MASS,
    MODULUS,
    RATE,
    shown,
    to_si,
)
from .data import (
    EQUILIBRIUM,
    INEXTENSIBLE,
    MAX_SANE_STRAIN,
    QUADRATURE_RANGE,
    SHAPES,
    SIDES,
    TETHER_MODELS,
    Body,
    InitialShape,
    Release,
    Tether,
)
from .keys import (
    _NOTHING,
    _choice,
    _integer,
    _named_tables,
    _quantity,
    _quoted,
    _required,
    _string,
    _suggest,
    _table,
    _vector,
)
from .reels import parse_reel, rods_for


_TETHER_KEYS = (
    "from",
    "to",
    "rods",
    "length",
    "EA",
    "E",
    "diameter",
    "mass",
    "linear_density",
    "density",
    "damping",
    "model",
    "quadrature",
    "initial",
    "tension_only",
    "from_point",
    "to_point",
    "reel",
    "constraint_rate",
)


def _body_ref(value: Any, key: str, names: list[str]) -> str:
    expected = f"the name of a body ({_quoted(names)})"
    name = _string(value, key, expected)
    if name not in names:
        raise SceneError(key, expected, f"{name!r} (no such body)", hint=_suggest(name, names))
    return name


def _parse_tethers(value: Any, bodies: tuple[Body, ...]) -> tuple[Tether, ...]:
    tables = _named_tables(value, "tethers", "tethers")
    names = [b.name for b in bodies]
    tethers = []
    to_owner: dict[str, str] = {}
    for name, raw in tables.items():
        path = f"tethers.{name}"
        table = _table(raw, path, _TETHER_KEYS)
        start = _body_ref(_required(table, "from", path, "the name of the body at end A_1"), f"{path}.from", names)
        end = _body_ref(_required(table, "to", path, "the name of the body at end B_n"), f"{path}.to", names)
        if end == start:
            raise SceneError(f"{path}.to", f"a body other than 'from' ({start!r})", f"{end!r} (the same body at both ends)")
        to_owner[end] = name
        length = _quantity(_required(table, "length", path, LENGTH.describe()), f"{path}.length", LENGTH, positive=True)
        reel = parse_reel(table["reel"], f"{path}.reel", length) if "reel" in table else None
        if reel is None:
            rods = _integer(_required(table, "rods", path, "an integer >= 1"), f"{path}.rods", 1)
        else:
            # the reel decides the rods: full rods of reel.rod_length and the one at the reel
            rods = rods_for(length, reel)
            if "rods" in table and table["rods"] != rods:
                raise SceneError(f"{path}.rods", f"no 'rods' with a reel, or the count its rod_length gives ({rods})",
                                 shown(table["rods"]))  # fmt: skip
        diameter = _quantity(table["diameter"], f"{path}.diameter", LENGTH, positive=True) if "diameter" in table else None
        area = None if diameter is None else math.pi * diameter * diameter / 4.0

        # Axial stiffness: EA directly, or modulus E times the cross-section of `diameter`.
        if "EA" in table and "E" in table:
            raise SceneError(f"{path}.E", "either EA or E (with diameter), not both", "both EA and E")
        if "EA" in table:
            ea = _quantity(table["EA"], f"{path}.EA", FORCE, positive=True)
        elif "E" in table:
            modulus = _quantity(table["E"], f"{path}.E", MODULUS, positive=True)
            if area is None:
                raise SceneError(f"{path}.diameter", f"a diameter to go with E ({LENGTH.describe()})", _NOTHING)
            ea = modulus * area
        else:
            raise SceneError(f"{path}.EA", f"the axial stiffness EA ({FORCE.describe()}), or E with diameter", _NOTHING)

        # Mass: given, per unit length, or from the material density and cross-section.
        given = [k for k in ("mass", "linear_density", "density") if k in table]
        if not given:
            raise SceneError(f"{path}.mass", f"the tether mass ({MASS.describe()}), or linear_density, or density with diameter", _NOTHING)
        if len(given) > 1:
            raise SceneError(f"{path}.{given[1]}", "only one of mass, linear_density, density", f"both {given[0]} and {given[1]}")
        if given[0] == "mass":
            mass = _quantity(table["mass"], f"{path}.mass", MASS, positive=True)
        elif given[0] == "linear_density":
            mass = _quantity(table["linear_density"], f"{path}.linear_density", LINEAR_DENSITY, positive=True) * length
        else:
            density = _quantity(table["density"], f"{path}.density", DENSITY, positive=True)
            if area is None:
                raise SceneError(f"{path}.diameter", f"a diameter to go with density ({LENGTH.describe()})", _NOTHING)
            mass = density * area * length

        damping = _quantity(table["damping"], f"{path}.damping", DAMPING, nonnegative=True) if "damping" in table else 0.0
        model = _choice(table.get("model", "paper"), f"{path}.model", TETHER_MODELS)
        quadrature = _integer(table.get("quadrature", 2), f"{path}.quadrature", *QUADRATURE_RANGE)
        initial = _parse_initial(table["initial"], f"{path}.initial", rods) if "initial" in table else None
        tension_only = table.get("tension_only", False)
        if not isinstance(tension_only, bool):
            raise SceneError(f"{path}.tension_only", "true or false", f"{shown(tension_only)} ({type(tension_only).__name__})")
        from_point = _vector(table["from_point"], f"{path}.from_point", LENGTH) if "from_point" in table else None
        to_point = _vector(table["to_point"], f"{path}.to_point", LENGTH) if "to_point" in table else None
        rate = _inextensible_keys(table, path, model, reel, tension_only, damping)
        rigid_start = any(b.name == start and b.rigid is not None for b in bodies)
        if reel is not None and reel.point_m is not None and rigid_start:  # the reel's exit is the attachment
            if from_point is None:
                from_point = reel.point_m
            elif any(abs(a - b) > 1e-12 * max(1.0, abs(b)) for a, b in zip(from_point, reel.point_m)):
                raise SceneError(f"{path}.from_point", f"the reel's point {reel.point_m} m (the tether leaves the reel at its "
                                 "exit: leave from_point out or write the same point)", f"{from_point} m")  # fmt: skip
        tethers.append(
            Tether(name, start, end, rods, length, ea, mass, damping, model, quadrature, diameter, tension_only=tension_only,
                   initial=initial, from_point_m=from_point, to_point_m=to_point, reel=reel, constraint_rate_1_s=rate)
        )
    return tuple(tethers)


def _inextensible_keys(table, path: str, model: str, reel, tension_only: bool, damping: float) -> float | None:
    """The constraint rate of an inextensible tether (None: the default), and the keys that an
    inextensible tether cannot have, refused by name (docs/inextensible.md section 5)."""
    if model != INEXTENSIBLE:
        if "constraint_rate" in table:
            raise SceneError(f"{path}.constraint_rate", "model = 'inextensible' with a constraint rate (only its "
                             "length constraints have one)", f"model {model!r}")  # fmt: skip
        return None
    if tension_only:
        raise SceneError(f"{path}.tension_only", "no tension_only with model = 'inextensible' (its rods cannot go "
                         "slack: a tension reaching zero stops the run; use model = 'paper' for a slack tether)",
                         "true")  # fmt: skip
    if reel is not None:
        raise SceneError(f"{path}.reel", "no reel with model = 'inextensible' (a reel pays out an elastic chain)",
                         "a reel table")  # fmt: skip
    if damping != 0.0:
        raise SceneError(f"{path}.damping", "no axial damping with model = 'inextensible' (its rods do not stretch)",
                         shown(table.get("damping")))  # fmt: skip
    if "constraint_rate" not in table:
        return None
    return _quantity(table["constraint_rate"], f"{path}.constraint_rate", RATE, nonnegative=True)


def _angles(value: Any, key: str, shape: str, rods: int) -> float | tuple[float, ...]:
    if isinstance(value, u.Quantity) and value.ndim == 1:
        value = list(value)  # an angle array from Python counts as a list
    if shape == "straight":
        if isinstance(value, (list, tuple)):
            raise SceneError(key, f"a single angle for shape 'straight' ({ANGLE.describe()})", shown(value))
        return to_si(value, ANGLE, key=key)
    if not isinstance(value, (list, tuple)) or len(value) != rods:
        got = f"{len(value)} angles" if isinstance(value, (list, tuple)) else shown(value)
        raise SceneError(key, f"a list of {rods} angles, one per rod (rods = {rods})", got)
    return tuple(to_si(item, ANGLE, key=f"{key}[{j}]") for j, item in enumerate(value))


def _parse_initial(value: Any, path: str, rods: int) -> InitialShape:
    table = _table(value, path, ("shape", "theta", "phi", "side", "strain", "release"))
    shape = _choice(table.get("shape", "straight"), f"{path}.shape", SHAPES)
    if shape == EQUILIBRIUM:
        # the static solve decides every rod's direction and strain: nothing else to give but
        # the release from the free hang
        extra = [k for k in table if k not in ("shape", "release")]
        if extra:
            raise SceneError(
                f"{path}.{extra[0]}", "no other key than release with shape 'equilibrium' (the statics solve sets the shape)",
                shown(table[extra[0]]),
            )
        release = _parse_release(table["release"], f"{path}.release") if "release" in table else None
        return InitialShape(EQUILIBRIUM, release=release)
    if "release" in table:
        raise SceneError(f"{path}.release", "shape = 'equilibrium' with a release (it perturbs the free hang)", f"shape {shape!r}")
    if shape == "rods":
        theta = _angles(_required(table, "theta", path, f"a list of {rods} angles, one per rod"), f"{path}.theta", shape, rods)
        phi = _angles(table["phi"], f"{path}.phi", shape, rods) if "phi" in table else (0.0,) * rods
    else:
        theta = _angles(table["theta"], f"{path}.theta", shape, rods) if "theta" in table else 0.0
        phi = _angles(table["phi"], f"{path}.phi", shape, rods) if "phi" in table else 0.0
    side = _choice(table.get("side", "up"), f"{path}.side", SIDES)
    strain = to_si(table.get("strain", 0.0), DIMENSIONLESS, key=f"{path}.strain")
    if not (-1.0 < strain <= MAX_SANE_STRAIN):
        raise SceneError(
            f"{path}.strain",
            f"a strain in (-1, {MAX_SANE_STRAIN!r}] (MAX_SANE_STRAIN: beyond any real tether's elastic range)",
            shown(table.get("strain")),
        )
    return InitialShape(shape, theta, phi, side, strain)


def _parse_release(value: Any, path: str) -> Release:
    """``release = { angle = "5 deg" }`` or ``release = { mode = 1, amplitude = "1 cm" }``."""
    table = _table(value, path, ("angle", "mode", "amplitude"))
    if "angle" in table:
        if "mode" in table or "amplitude" in table:
            other = "mode" if "mode" in table else "amplitude"
            raise SceneError(f"{path}.{other}", "either angle, or mode with amplitude, not both", shown(table[other]))
        angle = to_si(table["angle"], ANGLE, key=f"{path}.angle")
        if not (math.isfinite(angle) and 0.0 < abs(angle) < 0.5 * math.pi):
            raise SceneError(f"{path}.angle", "an angle between 0 and 90 deg (either sign), the swing's start", shown(table["angle"]))
        return Release(angle_rad=angle)
    if "mode" not in table:
        raise SceneError(f"{path}.angle", "angle (e.g. '5 deg'), or mode with amplitude (e.g. mode = 1, amplitude = '1 cm')", _NOTHING)
    mode = _integer(table["mode"], f"{path}.mode", 1)
    amplitude = _quantity(_required(table, "amplitude", path, "the end mass's sideways displacement (e.g. '1 cm')"),
                          f"{path}.amplitude", LENGTH)  # fmt: skip
    if not (math.isfinite(amplitude) and amplitude != 0.0):
        raise SceneError(f"{path}.amplitude", "a non-zero length (the end mass's sideways displacement)", shown(table["amplitude"]))
    return Release(mode=mode, amplitude_m=amplitude)
