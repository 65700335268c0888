"""Oracles: independent code paths that check the TMED simulator (issue 4).

``bead``: the lumped-mass tether model with its own right-hand side; ``bead_scene``: its initial
state from a scene; ``continuum``: closed-form and ODE references for a continuous tether.
None of them imports the TMED tether code (``tetherlab.tether``, ``tetherlab.system``,
``tetherlab.kernel.effects``).
"""
