"""Physical effects; importing this package registers every effect module."""

from . import central_gravity  # noqa: F401  (registers)
# -- electromagnetic environment (codes 20-29) --
from . import drag, electrodynamic  # noqa: F401  (registers)
from .registry import EFFECTS, EffectSpec, ParamSpec, effect

__all__ = ["EFFECTS", "EffectSpec", "ParamSpec", "effect"]
