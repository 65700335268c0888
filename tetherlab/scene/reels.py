"""[tethers.NAME.reel]: a reel at the tether's `from` end and its law (docs/deployment.md,
docs/scenes.md).  Checked here: every bound positive, the birth and retirement bounds apart by
more than a rod (the hysteresis that keeps a birth from being undone at once), the law's
parameter present and the initial length within one rod's bounds."""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

from ..errors import SceneError
from ..units import ANGULAR_RATE, FORCE, LENGTH, MASS, MOMENT_OF_INERTIA, RATE, SPEED, TIME, TORQUE, Kind, shown
from .data import REEL_BIRTHS, REEL_EXITS, REEL_LAWS, Reel, SpoolLaw, SpoolStage
from .keys import _choice, _number, _quantity, _required, _table, _vector

#: the spool laws' keys (docs/deployment.md 10, docs/scenes.md)
_SPOOL_KEYS = ("spool_inertia", "drum_radius", "torque", "viscous_friction", "coulomb_friction", "friction_speed",
               "max_torque", "torque_limit_width", "max_speed", "speed_brake_gain", "speed_limit_width")
_TENSION_KEYS = ("reduced_mass", "orbit_rate", "commanded_length", "k1", "k2", "min_tension", "max_tension",
                 "limit_width", "stages")
#: the keys of one entry of a tension law's `stages` (docs/deployment.md 10.6, 10.7): when it takes
#: over (exactly one of start and at_length), its commanded length, and the gains and limits it sets
_STAGE_LIMIT_KEYS = ("k1", "k2", "min_tension", "max_tension", "limit_width", "max_speed", "speed_brake_gain",
                     "speed_limit_width")
_STAGE_KEYS = ("start", "at_length", "commanded_length") + _STAGE_LIMIT_KEYS
_REEL_KEYS = ("at", "exit", "law", "speed", "rate", "times", "lengths", "rod_length", "birth_length", "retire_length",
              "stored_length", "point", "exit_direction", "spool_radius", "spool_axis", "birth") + _SPOOL_KEYS + _TENSION_KEYS
VISCOUS = Kind("N s / m", "a viscous friction coefficient (force per speed)", "20 N s/m")
#: default v_s of the Coulomb friction's smooth sign tanh(L'/v_s): 1 cm/s, below any pay-out
#: speed of interest and wide enough for the implicit integrators' Newton iteration
FRICTION_SPEED_DEFAULT = "0.01 m/s"

#: the smooth limits' default corner width, as a fraction of the limit, and the widest allowed (a
#: wider corner bends the law far inside the limit: at zero torque the corners of +-tau_max meet)
LIMIT_WIDTH_DEFAULT = 0.01
LIMIT_WIDTH_MAX = 0.1

#: a drum's axis must be perpendicular to its exit direction within this cosine (its rim moves along
#: the exit direction where the line leaves it)
DRUM_AXIS_COS = 1e-6

#: Default bounds in rod lengths: a birth at 1.5 leaves a first rod of 0.5, a retirement at 0.25
#: leaves one of 1.25, both a quarter of a rod from the other bound.
BIRTH_DEFAULT = 1.5
RETIRE_DEFAULT = 0.25


def rods_for(length_m: float, reel: Reel) -> int:
    """Rods of a reel tether of deployed length ``length_m``: full rods of ``rod_length_m`` and the
    first, between the retirement and the birth bounds."""
    n = 1
    first = length_m
    while first > reel.birth_length_m:
        first -= reel.rod_length_m
        n += 1
    return n


