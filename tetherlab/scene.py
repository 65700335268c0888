"""The scene: what to simulate, read from a TOML file or a Python dictionary, validated once.

A scene says which central body, which effects, which bodies and tethers, where they start, how
to integrate and what to output.  :func:`load_scene` reads a TOML file (``docs/scenes.md`` is the
reference of every key); :meth:`Scene.from_dict` reads the same structure from Python, where any
quantity may be a string ("5 km") or an astropy Quantity (``5 * u.km``).  Both return a
:class:`Scene`: frozen dataclasses holding SI floats (angles in rad), unit suffixes in the field
names (``length_m``, ``mass_kg``).

Every check happens here, at load, before anything is integrated; every failure is a
:class:`~tetherlab.errors.SceneError` naming the dotted key, what was expected and what was got.
The dataclasses are the *output* of that validation: build them through :meth:`Scene.from_dict`
(or :func:`load_scene`) and change them through :meth:`Scene.replace`, which re-validates.
"""

from __future__ import annotations

import dataclasses
import datetime
import difflib
import math
import numbers
import re
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import astropy.units as u
import numpy as np

from .errors import SceneError
from .forces import EFFECTS
from .model import topology
from .model.topology import LayoutStep
from .orbits import kepler
from .units import (
    ANGLE,
    DAMPING,
    DENSITY,
    DIMENSIONLESS,
    FORCE,
    GRAVITATIONAL_PARAMETER,
    LENGTH,
    LINEAR_DENSITY,
    MASS,
    MODULUS,
    ANGULAR_MOMENTUM,
    ANGULAR_RATE,
    MOMENT_OF_INERTIA,
    SPEED,
    TIME,
    TORQUE,
    Kind,
    format_si,
    is_number,
    kind_for_unit,
    shown,
    to_si,
)

# Largest strain a scene may start with, or imply by placing a tether's two ends.  5 % is far
# beyond the elastic limit of aluminium (about 0.3 %) and the working range of polymer tethers
# (Dyneema/Spectra fail near 3-4 %), so anything larger is a units or placement mistake, not a
# physical initial condition.
MAX_SANE_STRAIN = 0.05

CENTER_OF_MASS = "center_of_mass"
TETHER_MODELS = ("paper", "energy")
SHAPES = ("straight", "rods", "equilibrium")
EQUILIBRIUM = "equilibrium"  # static shape between two placed ends (tetherlab.statics)
SIDES = ("up", "down")
MOTIONS = ("corotating", "translating", "equilibrium", "quasi-static")
INTEGRATOR_METHODS = (
    "dop853",
    "vern9",
    "radau5",
    "abm",  # DROMO sigma form only (pipeline._formulation; docs/integrators.md section 8)
    "scipy:DOP853",
    "scipy:Radau",
    "scipy:LSODA",
    "scipy:BDF",
    "scipy:RK45",
)
QUADRATURE_RANGE = (1, 8)  # Gauss-Legendre nodes per half-rod
# Effects whose field is singular at the origin of the scene frame (the central body's centre):
# with one of them named, no body may start there.
SINGULAR_AT_ORIGIN = ("central_gravity", "j2", "zonal")

Vector3 = tuple[float, float, float]

#: Euler sequences accepted for a rigid body's initial attitude (intrinsic rotations, scipy's
#: upper-case convention): the six Tait-Bryan and the six proper Euler sequences.
EULER_SEQUENCES = ("XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX", "XYX", "XZX", "YXY", "YZY", "ZXZ", "ZYZ")
#: |q| of a given quaternion must be within this of 1 (then it is normalised): a larger error is a
#: typo, not round-off of printed digits.
QUATERNION_NORM_TOL = 1e-6
ATTITUDE_FRAMES = ("inertial", "orbit")
RATE_FRAMES = ("body", "orbit")
WHEEL_TORQUE_CONTROL = "control"


# --------------------------------------------------------------------------------------------
# The validated scene: SI floats only.
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class CentralBody:
    name: str
    mu_m3_s2: float
    radius_m: float


# Only known presets are allowed: a misspelt or unsupported body must not silently become Earth.
CENTRAL_BODY_PRESETS: dict[str, CentralBody] = {
    # WGS 84 (NIMA TR8350.2, 3rd ed., tables 3.1 and 3.4): GM = 3.986004418e14 m^3/s^2 (with the
    # atmosphere; also the IERS Conventions 2010 value) and equatorial radius a = 6378137.0 m.
    "earth": CentralBody("earth", 3.986004418e14, 6378137.0),
}


@dataclass(frozen=True)
class Elements:
    """Classical orbital elements; conventions of :mod:`tetherlab.orbits.kepler`."""

    a_m: float
    e: float
    i_rad: float = 0.0
    raan_rad: float = 0.0
    argp_rad: float = 0.0
    nu_rad: float = 0.0

    def to_cartesian(self, mu_m3_s2: float) -> tuple[np.ndarray, np.ndarray]:
        return kepler.elements_to_cartesian(
            mu_m3_s2, self.a_m, self.e, self.i_rad, self.raan_rad, self.argp_rad, self.nu_rad
        )


@dataclass(frozen=True)
class Attitude:
    """Initial attitude (docs/scenes.md): kind "orbit", "quaternion" (values = (w, x, y, z), unit)
    or "euler" (values = 3 angles in rad, ``sequence``); ``frame`` the frame body axes map to."""

    kind: str = "orbit"
    values: tuple = ()
    sequence: str = "ZYX"
    frame: str = "inertial"


@dataclass(frozen=True)
class Wheel:
    name: str
    axis: Vector3  # unit, body axes
    inertia_kg_m2: float
    speed_rad_s: float = 0.0
    max_speed_rad_s: float | None = None
    max_torque_N_m: float | None = None
    torque: Any = 0.0  # float (N m), "control", or (times_s, values_N_m)


@dataclass(frozen=True)
class Control:
    law: str
    target: str  # "orbit" | "inertial"
    kp_N_m: float
    kd_N_m_s: float
    quaternion: tuple | None = None  # inertial target (w, x, y, z), unit


@dataclass(frozen=True)
class Rigid:
    """A rigid body's inertia (J_B about G, body axes, wheels locked), initial attitude and rate,
    wheels and controller (docs/scenes.md, [bodies.NAME.rigid])."""

    inertia_kg_m2: tuple  # 3x3 nested tuple, symmetric
    attitude: Attitude = Attitude()
    angular_velocity_rad_s: Vector3 = (0.0, 0.0, 0.0)
    angular_velocity_frame: str = "orbit"
    wheels: tuple = ()
    control: Control | None = None


@dataclass(frozen=True)
class Body:
    """A point mass (or, with ``rigid``, a rigid body whose position is its centre of mass).  Its initial state is explicit (position/velocity, elements, or fixed with a
    position) or, when all three are absent, laid out from the orbit and the tether shapes."""

    name: str
    mass_kg: float
    fixed: bool = False
    position_m: Vector3 | None = None
    velocity_m_s: Vector3 | None = None
    elements: Elements | None = None
    rigid: Rigid | None = None

    @property
    def has_state(self) -> bool:
        return self.position_m is not None or self.elements is not None

    def state(self, mu_m3_s2: float) -> tuple[np.ndarray, np.ndarray] | None:
        """Explicit inertial (r, v) in m and m/s, or None when the layout places the body."""
        if self.elements is not None:
            return self.elements.to_cartesian(mu_m3_s2)
        if self.position_m is None:
            return None
        velocity = (0.0, 0.0, 0.0) if self.fixed else self.velocity_m_s
        return np.array(self.position_m, dtype=float), np.array(velocity, dtype=float)


@dataclass(frozen=True)
class InitialShape:
    """Initial layout of a tether laid out from one placed end.

    ``theta_rad``/``phi_rad`` are single floats for ``shape = "straight"`` and tuples with one
    angle per rod for ``shape = "rods"``.
    """

    shape: str = "straight"
    theta_rad: float | tuple[float, ...] = 0.0
    phi_rad: float | tuple[float, ...] = 0.0
    side: str = "up"
    strain: float = 0.0

    def rod_angles_rad(self, rods: int) -> tuple[tuple[float, ...], tuple[float, ...]]:
        """(theta, phi) of every rod, whatever the shape."""
        if self.shape == "straight":
            return (float(self.theta_rad),) * rods, (float(self.phi_rad),) * rods
        return tuple(self.theta_rad), tuple(self.phi_rad)


@dataclass(frozen=True)
class Tether:
    name: str
    from_body: str  # body at end A_1
    to_body: str  # body at end B_n
    rods: int
    length_m: float  # unstretched length L_u
    EA_N: float  # axial stiffness
    mass_kg: float
    damping_N_s: float = 0.0  # D in T = EA eps + D d(eps)/dt
    model: str = "paper"
    quadrature: int = 2
    diameter_m: float | None = None
    # A real tether cannot push: with tension_only the axial force is max(0, EA eps + D eps') for
    # eps > 0 and zero otherwise; the kinks where it switches are located as events.
    tension_only: bool = False
    # None when both ends are placed before the tether is laid (see Scene.layout_plan): it then
    # starts straight between them.
    initial: InitialShape | None = None
    from_point_m: Vector3 | None = None  # attachment on the rigid `from` body, body axes
    to_point_m: Vector3 | None = None


