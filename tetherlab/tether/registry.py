"""Every tether part type: its kind code, its module, its name in a TetherSpec.

The tether side of the part registry (the body side: bodies/registry.py, whose docstring says how
the dispatcher is generated).  A tether part is what runs between its parent's attachment point
A_1 and its end B_n: today the chain of TMED rods (tether/chain.py); a reel feeding a chain or an
inextensible chain is one module defining :data:`INTERFACE` and one line in :data:`PARTS`, then

    python -m tetherlab.model.dispatch

regenerates tether/parts.py, whose ``tether_<name>`` functions the forest driver (tether/solve.py)
and the diagnostics call.  build_model writes each tether's code into its TT_PART slot from the
TetherSpec's ``part`` name (without one: ``chain``).  Imports nothing of tetherlab but the body
registry's table type.
"""

from __future__ import annotations

from ..bodies.registry import PartType, check, part_named  # noqa: F401  (the same table type and checks)

# The tether part interface, in the driver's order (docs/model.md 12.4): name -> arguments.
INTERFACE = {
    # kinematics A_1 -> B_n, and (with_forces) its rods' forces: -> (code, B_n position, velocity)
    "walk": "t, q, qd, p, k, with_forces, ax, ay, az, avx, avy, avz",
    # its elimination down to A_1 (J_0 = W (s_0 + a_A)): -> failure code
    "reduce": "t, p, k",
    # its accelerations once a_A is known (into acc): -> failure code
    "back_substitute": "t, p, k, aax, aay, aaz, acc",
    # its energy and momentum share, from A_1's state
    "share": "t, q, qd, p, k, elastic, ax, ay, az, avx, avy, avz, sh",
}

# The first line is the default: a tether whose code matches no other line runs it.
PARTS = (
    PartType(0, "chain", "chain"),
    PartType(1, "inextensible", "inextensible"),
)


def part_of(tether, parts=PARTS) -> PartType:
    """The part type of a TetherSpec: its ``part`` name, else the rod chain."""
    return part_named(getattr(tether, "part", "") or "chain", parts)