def parse_reel(value: Any, path: str, length_m: float) -> Reel:
    table = _table(value, path, _REEL_KEYS)
    at = _choice(table.get("at", "from"), f"{path}.at", ("from",))
    del at  # one end today: the tether's `from` end, its attachment on the parent body
    exit_ = _choice(table.get("exit", "canister"), f"{path}.exit", REEL_EXITS)
    law = _choice(_required(table, "law", path, f"one of {REEL_LAWS}"), f"{path}.law", REEL_LAWS)
    speed = rate = 0.0
    times: tuple = ()
    lengths: tuple = ()
    prescribed = ("rate", "times", "lengths")
    others = {"constant": ("rate", "times", "lengths"), "exponential": ("speed", "times", "lengths"),
              "table": ("speed", "rate"), "spool": prescribed, "tension": prescribed}[law]  # fmt: skip
    if law not in ("spool", "tension"):
        others = others + _SPOOL_KEYS + _TENSION_KEYS
    elif law == "spool":
        others = others + _TENSION_KEYS
    else:
        others = others + ("torque",)
    for key in others:
        if key in table:
            raise SceneError(f"{path}.{key}", f"no {key!r} with law {law!r}", shown(table[key]))
    if law == "table":
        times, lengths = _table_law(table, path, length_m)
    elif law == "constant":
        speed = _quantity(_required(table, "speed", path, SPEED.describe()), f"{path}.speed", SPEED)
    elif law in ("spool", "tension"):
        speed = _quantity(table.get("speed", "0 m/s"), f"{path}.speed", SPEED)  # L'(0)
    else:
        rate = _quantity(_required(table, "rate", path, RATE.describe()), f"{path}.rate", RATE)
    rod = _quantity(_required(table, "rod_length", path, LENGTH.describe()), f"{path}.rod_length", LENGTH, positive=True)
    birth = (_quantity(table["birth_length"], f"{path}.birth_length", LENGTH, positive=True)
             if "birth_length" in table else BIRTH_DEFAULT * rod)  # fmt: skip
    retire = (_quantity(table["retire_length"], f"{path}.retire_length", LENGTH, positive=True)
              if "retire_length" in table else RETIRE_DEFAULT * rod)  # fmt: skip
    if not retire + rod < birth:
        raise SceneError(
            f"{path}.birth_length",
            f"more than retire_length + rod_length = {retire + rod:.6g} m (a rod born at the birth bound must leave a "
            "first rod longer than the retirement bound, and a merge one shorter than the birth bound)",
            f"{birth:.6g} m with retire_length {retire:.6g} m and rod_length {rod:.6g} m",
        )
    stored = _quantity(table.get("stored_length", "0 m"), f"{path}.stored_length", LENGTH, nonnegative=True)
    birth_kind = _choice(table.get("birth", "straight"), f"{path}.birth", REEL_BIRTHS)
    if length_m < retire:
        raise SceneError(
            f"{path}.retire_length", f"at most the deployed length ({length_m:.6g} m): at least one rod must be out",
            f"{retire:.6g} m",
        )
    hub = _parse_hub(table, path, exit_)
    spool = _spool_law(table, path, law, exit_, length_m, stored) if law in ("spool", "tension") else None
    return Reel(law, exit_, speed, rate, rod, birth, retire, stored, times, lengths, spool=spool, birth=birth_kind,
                **hub)


def _unit_vector(raw, key: str) -> tuple:
    """A direction in body axes: 3 plain numbers, not all zero; returned normalised."""
    if not isinstance(raw, (list, tuple)) or len(raw) != 3:
        raise SceneError(key, "a list of 3 numbers (a direction in body axes, e.g. [0, 0, 1])", shown(raw))
    v = [_number(x, f"{key}[{j}]", "a number") for j, x in enumerate(raw)]
    n = math.sqrt(sum(x * x for x in v))
    if not n > 0.0:
        raise SceneError(key, "a direction of non-zero length (body axes)", shown(raw))
    return tuple(x / n for x in v)


