"""Central-body point-mass gravity, a = -mu r / |r|^3.

Reference: Newton; the potential is U = -mu/|r| per unit mass.

| parameter | unit | required | meaning |
|-----------|------|----------|---------|
| (none)    |      |          | mu comes from the scene's ``[central_body]`` |
"""

from __future__ import annotations

from .registry import EffectSpec, register

CODE = 1

SPEC = register(
    EffectSpec(
        name="central_gravity",
        code=CODE,
        doc="Point-mass gravity of the central body (mu from [central_body]).",
        params={},
        velocity_dependent=False,
        conservative=True,
        pack=lambda params, central, ctx: [central["mu_m3_s2"]],
    )
)

# -- compiled kernels (SI floats only) -----------------------------------------------------------
from .._jit import njit  # noqa: E402  (kernels below the declaration, as in every effect module)


@njit(cache=True)
def accel(mu, x, y, z):
    """Acceleration -mu r/|r|^3 (m/s^2)."""
    r2 = x * x + y * y + z * z
    k = -mu / (r2 * (r2**0.5))
    return k * x, k * y, k * z


@njit(cache=True)
def potential(mu, x, y, z):
    """Potential per unit mass -mu/|r| (J/kg); its gradient is minus :func:`accel`."""
    return -mu / (x * x + y * y + z * z) ** 0.5
