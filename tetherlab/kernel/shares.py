"""The energy and momentum share vector: what every part adds its own share to.

Each part type (tether/chain.py for a chain of rods, bodies/point.py, bodies/rigid.py with its
wheel set) has a ``*_share`` function that adds its linear momentum, angular momentum about the
origin, kinetic energy and potential energies to one float64 vector with these slots; the
diagnostics (tetherlab/diagnostics.py) sum the parts in a fixed order and read the totals.
"""

SH_PX, SH_PY, SH_PZ = 0, 1, 2    # linear momentum (kg m/s)
SH_HX, SH_HY, SH_HZ = 3, 4, 5    # angular momentum about the origin (kg m^2/s)
SH_KE = 6                        # kinetic energy, translational and rotational (J)
SH_VG = 7                        # potential of the conservative effects (J)
SH_VE = 8                        # elastic energy of the rods, 1/2 EA L_u eps^2 each (J)
SH_E = 9                         # KE + VG + VE: written by the diagnostics, not by the parts
SH_KROT = 10                     # the rotational part of SH_KE (rigid bodies and wheels)
SH_SIZE = 11