def _parse_hub(table, path: str, exit_: str) -> dict:
    """The keys of a reel on a rigid body (docs/deployment.md 9): the exit point (body axes, from
    the centre of mass), the exit direction, the spool's radius and, for a drum, its axis.  Whether
    the body is rigid is checked with the scene (scene/checks.py)."""
    out: dict = {}
    if "point" in table:
        out["point_m"] = _vector(table["point"], f"{path}.point", LENGTH)
    if "exit_direction" in table:
        out["exit_direction"] = _unit_vector(table["exit_direction"], f"{path}.exit_direction")
    if "spool_radius" in table:
        out["spool_radius_m"] = _quantity(table["spool_radius"], f"{path}.spool_radius", LENGTH, positive=True)
    if "spool_axis" in table:
        if exit_ != "drum":
            raise SceneError(f"{path}.spool_axis", "no spool_axis with exit 'canister' (a canister's axis is its "
                             "exit_direction: the line is pulled off the end of the spool)", shown(table["spool_axis"]))  # fmt: skip
        axis = _unit_vector(table["spool_axis"], f"{path}.spool_axis")
        e = out.get("exit_direction")
        if e is not None and abs(sum(a * b for a, b in zip(axis, e))) > DRUM_AXIS_COS:
            raise SceneError(f"{path}.spool_axis", "an axis perpendicular to exit_direction (the drum's rim moves along "
                             "the exit direction where the line leaves it)", f"{shown(table['spool_axis'])}, "
                             f"cosine {sum(a * b for a, b in zip(axis, e)):.3g} with exit_direction")  # fmt: skip
        out["spool_axis"] = axis
    return out


def _spool_law(table, path: str, law: str, exit_: str, length_m: float, stored_m: float) -> SpoolLaw:
    """The spool and its friction, and the tension law's gains and limits (docs/deployment.md 10)."""
    drum = exit_ == "drum"
    if drum:
        inertia = _quantity(_required(table, "spool_inertia", path, f"{MOMENT_OF_INERTIA.describe()} (a drum's spool)"),
                            f"{path}.spool_inertia", MOMENT_OF_INERTIA, positive=True)  # fmt: skip
    else:
        if "spool_inertia" in table:
            raise SceneError(f"{path}.spool_inertia", "no spool inertia with exit 'canister' (the line leaves a "
                             "canister at rest: no spool turns; use exit = 'drum')", shown(table["spool_inertia"]))  # fmt: skip
        inertia = 0.0
    needs_radius = drum or "torque" in table or "max_torque" in table
    radius = 0.0
    if needs_radius:
        radius = _quantity(_required(table, "drum_radius", path, f"{LENGTH.describe()} (the torque's arm)"),
                           f"{path}.drum_radius", LENGTH, positive=True)  # fmt: skip
    elif "drum_radius" in table:
        radius = _quantity(table["drum_radius"], f"{path}.drum_radius", LENGTH, positive=True)
    torque = _quantity(table.get("torque", "0 N m"), f"{path}.torque", TORQUE)
    viscous = _quantity(table.get("viscous_friction", "0 N s/m"), f"{path}.viscous_friction", VISCOUS,
                        nonnegative=True)  # fmt: skip
    coulomb = _quantity(table.get("coulomb_friction", "0 N"), f"{path}.coulomb_friction", FORCE, nonnegative=True)
    vs = _quantity(table.get("friction_speed", FRICTION_SPEED_DEFAULT), f"{path}.friction_speed", SPEED, positive=True)
    limits = _limits(table, path, law, torque)
    if law == "spool":
        return SpoolLaw(inertia, radius, torque, viscous, coulomb, vs, **limits)
    mstar = _quantity(_required(table, "reduced_mass", path, MASS.describe()), f"{path}.reduced_mass", MASS,
                      positive=True)  # fmt: skip
    omega = _quantity(_required(table, "orbit_rate", path, ANGULAR_RATE.describe()), f"{path}.orbit_rate",
                      ANGULAR_RATE, positive=True)  # fmt: skip
    lc = _quantity(_required(table, "commanded_length", path, LENGTH.describe()), f"{path}.commanded_length", LENGTH,
                   positive=True)  # fmt: skip
    k1 = _number(_required(table, "k1", path, "a number"), f"{path}.k1", "a number (the gain on l - l_c)")
    k2 = _number(_required(table, "k2", path, "a number"), f"{path}.k2", "a number (the gain on l'/Omega)")
    tmin = tmax = width = 0.0
    if "min_tension" in table or "max_tension" in table:
        tmin = _quantity(table.get("min_tension", "0 N"), f"{path}.min_tension", FORCE, nonnegative=True)
        tmax = _quantity(table["max_tension"], f"{path}.max_tension", FORCE, positive=True) if "max_tension" in table else 0.0
        if tmax and not tmax > tmin:
            raise SceneError(f"{path}.max_tension", f"more than min_tension ({tmin:.6g} N)", f"{tmax:.6g} N")
        # the corners' width: 1 % of the band (or of the equilibrium tension without an upper limit)
        scale = (tmax - tmin) if tmax else mstar * omega * omega * 3.0 * lc
        width = _quantity(table.get("limit_width", f"{0.01 * scale!r} N"), f"{path}.limit_width", FORCE, positive=True)
    elif "limit_width" in table:
        raise SceneError(f"{path}.limit_width", "a min_tension or max_tension for it to round", shown(table["limit_width"]))
    law_ = SpoolLaw(inertia, radius, 0.0, viscous, coulomb, vs, mstar, omega, lc, k1, k2, tmin, tmax, width, **limits)
    if "stages" not in table:
        return law_
    return replace(law_, stages=_stages(table, path, law_, length_m, length_m + stored_m))