@dataclass(frozen=True)
class Orbit:
    """Initial orbit of the reference point (the centre of mass, or a body)."""

    reference: str = CENTER_OF_MASS
    elements: Elements | None = None
    position_m: Vector3 | None = None
    velocity_m_s: Vector3 | None = None
    motion: str = "corotating"

    def state(self, mu_m3_s2: float) -> tuple[np.ndarray, np.ndarray] | None:
        if self.elements is not None:
            return self.elements.to_cartesian(mu_m3_s2)
        if self.position_m is None:
            return None
        return np.array(self.position_m, dtype=float), np.array(self.velocity_m_s, dtype=float)


@dataclass(frozen=True)
class IntegratorSpec:
    method: str = "dop853"
    rtol: float = 1e-10
    atol: float = 1e-10  # in units of each state component's natural scale
    max_step_s: float | None = None
    max_steps: int | None = None
    # "cowell", or "dromo": the orbit in DROMO elements (docs/dromo.md); for a single point mass
    # with the ideal anomaly as independent variable, with tethers in time form; "dromo-time":
    # the time form always; "cowell-orbit": Cowell's equations in a frame turning uniformly with
    # the orbit (formulations/cowell_orbit.py), for RADAU5 on many-rod tethers
    formulation: str = "cowell"
    # DROMO's sigma form (a point mass): "none", state component 0 is the physical time; "linear",
    # the linear time element (docs/dromo.md section 11: elliptic orbits, fewer steps where the
    # perturbation is small at apocentre)
    time_element: str = "none"


FORMULATIONS = ("cowell", "dromo", "dromo-time", "cowell-orbit")
TIME_ELEMENTS = ("none", "linear")


@dataclass(frozen=True)
class OutputSpec:
    """Exactly one of the three is set."""

    step_s: float | None = None
    count: int | None = None
    times_s: tuple[float, ...] | None = None


@dataclass(frozen=True)
class EffectUse:
    name: str
    # every declared parameter, defaults filled: an SI float in ParamSpec.unit, the string of a
    # choice parameter, or {body name: SI float} for a per-body parameter
    params_si: dict[str, Any]


@dataclass(frozen=True)
class Stop:
    """Conditions that end a run before its duration (each located as a terminal event)."""

    altitude_m: float | None = None  # the root body's altitude above the central body's radius


@dataclass(frozen=True)
class Scene:
    name: str
    duration_s: float | None  # exactly one of duration_s and duration_orbits is set
    duration_orbits: float | None
    central_body: CentralBody
    effects: tuple[EffectUse, ...]
    bodies: tuple[Body, ...]
    tethers: tuple[Tether, ...]
    orbit: Orbit | None
    integrator: IntegratorSpec
    output: OutputSpec
    description: str | None = None
    epoch: str | None = None  # ISO date, TDB
    stop: Stop | None = None
    source: str = field(default="<dict>", compare=False)  # file path, or "<dict>"
    # the graph of bodies and tethers (tetherlab/model/topology.py), derived at load: not part of
    # the scene's value (equality, to_dict) any more than its source is
    graph: topology.Graph | None = field(default=None, compare=False, repr=False)

    # -- construction ---------------------------------------------------------------------

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: str = "<dict>") -> "Scene":
        """Validate ``data`` (the TOML structure; quantities as strings or astropy Quantities)."""
        try:
            return _parse_scene(data, str(source))
        except SceneError as exc:
            if exc.source is None:
                raise exc.with_source(str(source)) from None
            raise

    def to_dict(self) -> dict[str, Any]:
        """The scene as a TOML-shaped dictionary with SI strings ("5000.0 m").

        ``Scene.from_dict(scene.to_dict()) == scene`` holds exactly: floats are written with
        ``repr`` so no digit is lost.
        """
        return _scene_to_dict(self)

    def replace(self, **changes: Any) -> "Scene":
        """A validated copy with some values changed, for parameter sweeps.

        Two spellings, mixable:

        * a field of :class:`Scene` (``scene.replace(name="b")``), as ``dataclasses.replace``;
        * a (dotted) scene key with a scene-file value, passed through ``**``:
          ``scene.replace(**{"tethers.main.rods": 8, "duration": "2 orbits"})``; ``None``
          removes the key (``{"tethers.main.EA": None, "tethers.main.E": "70 GPa"}``).

        The result goes through :meth:`from_dict` again, so a change that breaks the scene
        raises a SceneError just as a bad file would.
        """
        names = {f.name for f in dataclasses.fields(Scene)}

        def parsed(v):  # a value already of a Scene field's type (OutputSpec, a tuple of Body...)
            return dataclasses.is_dataclass(v) or (isinstance(v, tuple) and all(map(dataclasses.is_dataclass, v)))

        # a name that is both a field and a scene key ("output") takes a scene-file value unless
        # it is given already parsed: output={"count": 20} is validated like a file's [output]
        as_field = {k for k in changes if k in names and not (k in _TOP_KEYS and not parsed(changes[k]))}
        fields = {k: v for k, v in changes.items() if k in as_field}
        keys = {k: v for k, v in changes.items() if k not in as_field}
        # The duration is one of two fields; setting one clears the other.
        if "duration_s" in fields and "duration_orbits" not in fields:
            fields["duration_orbits"] = None
        if "duration_orbits" in fields and "duration_s" not in fields:
            fields["duration_s"] = None
        scene = dataclasses.replace(self, **fields) if fields else self
        data = scene.to_dict()
        for path, value in keys.items():
            _set_dotted(data, path, value)
        return Scene.from_dict(data, source=self.source)

    # -- look-ups and derived values --------------------------------------------------------

    def body(self, name: str) -> Body:
        for item in self.bodies:
            if item.name == name:
                return item
        raise KeyError(f"no body {name!r} in scene {self.name!r}")

    def tether(self, name: str) -> Tether:
        for item in self.tethers:
            if item.name == name:
                return item
        raise KeyError(f"no tether {name!r} in scene {self.name!r}")

    def reference_state(self) -> tuple[np.ndarray, np.ndarray] | None:
        """Initial inertial (r, v) of the orbit reference point, None without an [orbit]."""
        return _reference_state(self.orbit, self.bodies, self.central_body.mu_m3_s2)

    def orbit_period_s(self) -> float:
        """Keplerian period of the reference point's initial osculating orbit."""
        state = self.reference_state()
        if state is None:
            raise ValueError(f"scene {self.name!r} has no [orbit], hence no orbit period")
        return _period_of_state(self.central_body.mu_m3_s2, *state)

    def duration_seconds(self) -> float:
        """The run length in seconds, "N orbits" resolved with :meth:`orbit_period_s`."""
        if self.duration_s is not None:
            return self.duration_s
        return self.duration_orbits * self.orbit_period_s()

    def layout_plan(self) -> tuple[LayoutStep, ...]:
        """The order in which the initial layout places the bodies (see docs/scenes.md)."""
        return self.graph_of().layout

    def graph_of(self) -> topology.Graph:
        """The scene's graph: the one built at load, or (a Scene made by hand) built now."""
        if self.graph is not None:
            return self.graph
        return topology.build(self.bodies, self.tethers).with_layout(self.bodies, self.tethers, self.orbit)


def load_scene(path: str | Path) -> Scene:
    """Read and validate a TOML scene file."""
    path = Path(path)
    if not path.is_file():
        where = path.resolve()
        reason = "is a directory, not a scene file" if path.is_dir() else "does not exist"
        raise FileNotFoundError(f"scene file {str(path)!r} {reason} (resolved to {str(where)!r})")
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise SceneError("", "a UTF-8 text file", f"undecodable bytes ({exc.reason})", source=str(path)) from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        # Python 3.11 has no lineno attribute on the exception; the message ends "(at line L, column C)".
        match = re.search(r"at line (\d+)", str(exc))
        line = int(match.group(1)) if match else None
        raise SceneError("", "valid TOML", str(exc), source=str(path), line=line) from None
    return Scene.from_dict(data, source=str(path))


# --------------------------------------------------------------------------------------------
# Reading helpers: every one names the dotted key it reads.
# --------------------------------------------------------------------------------------------

_NOTHING = "nothing (the key is missing)"


def _join(path: str, key: str) -> str:
    return f"{path}.{key}" if path else key


# Common other spellings of orbital elements, too short or too different for difflib to match.
_ALIASES = {
    "sma": "a",
    "semi_major_axis": "a",
    "ecc": "e",
    "eccentricity": "e",
    "inc": "i",
    "inclination": "i",
    "Omega": "raan",
    "lan": "raan",
    "omega": "argp",
    "w": "argp",
    "aop": "argp",
    "ta": "nu",
    "true_anomaly": "nu",
    "anomaly": "nu",
}


