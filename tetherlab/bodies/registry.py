"""Every body part type: its kind code, its module, its name in a BodySpec.

A part type is one module in tetherlab/bodies/ that defines the part interface (the functions of
:data:`INTERFACE`, with those signatures) and one line in :data:`PARTS` below.  Numba has no
virtual calls, so the dispatcher that chooses a part's function by the body's kind code
(bodies/parts.py) is generated from this table: after adding a line, run

    python -m tetherlab.model.dispatch

and commit the regenerated bodies/parts.py with it (tests/test_part_registry.py fails while the two
disagree).  The tethers have the same shape: tether/registry.py, tether/parts.py.  build_model writes each body's code into its BT_PART slot, from the body's ``part``
name (a BodySpec without one: ``rigid`` if it has a rigid table, else ``point``).

This module imports nothing of tetherlab, so the generator reads it on a package whose dispatcher
is out of date.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class PartType:
    """``code``: the kind code in the body's BT_PART slot; ``name``: what a BodySpec's ``part``
    says; ``module``: the module of tetherlab.bodies with the interface functions."""

    code: int
    name: str
    module: str


# The part interface, in the driver's order (docs/model.md 12.4; tether/solve.py calls each through
# the dispatcher ``body_<name>``).  Signatures: name -> arguments.
INTERFACE = {
    "root_state": "att, p, b",  # a root's own kinematics once its centre of mass is in its scratch
    "end_state": "att, p, c, bx, by, bz, bvx, bvy, bvz",  # a child's, from its tether's end B_n
    "attach": "p, b, tb, ts, ax, ay, az, avx, avy, avz",  # -> A_1 (r, v) of the tether tb on b
    "setup": "t, att, p, b, datt",  # external forces, own torques and derivatives, M and F
    "add_child": "p, b, k, W, s0",  # an eliminated child tether's compliance into M, F
    "compliance": "p, c, work",  # -> determinant; a_B = C J_n + f as the parent tether's tip needs it
    "root_solve": "p, b",  # -> determinant; a root's own system M a = F
    "point_acceleration": "p, b, ts",  # -> a_A of a child tether's attachment point
    "back_substitute": "p, c, jn",  # its acceleration once its parent's J_n is known
    "derivatives": "att, p, b, datt",  # -> False if not finite; its own state's derivatives
    "share": "t, att, p, b, sh",  # its energy and momentum share
}

# The first line is the default: a body whose code matches no other line runs it.
PARTS = (
    PartType(0, "point", "point"),
    PartType(1, "rigid", "rigid_body"),
)


def check(parts=PARTS) -> None:
    """Refuse a table the dispatcher cannot be generated from, naming what is wrong."""
    seen_codes, seen_names = {}, {}
    for part in parts:
        if not isinstance(part.code, int) or isinstance(part.code, bool) or part.code < 0:
            raise ValueError(f"part {part.name!r}: code: expected an int >= 0, got {part.code!r}")
        if not part.module.isidentifier() or not part.name.isidentifier():
            raise ValueError(f"part {part.name!r}: name and module: expected identifiers, got {part.name!r}, {part.module!r}")
        if part.code in seen_codes:
            raise ValueError(f"part {part.name!r}: code {part.code} is already {seen_codes[part.code]!r}'s")
        if part.name in seen_names:
            raise ValueError(f"part {part.name!r}: the name is already taken (code {seen_names[part.name]})")
        seen_codes[part.code] = part.name
        seen_names[part.name] = part.code


def part_named(name: str, parts=PARTS) -> PartType:
    for part in parts:
        if part.name == name:
            return part
    raise ValueError(f"part: expected one of {[q.name for q in parts]}, got {name!r}")


def part_of(body, parts=PARTS) -> PartType:
    """The part type of a BodySpec: its ``part`` name, else rigid or point by its rigid table."""
    name = getattr(body, "part", "") or ("rigid" if body.rigid is not None else "point")
    return part_named(name, parts)
