"""Physical effects; importing this package registers every effect module."""

from . import central_gravity  # noqa: F401  (registers)
from . import stiefel_moon  # noqa: F401  (registers)
from .registry import EFFECTS, EffectSpec, ParamSpec, effect

__all__ = ["EFFECTS", "EffectSpec", "ParamSpec", "effect"]