def _suggest(word: str, options) -> str | None:
    options = [str(o) for o in options]
    if _ALIASES.get(word) in options:
        return f"did you mean {_ALIASES[word]!r}?"
    lower = {o.lower(): o for o in options}
    if word.lower() in lower:
        return f"did you mean {lower[word.lower()]!r}?"
    close = difflib.get_close_matches(word.lower(), list(lower), n=1, cutoff=0.6)
    return f"did you mean {lower[close[0]]!r}?" if close else None


def _quoted(options) -> str:
    return ", ".join(repr(o) for o in options)


def _table(value: Any, path: str, allowed: tuple[str, ...]) -> Mapping[str, Any]:
    """``value`` as a table whose keys are all in ``allowed`` (unknown keys raise, with a hint)."""
    keys = f"keys among {_quoted(allowed)}" if allowed else "no keys ({} : it takes no parameters)"
    if not isinstance(value, Mapping):
        raise SceneError(path or "(top level)", f"a table with {keys}", f"{shown(value)} ({type(value).__name__})")
    for key in value:
        if not isinstance(key, str):
            raise SceneError(_join(path, repr(key)), "a string key", f"{shown(key)} ({type(key).__name__})")
        if key not in allowed:
            raise SceneError(
                _join(path, key),
                f"one of the keys {_quoted(allowed)}" if allowed else keys,
                f"an unknown key {key!r}",
                hint=_suggest(key, allowed),
            )
    return value


def _named_tables(value: Any, path: str, what: str) -> Mapping[str, Any]:
    """A table of user-named sub-tables (bodies, tethers): names must be identifiers."""
    if not isinstance(value, Mapping):
        raise SceneError(path, f"a table of {what}", f"{shown(value)} ({type(value).__name__})")
    for name in value:
        if not (isinstance(name, str) and name.isidentifier()):
            raise SceneError(_join(path, str(name)), f"a {what[:-1]} name that is an identifier (letters, digits, _)", repr(name))
    return value


def _required(table: Mapping[str, Any], key: str, path: str, expected: str) -> Any:
    if key not in table:
        raise SceneError(_join(path, key), expected, _NOTHING)
    return table[key]


#: Largest magnitude accepted for a scene quantity (SI).  The model multiplies up to about four
#: inputs (mu / r^3 times a mass, a norm squared): 1e40^4 = 1e160 stays far inside the double
#: range (1e308), and every physical input of a tether scene fits with room (the Sun's mass is
#: 2e30 kg, a light year 9.5e15 m).  Without it, a = "1e300 m" overflowed |r|^2 into a warning.
SI_MAX = 1e40


def _bounded(result: float, key: str, kind: Kind, value: Any) -> float:
    if abs(result) > SI_MAX:
        raise SceneError(key, f"{kind.describe()}, of magnitude at most {SI_MAX:g} in SI units (beyond, products "
                         "of a few such values overflow double precision)", shown(value))  # fmt: skip
    return result


def _quantity(value: Any, key: str, kind: Kind, *, positive: bool = False, nonnegative: bool = False) -> float:
    result = _bounded(to_si(value, kind, key=key), key, kind, value)
    if positive and not result > 0.0:
        raise SceneError(key, f"{kind.label} > 0 (e.g. '{kind.example}')", shown(value))
    if nonnegative and not result >= 0.0:
        raise SceneError(key, f"{kind.label} >= 0 (e.g. '{kind.example}')", shown(value))
    return result


def _vector(value: Any, key: str, kind: Kind) -> Vector3:
    if isinstance(value, u.Quantity) and not value.isscalar:
        items = list(value.flatten()) if value.ndim == 1 else [value]
    elif isinstance(value, (list, tuple)):
        items = list(value)
    else:
        items = None
    if items is None or len(items) != 3:
        raise SceneError(key, f"a list of 3 components, each {kind.describe()}", shown(value))
    return tuple(_bounded(to_si(item, kind, key=f"{key}[{j}]"), f"{key}[{j}]", kind, item) for j, item in enumerate(items))


def _integer(value: Any, key: str, low: int, high: int | None = None) -> int:
    bound = f">= {low}" if high is None else f"from {low} to {high}"
    if not (isinstance(value, numbers.Integral) and not isinstance(value, bool)):
        raise SceneError(key, f"an integer {bound}", f"{shown(value)} ({type(value).__name__})")
    if value < low or (high is not None and value > high):
        raise SceneError(key, f"an integer {bound}", shown(value))
    return int(value)


def _number(value: Any, key: str, expected: str) -> float:
    if not is_number(value):
        raise SceneError(key, expected, f"{shown(value)} ({type(value).__name__})")
    result = float(value)
    if not math.isfinite(result):
        raise SceneError(key, expected, f"{shown(value)} (not finite)")
    return result


def _string(value: Any, key: str, expected: str = "a string") -> str:
    if not isinstance(value, str):
        raise SceneError(key, expected, f"{shown(value)} ({type(value).__name__})")
    return value


def _choice(value: Any, key: str, options: tuple[str, ...]) -> str:
    expected = f"one of {_quoted(options)}"
    text = _string(value, key, expected)
    if text not in options:
        raise SceneError(key, expected, repr(text), hint=_suggest(text, options))
    return text


def _reject_non_finite(value: Any, path: str) -> None:
    """NaN and infinity are no physical input, wherever they appear (TOML has nan/inf literals)."""
    if isinstance(value, float) and not math.isfinite(value):
        raise SceneError(path or "(top level)", "a finite number", repr(value))
    if isinstance(value, Mapping):
        for key, item in value.items():
            _reject_non_finite(item, _join(path, str(key)))
    elif isinstance(value, (list, tuple)):
        for j, item in enumerate(value):
            _reject_non_finite(item, f"{path}[{j}]")


def _set_dotted(data: dict, path: str, value: Any) -> None:
    *parents, last = path.split(".")
    node = data
    for j, part in enumerate(parents):
        nxt = node.get(part)
        if nxt is None:
            nxt = node[part] = {}
        if not isinstance(nxt, dict):
            raise SceneError(".".join(parents[: j + 1]), "a table to change a key in", shown(nxt))
        node = nxt
    if value is None:
        node.pop(last, None)
    else:
        node[last] = value


# --------------------------------------------------------------------------------------------
# Sections.
# --------------------------------------------------------------------------------------------

_TOP_KEYS = (
    "name",
    "description",
    "epoch",
    "duration",
    "central_body",
    "effects",
    "bodies",
    "tethers",
    "orbit",
    "integrator",
    "output",
    "stop",
)
_ORBITS_RE = re.compile(r"^\s*([+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)\s*orbits?\s*$")


def _parse_scene(data: Mapping[str, Any], source: str) -> Scene:
    _reject_non_finite(data, "")
    top = _table(data, "", _TOP_KEYS)

    if "name" in top:
        name = _string(top["name"], "name", "a non-empty string")
        if not name.strip():
            raise SceneError("name", "a non-empty string", repr(name))
    else:
        name = Path(source).stem if source != "<dict>" else "scene"
    description = _string(top["description"], "description") if "description" in top else None
    epoch = _parse_epoch(top["epoch"]) if "epoch" in top else None

    central = _parse_central_body(top.get("central_body", {}))
    mu = central.mu_m3_s2
    effects = _parse_effects(_required(top, "effects", "", "a table of effects, e.g. central_gravity = {}"))
    origin_singular = [e.name for e in effects if e.name in SINGULAR_AT_ORIGIN]
    bodies = _parse_bodies(
        _required(top, "bodies", "", "a table of bodies, e.g. [bodies.m0] with mass = '1000 kg'"), mu, origin_singular
    )
    effects = _expand_per_body(effects, bodies)
    tethers = _parse_tethers(top.get("tethers", {}), bodies)
    graph = topology.build(bodies, tethers)
    _check_forest(bodies, tethers, graph)
    orbit = _parse_orbit(top["orbit"], bodies, mu) if "orbit" in top else None
    graph = graph.with_layout(bodies, tethers, orbit)
    tethers = _check_layout(bodies, tethers, orbit, mu, graph)

    duration_s, duration_orbits = _parse_duration(_required(top, "duration", "", "a time (e.g. '6000 s') or 'N orbits'"))
    if duration_orbits is not None:
        _check_orbits_duration(top["duration"], orbit, bodies, mu)
    integrator = _parse_integrator(top.get("integrator", {}))
    stop = _parse_stop(top["stop"], central) if "stop" in top else None
    scene = Scene(
        name=name,
        duration_s=duration_s,
        duration_orbits=duration_orbits,
        central_body=central,
        effects=effects,
        bodies=bodies,
        tethers=tethers,
        orbit=orbit,
        integrator=integrator,
        output=OutputSpec(),  # filled below: checking output times needs the resolved duration
        description=description,
        epoch=epoch,
        stop=stop,
        source=source,
        graph=graph,
    )
    output = _parse_output(_required(top, "output", "", "a table with one of step, count, times"), scene.duration_seconds())
    scene = dataclasses.replace(scene, output=output)
    _check_run(scene)
    return scene


