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
        pack=lambda params, central: [central["mu_m3_s2"]],
    )
)