def _stages(table, path: str, law: SpoolLaw, length0_m: float, line_m: float) -> tuple:
    """A tension law's later stages (SpoolStage, docs/deployment.md 10.6, 10.7), in the order they
    take over.  A stage starts at a time (``start``: after 0 and after the previous time stage) or
    on reaching a deployed length (``at_length``: positive, within the line, and on the side the
    previous stage's command drives L to from where that stage began); exactly one of the two.
    Once a stage is started by a length, the later ones are too: a time stage after it would have
    to wait for a switch whose time the scene does not know.  The gains and limits a stage does
    not give are the law's."""
    raw = table["stages"]
    key = f"{path}.stages"
    example = "[{start = '2 h', commanded_length = '30 km'}] or [{at_length = '3.4 km', commanded_length = '30 km'}]"
    if not isinstance(raw, (list, tuple)) or not raw:
        raise SceneError(key, f"a non-empty list of stages, each a table of start (or at_length) and commanded_length "
                         f"(e.g. {example})", shown(raw))  # fmt: skip
    out: list = []
    for j, st in enumerate(raw):
        sk = f"{key}[{j}]"
        st = _table(st, sk, _STAGE_KEYS)
        if ("start" in st) == ("at_length" in st):
            got = "both" if "start" in st else "neither"
            raise SceneError(sk, "exactly one of start (a time) and at_length (a deployed length): when the stage's "
                             "command takes over", f"{got} ({shown(st)})")  # fmt: skip
        lc = _quantity(_required(st, "commanded_length", sk, LENGTH.describe()), f"{sk}.commanded_length", LENGTH,
                       positive=True)  # fmt: skip
        prev = out[-1] if out else None
        start = at = None
        if "start" in st:
            start = _quantity(st["start"], f"{sk}.start", TIME)
            if prev is not None and prev.at_length_m is not None:
                raise SceneError(f"{sk}.start", "an at_length, as the previous stage's (a stage after one started by a "
                                 "length is started by a length: the previous switch's time is not known ahead)",
                                 f"start {start:.6g} s")  # fmt: skip
            before = prev.start_s if prev is not None else 0.0
            if not start > before:
                raise SceneError(f"{sk}.start", f"a start after {'the previous stage' if out else 't = 0'} "
                                 f"({before:.6g} s): stages in order of time", f"{start:.6g} s")  # fmt: skip
        else:
            at = _quantity(st["at_length"], f"{sk}.at_length", LENGTH, positive=True)
            if at > line_m * (1.0 + 1e-12):
                raise SceneError(f"{sk}.at_length", f"at most the whole line ({line_m:.6g} m: the tether's length and "
                                 "stored_length)", f"{at:.6g} m")  # fmt: skip
            _reachable(sk, at, prev, law, length0_m)
        stage = SpoolStage(start, lc, at, **_stage_overrides(st, sk, law, lc))
        out.append(stage)
    return tuple(out)