def _parse_epoch(value: Any) -> str:
    from astropy.time import Time

    expected = "an ISO date such as '2026-01-01T00:00:00' (TDB)"
    if isinstance(value, datetime.datetime):
        if value.tzinfo is not None:
            raise SceneError("epoch", f"{expected} without a UTC offset (the scale is TDB)", value.isoformat())
        value = value.isoformat()
    elif isinstance(value, datetime.date):
        value = value.isoformat()
    text = _string(value, "epoch", expected)
    for fmt in ("isot", "iso"):
        try:
            Time(text, format=fmt, scale="tdb")
            return text
        except ValueError:
            continue
    raise SceneError("epoch", expected, repr(text))


def _parse_central_body(value: Any) -> CentralBody:
    path = "central_body"
    table = _table(value, path, ("name", "mu", "radius"))
    name = _string(table.get("name", "earth"), f"{path}.name", f"one of {_quoted(CENTRAL_BODY_PRESETS)}")
    if name not in CENTRAL_BODY_PRESETS:
        raise SceneError(
            f"{path}.name",
            f"one of the known central bodies {_quoted(CENTRAL_BODY_PRESETS)}",
            repr(name),
            hint=_suggest(name, CENTRAL_BODY_PRESETS),
        )
    preset = CENTRAL_BODY_PRESETS[name]
    mu = _quantity(table["mu"], f"{path}.mu", GRAVITATIONAL_PARAMETER, positive=True) if "mu" in table else preset.mu_m3_s2
    radius = _quantity(table["radius"], f"{path}.radius", LENGTH, positive=True) if "radius" in table else preset.radius_m
    return CentralBody(name, mu, radius)


def _parse_effects(value: Any) -> tuple[EffectUse, ...]:
    if not isinstance(value, Mapping):
        raise SceneError("effects", "a table of effect name -> table of parameters", f"{shown(value)} ({type(value).__name__})")
    uses = []
    for name, params in value.items():
        path = _join("effects", str(name))
        if name not in EFFECTS:
            raise SceneError(
                path,
                f"one of the known effects {_quoted(sorted(EFFECTS))}",
                f"{name!r} (unknown effect)",
                hint=_suggest(str(name), EFFECTS),
            )
        spec = EFFECTS[name]
        table = _table(params, path, tuple(spec.params))
        params_si: dict[str, Any] = {}
        for pname, pspec in spec.params.items():
            key = _join(path, pname)
            if pspec.choices is not None:
                if pname in table:
                    params_si[pname] = _choice(table[pname], key, pspec.choices)
                elif pspec.required:
                    raise SceneError(key, f"one of {_quoted(pspec.choices)}", _NOTHING)
                elif pspec.default is not None:
                    params_si[pname] = str(pspec.default)
                continue
            kind = kind_for_unit(pspec.unit)
            if pname in table:
                if pspec.per_body and isinstance(table[pname], Mapping):
                    params_si[pname] = {
                        str(b): _bounded(to_si(v, kind, key=_join(key, str(b))), _join(key, str(b)), kind, v) for b, v in table[pname].items()
                    }
                else:
                    params_si[pname] = _bounded(to_si(table[pname], kind, key=key), key, kind, table[pname])
            elif pspec.required:
                what = f"{kind.describe()}, or a table of one per body" if pspec.per_body else kind.describe()
                raise SceneError(key, what, _NOTHING)
            elif pspec.default is not None:
                # A float default is already in the declared SI unit; a string one is parsed.
                default = pspec.default
                params_si[pname] = float(default) if is_number(default) else to_si(default, kind, key=key)
        uses.append(EffectUse(name, params_si))
    return tuple(uses)


def _expand_per_body(effects: tuple[EffectUse, ...], bodies: tuple[Body, ...]) -> tuple[EffectUse, ...]:
    """Per-body effect parameters as {body: SI float} naming exactly the scene's bodies.

    One value written for all bodies is expanded here; a table must name every body and no other
    (a body silently left without, say, a drag area would be a hidden zero).
    """
    names = [b.name for b in bodies]
    out = []
    for use in effects:
        spec = EFFECTS[use.name]
        params = dict(use.params_si)
        for pname, pspec in spec.params.items():
            if not pspec.per_body or pname not in params:
                continue
            key = f"effects.{use.name}.{pname}"
            value = params[pname]
            if not isinstance(value, dict):
                params[pname] = {n: float(value) for n in names}
                continue
            for b in value:
                if b not in names:
                    raise SceneError(
                        f"{key}.{b}", f"a body of the scene ({_quoted(names)})", f"{b!r} (no such body)", hint=_suggest(b, names)
                    )
            missing = [n for n in names if n not in value]
            if missing:
                raise SceneError(
                    f"{key}.{missing[0]}",
                    f"a value for every body ({_quoted(names)}), or one value for all",
                    _NOTHING,
                )
            params[pname] = {n: value[n] for n in names}
        out.append(EffectUse(use.name, params))
    return tuple(out)


# -- bodies and states ------------------------------------------------------------------------

_ELEMENT_KEYS = ("a", "e", "i", "raan", "argp", "nu")


def _parse_elements(value: Any, path: str) -> Elements:
    table = _table(value, path, _ELEMENT_KEYS)
    a = _quantity(_required(table, "a", path, LENGTH.describe()), f"{path}.a", LENGTH)
    e_raw = _required(table, "e", path, "an eccentricity (a number >= 0, e.g. 0.01)")
    e = _bounded(to_si(e_raw, DIMENSIONLESS, key=f"{path}.e"), f"{path}.e", DIMENSIONLESS, e_raw)
    angles = {k: to_si(table[k], ANGLE, key=f"{path}.{k}") if k in table else 0.0 for k in _ELEMENT_KEYS[2:]}

    if e < 0.0:
        raise SceneError(f"{path}.e", "an eccentricity >= 0", shown(e_raw))
    if e == 1.0:
        raise SceneError(
            f"{path}.e",
            "e != 1 (a parabolic orbit has no finite semi-major axis; give position and velocity instead)",
            shown(e_raw),
        )
    if e < 1.0 and not a > 0.0:
        raise SceneError(f"{path}.a", "a > 0 for an elliptic orbit (e < 1)", f"{shown(table['a'])} with e = {e!r}")
    if e > 1.0 and not a < 0.0:
        raise SceneError(f"{path}.a", "a < 0 for a hyperbolic orbit (e > 1)", f"{shown(table['a'])} with e = {e!r}")
    # 180 deg converts to pi give or take an ulp; the tolerance keeps that legal.
    if not (-1e-12 <= angles["i"] <= math.pi + 1e-12):
        raise SceneError(f"{path}.i", "an inclination from 0 to 180 deg", shown(table["i"]))
    if e > 1.0 and not 1.0 + e * math.cos(angles["nu"]) > 0.0:
        limit = math.degrees(math.acos(-1.0 / e))
        raise SceneError(
            f"{path}.nu",
            f"a true anomaly between the asymptotes of the hyperbola, |nu| < {limit:.6g} deg",
            shown(table["nu"]),
        )
    return Elements(a, e, angles["i"], angles["raan"], angles["argp"], angles["nu"])


def _parse_state(table: Mapping[str, Any], path: str, *, fixed: bool = False):
    """(position, velocity, elements) of a body or of [orbit]; all None when none is given."""
    has_elements = "elements" in table
    has_position = "position" in table
    has_velocity = "velocity" in table
    if fixed:
        if has_elements or has_velocity:
            bad = "elements" if has_elements else "velocity"
            raise SceneError(
                _join(path, bad),
                "no velocity or elements for a fixed body (it is held at rest: give position only)",
                shown(table[bad]),
            )
        if not has_position:
            raise SceneError(_join(path, "position"), f"the position of the fixed body ({LENGTH.describe()} x 3)", _NOTHING)
        return _vector(table["position"], _join(path, "position"), LENGTH), None, None
    if has_elements and (has_position or has_velocity):
        raise SceneError(
            _join(path, "elements"),
            "either elements or position/velocity, not both",
            "both elements and " + ("position" if has_position else "velocity"),
        )
    if has_elements:
        return None, None, _parse_elements(table["elements"], _join(path, "elements"))
    if has_position and not has_velocity:
        raise SceneError(_join(path, "velocity"), f"a velocity to go with position ({SPEED.describe()} x 3)", _NOTHING)
    if has_velocity and not has_position:
        raise SceneError(_join(path, "position"), f"a position to go with velocity ({LENGTH.describe()} x 3)", _NOTHING)
    if has_position:
        return (
            _vector(table["position"], _join(path, "position"), LENGTH),
            _vector(table["velocity"], _join(path, "velocity"), SPEED),
            None,
        )
    return None, None, None


