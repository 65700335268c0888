"""Has a run left the regime its user assumed?  Warnings for the run summary, each with its time.

A run can be correct to round-off and still not be the run its author meant. Checked after every
run (``tetherlab.simulate`` puts them in ``result.stats["warnings"]``, ``tetherlab run`` in run.json
and on the terminal):

* **compression**: a rod of a tether without ``tension_only`` shortened below its natural length
  (strain < ``COMPRESSION_STRAIN``): the TMED rod is a bar, it pushes as it pulls, which a real
  tether cannot (docs/scenes.md, ``tension_only``);
* **tumbling**: a tether's libration angle θ or φ passed ±90 degrees: the libration became a
  rotation (a tumbling tether, or a spinning system whose spin is meant).  Only about a central
  body: free space has no orbital frame, its angle columns are NaN (docs/model.md 7), and a
  scene whose effects have no central gravity is not checked at all, so a run directory written
  before those columns were NaN does not warn either;
* **slow-down**: the simulated time advanced ``SLOWDOWN_FACTOR`` times slower per wall-clock second
  than at the start of the run (stiffness: a rod gone slack or nearly so, a collapse on the way);
* **light rod**: a tether so much lighter than the lighter of its end bodies that the round-off
  floor of the solution, about EPS * M / m, lies above the requested ``rtol``: the integrator
  then chases noise (steps and rejections pile up) and the results drift with the tolerance
  (docs/scenes.md, "A very light tether").

Each warning is ``{"kind", "t_s", "text"}``, ``t_s`` the first time it happened (None when it is
a property of the scene).
"""

from __future__ import annotations

import math

import numpy as np

#: strain below which a rod counts as compressed: far above round-off (1e-16 relative) and far
#: below any strain a loaded tether has (1e-6 to 1e-2)
COMPRESSION_STRAIN = -1e-9
#: loss of simulated time per wall-clock second, from the run's first tenth to any later chunk
SLOWDOWN_FACTOR = 100.0
#: double-precision round-off: a tether of mass m joining bodies of mass M >> m carries a relative
#: error floor of about EPS * M / m (measured: docs/scenes.md, "A very light tether")
EPS = float(np.finfo(float).eps)


def format_time(t_s: float) -> str:
    """A run time the way a user reads it: seconds, hours or days."""
    if abs(t_s) >= 2 * 86400.0:
        return f"{t_s / 86400.0:.4g} d"
    if abs(t_s) >= 2 * 3600.0:
        return f"{t_s / 3600.0:.4g} h"
    return f"{t_s:.6g} s"


def _fmt_t(t_s: float) -> str:
    return f"t = {format_time(t_s)}"


def _tethers(scene_dict: dict) -> dict:
    t = scene_dict.get("tethers") or {}
    return t if isinstance(t, dict) else {}


def _compression_facts(ts, scene_dict: dict) -> dict:
    """{tether: (first time, compressed outputs, outputs, largest push N)} of a table of outputs."""
    out = {}
    if ts is None or "t_s" not in getattr(ts, "columns", ()):
        return out
    t = np.asarray(ts["t_s"], float)
    for name, spec in _tethers(scene_dict).items():
        if isinstance(spec, dict) and spec.get("tension_only"):
            continue
        cols = [c for c in ts.columns if c.startswith(f"{name}.rod") and c.endswith(".strain")]
        if not cols:
            continue
        strain = np.asarray(ts[cols], float)
        with np.errstate(invalid="ignore"):  # NaN rows of a failed run count as not compressed
            bad = np.any(strain < COMPRESSION_STRAIN, axis=1)
        fcols = [c.replace(".strain", ".axial_force_N") for c in cols if c.replace(".strain", ".axial_force_N") in ts.columns]
        forces = np.asarray(ts[fcols], float) if fcols else np.full((1, 1), np.nan)
        push = float(-np.min(np.where(np.isfinite(forces), forces, np.inf))) if bad.any() else -math.inf
        first = float(t[int(np.argmax(bad))]) if bad.any() else math.inf
        out[name] = (first, int(bad.sum()), int(bad.size), push)
    return out


def _tumbling_facts(dg) -> dict:
    """{tether: first time its libration angle passed 90 deg (inf: never)} of a table of outputs."""
    out = {}
    if dg is None or "t_s" not in getattr(dg, "columns", ()):
        return out
    t = np.asarray(dg["t_s"], float)
    for col in [c for c in dg.columns if c.endswith(".theta_rad")]:
        name = col[: -len(".theta_rad")]
        th = np.abs(np.asarray(dg[col], float))
        ph = np.abs(np.asarray(dg[f"{name}.phi_rad"], float)) if f"{name}.phi_rad" in dg.columns else np.zeros_like(th)
        with np.errstate(invalid="ignore"):
            over = (th > 0.5 * math.pi) | (ph >= 0.5 * math.pi)
        out[name] = float(t[int(np.argmax(over))]) if over.any() else math.inf
    return out


def _has_orbital_frame(scene_dict: dict) -> bool:
    """A scene about a central body (the test of diagnostics.has_orbital_frame, read from the
    scene's effects); a table of outputs handed without a scene's effects is taken as one."""
    effects = scene_dict.get("effects") if isinstance(scene_dict, dict) else None
    return effects is None or "central_gravity" in effects