def _reachable(sk: str, at_m: float, prev, law: SpoolLaw, length0_m: float) -> None:
    """A stage's at_length must lie where the previous stage's command drives L from where that
    stage began: beyond its start towards its commanded length (the law's own from the tether's
    length at t = 0; a length stage's from its at_length).  After a time stage, where L is at its
    start is not known ahead and only the length's bounds are checked."""
    if prev is not None and prev.at_length_m is None:
        return
    begin = length0_m if prev is None else prev.at_length_m
    aim = law.commanded_length_m if prev is None else prev.commanded_length_m
    by = "the law's commanded_length" if prev is None else "the previous stage's commanded_length"
    if (aim - begin) * (at_m - begin) > 0.0:
        return
    side = "above" if aim > begin else "below" if aim < begin else "away from"
    raise SceneError(f"{sk}.at_length", f"a length {side} {begin:.6g} m, where the previous stage begins, on the side "
                     f"{by} ({aim:.6g} m) drives the deployed length to (else it is never reached)",
                     f"{at_m:.6g} m")  # fmt: skip


def _stage_overrides(st, sk: str, law: SpoolLaw, lc_m: float) -> dict:
    """The gains and limits a stage gives (the others None: the law's), checked as the law's are,
    together with the law's values they combine with."""
    out: dict = {}
    if "k1" in st:
        out["k1"] = _number(st["k1"], f"{sk}.k1", "a number (the gain on l - l_c)")
    if "k2" in st:
        out["k2"] = _number(st["k2"], f"{sk}.k2", "a number (the gain on l'/Omega)")
    if "min_tension" in st:
        out["min_tension_N"] = _quantity(st["min_tension"], f"{sk}.min_tension", FORCE, nonnegative=True)
    if "max_tension" in st:
        out["max_tension_N"] = _quantity(st["max_tension"], f"{sk}.max_tension", FORCE, positive=True)
    tmin = out.get("min_tension_N", law.min_tension_N)
    tmax = out.get("max_tension_N", law.max_tension_N)
    if tmax and not tmax > tmin:
        raise SceneError(f"{sk}.max_tension" if "max_tension" in st else f"{sk}.min_tension",
                         f"max_tension above min_tension (the stage's or the law's): {tmax:.6g} N", f"min_tension "
                         f"{tmin:.6g} N")  # fmt: skip
    limited = law.limit_width_N > 0.0 or "min_tension" in st or "max_tension" in st
    if "limit_width" in st:
        if not limited:
            raise SceneError(f"{sk}.limit_width", "a min_tension or max_tension (the stage's or the law's) for it to "
                             "round", shown(st["limit_width"]))  # fmt: skip
        out["limit_width_N"] = _quantity(st["limit_width"], f"{sk}.limit_width", FORCE, positive=True)
    elif "min_tension" in st or "max_tension" in st:
        # the law's default corner, 1 % of the stage's band (or of its equilibrium tension)
        scale = (tmax - tmin) if tmax else law.reduced_mass_kg * law.orbit_rate_rad_s**2 * 3.0 * lc_m
        out["limit_width_N"] = 0.01 * scale
    if "max_speed" in st:
        out["max_speed_m_s"] = _quantity(st["max_speed"], f"{sk}.max_speed", SPEED, positive=True)
    if "speed_brake_gain" in st:
        out["speed_brake_gain_N_s_m"] = _quantity(st["speed_brake_gain"], f"{sk}.speed_brake_gain", VISCOUS,
                                                  positive=True)  # fmt: skip
    vmax = out.get("max_speed_m_s", law.max_speed_m_s)
    if vmax > 0.0 and not out.get("speed_brake_gain_N_s_m", law.speed_brake_gain_N_s_m) > 0.0:
        raise SceneError(f"{sk}.speed_brake_gain", f"{VISCOUS.describe()} (the regulating brake's force per m/s "
                         "beyond max_speed: the law has none)", "none")  # fmt: skip
    if "speed_limit_width" in st:
        if not vmax > 0.0:
            raise SceneError(f"{sk}.speed_limit_width", "a max_speed (the stage's or the law's) for the regulating "
                             "brake to hold", shown(st["speed_limit_width"]))  # fmt: skip
        out["speed_limit_width_m_s"] = _limit_width(st, sk, "speed_limit_width", vmax, SPEED, "m/s")
    elif "max_speed" in st:
        out["speed_limit_width_m_s"] = LIMIT_WIDTH_DEFAULT * vmax
    return out


