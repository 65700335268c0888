"""The validated scene: frozen dataclasses holding SI floats (angles in rad), unit suffixes in the
field names, and the constants that say what a scene may contain.

Build them through :meth:`Scene.from_dict` or :func:`~tetherlab.scene.load_scene` and change them
through :meth:`Scene.replace`, which re-validates.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np

from ..errors import SceneError
from ..model import topology
from ..model.topology import LayoutStep
from ..orbits import kepler


# Largest strain a scene may start with, or imply by placing a tether's two ends.  5 % is far
# beyond the elastic limit of aluminium (about 0.3 %) and the working range of polymer tethers
# (Dyneema/Spectra fail near 3-4 %), so anything larger is a units or placement mistake, not a
# physical initial condition.
MAX_SANE_STRAIN = 0.05

CENTER_OF_MASS = "center_of_mass"
TETHER_MODELS = ("paper", "energy", "inextensible")
INEXTENSIBLE = "inextensible"  # rods of fixed length, tensions as multipliers (docs/inextensible.md)
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
class Release:
    """A lateral perturbation of the free-hanging equilibrium (shape 'equilibrium' with
    ``release``; docs/scenes.md, docs/hanging-chain.md section 3): every rod turned by
    ``angle_rad`` about the root, or the rods laid along lateral mode ``mode`` of the hanging
    chain with the end mass moved sideways by ``amplitude_m``; then every rod's strain set to the
    tension it carries at the release, so the release rings no axial mode."""

    angle_rad: float | None = None
    mode: int = 0
    amplitude_m: float = 0.0


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
    release: Release | None = None  # shape 'equilibrium' only: released from the free hang

    def rod_angles_rad(self, rods: int) -> tuple[tuple[float, ...], tuple[float, ...]]:
        """(theta, phi) of every rod, whatever the shape."""
        if self.shape == "straight":
            return (float(self.theta_rad),) * rods, (float(self.phi_rad),) * rods
        return tuple(self.theta_rad), tuple(self.phi_rad)


REEL_LAWS = ("constant", "exponential", "table", "spool", "tension")
REEL_EXITS = ("canister", "drum")
#: where a birth puts the new joint (docs/deployment.md 6.1, 6.4): on the straight rod it splits
#: (every material point kept) or on the line's quasi-static shape (momenta kept, energy budgeted)
REEL_BIRTHS = ("straight", "quasi-static")


@dataclass(frozen=True)
class Reel:
    """A reel at the tether's `from` end paying it out or hauling it in (docs/deployment.md).

    The deployed unstretched length follows the law from the tether's ``length`` at t = 0; the
    first rod (at the reel) varies, the others have ``rod_length_m``; a rod is born when the first
    exceeds ``birth_length_m`` and the first is merged into the next below ``retire_length_m``."""

    law: str  # REEL_LAWS
    exit: str = "canister"  # REEL_EXITS
    speed_m_s: float = 0.0  # law 'constant': dL/dt
    rate_1_s: float = 0.0  # law 'exponential': L = L0 exp(rate t)
    rod_length_m: float = 0.0
    birth_length_m: float = 0.0
    retire_length_m: float = 0.0
    stored_length_m: float = 0.0  # tether still on the reel at t = 0
    times_s: tuple = ()  # law 'table': times from 0, increasing
    lengths_m: tuple = ()  # law 'table': L at those times (a natural cubic spline between them)
    # on a rigid body (docs/deployment.md 9): the exit point and direction, body axes; the stored
    # tether is a thin ring of spool_radius_m about spool_axis centred at the exit point
    point_m: Vector3 | None = None
    exit_direction: Vector3 | None = None  # unit
    spool_radius_m: float = 0.0
    spool_axis: Vector3 | None = None  # unit; a canister's is its exit direction
    spool: "SpoolLaw | None" = None  # laws 'spool' and 'tension': L and L' are state (speed_m_s is L'(0))
    birth: str = "straight"  # REEL_BIRTHS


class SpoolStage(NamedTuple):
    """A later stage of a tension law (docs/deployment.md 10.6, 10.7): it takes over at a time
    (``start_s``) or on reaching a deployed length (``at_length_m``), the other None, with its
    commanded length and the gains and limits it sets (None: the law's own)."""

    start_s: float | None
    commanded_length_m: float
    at_length_m: float | None = None
    k1: float | None = None
    k2: float | None = None
    min_tension_N: float | None = None
    max_tension_N: float | None = None
    limit_width_N: float | None = None
    max_speed_m_s: float | None = None
    speed_brake_gain_N_s_m: float | None = None
    speed_limit_width_m_s: float | None = None


@dataclass(frozen=True)
class SpoolLaw:
    """The reel as a dynamical system (docs/deployment.md 10): the spool (a drum: inertia J and
    radius R; a canister: no inertia), a torque (positive hauling in) or the tension law's
    command, viscous and Coulomb friction against the pay-out."""

    spool_inertia_kg_m2: float = 0.0
    drum_radius_m: float = 0.0
    torque_N_m: float = 0.0
    viscous_N_s_m: float = 0.0
    coulomb_N: float = 0.0
    friction_speed_m_s: float = 0.01
    # law 'tension': T_c = m* Omega^2 [3 l_c + k1 (L - l_c) + k2 L'/Omega]
    reduced_mass_kg: float = 0.0
    orbit_rate_rad_s: float = 0.0
    commanded_length_m: float = 0.0
    k1: float = 0.0
    k2: float = 0.0
    min_tension_N: float = 0.0
    max_tension_N: float = 0.0
    limit_width_N: float = 0.0  # 0: no limits
    # law 'tension': later stages (SpoolStage), each taking over from the one before at its start
    # time or on reaching its length; commanded_length_m and the law's gains and limits hold until
    # the first (docs/deployment.md 10.6, 10.7)
    stages: tuple = ()
    # either law: the motor's torque within |tau| <= max_torque, and a regulating brake of gain
    # speed_brake_gain engaging above |L'| = max_speed, both through smooth corners (10.4)
    max_torque_N_m: float = 0.0  # 0: no limit
    torque_limit_width_N_m: float = 0.0
    max_speed_m_s: float = 0.0  # 0: no limit
    speed_brake_gain_N_s_m: float = 0.0
    speed_limit_width_m_s: float = 0.0


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
    reel: Reel | None = None  # a tether of varying length (docs/deployment.md)
    # model "inextensible": the Baumgarte rate of the length constraints (None: the scene's
    # reference rate, docs/inextensible.md section 4; 0: no stabilisation)
    constraint_rate_1_s: float | None = None


#: frames a spin axis may be written in
SPIN_FRAMES = ("orbit", "inertial")


@dataclass(frozen=True)
class Spin:
    """A rigid rotation of the point masses and tethers about the orbit reference at t = 0, on
    top of ``motion`` (docs/scenes.md, ``[orbit] spin``)."""

    rate_rad_s: float
    axis: Vector3 = (0.0, 0.0, 1.0)  # unit vector; in the orbit frame: (radial, along-track, normal)
    frame: str = "orbit"


@dataclass(frozen=True)
class Orbit:
    """Initial orbit of the reference point (the centre of mass, or a body)."""

    reference: str = CENTER_OF_MASS
    elements: Elements | None = None
    position_m: Vector3 | None = None
    velocity_m_s: Vector3 | None = None
    motion: str = "corotating"
    spin: Spin | None = None

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
    # What the rods' error is measured against (docs/integrators.md section 15): "rod", each rod's
    # own length (resolves the axial ringing of short rods); "tether", the whole tether's length
    # (the error a user sees in a point's position along the tether)
    error_scale: str = "rod"


FORMULATIONS = ("cowell", "dromo", "dromo-time", "cowell-orbit")
TIME_ELEMENTS = ("none", "linear")
ERROR_SCALES = ("rod", "tether")


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
    continue_from: str | None = None  # a finished run's directory: start from its final state
    source: str = field(default="<dict>", compare=False)  # file path, or "<dict>"
    # the graph of bodies and tethers (tetherlab/model/topology.py), derived at load: not part of
    # the scene's value (equality, to_dict) any more than its source is
    graph: topology.Graph | None = field(default=None, compare=False, repr=False)

    # -- construction ---------------------------------------------------------------------

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: str = "<dict>") -> "Scene":
        """Validate ``data`` (the TOML structure; quantities as strings or astropy Quantities)."""
        from .load import _parse_scene  # (the reader builds these dataclasses)

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
        from .serialise import _scene_to_dict

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
        from .keys import _set_dotted
        from .load import _TOP_KEYS

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
