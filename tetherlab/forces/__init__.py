"""Physical effects; importing this package registers every effect module."""

from . import applied_force, central_gravity, uniform_gravity  # noqa: F401  (registers)
from .registry import EFFECTS, EffectSpec, ParamSpec, effect

__all__ = ["EFFECTS", "EffectSpec", "ParamSpec", "effect"]