def stage_parameters(spool: SpoolLaw, j: int) -> dict:
    """The tension law's parameters while stage j holds (-1: the law's own, before the first
    stage): the kernel's reel fields (tetherlab/kernel/schema.py REEL) by name."""
    lc, k1, k2 = spool.commanded_length_m, spool.k1, spool.k2
    tmin, tmax, tw = spool.min_tension_N, spool.max_tension_N, spool.limit_width_N
    vmax, vgain, vw = spool.max_speed_m_s, spool.speed_brake_gain_N_s_m, spool.speed_limit_width_m_s
    if j >= 0:
        s = spool.stages[j]

        def pick(a, b):
            return b if a is None else a

        lc, k1, k2 = s.commanded_length_m, pick(s.k1, k1), pick(s.k2, k2)
        tmin, tmax, tw = pick(s.min_tension_N, tmin), pick(s.max_tension_N, tmax), pick(s.limit_width_N, tw)
        vmax, vgain, vw = pick(s.max_speed_m_s, vmax), pick(s.speed_brake_gain_N_s_m, vgain), pick(s.speed_limit_width_m_s, vw)
    return {"lc_m": lc, "k1": k1, "k2": k2, "tmin_N": tmin, "tmax_N": tmax, "twidth_N": tw, "max_speed_m_s": vmax,
            "speed_gain_N_s_m": vgain, "speed_width_m_s": vw}


def _limit_width(table, path: str, key: str, limit: float, kind, unit: str) -> float:
    """The corner width of a smooth limit: LIMIT_WIDTH_DEFAULT of the limit unless given, positive
    and at most LIMIT_WIDTH_MAX of it."""
    if key not in table:
        return LIMIT_WIDTH_DEFAULT * limit
    width = _quantity(table[key], f"{path}.{key}", kind, positive=True)
    if width > LIMIT_WIDTH_MAX * limit:
        raise SceneError(f"{path}.{key}", f"at most {LIMIT_WIDTH_MAX:g} of the limit ({LIMIT_WIDTH_MAX * limit:.6g} "
                         f"{unit}: a wider corner bends the law far inside the limit)", f"{width:.6g} {unit}")  # fmt: skip
    return width


