"""The initial state of a star of point masses written from its root (``Graph.simple``).

Rods along each tether's initial shape in the reference orbit's LVLH frame (docs/scenes.md,
"Initial layout"), or straight between explicit ends; the original layout code of a single
tether, kept for stars because its round-off is what every star scene was recorded with.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import SceneError
from ..orbits.kepler import elements_to_cartesian
from ..system import Model, center_of_mass, chain_state
from .equilibrium import quasi_static, relative_equilibrium
from .spin import with_spin


def state_of(entity, mu: float):
    """(r, v) of a body or orbit block with position/velocity or elements, else None."""
    if getattr(entity, "elements", None) is not None:
        el = entity.elements
        r, v = elements_to_cartesian(mu, el.a_m, el.e, el.i_rad, el.raan_rad, el.argp_rad, el.nu_rad)
        return np.asarray(r, float), np.asarray(v, float)
    if getattr(entity, "position_m", None) is not None:
        v = entity.velocity_m_s if entity.velocity_m_s is not None else (0.0, 0.0, 0.0)
        return np.asarray(entity.position_m, float), np.asarray(v, float)
    return None



def star_state(scene, graph, model: Model, mu: float, eq_model: Model | None = None):
    """(y0, r_ref, v_ref, sides) of a star of point masses around kernel body 0 (``graph.simple``).

    Straight between explicit ends when the root and every tip carry states; otherwise every
    tether laid from its shape with the root at the origin, then the reference point moved onto
    its orbit, and for orbit.motion 'equilibrium'/'quasi-static' the rods solved for a rigid
    rotation (tetherlab/initial/equilibrium.py).  The scene checks at load guarantee an [orbit]
    or a root state (tetherlab/scene/checks.py, _check_layout).
    """
    from ..diagnostics import direction_from_angles

    root_name = graph.roots[0]
    tethers = list(scene.tethers)

    root = scene.body(root_name)
    root_state = state_of(root, mu)
    orbit = scene.orbit
    sides = []
    # 1. every tether whose both ends carry explicit states: a straight line between them
    explicit_tips = [state_of(scene.body(t.to_body), mu) for t in tethers]
    if tethers and root_state is not None and all(s is not None for s in explicit_tips):
        r0, v0 = root_state
        dirs, strains = [], []
        rod_vel = []
        for t, (rt, vt) in zip(tethers, explicit_tips):
            span = rt - r0
            dist = float(np.linalg.norm(span))
            dirs.append(np.tile(span / dist, (t.rods, 1)))
            strains.append(dist / t.length_m - 1.0)
            rod_vel.append((vt - v0) / (2 * math.sqrt(3) * t.rods))
            sides.append(1.0)
        y0 = chain_state(model, r0, v0, dirs, strains, None)
        lay = model.state
        for k, sl in enumerate(model.rod_slices):
            for g in range(sl.start, sl.stop):
                y0[lay.rod_rate(g)] = rod_vel[k]
        return y0, r0, v0, sides

    # 2. the reference point's orbit: [orbit] block, or the root's own state
    if orbit is not None:
        ref = state_of(orbit, mu)
        reference = orbit.reference
        motion = orbit.motion
    else:  # without an [orbit] every body carries its state (checked at load)
        ref = root_state
        reference = root_name
        motion = "corotating"
    r_ref, v_ref = ref
    # (a reference point at the centre has no orbit to corotate with: no rotation)
    rr2 = float(r_ref @ r_ref)
    omega = np.cross(r_ref, v_ref) / rr2 if motion in ("corotating", "equilibrium", "quasi-static") and rr2 > 0 else None
    omega = with_spin(omega, orbit, r_ref, v_ref)
    dirs, strains = [], []
    for t in tethers:
        ini = t.initial
        if ini is None:  # both ends placed, the far one by the [orbit]: not laid by this path
            raise SceneError(
                f"tethers.{t.name}.initial", "an initial shape (only one end has an explicit state)", "none"
            )
        side = 1.0 if ini.side == "up" else -1.0
        sides.append(side)
        thetas, phis = ini.rod_angles_rad(t.rods)
        dirs.append(np.array([direction_from_angles(r_ref, v_ref, th, ph, side) for th, ph in zip(thetas, phis)]))
        strains.append(ini.strain)
    # lay out with the root at the origin, then move the reference point onto its orbit
    y0 = chain_state(model, np.zeros(3), np.zeros(3), dirs, strains, omega)
    if reference == "center_of_mass":
        c, _ = center_of_mass(model, y0)
    elif reference == root_name:
        c = np.zeros(3)
    else:
        k = [t.to_body for t in tethers].index(reference)
        from ..system import point_positions

        c = point_positions(model, y0)["joints"][k][-1]
    r0 = r_ref - c
    v0 = v_ref + (np.cross(omega, r0 - r_ref) if omega is not None else 0.0)
    lay = model.state
    y0[lay.root_r] = r0
    y0[lay.root_v] = v0
    if motion in ("equilibrium", "quasi-static"):
        y0 = relative_equilibrium(eq_model or model, y0, r_ref, v_ref, omega, reference, root_name, tethers)
    if motion == "quasi-static":
        y0 = quasi_static(model, y0, r_ref, reference, root_name, tethers)
    return y0, r_ref, v_ref, sides
