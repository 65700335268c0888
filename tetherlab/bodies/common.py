"""What every body part shares: its centre of mass (position, velocity) in its scratch record.

The driver (tether/solve.py) writes a root's from q through the dispatcher; a part whose body hangs
on a tether writes its own (from the end B_n of that tether, less any offset of its attachment).
"""

from __future__ import annotations

from .._jit import njit
from ..kernel.layout import BS_R, BS_SIZE, BS_V, H_OFF_BSCR


@njit(cache=True, inline="always")
def set_body_state(p, b, rx, ry, rz, vx, vy, vz):
    bs = int(p[H_OFF_BSCR]) + b * BS_SIZE
    p[bs + BS_R] = rx
    p[bs + BS_R + 1] = ry
    p[bs + BS_R + 2] = rz
    p[bs + BS_V] = vx
    p[bs + BS_V + 1] = vy
    p[bs + BS_V + 2] = vz