def _parse_bodies(value: Any, mu: float, origin_singular: list[str] = ()) -> tuple[Body, ...]:
    tables = _named_tables(value, "bodies", "bodies")
    if not tables:
        raise SceneError("bodies", "at least one body", "an empty table")
    bodies = []
    for name, raw in tables.items():
        path = f"bodies.{name}"
        if name == CENTER_OF_MASS:
            raise SceneError(path, f"a body name other than {CENTER_OF_MASS!r} (it names the centre of mass in [orbit])", repr(name))
        table = _table(raw, path, ("mass", "position", "velocity", "elements", "fixed", "rigid", "wheels", "control"))
        fixed = table.get("fixed", False)
        if not isinstance(fixed, bool):
            raise SceneError(f"{path}.fixed", "true or false", f"{shown(fixed)} ({type(fixed).__name__})")
        # A fixed body (the catenary's "nail") never moves, so its mass plays no part: optional,
        # stored as 0.0 when absent (and left out again by to_dict).
        if fixed and "mass" not in table:
            mass = 0.0
        else:
            mass = _quantity(_required(table, "mass", path, MASS.describe()), f"{path}.mass", MASS, positive=True)
        position, velocity, elements = _parse_state(table, path, fixed=fixed)
        rigid = _parse_rigid(table, path, fixed)
        body = Body(name, mass, fixed, position, velocity, elements, rigid)
        # The origin is the centre of the central body only for the effects singular there; a
        # surface-frame scene (uniform_gravity alone) may put its nail at the origin.
        if body.has_state and origin_singular:
            r, _ = body.state(mu)
            if not np.linalg.norm(r) > 0.0:
                raise SceneError(
                    _join(path, "position"),
                    f"a position away from the centre of the central body (effect {origin_singular[0]!r} is singular there)",
                    "the origin",
                )
        bodies.append(body)
    return tuple(bodies)


# -- rigid bodies, wheels, control (issue 10) --------------------------------------------------

_INERTIA_KEYS = ("xx", "yy", "zz", "xy", "xz", "yz")


def _unit_quaternion(value: Any, key: str) -> tuple:
    if not isinstance(value, (list, tuple)) or len(value) != 4:
        raise SceneError(key, "a list of 4 numbers [w, x, y, z] (scalar first)", shown(value))
    q = np.array([_number(x, f"{key}[{j}]", "a number") for j, x in enumerate(value)])
    norm = float(np.linalg.norm(q))
    if not abs(norm - 1.0) <= QUATERNION_NORM_TOL:
        raise SceneError(key, f"a unit quaternion (|q| within {QUATERNION_NORM_TOL:g} of 1)", f"|q| = {norm:.9g}")
    return tuple(float(x) for x in q / norm)


def _parse_inertia(value: Any, key: str) -> tuple:
    table = _table(value, key, _INERTIA_KEYS)
    for k in ("xx", "yy", "zz"):
        _required(table, k, key, MOMENT_OF_INERTIA.describe())
    v = {k: (_quantity(table[k], f"{key}.{k}", MOMENT_OF_INERTIA) if k in table else 0.0) for k in _INERTIA_KEYS}
    J = np.array([[v["xx"], v["xy"], v["xz"]], [v["xy"], v["yy"], v["yz"]], [v["xz"], v["yz"], v["zz"]]])
    lam = np.linalg.eigvalsh(J)
    if not lam[0] > 0.0:
        raise SceneError(key, "a symmetric positive definite inertia tensor", f"principal moments {lam.tolist()}")
    # a real mass distribution: each principal moment at most the sum of the other two
    if lam[2] > (lam[0] + lam[1]) * (1.0 + 1e-12):
        raise SceneError(
            key, "principal moments satisfying the triangle inequality J3 <= J1 + J2 (a real mass distribution)",
            f"principal moments {lam.tolist()}",
        )
    return tuple(tuple(float(x) for x in row) for row in J)


def _parse_attitude(value: Any, key: str) -> Attitude:
    if isinstance(value, str):
        if value != "orbit":
            raise SceneError(key, "'orbit', or a table with quaternion or euler", repr(value), hint=_suggest(value, ["orbit"]))
        return Attitude()
    table = _table(value, key, ("quaternion", "euler", "sequence", "frame"))
    frame = _choice(table.get("frame", "inertial"), f"{key}.frame", ATTITUDE_FRAMES)
    if ("quaternion" in table) == ("euler" in table):
        raise SceneError(key, "exactly one of quaternion and euler", "both" if "quaternion" in table else "neither")
    if "quaternion" in table:
        if "sequence" in table:
            raise SceneError(f"{key}.sequence", "no sequence with a quaternion", shown(table["sequence"]))
        return Attitude("quaternion", _unit_quaternion(table["quaternion"], f"{key}.quaternion"), "ZYX", frame)
    seq = _choice(table.get("sequence", "ZYX"), f"{key}.sequence", EULER_SEQUENCES)
    angles = table["euler"]
    if not isinstance(angles, (list, tuple)) or len(angles) != 3:
        raise SceneError(f"{key}.euler", f"a list of 3 angles ({ANGLE.describe()})", shown(angles))
    vals = tuple(to_si(a, ANGLE, key=f"{key}.euler[{j}]") for j, a in enumerate(angles))
    return Attitude("euler", vals, seq, frame)


def _parse_wheel(name: str, raw: Any, path: str) -> Wheel:
    table = _table(raw, path, ("axis", "inertia", "speed", "max_speed", "max_torque", "torque"))
    axis_raw = _required(table, "axis", path, "3 numbers (body axes)")
    if not isinstance(axis_raw, (list, tuple)) or len(axis_raw) != 3:
        raise SceneError(f"{path}.axis", "a list of 3 numbers (body axes)", shown(axis_raw))
    axis = np.array([_number(x, f"{path}.axis[{j}]", "a number") for j, x in enumerate(axis_raw)])
    n = float(np.linalg.norm(axis))
    if not n > 0.0:
        raise SceneError(f"{path}.axis", "a non-zero axis", shown(axis_raw))
    inertia = _quantity(_required(table, "inertia", path, MOMENT_OF_INERTIA.describe()), f"{path}.inertia", MOMENT_OF_INERTIA, positive=True)
    speed = _quantity(table["speed"], f"{path}.speed", ANGULAR_RATE) if "speed" in table else 0.0
    max_speed = _quantity(table["max_speed"], f"{path}.max_speed", ANGULAR_RATE, positive=True) if "max_speed" in table else None
    max_torque = _quantity(table["max_torque"], f"{path}.max_torque", TORQUE, positive=True) if "max_torque" in table else None
    if max_speed is not None and abs(speed) > max_speed:
        raise SceneError(f"{path}.speed", f"an initial speed within max_speed ({max_speed:g} rad/s)", f"{speed:g} rad/s")
    torque: Any = 0.0
    if "torque" in table:
        raw_t = table["torque"]
        key = f"{path}.torque"
        if isinstance(raw_t, str) and raw_t.strip() == WHEEL_TORQUE_CONTROL:
            torque = WHEEL_TORQUE_CONTROL
        elif isinstance(raw_t, Mapping):
            tt = _table(raw_t, key, ("times", "values"))
            times = _required(tt, "times", key, "a list of times")
            values = _required(tt, "values", key, "a list of torques")
            if not isinstance(times, (list, tuple)) or not isinstance(values, (list, tuple)) or len(times) != len(values) or len(times) < 1:
                raise SceneError(key, "times and values: two lists of the same length >= 1", f"{shown(times)}, {shown(values)}")
            ts = tuple(to_si(x, TIME, key=f"{key}.times[{j}]") for j, x in enumerate(times))
            if any(b <= a for a, b in zip(ts, ts[1:])):
                raise SceneError(f"{key}.times", "strictly increasing times", shown(times))
            vs = tuple(to_si(x, TORQUE, key=f"{key}.values[{j}]") for j, x in enumerate(values))
            torque = (ts, vs)
        else:
            torque = to_si(raw_t, TORQUE, key=key)
    return Wheel(name, tuple(float(x) for x in axis / n), inertia, speed, max_speed, max_torque, torque)


def _parse_control(raw: Any, path: str) -> Control:
    table = _table(raw, path, ("law", "target", "kp", "kd"))
    law = _choice(table.get("law", "pd"), f"{path}.law", ("pd",))
    target_raw = _required(table, "target", path, "'orbit' or { quaternion = [w, x, y, z] } (a controller needs a target)")
    quat = None
    if isinstance(target_raw, str):
        target = _choice(target_raw, f"{path}.target", ("orbit",))
    else:
        tt = _table(target_raw, f"{path}.target", ("quaternion",))
        quat = _unit_quaternion(_required(tt, "quaternion", f"{path}.target", "[w, x, y, z]"), f"{path}.target.quaternion")
        target = "inertial"
    kp = _quantity(_required(table, "kp", path, TORQUE.describe()), f"{path}.kp", TORQUE, positive=True)
    kd = _quantity(_required(table, "kd", path, ANGULAR_MOMENTUM.describe()), f"{path}.kd", ANGULAR_MOMENTUM, nonnegative=True)
    return Control(law, target, kp, kd, quat)


