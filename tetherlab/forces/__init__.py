"""Physical effects; importing this package registers every effect module."""

from . import central_gravity  # noqa: F401  (registers)
from . import stiefel_moon  # noqa: F401  (registers)
from . import third_body, zonal  # noqa: F401  (gravity family: j2, zonal, moon_de421, sun_de421)
from .registry import EFFECTS, EffectSpec, ParamSpec, effect

__all__ = ["EFFECTS", "EffectSpec", "ParamSpec", "effect"]
