"""The initial layout of a scene: its state vector at t = 0, laid out from the scene's graph.

Straight tethers, per-rod angles, explicit end states, the relative equilibrium and the
quasi-static start (docs/scenes.md, "Initial layout"; docs/model.md section 8), all read the one
graph built at load (tetherlab/model/topology.py): its roots, components, orientation and the order
parents-before-children.

Two layout paths remain, on purpose:

* :func:`~tetherlab.initial.star.star_state` for a star of point masses written from its root
  (``graph.simple``): it lays the rods with the root at the origin and shifts the reference point
  onto its orbit, and is the only one with the equilibrium solves (orbit.motion 'equilibrium',
  'quasi-static') and the statics start (shape 'equilibrium');
* :func:`~tetherlab.initial.forest.forest_state` for any other forest (tethers in either
  direction, rigid bodies, several roots): it places each body from its parent and anchors each
  component.

On a star both give the same positions and velocities up to round-off, not bit for bit (the
forest path sums rod vectors from the attachment point and anchors afterwards; the star path adds
the reference's shift once): every shipped star scene was recorded with the star path, so
merging them would change their outputs in the last bits.
"""

from __future__ import annotations

from .forest import body_attitude, forest_state
from .star import star_state, state_of
from .static_start import static_start

__all__ = ["initial_state", "star_state", "forest_state", "static_start", "body_attitude", "state_of"]


def initial_state(scene, graph, model, mu: float, eq_model=None):
    """(y0, r_ref, v_ref, sides) of ``scene`` laid out on ``model`` (built from ``graph``).

    ``eq_model``: the model of the conservative effects alone, for the relative equilibrium."""
    if graph.simple:
        return star_state(scene, graph, model, mu, eq_model)
    return forest_state(scene, graph, model, mu)
