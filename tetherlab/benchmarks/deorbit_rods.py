"""``make bench`` section: the electrodynamic de-orbit against the rod count.

RADAU5 in the frame turning with the orbit from the quasi-static start
(:data:`tetherlab.benchmarks.deorbit.RODS_SETTINGS`; docs/integrators.md section 11).  Command line:
``python -m tetherlab.benchmarks.deorbit --rod-counts 1 4 16 64``.
"""

from __future__ import annotations

from .deorbit import rods_table


def bench_rows() -> list[dict]:
    return rods_table((1, 4, 16, 64))
