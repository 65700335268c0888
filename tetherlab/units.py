"""Quantities at the boundary: "5 km" or ``5 * u.km`` in, an SI float out.

Every dimensional number a user writes carries its unit ("5 km", "30 deg", "5e4 N"); this module
parses it with :mod:`astropy.units`, checks its dimension against what the key needs, and returns a
plain float in SI (angles in rad).  Past this boundary the simulator only sees SI floats, so unit
mistakes are caught once, at load, with the key named.

Angular rates are written in the field's units: "rad/s", "deg/s", "rpm", "rev/min", "rev/s"
(astropy knows no revolution; :data:`REVOLUTION` and :data:`RPM` are defined here as exact multiples
of 2 pi rad and enabled only while a value is parsed, so they never leak into astropy's registry).

A bare number where a unit is required is refused ("missing unit"): guessing degrees versus
radians or km versus m is exactly the silent error this layer exists to prevent.  NaN and infinity
are refused everywhere, since no physical input is either.
"""

from __future__ import annotations

import math
import numbers
import warnings
from dataclasses import dataclass
from functools import lru_cache

import astropy.units as u

from .errors import SceneError

#: One revolution, 2 pi rad ("rev", "revolution"); "rev/s", "rev/min".
REVOLUTION = u.def_unit(["rev", "revolution"], 2.0 * math.pi * u.rad, doc="one revolution (2 pi rad)")
#: Revolutions per minute ("rpm"), the unit wheel and spin rates are quoted in.
RPM = u.def_unit(["rpm"], REVOLUTION / u.min, doc="revolutions per minute")
#: The unit spellings of an angular rate a scene accepts (docs/scenes.md lists them).
ANGULAR_RATE_SPELLINGS = ("rad/s", "deg/s", "rpm", "rev/min", "rev/s")


@dataclass(frozen=True)
class Kind:
    """What a key holds: the SI unit of the float handed on, and how to describe it to a user."""

    unit: str  # astropy unit string of the SI float; "" = dimensionless
    label: str  # "a force"
    example: str  # "5e4 N"

    @property
    def dimensionless(self) -> bool:
        return self.unit == ""

    def describe(self) -> str:
        return f"{self.label} (e.g. '{self.example}')"


LENGTH = Kind("m", "a length", "5 km")
MASS = Kind("kg", "a mass", "392.2 kg")
TIME = Kind("s", "a time", "60 s")
ANGLE = Kind("rad", "an angle", "30 deg")
FORCE = Kind("N", "a force", "5e4 N")
SPEED = Kind("m / s", "a speed", "7.3 km/s")
DAMPING = Kind("N s", "a damping coefficient (force x time)", "1e-3 N s")
GRAVITATIONAL_PARAMETER = Kind("m3 / s2", "a gravitational parameter", "3.986004418e14 m3 / s2")
MODULUS = Kind("Pa", "an elastic modulus (a pressure)", "70 GPa")
DENSITY = Kind("kg / m3", "a density", "2700 kg/m3")
LINEAR_DENSITY = Kind("kg / m", "a linear density", "2 g/m")
DIMENSIONLESS = Kind("", "a number", "0.5")
MOMENT_OF_INERTIA = Kind("kg m2", "a moment of inertia", "400 kg m2")
ANGULAR_RATE = Kind("rad / s", "an angular rate in rad/s, deg/s, rpm, rev/min or rev/s", "500 rpm")
TORQUE = Kind("N m", "a torque", "0.05 N m")
RATE = Kind("1 / s", "a rate (per unit time)", "2e-4 1/s")
ANGULAR_MOMENTUM = Kind("N m s", "an angular momentum (torque x time)", "20 N m s")

_KNOWN_KINDS = (
    LENGTH,
    MASS,
    TIME,
    ANGLE,
    FORCE,
    SPEED,
    DAMPING,
    GRAVITATIONAL_PARAMETER,
    MODULUS,
    DENSITY,
    LINEAR_DENSITY,
    ANGULAR_RATE,
)


