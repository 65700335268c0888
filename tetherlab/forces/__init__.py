"""Physical effects; importing this package registers every effect module."""

from . import applied_force, central_gravity, uniform_gravity  # noqa: F401  (registers)
from . import stiefel_moon  # noqa: F401  (registers)
from . import third_body, zonal  # noqa: F401  (gravity family: j2, zonal, moon_de421, sun_de421)
# -- electromagnetic environment (codes 20-29) --
from . import drag, electrodynamic  # noqa: F401  (registers)
from . import oml  # noqa: F401  (registers; OML bare-tether current)
from .registry import EFFECTS, EffectSpec, ParamSpec, effect

__all__ = ["EFFECTS", "EffectSpec", "ParamSpec", "effect"]
