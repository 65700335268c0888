"""Reading helpers: every one reads one value and names the dotted key it reads in its SceneError
(what was expected, what was got, a close spelling when there is one)."""

from __future__ import annotations

import difflib
import math
import numbers
from collections.abc import Mapping
from typing import Any

import astropy.units as u

from ..errors import SceneError
from ..units import Kind, is_number, shown, to_si
from .data import Vector3


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