def _limits(table, path: str, law: str, torque: float) -> dict:
    """The smooth limits of either spool law (docs/deployment.md 10.4): the motor's torque within
    |tau| <= max_torque, and a regulating brake of gain speed_brake_gain engaging above
    |L'| = max_speed.  Each width key needs its limit; the speed limit needs its brake's gain."""
    out: dict = {}
    if "max_torque" in table:
        tmax = _quantity(table["max_torque"], f"{path}.max_torque", TORQUE, positive=True)
        if law == "spool" and abs(torque) > tmax:
            raise SceneError(f"{path}.torque", f"at most max_torque ({tmax:.6g} N m) in magnitude (a constant torque "
                             "beyond the limit would never be applied)", f"{torque:.6g} N m")  # fmt: skip
        out["max_torque_N_m"] = tmax
        out["torque_limit_width_N_m"] = _limit_width(table, path, "torque_limit_width", tmax, TORQUE, "N m")
    elif "torque_limit_width" in table:
        raise SceneError(f"{path}.torque_limit_width", "a max_torque for it to round", shown(table["torque_limit_width"]))
    if "max_speed" in table:
        vmax = _quantity(table["max_speed"], f"{path}.max_speed", SPEED, positive=True)
        gain = _quantity(_required(table, "speed_brake_gain", path, f"{VISCOUS.describe()} (the regulating brake's "
                                   "force per m/s beyond max_speed)"), f"{path}.speed_brake_gain", VISCOUS,
                         positive=True)  # fmt: skip
        out["max_speed_m_s"] = vmax
        out["speed_brake_gain_N_s_m"] = gain
        out["speed_limit_width_m_s"] = _limit_width(table, path, "speed_limit_width", vmax, SPEED, "m/s")
    else:
        for key in ("speed_brake_gain", "speed_limit_width"):
            if key in table:
                raise SceneError(f"{path}.{key}", "a max_speed for the regulating brake to hold", shown(table[key]))
    return out


def _table_law(table, path: str, length_m: float) -> tuple[tuple, tuple]:
    """times (from 0, increasing) and lengths (> 0, the first the tether's length) of a table law."""
    raw_t = _required(table, "times", path, "a list of times from 0, increasing (e.g. ['0 s', '600 s'])")
    raw_l = _required(table, "lengths", path, "a list of deployed lengths, one per time")
    if not isinstance(raw_t, (list, tuple)) or len(raw_t) < 2:
        raise SceneError(f"{path}.times", "a list of at least 2 times from 0, increasing", shown(raw_t))
    times = tuple(_quantity(x, f"{path}.times[{j}]", TIME) for j, x in enumerate(raw_t))
    if times[0] != 0.0 or any(not b > a for a, b in zip(times, times[1:])):
        raise SceneError(f"{path}.times", "times from 0, strictly increasing", shown(raw_t))
    if not isinstance(raw_l, (list, tuple)) or len(raw_l) != len(times):
        raise SceneError(f"{path}.lengths", f"a list of {len(times)} lengths, one per time", shown(raw_l))
    lengths = tuple(_quantity(x, f"{path}.lengths[{j}]", LENGTH, positive=True) for j, x in enumerate(raw_l))
    if abs(lengths[0] - length_m) > 1e-12 * length_m:
        raise SceneError(f"{path}.lengths", f"a first length equal to the tether's length ({length_m:.6g} m): the "
                         "deployed length at t = 0", f"{lengths[0]:.6g} m")  # fmt: skip
    return times, lengths


def table_spline(reel: Reel):
    """The natural cubic spline of a table law (C2: the rod's apparent load, which has L'', stays
    continuous); beyond the table the last interval's cubic continues."""
    from scipy.interpolate import CubicSpline

    return CubicSpline(reel.times_s, reel.lengths_m, bc_type="natural", extrapolate=True)


def length_at(reel: Reel, length0_m: float, t_s: float) -> float:
    """The deployed unstretched length L(t) of the law."""
    if reel.law == "constant":
        return length0_m + reel.speed_m_s * t_s
    if reel.law == "table":
        return float(table_spline(reel)(t_s))
    return length0_m * math.exp(reel.rate_1_s * t_s)


def speed_at(reel: Reel, length0_m: float, t_s: float) -> float:
    """dL/dt of the law."""
    if reel.law == "constant":
        return reel.speed_m_s
    if reel.law == "table":
        return float(table_spline(reel)(t_s, 1))
    return reel.rate_1_s * length0_m * math.exp(reel.rate_1_s * t_s)
