"""The start of shape 'equilibrium': one tether in static equilibrium between a fixed root and
its placed end mass (tetherlab/statics.py)."""

from __future__ import annotations

import numpy as np

from ..errors import SceneError
from .star import state_of


def static_start(scene, root, tethers, specs, effects, central, nq, y0):
    """Initial state of a tether that starts in static equilibrium between its placed ends.

    The root is fixed, the tether the only one and the end mass placed at rest (checked at load:
    tetherlab/scene/checks.py); tetherlab.statics solves for the rods and for the holding force R_f
    (docs/catenary.md).  Returns (y0, R_f).  A solve that fails is refused here: only solving
    tells.
    """
    from ..statics import held_model, solve

    t = tethers[0]
    path = f"tethers.{t.name}.initial.shape"
    tip_r, _ = state_of(scene.body(t.to_body), scene.central_body.mu_m3_s2)
    r0 = y0[:3]
    orbital = any(e.name == "central_gravity" for e in scene.effects) and np.linalg.norm(r0) > 0
    down = -r0 / np.linalg.norm(r0) if orbital else np.array([0.0, 0.0, -1.0])  # for the first guess
    held = held_model(specs[0], effects, central, quadrature=nq, root_name=root.name)
    try:
        eq = solve(held, r0, tip_r, down=down)
    except ValueError as exc:
        raise SceneError(path, "a tether with a static equilibrium between its placed ends", str(exc)) from None
    return eq.y, eq.holding_force_N
