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
    from ..statics import NoTautEquilibrium, held_model, solve

    t = tethers[0]
    path = f"tethers.{t.name}.initial.shape"
    tip_r, _ = state_of(scene.body(t.to_body), scene.central_body.mu_m3_s2)
    r0 = y0[:3]
    orbital = any(e.name == "central_gravity" for e in scene.effects) and np.linalg.norm(r0) > 0
    down = -r0 / np.linalg.norm(r0) if orbital else np.array([0.0, 0.0, -1.0])  # for the first guess
    held = held_model(specs[0], effects, central, quadrature=nq, root_name=root.name)
    release = t.initial.release
    if release is not None:
        return _released(held, specs[0], r0, tip_r, release, f"tethers.{t.name}.initial.release")
    where = f"bodies.{t.to_body}.position"
    reach = float(np.linalg.norm(np.asarray(tip_r, float) - r0))
    if specs[0].model == "inextensible" and reach > specs[0].length_m:
        # rods that keep their length cannot span more than the tether's length
        raise SceneError(where, f"an end mass within the inextensible tether's length {specs[0].length_m:g} m of its root",
                         f"{reach:.9g} m from the root")  # fmt: skip
    try:
        # an inextensible tether's start restores its rods' lengths: a strut of the elastic
        # stand-in on the vertical at the tether's length becomes the straight, taut chain
        eq = solve(held, r0, tip_r, down=down, taut_only=specs[0].model != "inextensible")
    except NoTautEquilibrium as exc:
        # a tether does not push: where no taut equilibrium holds the end mass, its placement,
        # not the solver, is what the user can change
        raise SceneError(where, "an end mass placed where the tether hangs with every rod taut",
                         f"{reach:.9g} m from the root: {exc}") from None  # fmt: skip
    except ValueError as exc:
        if specs[0].tension_only:  # the placement, not the solver, is what the user can change
            raise SceneError(where, "an end mass placed where the tension-only tether hangs with every rod taut",
                             f"{reach:.9g} m from the root, where no static equilibrium was found ({exc}); "
                             "move the end mass off the vertical or closer to the root") from None  # fmt: skip
        raise SceneError(path, "a tether with a static equilibrium between its placed ends", str(exc)) from None
    if specs[0].tension_only and specs[0].rods > 1 and float(eq.strain.min()) <= 0.0:
        # the only equilibrium found has slack rods: a tether that cannot push does not hold that
        # shape (the line stretched by its own weight is longer than the span and has nowhere to
        # hang: a hold on, or too near, the vertical below the root at the tether's length)
        k = int(np.argmin(eq.strain))
        raise SceneError(where, "an end mass placed where the tension-only tether hangs with every rod taut",
                         f"{reach:.9g} m from the root: the equilibrium found has rod {k + 1} of {specs[0].rods} "
                         f"slack (strain {float(eq.strain[k]):.3g}); move the end mass off the vertical or closer to the root")  # fmt: skip
    return eq.y, eq.holding_force_N


def _released(held, spec, r0, tip_r, release, path):
    """(y0, R_f of the hang) of a tether released from its free hang (tetherlab/initial/release.py).

    The placed end mass gives only the vertical plane of the swing (the horizontal direction from
    the root to it; the scene's +x when it is placed on the vertical)."""
    from ..statics import _force_slot, _uniform_loads, hang_joints, solve
    from .release import consistent_lengths, released_state

    g_vec, tip_force = _uniform_loads(held.p, _force_slot(held)) or (None, None)
    if g_vec is None or not np.linalg.norm(g_vec) > 0.0:
        raise SceneError(path, "a tether hanging under uniform_gravity alone (and constant forces on its end mass)",
                         "other position-dependent effects in [effects]")  # fmt: skip
    tip_load = tip_force + spec.tip_mass_kg * g_vec
    joints = hang_joints(r0, held.rod_lengths(), held.rod_masses(), held.p, g_vec, tip_load)
    try:
        eq = solve(held, r0, joints[-1], guess_joints=joints)
    except ValueError as exc:
        raise SceneError(path, "a tether with a static hang under uniform gravity", str(exc)) from None
    down = g_vec / np.linalg.norm(g_vec)
    side = np.asarray(tip_r, float) - r0
    side = side - (side @ down) * down
    if not np.linalg.norm(side) > 1e-12 * spec.length_m:
        side = np.array([1.0, 0.0, 0.0]) - down[0] * down
    toward = side / np.linalg.norm(side)
    y = released_state(held, eq.y, release, g_vec, spec.tip_mass_kg, toward, path)
    y, _ = consistent_lengths(held, y, held.fresh_params(), _force_slot(held))
    return y, eq.holding_force_N