@lru_cache(maxsize=256)
def kind_for_unit(unit: str) -> Kind:
    """The :class:`Kind` for an astropy unit string (as declared by an effect's ``ParamSpec``).

    Known SI units get their friendly label; any other unit gets a generic description, so new
    effects need not touch this module.  Cached: the strings are the effects' declarations (a
    few dozen), and parsing one with astropy costs ~0.2 ms, paid again by every serialised scene.
    """
    if unit.strip() == "":
        return DIMENSIONLESS
    target = u.Unit(unit)
    for kind in _KNOWN_KINDS:
        if u.Unit(kind.unit) == target:
            return kind
    return Kind(unit, f"a quantity in units of {unit!r} or equivalent", f"1 {unit}")


def _as_kind(kind: Kind | str) -> Kind:
    return kind if isinstance(kind, Kind) else kind_for_unit(kind)


def _dimension(unit: u.UnitBase) -> str:
    physical = str(unit.physical_type)
    if physical == "unknown":
        # astropy names no dimension for e.g. m3 / s2; the SI decomposition is the next best thing.
        return unit.si.to_string()
    return physical


def shown(value: object) -> str:
    """How a user's value is quoted back in an error message."""
    if isinstance(value, u.Quantity):
        return f"Quantity({value})"
    return repr(value)


def _short(message: str) -> str:
    # astropy's parse errors run on with a link to its docs; the first sentences say it all.
    return message.split(" If this is meant", 1)[0].strip()


def is_number(value: object) -> bool:
    """A real number given bare (int or float, numpy scalars included), never a bool."""
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def parse_quantity(value: object, *, key: str) -> u.Quantity:
    """A scalar astropy Quantity from a string like "5 km" or a Quantity; anything else raises.

    A string without a unit ("0.5") parses as a dimensionless quantity; the caller decides whether
    that is acceptable.
    """
    if isinstance(value, u.Quantity):
        if not value.isscalar:
            raise SceneError(key, "a single quantity", f"{shown(value)} (an array)")
        return value
    if isinstance(value, str):
        try:
            # Unit-parse warnings (deprecated spellings and the like) must not leak out as
            # warnings far from the key: a value that does not parse cleanly is reported here.
            with warnings.catch_warnings(), u.add_enabled_units([REVOLUTION, RPM]):
                warnings.simplefilter("error")
                quantity = u.Quantity(value)
        except (TypeError, ValueError, Warning) as exc:
            raise SceneError(
                key, "a quantity with a unit, e.g. '5 km'", f"{value!r} ({_short(str(exc))})"
            ) from None
        if not quantity.isscalar:
            raise SceneError(key, "a single quantity", f"{value!r} (an array)")
        return quantity
    raise SceneError(key, "a quantity with a unit, e.g. '5 km'", f"{shown(value)} ({type(value).__name__})")


def to_si(value: object, kind: Kind | str, *, key: str) -> float:
    """The SI float for ``value`` ("5 km", ``5 * u.km``, or a bare number if ``kind`` is dimensionless).

    Raises :class:`SceneError` naming ``key`` for a missing unit, a wrong dimension, an
    unparsable string or a non-finite value.
    """
    kind = _as_kind(kind)
    if is_number(value):
        if not kind.dimensionless:
            raise SceneError(key, kind.describe(), f"{shown(value)} (missing unit)")
        result = float(value)
    elif kind.dimensionless and not isinstance(value, (str, u.Quantity)):
        raise SceneError(key, kind.describe(), f"{shown(value)} ({type(value).__name__})")
    else:
        quantity = parse_quantity(value, key=key)
        target = u.Unit(kind.unit) if kind.unit else u.dimensionless_unscaled
        if quantity.unit.is_equivalent(target):
            result = float(quantity.to_value(target))
        elif quantity.unit.physical_type == "dimensionless":
            raise SceneError(key, kind.describe(), f"{shown(value)} (missing unit)")
        else:
            raise SceneError(
                key, kind.describe(), f"{shown(value)} (dimension {_dimension(quantity.unit)})"
            )
    if not math.isfinite(result):
        raise SceneError(key, f"a finite value: {kind.describe()}", f"{shown(value)} (not finite)")
    return result


def format_si(value: float, kind: Kind | str) -> str | float:
    """The scene-file form of an SI float: "5000.0 m"; a dimensionless value stays a float.

    ``repr`` keeps every digit, so ``to_si(format_si(x, k), k) == x`` exactly.
    """
    kind = _as_kind(kind)
    if kind.dimensionless:
        return float(value)
    return f"{float(value)!r} {kind.unit}"
