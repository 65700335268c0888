"""Initial state of a forest of bodies and tethers: any tree, tethers written in either direction,
rigid bodies with attachment points, bodies without tethers (the scene's graph says which body is
each tether's parent, the roots and components).

The rules (docs/scenes.md, "Initial layout" and "Body order in the kernel"):

* each tether's rods point from its `from` end to its `to` end along its initial shape (theta, phi,
  side, strain in the orbit reference's LVLH frame), starting at the attachment point; a tether
  whose both ends carry explicit states (`Tether.initial is None`) runs straight between the two
  attachment points;
* each component is anchored by the orbit reference (a body or the centre of mass) if it holds
  it, else by its first body with an explicit state;
* velocities: `motion = "corotating"` gives every point v_a + w_o x (r - r_a) (w_o = r x v / r^2 of
  the reference orbit), `"translating"` v_a; on top of that the points beyond a rigid body turn
  with its own rotation relative to that motion, (w_body - w_o) x (r - r_G) (a spinning hub carries
  its spokes along);
* a rigid body's attitude "orbit" and its rates relative to the orbit frame use its own centre of
  mass's (r, v); the layout is repeated three times so that the frames follow the laid-out
  positions (each pass reduces the change by the ratio of the system's size to the orbit radius).
"""

from __future__ import annotations

import numpy as np

from ..errors import SceneError
from ..system import SQ3, Model, attitude_block, center_of_mass
from .spin import with_spin

_PASSES = 3


def _orbit_frame(r, v):
    """Columns o1, o2, o3 (docs/scenes.md) and its rate r x v / r^2; None when r x v = 0."""
    h = np.cross(r, v)
    hn = float(np.linalg.norm(h))
    rn = float(np.linalg.norm(r))
    if not (hn > 0.0 and rn > 0.0):
        return None, None
    o3 = -r / rn
    o2 = -h / hn
    o1 = np.cross(o2, o3)
    return np.column_stack([o1, o2, o3]), h / (rn * rn)


def _quat_of(R) -> tuple:
    from scipy.spatial.transform import Rotation

    x, y, z, w = Rotation.from_matrix(R).as_quat()
    q = np.array([w, x, y, z])
    return tuple(q / np.linalg.norm(q))


def _rot_of_quat(q) -> np.ndarray:
    from scipy.spatial.transform import Rotation

    w, x, y, z = q
    return Rotation.from_quat([x, y, z, w]).as_matrix()


def orbit_frame_needs(body) -> list[tuple[str, str]]:
    """The keys of a rigid body that read its orbit frame, each with the value that would not:
    the default attitude ("orbit") and the default rate frame ("orbit", zero relative to the
    orbit frame) both do.  Empty for a body whose attitude and rate are inertial."""
    rig = body.rigid
    key = f"bodies.{body.name}.rigid"
    out = []
    a = rig.attitude
    if a.kind == "orbit" or a.frame == "orbit":
        out.append((f"{key}.attitude", "an inertial attitude, e.g. attitude = { quaternion = [1.0, 0.0, 0.0, 0.0] }"))
    if rig.angular_velocity_frame == "orbit":
        out.append((f"{key}.angular_velocity",
                    "an inertial rate, e.g. angular_velocity = { vector = ['0 rad/s', '0 rad/s', '0 rad/s'], frame = 'body' }"))
    return out


def undefined_frame_error(missing: list[tuple[str, str]]) -> SceneError:
    """One error naming every key that needs a value because an orbit frame is undefined (a body
    at rest, or moving along its radius: r x v = 0, as in free space)."""
    keys = [k for k, _ in missing]
    expected = "; ".join(f"{k}: {fix}" for k, fix in missing)
    return SceneError(
        keys[0],
        f"a value for each of {len(keys)} key(s) that default to the orbit frame ({expected})",
        "no orbit frame: the body's r x v = 0 (free space, or a body at rest), so the default attitude and "
        "angular velocity, both relative to the orbit frame, are undefined",
    )


def body_attitude(body, r, v) -> tuple[np.ndarray, np.ndarray]:
    """(R body -> inertial, omega in body axes) of a rigid scene body whose centre of mass is at
    (r, v).  Where the orbit frame is undefined (r x v = 0) every key that reads it is named in one
    :class:`SceneError`."""
    from scipy.spatial.transform import Rotation

    rig = body.rigid
    O, w_o = _orbit_frame(np.asarray(r, float), np.asarray(v, float))
    if O is None:
        missing = orbit_frame_needs(body)
        if missing:
            raise undefined_frame_error(missing)
    a = rig.attitude
    if a.kind == "orbit":
        R = O.copy()
    else:
        Rb = _rot_of_quat(a.values) if a.kind == "quaternion" else Rotation.from_euler(a.sequence, a.values).as_matrix()
        R = O @ Rb if a.frame == "orbit" else Rb
    w = np.asarray(rig.angular_velocity_rad_s, float)
    if rig.angular_velocity_frame == "orbit":
        w = w + R.T @ w_o
    return R, w


