"""The spin of a scene's initial layout (``[orbit] spin``): a rigid rotation of the point masses
and the tethers about the orbit reference, added to the rotation of ``motion``.

Every laid-out point gets v = v_ref + (w_motion + w_spin) x (r - r_ref): the whole system turns
rigidly about the reference point (the centre of mass, or the reference body), so its centre of
mass keeps the orbit's velocity when it is the reference. Rigid bodies keep the angular velocity
their own ``angular_velocity`` gives them (docs/scenes.md).
"""

from __future__ import annotations

import numpy as np

from ..diagnostics import orbital_frame


def spin_vector(orbit, r_ref, v_ref) -> np.ndarray | None:
    """The spin's inertial angular velocity (rad/s), None without a spin."""
    spin = getattr(orbit, "spin", None)
    if spin is None:
        return None
    axis = np.asarray(spin.axis, float)
    if spin.frame == "orbit":
        frame = orbital_frame(np.asarray(r_ref, float)[None], np.asarray(v_ref, float)[None])[0]
        axis = frame.T @ axis  # rows of the frame: radial, along-track, normal
    return spin.rate_rad_s * axis


def with_spin(omega, orbit, r_ref, v_ref):
    """``omega`` (the motion's frame rate, or None) plus the spin's."""
    w = spin_vector(orbit, r_ref, v_ref)
    if w is None:
        return omega
    return w if omega is None else np.asarray(omega, float) + w
