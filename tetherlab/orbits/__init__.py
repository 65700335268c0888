"""Two-body orbits: classical elements <-> Cartesian state (plain floats, SI)."""

from .kepler import KeplerElements, cartesian_to_elements, check_elements, elements_to_cartesian, period

__all__ = ["KeplerElements", "cartesian_to_elements", "check_elements", "elements_to_cartesian", "period"]
