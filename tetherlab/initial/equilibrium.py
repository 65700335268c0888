"""Rigidly rotating starts of a star of point masses: orbit.motion 'equilibrium' (the relative
equilibrium under the conservative effects, docs/model.md section 8) and 'quasi-static' (every rod
at rest in the frame turning with it under every effect, section 8.1).

Both are Newton solves with finite-difference Jacobians on the built model (set-up cost only);
a solve that does not converge is refused here, naming orbit.motion: only solving tells.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import SceneError
from ..system import center_of_mass


def rigidly_rotating(model, y0, d, W, r_ref, reference, root_name, tethers):
    """y0 with the rod vectors ``d`` (nrods x 3), the reference point at ``r_ref`` and every point
    rotating rigidly with ``W`` about the centre of the central body."""
    lay = model.state  # a star of point masses: y = [r0, d, v0, d'] (equilibrium starts are refused elsewhere)
    y = y0.copy()
    y[lay.rods_d] = d.ravel()
    if reference == "center_of_mass":
        y[lay.root_r] = 0.0
        c, _ = center_of_mass(model, y)
    elif reference == root_name:
        c = np.zeros(3)
    else:
        from ..system import point_positions

        y[lay.root_r] = 0.0
        k = [t.to_body for t in tethers].index(reference)
        c = point_positions(model, y)["joints"][k][-1]
    y[lay.root_r] = r_ref - c if reference != root_name else r_ref
    y[lay.root_v] = np.cross(W, y[lay.root_r])
    y[lay.rods_dd] = np.cross(W, d).ravel()
    return y


def quasi_static(model, y0, r_ref, reference, root_name, tethers):
    """The rigidly rotating configuration under every effect of the scene at t = 0 (docs/model.md,
    section 8.1; ``orbit.motion = "quasi-static"``).

    Starts from the relative equilibrium ``y0`` of the conservative effects (spin rate W kept) and
    solves all three components of every rod vector d_g so that, in the frame rotating with W, every
    rod's relative acceleration d''_g - W x (W x d_g) vanishes: the tether takes the bowed and tilted
    shape the non-conservative forces (electrodynamic, drag) hold it in at t = 0.  Those forces
    vary along the orbit at the orbital frequency, far below the tether's lateral modes, so from
    this start the lateral modes are hardly excited; from the straight start they ring undamped for
    the whole run (the de-orbit: docs/integrators.md, section 11).  The centre of mass still
    decelerates: only the relative motion is in equilibrium.  Newton with a finite-difference
    Jacobian (3 n unknowns; set-up cost only).
    """
    from ..formulations.cowell import cowell_rhs_py

    nrods = model.n_rods
    lay = model.state
    r0 = y0[lay.root_r]
    W = np.cross(r0, y0[lay.root_v]) / float(r0 @ r0)  # the rigid rotation of the equilibrium
    w2 = float(W @ W)
    d0 = y0[lay.rods_d].reshape(nrods, 3)
    size = 2 * math.sqrt(3) * float(np.linalg.norm(d0, axis=1).sum())
    dscale = float(np.max(np.linalg.norm(d0, axis=1)))

    def residual(x):
        d = x.reshape(nrods, 3)
        y = rigidly_rotating(model, y0, d, W, r_ref, reference, root_name, tethers)
        acc = cowell_rhs_py(model, y)[lay.rods_dd].reshape(nrods, 3)
        return (acc - np.cross(W, np.cross(W, d))).ravel() / (w2 * size)

    x = d0.ravel().copy()
    f = residual(x)
    step_max = np.inf
    for _ in range(30):
        J = np.empty((x.size, x.size))
        for j in range(x.size):
            dx = 1e-7 * max(1.0, abs(x[j]))
            xp = x.copy()
            xp[j] += dx
            J[:, j] = (residual(xp) - f) / dx
        step = np.linalg.lstsq(J, f, rcond=None)[0]
        x = x - step
        f = residual(x)
        step_max = float(np.max(np.abs(step)))
        # The rod vectors to 1e-10 of their length: the residual has a round-off floor (orbital
        # accelerations of ~8 m/s^2 against tidal ones of ~1e-3 m/s^2), the step does not.
        if step_max < 1e-10 * dscale:
            break
    if not step_max < 1e-10 * dscale:
        raise SceneError(
            "orbit.motion", "a configuration with a quasi-static equilibrium under every effect (Newton converging)",
            f"last Newton step {step_max:.3g} m on rod vectors of {dscale:.3g} m after 30 iterations",
        )
    return rigidly_rotating(model, y0, x.reshape(nrods, 3), W, r_ref, reference, root_name, tethers)


def relative_equilibrium(model, y0, r_ref, v_ref, omega, reference, root_name, tethers):
    """Rod lengths and spin rate that make the laid-out system rotate rigidly (docs/model.md 8).

    Unknowns: one length factor per rod and the spin rate Omega (about the orbit normal).
    Equations: in the frame rotating with Omega, the axial component of every rod's relative
    acceleration d'' - Omega x (Omega x d) and the radial component of the root's vanish.  For a
    tether along the local vertical this is the exact relative equilibrium of paper section 4.3
    (the tether stays vertical and the rods do not breathe); for a tilted tether it removes the
    axial transient and leaves the libration.  The reference point is kept on its orbit.
    """
    from ..formulations.cowell import cowell_rhs_py

    nrods = model.n_rods
    lay = model.state
    zhat = omega / np.linalg.norm(omega)
    w0 = float(np.linalg.norm(omega))
    d0 = y0[lay.rods_d].reshape(nrods, 3).copy()
    size = 2 * math.sqrt(3) * float(np.linalg.norm(d0, axis=1).sum())  # whole tether length

    def build(x):
        W = x[-1] * w0 * zhat
        return rigidly_rotating(model, y0, d0 * x[:-1, None], W, r_ref, reference, root_name, tethers), W

    def residual(x):
        y, W = build(x)
        dy = cowell_rhs_py(model, y)
        acc = dy[lay.qd]
        r0 = y[lay.root_r]
        d = y[lay.rods_d].reshape(nrods, 3)
        res = np.empty(nrods + 1)
        a_rel0 = acc[:3] - np.cross(W, np.cross(W, r0))
        res[0] = a_rel0 @ r0 / np.linalg.norm(r0) / (w0 * w0 * np.linalg.norm(r0))
        # every rod at once (a Python loop of per-rod cross products made this solve O(n^2) in
        # interpreter calls: 12 s at n = 256)
        u = d / np.linalg.norm(d, axis=1)[:, None]
        a_rel = acc[3:].reshape(nrods, 3) - np.cross(W, np.cross(W, d))
        res[1:] = (a_rel * u).sum(axis=1) / (w0 * w0 * size)
        return res

    # Newton with a finite-difference Jacobian; the residuals are relative accelerations in units
    # of Omega^2 * size, whose round-off floor is ~1e-12 (8 m/s^2 gravity against ~1e-3 m/s^2
    # tidal terms), so convergence is judged on the step, not on the residual alone.
    x = np.ones(nrods + 1)
    f = residual(x)
    for _ in range(40):
        J = np.empty((nrods + 1, nrods + 1))
        for j in range(nrods + 1):
            dx = 1e-6 * max(1.0, abs(x[j]))
            xp = x.copy()
            xp[j] += dx
            J[:, j] = (residual(xp) - f) / dx
        step = np.linalg.solve(J, f)
        x = x - step
        f = residual(x)
        if np.max(np.abs(step)) < 1e-14 or np.max(np.abs(f)) < 1e-12:
            break
    # Converged when the solution is known to 1e-11 in the unknowns (rod length factors ~ strain,
    # spin rate relative): the residual alone has a scene-dependent round-off floor (1.4e-9
    # measured on the de-orbit tether, i.e. a strain error of ~4e-12).
    x_err = float(np.max(np.abs(np.linalg.solve(J, f))))
    if not x_err < 1e-11:
        raise SceneError(
            "orbit.motion", "a configuration with a relative equilibrium (Newton converging)",
            f"residual {np.max(np.abs(f)):.3g} (error in the unknowns ~{x_err:.2g}) after 40 iterations",
        )
    return build(x)[0]
