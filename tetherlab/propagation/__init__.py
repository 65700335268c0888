"""Integration drivers that belong to a formulation rather than to an integrator
(the DROMO sigma form's output clock, the time form's driver call): :mod:`.dromo`."""
