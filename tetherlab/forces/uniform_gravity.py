"""Uniform surface gravity, a = -g z_hat in the scene frame (a "flat Earth" laboratory frame).

For experiments at the Earth's surface (the catenary of paper section 4.2): the scene frame is a
local frame with z up, and every mass element feels the same acceleration g downwards.  It is
conservative with potential U = g z per unit mass (gradient g z_hat = minus the acceleration).

| parameter | unit   | required | meaning |
|-----------|--------|----------|---------|
| g         | m / s2 | no (9.80665 m/s2) | magnitude of the acceleration, along -z |

Default: standard gravity g_n = 9.80665 m/s^2 (3rd CGPM 1901; BIPM SI Brochure, 9th ed., 2019).
"""

from __future__ import annotations

from .registry import EffectSpec, ParamSpec, register

CODE = 40
STANDARD_GRAVITY_M_S2 = 9.80665  # 3rd CGPM (1901), exact by definition


def _pack(params, central, ctx):
    return [params["g"]]


SPEC = register(
    EffectSpec(
        name="uniform_gravity",
        code=CODE,
        doc="Uniform gravity g along -z of the scene frame (surface experiments).",
        params={
            "g": ParamSpec("m / s2", required=False, default=STANDARD_GRAVITY_M_S2,
                           doc="acceleration of gravity along -z (standard gravity by default)"),
        },
        velocity_dependent=False,
        conservative=True,
        pack=_pack,
    )
)

# -- compiled kernels (SI floats only) -----------------------------------------------------------
from .._jit import njit  # noqa: E402


@njit(cache=True)
def accel(g, x, y, z):
    """Acceleration (0, 0, -g) (m/s^2), the same everywhere."""
    return 0.0, 0.0, -g


@njit(cache=True)
def potential(g, x, y, z):
    """Potential per unit mass g z (J/kg); its gradient is minus :func:`accel`."""
    return g * z
