"""[bodies]: masses, explicit states (position and velocity, elements, fixed), rigid bodies with
their inertia, attitude, wheels and attitude control."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from ..errors import SceneError
from ..units import (
    ANGLE,
    ANGULAR_MOMENTUM,
    ANGULAR_RATE,
    DIMENSIONLESS,
    LENGTH,
    MASS,
    MOMENT_OF_INERTIA,
    SPEED,
    TIME,
    TORQUE,
    shown,
    to_si,
)
from .data import (
    ATTITUDE_FRAMES,
    CENTER_OF_MASS,
    EULER_SEQUENCES,
    QUATERNION_NORM_TOL,
    RATE_FRAMES,
    WHEEL_TORQUE_CONTROL,
    Attitude,
    Body,
    Control,
    Elements,
    Rigid,
    Vector3,
    Wheel,
)
from .keys import (
    _NOTHING,
    _bounded,
    _choice,
    _join,
    _named_tables,
    _number,
    _quantity,
    _required,
    _suggest,
    _table,
    _vector,
)


_ELEMENT_KEYS = ("a", "e", "i", "raan", "argp", "nu", "altitude", "perigee_altitude", "apogee_altitude")
#: the ways of giving the orbit's size (one of them), each with the keys it reads
_SIZE_KEYS = ("a", "altitude", "perigee_altitude", "apogee_altitude")


def _orbit_size(table: Mapping[str, Any], path: str, radius_m: float | None) -> tuple[float, Any, float, Any]:
    """(a, the raw value a is reported with, e, the raw e) from a, altitude, perigee_altitude
    and/or apogee_altitude (altitudes above the central body's radius)."""
    given = [k for k in _SIZE_KEYS if k in table]
    pair = set(given) == {"perigee_altitude", "apogee_altitude"}
    if not given or (len(given) > 1 and not pair):
        raise SceneError(
            f"{path}.a",
            "the orbit's size as one of: a (semi-major axis), altitude (a minus the central body's radius), "
            "perigee_altitude, apogee_altitude, or perigee_altitude with apogee_altitude",
            _NOTHING if not given else " and ".join(given),
        )
    if given == ["a"]:
        a = _quantity(table["a"], f"{path}.a", LENGTH)
        e_raw = _required(table, "e", path, "an eccentricity (a number >= 0, e.g. 0.01)")
        return a, table["a"], _bounded(to_si(e_raw, DIMENSIONLESS, key=f"{path}.e"), f"{path}.e", DIMENSIONLESS, e_raw), e_raw
    if radius_m is None:  # pragma: no cover - every caller passes the central body's radius
        raise SceneError(f"{path}.{given[0]}", "a central body to measure the altitude from", _NOTHING)
    h = {k: _quantity(table[k], f"{path}.{k}", LENGTH) for k in given}
    for k, v in h.items():
        if not v > -radius_m:
            raise SceneError(f"{path}.{k}", f"an altitude above the centre of the central body (> {-radius_m:.6g} m)",
                             shown(table[k]))  # fmt: skip
    if pair:
        if "e" in table:
            raise SceneError(f"{path}.e", "no eccentricity: perigee_altitude and apogee_altitude set it", shown(table["e"]))
        rp, ra = radius_m + h["perigee_altitude"], radius_m + h["apogee_altitude"]
        if ra < rp:
            raise SceneError(f"{path}.apogee_altitude", f"an apogee altitude >= the perigee altitude "
                             f"({shown(table['perigee_altitude'])})", shown(table["apogee_altitude"]))  # fmt: skip
        e = (ra - rp) / (ra + rp)
        return 0.5 * (rp + ra), table["apogee_altitude"], e, e
    e_raw = table.get("e", 0.0)
    e = _bounded(to_si(e_raw, DIMENSIONLESS, key=f"{path}.e"), f"{path}.e", DIMENSIONLESS, e_raw)
    key = given[0]
    if key == "altitude":
        return radius_m + h[key], table[key], e, e_raw
    if key == "perigee_altitude":
        if e == 1.0:
            return math.nan, table[key], e, e_raw  # refused below as a parabola
        return (radius_m + h[key]) / (1.0 - e), table[key], e, e_raw
    if not 0.0 <= e < 1.0:
        raise SceneError(f"{path}.e", "an eccentricity in [0, 1) with apogee_altitude (only ellipses have an apogee)",
                         shown(e_raw))  # fmt: skip
    return (radius_m + h[key]) / (1.0 + e), table[key], e, e_raw


def _parse_elements(value: Any, path: str, radius_m: float | None = None) -> Elements:
    table = _table(value, path, _ELEMENT_KEYS)
    a, a_raw, e, e_raw = _orbit_size(table, path, radius_m)
    angles = {k: to_si(table[k], ANGLE, key=f"{path}.{k}") if k in table else 0.0 for k in ("i", "raan", "argp", "nu")}

    if e < 0.0:
        raise SceneError(f"{path}.e", "an eccentricity >= 0", shown(e_raw))
    if e == 1.0:
        raise SceneError(
            f"{path}.e",
            "e != 1 (a parabolic orbit has no finite semi-major axis; give position and velocity instead)",
            shown(e_raw),
        )
    if e < 1.0 and not a > 0.0:
        raise SceneError(f"{path}.a", "a > 0 for an elliptic orbit (e < 1)", f"{shown(a_raw)} with e = {e!r}")
    if e > 1.0 and not a < 0.0:
        raise SceneError(f"{path}.a", "a < 0 for a hyperbolic orbit (e > 1)", f"{shown(a_raw)} with e = {e!r}")
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


def _parse_state(table: Mapping[str, Any], path: str, *, fixed: bool = False, radius_m: float | None = None):
    """(position, velocity, elements) of a body or of [orbit]; all None when none is given
    (``radius_m``: the central body's, for altitudes given in the elements)."""
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
        return None, None, _parse_elements(table["elements"], _join(path, "elements"), radius_m)
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


def _parse_bodies(value: Any, mu: float, origin_singular: list[str] = (), radius_m: float | None = None) -> tuple[Body, ...]:
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
        position, velocity, elements = _parse_state(table, path, fixed=fixed, radius_m=radius_m)
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
            check_table_times(ts, times, f"{key}.times")
            vs = tuple(to_si(x, TORQUE, key=f"{key}.values[{j}]") for j, x in enumerate(values))
            torque = (ts, vs)
        else:
            torque = to_si(raw_t, TORQUE, key=key)
    return Wheel(name, tuple(float(x) for x in axis / n), inertia, speed, max_speed, max_torque, torque)


def check_table_times(ts: tuple, raw: Any, key: str) -> None:
    """The times of a time table: increasing, a time written twice being a jump (the value before
    it, then the value after it; an integrator breakpoint, docs/integrators.md section 14).  A time
    written three times, or going back, says nothing sensible: refused."""
    for j, (a, b) in enumerate(zip(ts, ts[1:])):
        if b < a:
            raise SceneError(key, "non-decreasing times (a time written twice is a jump)",
                             f"{shown(raw)} (times[{j + 1}] < times[{j}])")
        if j + 2 < len(ts) and a == b == ts[j + 2]:
            raise SceneError(key, "each time at most twice (twice: a jump from the first value to the second)",
                             f"{shown(raw)} (times[{j}] to times[{j + 2}] equal)")
    if len(ts) >= 2 and ts[0] == ts[1]:
        raise SceneError(key, "no jump at the first time (the table holds its first value before it: give the "
                         "value after the jump alone)", shown(raw))


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