def _parse_rigid(table: Mapping[str, Any], path: str, fixed: bool) -> Rigid | None:
    if "rigid" not in table:
        for key in ("wheels", "control"):
            if key in table:
                raise SceneError(f"{path}.{key}", f"a [{path}.rigid] table: {key} only on a rigid body", "a point mass")
        return None
    rpath = f"{path}.rigid"
    if fixed:
        raise SceneError(rpath, "no rigid table on a fixed body (it never moves or turns)", "a rigid table")
    rt = _table(table["rigid"], rpath, ("inertia", "attitude", "angular_velocity"))
    inertia = _parse_inertia(_required(rt, "inertia", rpath, "a table {xx, yy, zz, xy, xz, yz} of moments of inertia"), f"{rpath}.inertia")
    attitude = _parse_attitude(rt["attitude"], f"{rpath}.attitude") if "attitude" in rt else Attitude()
    omega: Vector3 = (0.0, 0.0, 0.0)
    frame = "orbit"
    if "angular_velocity" in rt:
        key = f"{rpath}.angular_velocity"
        at = _table(rt["angular_velocity"], key, ("vector", "frame"))
        omega = _vector(_required(at, "vector", key, f"3 x {ANGULAR_RATE.describe()}"), f"{key}.vector", ANGULAR_RATE)
        frame = _choice(at.get("frame", "body"), f"{key}.frame", RATE_FRAMES)
    wheels = tuple(
        _parse_wheel(name, raw, f"{path}.wheels.{name}")
        for name, raw in _named_tables(table.get("wheels", {}), f"{path}.wheels", "wheels").items()
    )
    control = _parse_control(table["control"], f"{path}.control") if "control" in table else None
    controlled = [w.name for w in wheels if w.torque == WHEEL_TORQUE_CONTROL]
    if control is not None and not controlled:
        raise SceneError(f"{path}.control", "at least one wheel with torque = 'control' to act through", "none")
    if controlled and control is None:
        raise SceneError(
            f"{path}.wheels.{controlled[0]}.torque", f"a [{path}.control] table for torque = 'control'", "no controller"
        )
    # the body with its wheels free must still have a positive definite inertia
    JS = np.array(inertia) - sum((w.inertia_kg_m2 * np.outer(w.axis, w.axis) for w in wheels), np.zeros((3, 3)))
    if wheels and not np.linalg.eigvalsh(JS)[0] > 0.0:
        raise SceneError(
            f"{path}.wheels", f"wheels whose axial inertias fit in {rpath}.inertia (J_B - sum I_k a_k a_k^T positive definite)",
            f"eigenvalues {np.linalg.eigvalsh(JS).tolist()}",
        )
    return Rigid(inertia, attitude, omega, frame, wheels, control)


def _check_forest(bodies: tuple[Body, ...], tethers: tuple["Tether", ...], graph: topology.Graph) -> None:
    """Bodies and tethers must form a forest: the graph's first cut tether (it joins two bodies
    already joined) closes a loop, refused naming it; attachment points only on rigid bodies."""
    if graph.cut:
        t = graph.cut[0]
        raise SceneError(
            f"tethers.{t.name}",
            "tethers forming a tree (no closed loop: the elimination runs towards one root)",
            f"tether {t.name!r} closes a loop between {t.from_body!r} and {t.to_body!r}",
        )
    by_name = {b.name: b for b in bodies}
    for t in tethers:
        for end, key in ((t.from_body, "from_point"), (t.to_body, "to_point")):
            point = t.from_point_m if key == "from_point" else t.to_point_m
            if point is not None and by_name[end].rigid is None:
                raise SceneError(
                    f"tethers.{t.name}.{key}", f"a rigid body at this end (give bodies.{end}.rigid), or no {key}",
                    f"an attachment point on the point mass {end!r}",
                )


# -- tethers -----------------------------------------------------------------------------------

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
        rods = _integer(_required(table, "rods", path, "an integer >= 1"), f"{path}.rods", 1)
        length = _quantity(_required(table, "length", path, LENGTH.describe()), f"{path}.length", LENGTH, positive=True)
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
        tethers.append(
            Tether(name, start, end, rods, length, ea, mass, damping, model, quadrature, diameter, tension_only=tension_only,
                   initial=initial, from_point_m=from_point, to_point_m=to_point)
        )
    return tuple(tethers)


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
    table = _table(value, path, ("shape", "theta", "phi", "side", "strain"))
    shape = _choice(table.get("shape", "straight"), f"{path}.shape", SHAPES)
    if shape == EQUILIBRIUM:
        # the static solve decides every rod's direction and strain: nothing else to give
        extra = [k for k in table if k != "shape"]
        if extra:
            raise SceneError(
                f"{path}.{extra[0]}", "no other key with shape 'equilibrium' (the statics solve sets the shape)",
                shown(table[extra[0]]),
            )
        return InitialShape(EQUILIBRIUM)
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


# -- orbit and layout --------------------------------------------------------------------------


def _parse_orbit(value: Any, bodies: tuple[Body, ...], mu: float) -> Orbit:
    path = "orbit"
    table = _table(value, path, ("reference", "elements", "position", "velocity", "motion"))
    names = [b.name for b in bodies]
    reference = _string(table.get("reference", CENTER_OF_MASS), f"{path}.reference", f"{CENTER_OF_MASS!r} or a body name")
    if reference != CENTER_OF_MASS and reference not in names:
        raise SceneError(
            f"{path}.reference",
            f"{CENTER_OF_MASS!r} or the name of a body ({_quoted(names)})",
            f"{reference!r} (no such body)",
            hint=_suggest(reference, [CENTER_OF_MASS, *names]),
        )
    position, velocity, elements = _parse_state(table, path)
    motion = _choice(table.get("motion", "corotating"), f"{path}.motion", MOTIONS)
    orbit = Orbit(reference, elements, position, velocity, motion)
    has_state = position is not None or elements is not None
    if has_state:
        r, _ = orbit.state(mu)
        if not np.linalg.norm(r) > 0.0:
            raise SceneError(f"{path}.position", "a position away from the centre of the central body", "the origin")

    explicit = [b for b in bodies if b.has_state]
    if reference == CENTER_OF_MASS:
        if explicit:
            raise SceneError(
                f"{path}.reference",
                "a body name when some bodies have explicit states (the centre of mass would depend on them)",
                f"{CENTER_OF_MASS!r} while body {explicit[0].name!r} has an explicit state",
            )
        if not has_state:
            raise SceneError(f"{path}.elements", "the initial orbit: elements, or position and velocity", _NOTHING)
    else:
        body = bodies[names.index(reference)]
        if body.fixed:
            raise SceneError(f"{path}.reference", "a moving body (a fixed body has no orbit)", f"{reference!r} (fixed)")
        if body.has_state and has_state:
            raise SceneError(
                f"{path}.{'elements' if elements is not None else 'position'}",
                f"no orbit state: the reference body {reference!r} already has its own (give it once)",
                "a second initial state",
            )
        if not body.has_state and not has_state:
            raise SceneError(
                f"{path}.elements",
                f"the initial orbit (elements, or position and velocity), or an explicit state on body {reference!r}",
                _NOTHING,
            )
    return orbit


def _reference_state(orbit: Orbit | None, bodies: tuple[Body, ...], mu: float):
    if orbit is None:
        return None
    state = orbit.state(mu)
    if state is None:  # the reference body carries the state
        state = next(b for b in bodies if b.name == orbit.reference).state(mu)
    return state


def _period_of_state(mu: float, r: np.ndarray, v: np.ndarray) -> float:
    # Vis-viva gives a from the energy alone; that is all a period needs (no angle is involved).
    energy = 0.5 * float(np.dot(v, v)) - mu / float(np.linalg.norm(r))
    if not energy < 0.0:
        raise ValueError("the reference orbit is not closed (energy >= 0): it has no period")
    return kepler.period(mu, -mu / (2.0 * energy))


def _check_layout(bodies, tethers, orbit, mu, graph: topology.Graph) -> tuple[Tether, ...]:
    """Check that every body can be placed; fill or forbid each tether's initial shape."""
    if orbit is None:
        if not any(b.has_state for b in bodies):
            raise SceneError(
                "orbit",
                "an [orbit] table giving the initial orbit, or explicit states for the bodies",
                "neither an [orbit] table nor any body with position/velocity, elements or fixed position",
            )
        for b in bodies:
            if not b.has_state:
                raise SceneError(
                    f"bodies.{b.name}",
                    "an initial state (position and velocity, elements, or fixed with position)",
                    "none",
                    hint="without an [orbit] table every body needs its own state; add [orbit] to "
                    "place it from the tether shapes",
                )
    steps, unplaced = graph.layout, graph.unplaced
    if unplaced:
        raise SceneError(
            f"bodies.{unplaced[0]}",
            "an explicit initial state, or a chain of tethers joining it to the orbit reference "
            f"{orbit.reference!r} or to a body with an explicit state",
            "neither",
        )
    by_name = {b.name: b for b in bodies}
    closing = {s.tether for s in steps if s.end is None}
    result = []
    for t in tethers:
        path = f"tethers.{t.name}"
        if t.initial is not None and t.initial.shape == EQUILIBRIUM and t.name not in closing:
            raise SceneError(
                f"{path}.initial.shape",
                "'straight' or 'rods' for a tether laid from one end ('equilibrium' needs both ends "
                "placed: the root fixed and the end mass with a position)",
                repr(EQUILIBRIUM),
            )
        if t.name in closing:
            if t.initial is not None and t.initial.shape != EQUILIBRIUM:
                raise SceneError(
                    f"{path}.initial",
                    "no initial shape: both ends are placed before this tether is laid, so it starts "
                    "straight between them",
                    "an [initial] table",
                )
            ends = (by_name[t.from_body].state(mu), by_name[t.to_body].state(mu))
            if ends[0] is not None and ends[1] is not None:
                _check_end_distance(t, float(np.linalg.norm(ends[1][0] - ends[0][0])), path)
        elif t.initial is None:
            t = dataclasses.replace(t, initial=InitialShape())
        result.append(t)
    return tuple(result)