def _merge(a: dict, b: dict) -> dict:
    """Facts of two consecutive tables of outputs as the facts of both."""
    out = dict(a)
    for k, v in b.items():
        if k not in out:
            out[k] = v
        elif isinstance(v, tuple):
            f0, n0, m0, p0 = out[k]
            f1, n1, m1, p1 = v
            out[k] = (min(f0, f1), n0 + n1, m0 + m1, max(p0, p1))
        else:
            out[k] = min(out[k], v)
    return out


def _compression_warnings(facts: dict) -> list[dict]:
    return [{
        "kind": "compression",
        "t_s": first,
        "text": f"tether {name!r} is in compression from {_fmt_t(first)} (at {n} of {m} outputs, largest push "
                f"{push:.3g} N): rods push unless the tether has tension_only = true",
    } for name, (first, n, m, push) in facts.items() if n > 0]  # fmt: skip


def _tumbling_warnings(facts: dict) -> list[dict]:
    return [{
        "kind": "tumbling",
        "t_s": first,
        "text": f"tether {name!r} passed a libration angle of 90 deg at {_fmt_t(first)}: it is tumbling "
                f"(rotating, not librating) from there on",
    } for name, first in facts.items() if math.isfinite(first)]  # fmt: skip


def compression(ts, scene_dict: dict) -> list[dict]:
    """Tethers (not tension-only) with a rod compressed, the first time and the strongest push."""
    return _compression_warnings(_compression_facts(ts, scene_dict))


def tumbling(dg) -> list[dict]:
    """Tethers whose libration angle θ or φ passed ±90 degrees, the first time."""
    return _tumbling_warnings(_tumbling_facts(dg))


def slowdown(progress: list[tuple[float, float]]) -> list[dict]:
    """A run whose simulated seconds per wall-clock second fell by SLOWDOWN_FACTOR or more.

    ``progress``: (wall-clock s, simulated s) after each chunk of accepted steps (the progress
    callback's calls); the reference rate is that of the first tenth of the chunks (at least 2)."""
    if len(progress) < 12:
        return []
    w = np.array([p[0] for p in progress], float)
    t = np.array([p[1] for p in progress], float)
    dw, dt = np.diff(w), np.diff(t)
    ok = dw > 0
    if ok.sum() < 11:
        return []
    rate = np.where(ok, dt / np.where(ok, dw, 1.0), np.nan)
    k0 = max(2, len(rate) // 10)
    ref = np.nanmedian(rate[:k0])
    if not ref > 0:
        return []
    slow = rate[k0:] < ref / SLOWDOWN_FACTOR
    if not slow.any():
        return []
    first = k0 + int(np.argmax(slow))
    worst = float(ref / max(np.nanmin(rate[k0:]), 1e-300))
    return [{
        "kind": "slow-down",
        "t_s": float(t[first]),
        "text": f"the run slowed down {worst:.3g} times from {_fmt_t(t[first])} (simulated time per wall-clock "
                f"second, against its start): the system turned stiff (a slack or collapsing rod, a fast mode)",
    }]  # fmt: skip


def light_rods(scene) -> list[dict]:
    """Tethers whose mass ratio puts the round-off floor EPS * M / m above the scene's rtol."""
    out = []
    rtol = float(getattr(getattr(scene, "integrator", None), "rtol", 1e-10))
    for t in getattr(scene, "tethers", ()):
        ends = [scene.body(t.from_body).mass_kg, scene.body(t.to_body).mass_kg]
        ends = [m for m in ends if m > 0]
        if not ends or not t.mass_kg > 0:
            continue
        ratio = t.mass_kg / min(ends)
        floor = EPS / ratio
        if floor > rtol:
            out.append({
                "kind": "light rod",
                "t_s": None,
                "text": f"tether {t.name!r} weighs {ratio:.3g} times its lighter end body: the round-off floor of the "
                        f"run, about {floor:.2g} relative, is above its rtol {rtol:g}, so steps are rejected chasing "
                        f"noise and results drift with the tolerance; a tether at least {EPS / rtol:.2g} times its "
                        f"end mass keeps the floor below rtol (docs/scenes.md, 'A very light tether')",
            })  # fmt: skip
    return out


def check(scene, ts, dg, progress=()) -> list[dict]:
    """Every warning of a run, in order of time (scene properties first)."""
    return check_parts(scene, [(ts, dg)], progress)


def check_parts(scene, parts, progress=()) -> list[dict]:
    """The same from the run's outputs in consecutive parts ((time series, diagnostics) pairs),
    read one at a time: a long run's columns never have to be in memory together."""
    scene_dict = scene.to_dict() if hasattr(scene, "to_dict") else (scene or {})
    comp: dict = {}
    tumb: dict = {}
    for ts, dg in parts:
        comp = _merge(comp, _compression_facts(ts, scene_dict))
        tumb = _merge(tumb, _tumbling_facts(dg))
    found = (light_rods(scene) if hasattr(scene, "tethers") else []) + _compression_warnings(comp)
    turning = _tumbling_warnings(tumb) if _has_orbital_frame(scene_dict) else []
    if getattr(getattr(scene, "orbit", None), "spin", None) is not None:
        for w in turning:  # a spinning system is meant to turn: say so rather than alarm
            w["text"] += " (as the scene's [orbit] spin sets it going)"
    found += turning + slowdown(list(progress))
    return sorted(found, key=lambda w: -math.inf if w["t_s"] is None else w["t_s"])
