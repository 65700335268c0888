"""The hanging chain with a tip mass against the Bessel solution, modes 1 and 2, n = 4 ... 256, both
tether models, by the linearised small-oscillation eigenproblem about the static hang
(docs/hanging-chain.md sections 5-7; tetherlab/verify/hanging_chain_modes.py).

    PYTHONPATH=. python studies/hanging_chain_modes.py [--rods 4,8,...,256] [--figure PATH]

Prints one markdown row per (model, mode, n): the frequency, its error against Bessel as computed
and with the elastic model's stretch offset removed (eq. H11), error n^2 against the derived
coefficient c (eq. H12), and the observed order from the previous rod count.
"""

from __future__ import annotations

import argparse
import math

from tetherlab.verify.hanging_chain_modes import NS, convergence_table, figure


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rods", default=",".join(str(n) for n in NS))
    ap.add_argument("--figure", default=None, help="write the log-log figure of the errors here (PNG)")
    args = ap.parse_args(argv)
    rows = convergence_table(tuple(int(k) for k in args.rods.split(",")))
    print("| model | mode | n | w (rad/s) | w/w_Bessel - 1 | error e | e n^2 | c (derived) | order |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        order = "-" if math.isnan(r["order"]) else f"{r['order']:.4f}"
        print(f"| {r['model']} | {r['mode']} | {r['n']} | {r['omega_rad_s']:.10f} | {r['w/w_Bessel - 1']:.4e} "
              f"| {r['error']:.4e} | {r['error n^2']:.5e} | {r['derived c']:.5e} | {order} |")
    if args.figure:
        figure(rows, args.figure)


if __name__ == "__main__":
    main()