def _shape_vectors(scene, t, r_ref, v_ref):
    """The from -> to rod vectors (n, 3) of a tether laid from its initial shape, and its side."""
    from ..diagnostics import direction_from_angles

    ini = t.initial
    side = 1.0 if ini.side == "up" else -1.0
    thetas, phis = ini.rod_angles_rad(t.rods)
    dirs = np.array([direction_from_angles(r_ref, v_ref, th, ph, side) for th, ph in zip(thetas, phis)])
    seg = t.length_m / t.rods * (1.0 + ini.strain)
    return dirs * seg, side


def forest_state(scene, graph, model: Model, mu: float):
    """(y0, r_ref, v_ref, sides) for any forest (see the module docstring).

    Checked at load (tetherlab/scene/checks.py: _check_run, _check_layout): orbit.motion is
    'corotating' or 'translating', no tether has shape 'equilibrium', every component holds the
    orbit reference or a body with an explicit state."""
    by_name = {b.name: b for b in scene.bodies}
    kindex = {b.name: i for i, b in enumerate(model.bodies) if b.name}
    orbit = scene.orbit
    tethers = scene.tethers
    parents, children, reversed_ = graph.parents, graph.child_names, graph.reversed
    roots = graph.roots
    if orbit is not None:
        ref = orbit.state(mu)
        if ref is None:
            ref = by_name[orbit.reference].state(mu)
        r_ref, v_ref = (np.asarray(x, float) for x in ref)
        reference = orbit.reference
        motion = orbit.motion
    else:
        root = by_name[roots[0]]
        r_ref, v_ref = (np.asarray(x, float) for x in root.state(mu))
        reference = root.name
        motion = "translating"
    _, w_o = _orbit_frame(r_ref, v_ref)
    w_frame = w_o if (motion == "corotating" and w_o is not None) else np.zeros(3)
    w_frame = with_spin(w_frame, orbit, r_ref, v_ref)

    # components (numbered as graph.roots) and their anchors
    comp_of = graph.component
    anchors = []
    for ri, root in enumerate(roots):
        group = [b.name for b in scene.bodies if comp_of.get(b.name) == ri]
        if reference == "center_of_mass" and ri == 0:
            anchors.append(("center_of_mass", r_ref, v_ref))
        elif reference in group:
            anchors.append((reference, r_ref, v_ref))
        else:
            explicit = next(n for n in group if by_name[n].has_state)
            r, v = by_name[explicit].state(mu)
            anchors.append((explicit, np.asarray(r, float), np.asarray(v, float)))

    # tethers with every parent before its children: each is laid from its parent's position,
    # so any such order gives the same numbers
    order = graph.placement_order

    sides = [1.0] * len(tethers)
    lay = model.state
    att_states = {}
    pos_guess = {n: (r_ref, v_ref) for n in kindex}  # each body's (r, v) for its orbit frame
    y = None
    for _ in range(_PASSES):
        # attitudes from the current guess of each body's state
        R = {}
        W = {}
        missing = []  # every key of every body that needs an orbit frame it does not have
        for n, b in kindex.items():
            body = by_name[n]
            if body.rigid is not None:
                if _orbit_frame(*(np.asarray(x, float) for x in pos_guess[n]))[0] is None:
                    missing.extend(orbit_frame_needs(body))
                    if missing:
                        continue
                R[n], W[n] = body_attitude(body, *pos_guess[n])
        if missing:
            raise undefined_frame_error(missing)
        pos = {}  # body -> centre of mass, relative to its component's root (anchored later)
        dvec = {}  # tether -> (n, 3) kernel-order rod vectors (2 sqrt3 d)
        for ri, root in enumerate(roots):
            name = anchors[ri][0]
            if name == root and by_name[root].has_state:
                pos[root] = np.asarray(by_name[root].state(mu)[0], float)
            elif name == root and name != "center_of_mass":
                pos[root] = anchors[ri][1].copy()
            else:
                pos[root] = np.zeros(3)
        for k in order:
            t = tethers[k]
            par, ch = parents[k], children[k]
            spec = model.tethers[k]
            rho_a = R[par] @ np.asarray(spec.from_point_m) if par in R else np.zeros(3)
            rho_c = R[ch] @ np.asarray(spec.to_point_m) if ch in R else np.zeros(3)
            A = pos[par] + rho_a
            if t.initial is None:  # both ends explicit: straight between the attachment points
                rc = np.asarray(by_name[ch].state(mu)[0], float)
                B = rc + rho_c
                vecs = np.tile((B - A) / t.rods, (t.rods, 1))
                if np.linalg.norm(B - A) == 0.0:
                    raise SceneError(f"tethers.{t.name}.to", "attachment points at different positions", "the same point")
            else:
                vecs, sides[k] = _shape_vectors(scene, t, r_ref, v_ref)
                if reversed_[k]:
                    vecs = -vecs[::-1]
            dvec[k] = vecs
            pos[ch] = A + vecs.sum(axis=0) - rho_c
        # anchor the components
        for ri, root in enumerate(roots):
            name, ra, _ = anchors[ri]
            if name == root or name == "center_of_mass":
                continue
            shift = ra - pos[name]
            group = [n for n in pos if comp_of.get(n) == ri]
            for n in group:
                pos[n] = pos[n] + shift
        # assemble y (positions), centre-of-mass reference shifted afterwards
        y = np.zeros(model.n_state)
        for ri, root in enumerate(roots):
            y[lay.root_position(kindex[root])] = pos[root]
        for k, vecs in dvec.items():
            y[lay.tether_rods(k)] = (vecs / (2.0 * SQ3)).ravel()
        states = {kindex[n]: (_quat_of(R[n]), tuple(W[n])) for n in R}
        y[lay.first_order] = attitude_block(model, states)
        if anchors[0][0] == "center_of_mass":
            c, _ = center_of_mass(model, y)
            shift = r_ref - c
            for n in list(pos):
                if comp_of.get(n) == 0:
                    pos[n] = pos[n] + shift
            qo = model.root_offset(0)
            y[qo : qo + 3] = pos[roots[0]]
        # velocities
        vel = {}
        anchor_v = {}
        for ri, root in enumerate(roots):
            name, ra, va = anchors[ri]
            ra = r_ref if name == "center_of_mass" else ra
            anchor_v[ri] = (ra, va)

        def base_v(ri, r):
            ra, va = anchor_v[ri]
            return va + np.cross(w_frame, r - ra)

        extra = {}  # body -> list of (omega_rel, centre) of rigid ancestors (incl. itself)
        for ri, root in enumerate(roots):
            vel[root] = base_v(ri, pos[root])
            if by_name[root].has_state and (anchors[ri][0] != "center_of_mass"):
                vel[root] = np.asarray(by_name[root].state(mu)[1], float) if anchors[ri][0] == root or orbit is None else vel[root]
            extra[root] = [(R[root] @ W[root] - w_frame, pos[root])] if root in R else []
        for k in order:
            t = tethers[k]
            par, ch = parents[k], children[k]
            ri = comp_of[par]
            ex = extra[par]
            if t.initial is None:
                spec = model.tethers[k]
                rho_a = R[par] @ np.asarray(spec.from_point_m) if par in R else np.zeros(3)
                rho_c = R[ch] @ np.asarray(spec.to_point_m) if ch in R else np.zeros(3)
                wa = R[par] @ W[par] if par in R else np.zeros(3)
                wc = R[ch] @ W[ch] if ch in R else np.zeros(3)
                vA = vel[par] + np.cross(wa, rho_a)
                vch = np.asarray(by_name[ch].state(mu)[1], float)
                vB = vch + np.cross(wc, rho_c)
                dd = np.tile((vB - vA) / (2.0 * SQ3 * t.rods), (t.rods, 1))
                vel[ch] = vch
            else:
                d = dvec[k] / (2.0 * SQ3)
                dd = np.cross(w_frame, d)
                for om, _c in ex:
                    dd = dd + np.cross(om, d)
                v = base_v(ri, pos[ch])
                for om, cen in ex:
                    v = v + np.cross(om, pos[ch] - cen)
                vel[ch] = v
            y[lay.tether_rates(k)] = dd.ravel()
            extra[ch] = ex + ([(R[ch] @ W[ch] - w_frame, pos[ch])] if ch in R else [])
        for ri, root in enumerate(roots):
            y[lay.root_velocity(kindex[root])] = vel[root]
        # a rigid body's velocity is that of its centre of mass; children of rigid parents got it
        # through their attachment velocities above (the kernel derives non-root states anyway)
        pos_guess = {n: (pos[n], vel[n]) for n in pos}
    return y, r_ref, v_ref, sides
