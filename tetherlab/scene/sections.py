"""The scene's sections other than bodies, tethers and orbit: epoch, central body, effects, duration,
stop conditions, integrator, outputs."""

from __future__ import annotations

import datetime
import math
import re
from collections.abc import Mapping
from typing import Any

import astropy.units as u

from ..errors import SceneError
from ..forces import EFFECTS
from ..units import GRAVITATIONAL_PARAMETER, LENGTH, TIME, is_number, kind_for_unit, shown, to_si
from .data import (
    CENTRAL_BODY_PRESETS,
    ERROR_SCALES,
    FORMULATIONS,
    INTEGRATOR_METHODS,
    TIME_ELEMENTS,
    Body,
    CentralBody,
    EffectUse,
    IntegratorSpec,
    OutputSpec,
    Stop,
)
from .keys import (
    _NOTHING,
    _bounded,
    _choice,
    _integer,
    _join,
    _number,
    _quantity,
    _quoted,
    _string,
    _suggest,
    _table,
)


_ORBITS_RE = re.compile(r"^\s*([+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)\s*orbits?\s*$")


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
    table = _table(value, path, ("method", "rtol", "atol", "max_step", "max_steps", "formulation", "time_element",
                                   "error_scale"))
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
    error_scale = _choice(table.get("error_scale", "rod"), f"{path}.error_scale", ERROR_SCALES)
    return IntegratorSpec(method, rtol, atol, max_step, max_steps, formulation, time_element, error_scale)


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
