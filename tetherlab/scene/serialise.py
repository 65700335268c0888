"""Back to a dictionary: the scene as TOML-shaped data with SI strings, such that
``Scene.from_dict(scene.to_dict()) == scene`` holds exactly."""

from __future__ import annotations

from typing import Any

from ..errors import SceneError
from ..forces import EFFECTS
from ..units import (
    ANGLE,
    ANGULAR_MOMENTUM,
    ANGULAR_RATE,
    DAMPING,
    FORCE,
    GRAVITATIONAL_PARAMETER,
    LENGTH,
    MASS,
    MOMENT_OF_INERTIA,
    RATE,
    SPEED,
    TIME,
    TORQUE,
    Kind,
    format_si,
)
from .bodies import _INERTIA_KEYS
from .data import EQUILIBRIUM, EffectUse, InitialShape, Rigid, Scene


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


def _equilibrium_dict(s: InitialShape) -> dict[str, Any]:
    out: dict[str, Any] = {"shape": s.shape}
    r = s.release
    if r is not None:
        out["release"] = (
            {"angle": format_si(r.angle_rad, ANGLE)} if r.angle_rad is not None
            else {"mode": r.mode, "amplitude": format_si(r.amplitude_m, LENGTH)}
        )
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
    if scene.continue_from is not None:
        out["continue_from"] = scene.continue_from
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
            if t.constraint_rate_1_s is not None:
                entry["constraint_rate"] = format_si(t.constraint_rate_1_s, RATE)
            if t.from_point_m is not None:
                entry["from_point"] = _vec(t.from_point_m, LENGTH)
            if t.to_point_m is not None:
                entry["to_point"] = _vec(t.to_point_m, LENGTH)
            if t.reel is not None:
                r = t.reel
                entry.pop("rods")  # the reel decides them
                entry["reel"] = {"exit": r.exit, "law": r.law, "rod_length": format_si(r.rod_length_m, LENGTH),
                                 "birth_length": format_si(r.birth_length_m, LENGTH),
                                 "retire_length": format_si(r.retire_length_m, LENGTH),
                                 "stored_length": format_si(r.stored_length_m, LENGTH)}  # fmt: skip
                if r.law == "constant":
                    entry["reel"]["speed"] = format_si(r.speed_m_s, SPEED)
                elif r.law == "exponential":
                    entry["reel"]["rate"] = format_si(r.rate_1_s, RATE)
                elif r.law in ("spool", "tension"):
                    entry["reel"].update(_spool_dict(r))
                else:
                    entry["reel"]["times"] = [format_si(x, TIME) for x in r.times_s]
                    entry["reel"]["lengths"] = [format_si(x, LENGTH) for x in r.lengths_m]
                if r.point_m is not None:  # a reel on a rigid body
                    entry["reel"]["point"] = _vec(r.point_m, LENGTH)
                if r.exit_direction is not None:
                    entry["reel"]["exit_direction"] = [float(x) for x in r.exit_direction]
                if r.spool_radius_m > 0.0:
                    entry["reel"]["spool_radius"] = format_si(r.spool_radius_m, LENGTH)
                if r.spool_axis is not None:
                    entry["reel"]["spool_axis"] = [float(x) for x in r.spool_axis]
                if r.birth != "straight":  # the default reads back the same
                    entry["reel"]["birth"] = r.birth
            # A default shape is left out: it reads back the same, and a sweep that later places
            # both ends explicitly is not tripped by a shape nobody asked for.
            if t.initial is not None and t.initial != InitialShape():
                s = t.initial
                entry["initial"] = _equilibrium_dict(s) if s.shape == EQUILIBRIUM else {
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
        if o.spin is not None:
            out["orbit"]["spin"] = {"rate": format_si(o.spin.rate_rad_s, ANGULAR_RATE), "axis": list(o.spin.axis),
                                    "frame": o.spin.frame}  # fmt: skip
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
    if ig.error_scale != "rod":
        integrator["error_scale"] = ig.error_scale
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


def _spool_dict(r) -> dict:
    """The keys of a spool or tension law (scene/reels.py reads them back)."""
    from ..units import ANGULAR_RATE, FORCE, MASS, MOMENT_OF_INERTIA, TORQUE
    from .reels import VISCOUS

    sp = r.spool
    out = {"speed": format_si(r.speed_m_s, SPEED), "viscous_friction": format_si(sp.viscous_N_s_m, VISCOUS),
           "coulomb_friction": format_si(sp.coulomb_N, FORCE), "friction_speed": format_si(sp.friction_speed_m_s, SPEED)}
    if r.exit == "drum":
        out["spool_inertia"] = format_si(sp.spool_inertia_kg_m2, MOMENT_OF_INERTIA)
    if sp.drum_radius_m > 0.0:
        out["drum_radius"] = format_si(sp.drum_radius_m, LENGTH)
    if sp.max_torque_N_m > 0.0:
        out["max_torque"] = format_si(sp.max_torque_N_m, TORQUE)
        out["torque_limit_width"] = format_si(sp.torque_limit_width_N_m, TORQUE)
    if sp.max_speed_m_s > 0.0:
        out["max_speed"] = format_si(sp.max_speed_m_s, SPEED)
        out["speed_brake_gain"] = format_si(sp.speed_brake_gain_N_s_m, VISCOUS)
        out["speed_limit_width"] = format_si(sp.speed_limit_width_m_s, SPEED)
    if r.law == "spool":
        if sp.drum_radius_m > 0.0:  # a torque needs its arm: without a drum radius it is zero and unwritten
            out["torque"] = format_si(sp.torque_N_m, TORQUE)
        return out
    out.update({"reduced_mass": format_si(sp.reduced_mass_kg, MASS), "orbit_rate": format_si(sp.orbit_rate_rad_s, ANGULAR_RATE),
                "commanded_length": format_si(sp.commanded_length_m, LENGTH), "k1": sp.k1, "k2": sp.k2})  # fmt: skip
    if sp.limit_width_N > 0.0:
        out["min_tension"] = format_si(sp.min_tension_N, FORCE)
        if sp.max_tension_N > 0.0:
            out["max_tension"] = format_si(sp.max_tension_N, FORCE)
        out["limit_width"] = format_si(sp.limit_width_N, FORCE)
    if sp.stages:
        out["stages"] = [_stage_dict(s) for s in sp.stages]
    return out


def _stage_dict(s) -> dict:
    """A tension law's stage as the scene writes it: its switch, its commanded length and the gains
    and limits it gives (those it leaves to the law are not written)."""
    from .reels import VISCOUS

    out: dict = {"start": format_si(s.start_s, TIME)} if s.start_s is not None else {"at_length": format_si(s.at_length_m, LENGTH)}
    out["commanded_length"] = format_si(s.commanded_length_m, LENGTH)
    for key, attr, kind in (("k1", "k1", None), ("k2", "k2", None), ("min_tension", "min_tension_N", FORCE),
                            ("max_tension", "max_tension_N", FORCE), ("limit_width", "limit_width_N", FORCE),
                            ("max_speed", "max_speed_m_s", SPEED), ("speed_brake_gain", "speed_brake_gain_N_s_m", VISCOUS),
                            ("speed_limit_width", "speed_limit_width_m_s", SPEED)):  # fmt: skip
        v = getattr(s, attr)
        if v is not None:
            out[key] = v if kind is None else format_si(v, kind)
    return out