def _check_run(scene: Scene) -> None:
    """The checks that need the whole scene and its graph: what the kernel, the initial layout and
    the integrators can run (they were made when a run was prepared; they are scene content).

    Checks that stay where the run is prepared, and why:

    * the statics solve of shape 'equilibrium' (tetherlab/initial/statics.py) and the Newton
      solves of orbit.motion 'equilibrium' and 'quasi-static' (tetherlab/initial/equilibrium.py):
      whether they converge is known only by solving them on the built model;
    * a rigid body's attitude relative to an undefined orbit frame (r x v = 0) and a tether
      straight between two attachment points at the same place (tetherlab/initial/forest.py):
      they need the laid-out positions and attitudes;
    * stop.altitude above the root body's start, and "N orbits" of a reference that is not on a
      closed orbit (pipeline.prepare): they need the laid-out initial state (the [orbit] itself is
      checked at load, in _check_orbits_duration);
    * the formulation (pipeline._formulation) and what follows from it (integrator.method 'abm',
      integrator.time_element): the formulation layer resolves them from the built model;
    * a star of point masses with a tether between two placed ends whose far end is placed by the
      [orbit] rather than by its own state (tetherlab/initial/star.py): the star layout cannot lay
      it, yet such a scene is a valid scene (it loads, round-trips and may be edited into a
      runnable one), so it is refused when it is laid out;
    * the memory and disk a run needs (tetherlab/resources.py): a property of the machine;
    * per-effect checks made when an effect packs its parameters against the kernel bodies
      (tetherlab/forces/).
    """
    graph = scene.graph
    for c, fixed in enumerate(graph.fixed):
        if len(fixed) > 1:
            raise SceneError(
                f"bodies.{fixed[1]}.fixed", "at most one fixed body in a group of bodies joined by tethers "
                "(the kernel holds only the root of a tree at rest)", f"true on {list(fixed)}",
            )  # fmt: skip
    tethers = scene.tethers
    nq = tethers[0].quadrature if tethers else 2
    if any(t.quadrature != nq for t in tethers):
        raise SceneError(
            "tethers.*.quadrature", "the same quadrature for every tether", str([t.quadrature for t in tethers])
        )
    by_name = {b.name: b for b in scene.bodies}
    mu = scene.central_body.mu_m3_s2
    orbit = scene.orbit
    if not graph.simple:
        if orbit is not None and orbit.motion in ("equilibrium", "quasi-static"):
            raise SceneError("orbit.motion", "'corotating' or 'translating' for a scene with rigid bodies or a tree other "
                             "than a star (the relative-equilibrium solve handles stars of point masses)", repr(orbit.motion))  # fmt: skip
        for k in graph.placement_order:
            t = tethers[k]
            if t.initial is not None and t.initial.shape == EQUILIBRIUM:
                raise SceneError(f"tethers.{t.name}.initial.shape", "'straight' or 'rods' in a tree other than a star of "
                                 "point masses (the statics solve handles one tether on a fixed root)", "'equilibrium'")  # fmt: skip
    if any(t.initial is not None and t.initial.shape == EQUILIBRIUM for t in tethers):
        root = by_name[graph.roots[0]]
        t = tethers[0]
        if not root.fixed:
            raise SceneError(
                f"bodies.{root.name}.fixed", "true: shape 'equilibrium' holds the tether between a fixed root and its end mass",
                "false",
            )  # fmt: skip
        if len(tethers) != 1:
            raise SceneError(f"tethers.{t.name}.initial.shape", "'equilibrium' only in a scene with a single tether",
                             f"{len(tethers)} tethers")  # fmt: skip
        tip = by_name[t.to_body].state(mu)
        if tip is not None and np.any(tip[1] != 0.0):
            raise SceneError(
                f"bodies.{t.to_body}.velocity", "[0, 0, 0] m/s: a static equilibrium starts at rest", str(tip[1].tolist())
            )
    # events (kernel/events.py::event_components): the stop altitude and every rod of a
    # tension-only tether
    events = (["stop"] if scene.stop is not None and scene.stop.altitude_m is not None else []) + (
        ["slack"] if any(t.tension_only for t in tethers) else []
    )
    if events and scene.integrator.method.startswith("scipy:"):
        raise SceneError(
            "integrator.method", "a native method (dop853 or radau5): this scene has events "
            f"({', '.join(sorted(events))}) that only they locate",
            repr(scene.integrator.method),
        )  # fmt: skip


def _check_end_distance(t: Tether, distance: float, path: str) -> None:
    if distance == 0.0:
        raise SceneError(f"{path}.to", f"a body at another position than {t.from_body!r}", f"{t.to_body!r} at the same position")
    strain = distance / t.length_m - 1.0
    if strain > MAX_SANE_STRAIN:
        raise SceneError(
            f"{path}.length",
            f"at least {distance / (1.0 + MAX_SANE_STRAIN):.6g} m, since the ends are {distance:.6g} m apart "
            f"and MAX_SANE_STRAIN is {MAX_SANE_STRAIN:.0%}",
            f"{t.length_m:.6g} m: ends farther apart than the tether can stretch (strain {strain:.3%})",
        )


def _parse_duration(value: Any) -> tuple[float | None, float | None]:
    expected = "a time (e.g. '6000 s', '35 d') or a number of orbits (e.g. '10 orbits')"
    if isinstance(value, str):
        match = _ORBITS_RE.match(value)
        if match:
            orbits = float(match.group(1))
            if not (math.isfinite(orbits) and orbits > 0.0):
                raise SceneError("duration", f"{expected}, > 0", repr(value))
            return None, orbits
    if is_number(value):
        raise SceneError("duration", expected, f"{shown(value)} (missing unit)")
    seconds = _bounded(to_si(value, TIME, key="duration"), "duration", TIME, value)
    if not seconds > 0.0:
        raise SceneError("duration", f"{expected}, > 0", shown(value))
    return seconds, None


def _check_orbits_duration(raw: Any, orbit: Orbit | None, bodies, mu: float) -> None:
    state = _reference_state(orbit, bodies, mu)
    if state is None:
        raise SceneError("duration", "a time: 'N orbits' needs an [orbit] table to say which orbit", repr(raw))
    try:
        _period_of_state(mu, *state)
    except ValueError:
        raise SceneError("duration", "a time: the reference orbit is not closed (e >= 1), so it has no period", repr(raw)) from None


def _parse_stop(value: Any, central: CentralBody) -> Stop:
    path = "stop"
    table = _table(value, path, ("altitude",))
    if not table:
        raise SceneError(path, "at least one stop condition (altitude)", "an empty table")
    altitude = None
    if "altitude" in table:
        altitude = _quantity(table["altitude"], f"{path}.altitude", LENGTH, positive=True)
    return Stop(altitude_m=altitude)


def _parse_integrator(value: Any) -> IntegratorSpec:
    path = "integrator"
    table = _table(value, path, ("method", "rtol", "atol", "max_step", "max_steps", "formulation", "time_element"))
    method = _choice(table.get("method", "dop853"), f"{path}.method", INTEGRATOR_METHODS)
    rtol = _number(table.get("rtol", 1e-10), f"{path}.rtol", "a relative tolerance in (0, 1)")
    if not 0.0 < rtol < 1.0:
        raise SceneError(f"{path}.rtol", "a relative tolerance in (0, 1)", shown(table["rtol"]))
    atol = _number(table.get("atol", 1e-10), f"{path}.atol", "an absolute tolerance >= 0 (dimensionless)")
    if not atol >= 0.0:
        raise SceneError(f"{path}.atol", "an absolute tolerance >= 0 (dimensionless)", shown(table["atol"]))
    max_step = _quantity(table["max_step"], f"{path}.max_step", TIME, positive=True) if "max_step" in table else None
    max_steps = _integer(table["max_steps"], f"{path}.max_steps", 1) if "max_steps" in table else None
    formulation = _choice(table.get("formulation", "cowell"), f"{path}.formulation", FORMULATIONS)
    time_element = _choice(table.get("time_element", "none"), f"{path}.time_element", TIME_ELEMENTS)
    return IntegratorSpec(method, rtol, atol, max_step, max_steps, formulation, time_element)


