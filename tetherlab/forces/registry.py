"""The effect registry: every physical effect a scene may name, with its declared parameters.

Modelled on REBOUNDx (``load_force``/``add_force``) and heyoka's "enabled if the argument is
provided": a scene lists the effects it wants under ``[effects]``; an effect that is not listed is
never evaluated by the kernel (its code is not even reached: the kernel loops over the codes of
the listed effects only).

Each effect module (``tetherlab/forces/<effect>.py``) declares one :class:`EffectSpec` and registers
it with :func:`register`.  The spec says:

* ``params``: name -> :class:`ParamSpec` (unit string parsed by astropy, required or default);
* ``velocity_dependent``: whether the force depends on velocity (drag does, gravity does not);
* ``conservative``: whether the force derives from a potential; then the effect also provides a
  potential kernel, which the energy diagnostics and the invariant tests use;
* ``code``: the integer the compiled kernel dispatches on.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable


@dataclass(frozen=True)
class ParamSpec:
    """One parameter of an effect.

    Three shapes, all validated when the scene is loaded:

    * a quantity (the default): ``unit`` is the astropy unit of the SI float handed on;
    * ``choices``: a string among ``choices`` (``unit`` is ignored), kept as the string;
    * ``per_body``: a quantity per body, written either as one quantity for every body or as a
      table ``{body_name = quantity}`` naming every body of the scene; kept as a dict
      ``{body_name: SI float}`` (one value given for all is expanded once the bodies are known).
    """

    unit: str  # astropy unit string of the SI value handed to the kernel ("" = dimensionless)
    required: bool = True
    default: str | float | None = None
    doc: str = ""
    choices: tuple[str, ...] | None = None
    per_body: bool = False
    # choices whose model is dated: the scene must give an epoch (checked at load, scene/checks.py)
    dated: tuple[str, ...] = ()


@dataclass(frozen=True)
class EffectSpec:
    name: str
    code: int
    doc: str
    params: dict[str, ParamSpec] = field(default_factory=dict)
    velocity_dependent: bool = False
    conservative: bool = False
    # the effect's model is dated (an ephemeris): the scene must give an epoch (checked at load)
    dated: bool = False
    # Packs the validated SI parameters (and the scene's central body) into the float block the
    # kernel reads.  Signature: pack(params_si, central, ctx) -> list[float], with
    # central = {"mu_m3_s2", "radius_m"} and ctx = {"bodies": names in kernel body order (0 = root,
    # 1 + k = tip of tether k), "tethers": [TetherSpec], "root_fixed": bool}.
    pack: Callable[[dict, dict, dict], list] | None = None


EFFECTS: dict[str, EffectSpec] = {}


def register(spec: EffectSpec) -> EffectSpec:
    if spec.name in EFFECTS:
        raise ValueError(f"effect {spec.name!r} registered twice")
    if any(s.code == spec.code for s in EFFECTS.values()):
        raise ValueError(f"effect code {spec.code} of {spec.name!r} is already used")
    EFFECTS[spec.name] = spec
    return spec


def effect(name: str) -> EffectSpec:
    try:
        return EFFECTS[name]
    except KeyError:
        import difflib

        close = difflib.get_close_matches(name, EFFECTS, n=1)
        hint = f" Did you mean {close[0]!r}?" if close else ""
        raise KeyError(
            f"unknown effect {name!r}; known effects: {sorted(EFFECTS)}.{hint}"
        ) from None
