"""A constant force on one point body (an actuator, a hand holding the end mass).

Used by :mod:`tetherlab.statics` for the external force R_f that holds the end mass of paper
section 4.2 at its required position; a scene may also name it.  The force is fixed in the scene
frame.  It is not flagged conservative: the energy diagnostics do not include its work.

| parameter | unit | required | meaning |
|-----------|------|----------|---------|
| body      |      | no (1)   | kernel index of the body: 0 = the root, 1 + k = the tip of tether k |
| fx, fy, fz| N    | no (0 N) | components of the force in the scene frame |
"""

from __future__ import annotations

from ..errors import SceneError
from .registry import EffectSpec, ParamSpec, register

CODE = 41


def _pack(params, central, ctx):
    bodies = ctx["bodies"]
    index = params["body"]
    if not (float(index).is_integer() and 0 <= index < len(bodies)):
        raise SceneError(
            "effects.applied_force.body",
            f"an integer body index from 0 to {len(bodies) - 1} (0 = root, 1 + k = tip of tether k: {bodies})",
            repr(index),
        )
    if int(index) == 0 and ctx["root_fixed"]:
        raise SceneError("effects.applied_force.body", "a moving body (the root is fixed)", "0")
    return [float(index), params["fx"], params["fy"], params["fz"]]


SPEC = register(
    EffectSpec(
        name="applied_force",
        code=CODE,
        doc="Constant force (scene frame) on one point body.",
        params={
            "body": ParamSpec("", required=False, default=1.0, doc="kernel body index (0 root, 1 + k tip k)"),
            "fx": ParamSpec("N", required=False, default=0.0, doc="x component"),
            "fy": ParamSpec("N", required=False, default=0.0, doc="y component"),
            "fz": ParamSpec("N", required=False, default=0.0, doc="z component"),
        },
        velocity_dependent=False,
        conservative=False,
        pack=_pack,
    )
)

#: offsets of the force components in the effect's parameter slot (after the body index)
PAR_BODY, PAR_F = 0, 1
