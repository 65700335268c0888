"""Parameter-only samples: one prepared model per worker, the sample's values re-packed into a copy
of its parameter block.

A sample that changes only parameters that enter the parameter block and nothing else -- the
parameters of a non-conservative effect (``effects.electrodynamic.current``,
``effects.drag.cd.satellite``, ...) -- does not need its scene re-serialised, re-parsed and
re-prepared: the model's layout, the initial state (the relative equilibrium is solved under the
conservative effects alone, ``pipeline.prepare``), the tolerances and the output times are those
of its base scene.  :class:`ParameterSample` carries the base scene and the sample's values;
:func:`prepared` builds the base's :class:`~tetherlab.pipeline.Prepared` once per worker process
and, for each sample, copies the parameter block and re-packs the changed effects through their
own ``pack`` functions into their slices (:class:`~tetherlab.model.params.ParamView`), exactly
as ``system.build_model`` packs them.

Bit for bit equal to the full path (``base.replace(**values)`` then ``prepare``), checked, not
assumed: the first sample of a base in each worker is also prepared the full way, and if any
field of the prepared scene or any bit of the parameter block differs, that worker uses the full
path for every sample of that base (a key this module wrongly took for parameter-only can cost
time, never a wrong number).  What falls back to the full path from the start
(:func:`reuse_refusal` says why): any key outside the non-conservative effects' quantity
parameters (masses, EA, the orbit, rod counts, effects' choices), a scene whose initial state is
solved under every effect (``orbit.motion = "quasi-static"``, ``shape = "equilibrium"``), and a
summary function that does not take samples (``accepts_parameter_samples``).

A sample's cache identity (tetherlab/sweep.py) is the hash of its :meth:`ParameterSample.to_dict`:
the base scene's hash and the values; it differs from the identity of the same sample run the
full way (a study keeps one path for all its samples, so extending it reuses its cache).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

#: prepared bases of this process: (base hash, changes) -> [Prepared, checked: bool | None, ctx]
_CACHE: dict[tuple, list] = {}
_CACHE_SIZE = 4


@dataclass(frozen=True)
class ParameterSample:
    """A sample = its base scene (after the study's [set]) with some parameter-only keys changed."""

    base: Any  # tetherlab.scene.Scene
    base_hash: str
    values: tuple[tuple[str, Any], ...]  # (dotted key, scene-file value), in the study's key order
    name: str = "sample"

    def to_dict(self) -> dict:
        """The sample's identity for the sweep cache (the base by its hash, then the values)."""
        return {"base_scene_sha256": self.base_hash, "parameters": dict(self.values)}

    def scene(self):
        """The full scene (the fallback path): the base with the values written in."""
        return self.base.replace(**dict(self.values))


def reuse_refusal(base, keys) -> str | None:
    """Why samples of these keys on this base must take the full path (None: they need not)."""
    from ..forces import EFFECTS

    orbit = getattr(base, "orbit", None)
    if orbit is not None and orbit.motion == "quasi-static":
        return "orbit.motion = 'quasi-static' solves the initial state under every effect"
    if any(t.initial is not None and t.initial.shape == "equilibrium" for t in base.tethers):
        return "a tether starting in shape = 'equilibrium' is solved under every effect"
    used = {e.name: e for e in base.effects}
    for key in keys:
        parts = key.split(".")
        if len(parts) not in (3, 4) or parts[0] != "effects" or parts[1] not in used:
            return f"{key!r} is not a parameter of one of the scene's effects"
        spec = EFFECTS[parts[1]]
        if spec.conservative:
            return f"{key!r}: the {parts[1]} effect is conservative (the relative equilibrium depends on it)"
        pspec = spec.params.get(parts[2])
        if pspec is None or pspec.choices is not None:
            return f"{key!r} is not a quantity parameter of the {parts[1]} effect"
        if (len(parts) == 4) != bool(pspec.per_body):
            return f"{key!r}: a per-body parameter is dispersed per body, a shared one as a whole"
    return None


def _effect_values(base_use, spec, changes: list[tuple[list[str], Any]]) -> dict:
    """The effect's SI parameters with the sample's values, parsed as the scene parses them."""
    from ..scene.keys import _bounded
    from ..units import kind_for_unit, to_si

    params = dict(base_use.params_si)
    for parts, value in changes:
        pspec = spec.params[parts[2]]
        kind = kind_for_unit(pspec.unit)
        key = ".".join(parts)
        si = _bounded(to_si(value, kind, key=key), key, kind, value)
        if len(parts) == 4:
            per = dict(params[parts[2]])
            if parts[3] not in per:
                from ..errors import SceneError

                raise SceneError(key, f"a body of the scene (one of {sorted(per)})", repr(parts[3]))
            per[parts[3]] = si
            params[parts[2]] = per
        else:
            params[parts[2]] = si
    return params


def repack(prep, scene, values, p: np.ndarray) -> None:
    """Write the sample's effect parameters into ``p`` (a copy of ``prep``'s block): each changed
    effect packed by its own ``pack`` with the context ``build_model`` gave it."""
    from ..forces import EFFECTS
    from ..model.params import ParamView
    from ..pipeline import _duration_hint

    by_effect: dict[str, list] = {}
    for key, value in values:
        parts = key.split(".")
        by_effect.setdefault(parts[1], []).append((parts, value))
    model = prep.model
    central = {"mu_m3_s2": scene.central_body.mu_m3_s2, "radius_m": scene.central_body.radius_m}
    ctx = {"bodies": [b.name for b in model.bodies], "tethers": list(model.tethers),
           "root_fixed": model.root_fixed, "epoch": scene.epoch, "duration_s": _duration_hint(scene), "meta": {}}
    view = ParamView(p)
    for e, use in enumerate(scene.effects):
        if use.name not in by_effect:
            continue
        spec = EFFECTS[use.name]
        vals = list(spec.pack(_effect_values(use, spec, by_effect[use.name]), central, ctx))
        block = view.effect_params(e)
        if len(vals) != block.size:  # a pack whose length depends on a value: not parameter-only
            raise ValueError(f"effect {use.name!r}: {len(vals)} packed parameters against {block.size} in the block")
        block[:] = vals


def _same_prepared(a, b) -> bool:
    """Every field of two Prepared equal bit for bit (the model by its block and layout sizes)."""
    if not np.array_equal(a.model.p, b.model.p):  # NaN-free blocks: equal means bit for bit here
        return False
    for f in dataclasses.fields(a):
        if f.name == "model":
            continue
        x, y = getattr(a, f.name), getattr(b, f.name)
        if isinstance(x, np.ndarray) or isinstance(y, np.ndarray):
            if x is None or y is None or not (np.shape(x) == np.shape(y) and np.array_equal(x, y)):
                return False
        elif x != y:
            return False
    return True


def prepared(item, changes: dict | None = None, *, repack_values: bool = True):
    """(Prepared, a fresh parameter block) of a scene or a :class:`ParameterSample`, with the
    summary's own ``changes`` (e.g. duration and stop altitude) applied.

    ``repack_values=False`` is a negative control only: the base's block without the sample's
    values (the defect "parameters never reach the kernel")."""
    from ..pipeline import prepare

    changes = dict(changes or {})
    if not isinstance(item, ParameterSample):
        prep = prepare(item.replace(**changes) if changes else item)
        return prep, prep.model.fresh_params()
    key = (item.base_hash, tuple(sorted((k, repr(v)) for k, v in changes.items())))
    entry = _CACHE.get(key)
    if entry is None:
        base = item.base.replace(**changes) if changes else item.base
        entry = [prepare(base), None, base]
        while len(_CACHE) >= _CACHE_SIZE:
            _CACHE.pop(next(iter(_CACHE)))
        _CACHE[key] = entry
    prep, checked, base = entry
    if checked is False:
        full = prepare(item.scene().replace(**changes) if changes else item.scene())
        return full, full.model.fresh_params()
    p = prep.model.fresh_params()
    if repack_values:
        repack(prep, base, item.values, p)
    if checked is None and repack_values:
        full_scene = item.scene()
        full = prepare(full_scene.replace(**changes) if changes else full_scene)
        entry[1] = _same_prepared(dataclasses.replace(prep, model=dataclasses.replace(prep.model, p=p)), full)
        if not entry[1]:
            return full, full.model.fresh_params()
    return prep, p


def reuse_state() -> dict:
    """What this process holds: base hash -> whether its first sample matched the full path."""
    return {k[0]: v[1] for k, v in _CACHE.items()}