def _parse_output(value: Any, duration_s: float) -> OutputSpec:
    path = "output"
    table = _table(value, path, ("step", "count", "times"))
    given = [k for k in ("step", "count", "times") if k in table]
    if len(given) != 1:
        raise SceneError(
            path,
            "exactly one of step, count, times",
            "none of them" if not given else " and ".join(given),
        )
    if "step" in table:
        return OutputSpec(step_s=_quantity(table["step"], f"{path}.step", TIME, positive=True))
    if "count" in table:
        return OutputSpec(count=_integer(table["count"], f"{path}.count", 2))
    raw = table["times"]
    key = f"{path}.times"
    if isinstance(raw, u.Quantity) and not raw.isscalar and raw.ndim == 1:
        raw = list(raw)
    if not isinstance(raw, (list, tuple)) or not raw:
        raise SceneError(key, f"a non-empty list of times ({TIME.describe()} each)", shown(raw))
    times = tuple(to_si(item, TIME, key=f"{key}[{j}]") for j, item in enumerate(raw))
    for j, t in enumerate(times):
        if not 0.0 <= t <= duration_s:
            raise SceneError(f"{key}[{j}]", f"a time within the run, from 0 to {duration_s!r} s", shown(raw[j]))
        if j and not t > times[j - 1]:
            raise SceneError(f"{key}[{j}]", "times in increasing order", f"{shown(raw[j])} after {shown(raw[j - 1])}")
    return OutputSpec(times_s=times)


# --------------------------------------------------------------------------------------------
# Back to a dictionary.
# --------------------------------------------------------------------------------------------


def _vec(values, kind: Kind) -> list:
    return [format_si(x, kind) for x in values]


def _state_dict(position, velocity, elements) -> dict[str, Any]:
    out: dict[str, Any] = {}
    if elements is not None:
        out["elements"] = {
            "a": format_si(elements.a_m, LENGTH),
            "e": float(elements.e),
            "i": format_si(elements.i_rad, ANGLE),
            "raan": format_si(elements.raan_rad, ANGLE),
            "argp": format_si(elements.argp_rad, ANGLE),
            "nu": format_si(elements.nu_rad, ANGLE),
        }
    if position is not None:
        out["position"] = _vec(position, LENGTH)
    if velocity is not None:
        out["velocity"] = _vec(velocity, SPEED)
    return out


def _rigid_dict(r: Rigid) -> dict[str, Any]:
    J = r.inertia_kg_m2
    inertia = {k: format_si(J[i][j], MOMENT_OF_INERTIA) for k, (i, j) in zip(_INERTIA_KEYS, ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)))}
    a = r.attitude
    if a.kind == "orbit":
        attitude: Any = "orbit"
    elif a.kind == "quaternion":
        attitude = {"quaternion": list(a.values), "frame": a.frame}
    else:
        attitude = {"euler": [format_si(x, ANGLE) for x in a.values], "sequence": a.sequence, "frame": a.frame}
    out: dict[str, Any] = {
        "rigid": {
            "inertia": inertia,
            "attitude": attitude,
            "angular_velocity": {"vector": _vec(r.angular_velocity_rad_s, ANGULAR_RATE), "frame": r.angular_velocity_frame},
        }
    }
    if r.wheels:
        wheels = {}
        for w in r.wheels:
            e: dict[str, Any] = {"axis": list(w.axis), "inertia": format_si(w.inertia_kg_m2, MOMENT_OF_INERTIA),
                                 "speed": format_si(w.speed_rad_s, ANGULAR_RATE)}
            if w.max_speed_rad_s is not None:
                e["max_speed"] = format_si(w.max_speed_rad_s, ANGULAR_RATE)
            if w.max_torque_N_m is not None:
                e["max_torque"] = format_si(w.max_torque_N_m, TORQUE)
            if isinstance(w.torque, str):
                e["torque"] = w.torque
            elif isinstance(w.torque, tuple):
                e["torque"] = {"times": [format_si(x, TIME) for x in w.torque[0]], "values": [format_si(x, TORQUE) for x in w.torque[1]]}
            else:
                e["torque"] = format_si(w.torque, TORQUE)
            wheels[w.name] = e
        out["wheels"] = wheels
    if r.control is not None:
        c = r.control
        out["control"] = {
            "law": c.law, "target": "orbit" if c.target == "orbit" else {"quaternion": list(c.quaternion)},
            "kp": format_si(c.kp_N_m, TORQUE), "kd": format_si(c.kd_N_m_s, ANGULAR_MOMENTUM),
        }
    return out


def _angles_dict(value) -> Any:
    if isinstance(value, tuple):
        return [format_si(x, ANGLE) for x in value]
    return format_si(value, ANGLE)


def _effect_params_dict(use: EffectUse) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for k, v in use.params_si.items():
        unit = EFFECTS[use.name].params[k].unit
        if isinstance(v, str):  # a choice parameter
            out[k] = v
        elif isinstance(v, dict):  # a per-body parameter
            out[k] = {b: format_si(x, unit) for b, x in v.items()}
        else:
            out[k] = format_si(v, unit)
    return out


def _scene_to_dict(scene: Scene) -> dict[str, Any]:
    if (scene.duration_s is None) == (scene.duration_orbits is None):
        raise SceneError("duration", "exactly one of duration_s and duration_orbits set", "both or neither")
    out: dict[str, Any] = {"name": scene.name}
    if scene.description is not None:
        out["description"] = scene.description
    if scene.epoch is not None:
        out["epoch"] = scene.epoch
    out["duration"] = (
        format_si(scene.duration_s, TIME) if scene.duration_s is not None else f"{float(scene.duration_orbits)!r} orbits"
    )
    cb = scene.central_body
    out["central_body"] = {
        "name": cb.name,
        "mu": format_si(cb.mu_m3_s2, GRAVITATIONAL_PARAMETER),
        "radius": format_si(cb.radius_m, LENGTH),
    }
    out["effects"] = {use.name: _effect_params_dict(use) for use in scene.effects}
    bodies = {}
    for b in scene.bodies:
        entry: dict[str, Any] = {} if (b.fixed and b.mass_kg == 0.0) else {"mass": format_si(b.mass_kg, MASS)}
        if b.fixed:
            entry["fixed"] = True
        entry.update(_state_dict(b.position_m, b.velocity_m_s, b.elements))
        if b.rigid is not None:
            entry.update(_rigid_dict(b.rigid))
        bodies[b.name] = entry
    out["bodies"] = bodies
    if scene.tethers:
        tethers = {}
        for t in scene.tethers:
            entry = {
                "from": t.from_body,
                "to": t.to_body,
                "rods": t.rods,
                "length": format_si(t.length_m, LENGTH),
                "EA": format_si(t.EA_N, FORCE),
                "mass": format_si(t.mass_kg, MASS),
                "damping": format_si(t.damping_N_s, DAMPING),
                "model": t.model,
                "quadrature": t.quadrature,
            }
            if t.diameter_m is not None:
                entry["diameter"] = format_si(t.diameter_m, LENGTH)
            if t.tension_only:
                entry["tension_only"] = True
            if t.from_point_m is not None:
                entry["from_point"] = _vec(t.from_point_m, LENGTH)
            if t.to_point_m is not None:
                entry["to_point"] = _vec(t.to_point_m, LENGTH)
            # A default shape is left out: it reads back the same, and a sweep that later places
            # both ends explicitly is not tripped by a shape nobody asked for.
            if t.initial is not None and t.initial != InitialShape():
                s = t.initial
                entry["initial"] = {"shape": s.shape} if s.shape == EQUILIBRIUM else {
                    "shape": s.shape,
                    "theta": _angles_dict(s.theta_rad),
                    "phi": _angles_dict(s.phi_rad),
                    "side": s.side,
                    "strain": float(s.strain),
                }
            tethers[t.name] = entry
        out["tethers"] = tethers
    if scene.orbit is not None:
        o = scene.orbit
        out["orbit"] = {"reference": o.reference, **_state_dict(o.position_m, o.velocity_m_s, o.elements), "motion": o.motion}
    ig = scene.integrator
    integrator: dict[str, Any] = {"method": ig.method, "rtol": float(ig.rtol), "atol": float(ig.atol)}
    if ig.max_step_s is not None:
        integrator["max_step"] = format_si(ig.max_step_s, TIME)
    if ig.max_steps is not None:
        integrator["max_steps"] = ig.max_steps
    if ig.formulation != "cowell":
        integrator["formulation"] = ig.formulation
    if ig.time_element != "none":
        integrator["time_element"] = ig.time_element
    out["integrator"] = integrator
    if scene.stop is not None and scene.stop.altitude_m is not None:
        out["stop"] = {"altitude": format_si(scene.stop.altitude_m, LENGTH)}
    op = scene.output
    if op.step_s is not None:
        out["output"] = {"step": format_si(op.step_s, TIME)}
    elif op.count is not None:
        out["output"] = {"count": op.count}
    else:
        out["output"] = {"times": [format_si(x, TIME) for x in op.times_s]}
    return out
