"""Oracles: independent code paths that check the TMED simulator.

``bead``: the lumped-mass tether model with its own right-hand side; ``bead_scene``: its initial
state from a scene; ``continuum``: closed-form and ODE references for a continuous tether;
``hanging_chain``: the hanging chain with a tip mass, its Bessel lateral modes and the rigid-link
chain's small-oscillation eigenproblem (docs/hanging-chain.md).
Rigid bodies (docs/rigid-oracles.md): ``torque_free`` (closed-form torque-free
asymmetric body, Jacobi elliptic functions), ``gg_attitude`` (gravity-gradient libration
frequencies and a nonlinear attitude integration), ``spinning_spokes`` (steady hub-and-spoke
tethers in free space), ``wheel_exchange`` (momentum exchange with wheels).
``reeled_pendulum``: the in-plane libration of a line of varying length as a rigid rod in the
Hill frame (docs/deployment.md 14).
None of them imports the TMED tether code (``tetherlab.tether``, ``tetherlab.system``,
``tetherlab.kernel.effects``).
"""
