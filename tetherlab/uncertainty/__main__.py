"""``python -m tetherlab.uncertainty STUDY.toml --out DIR [--samples N] [--workers N]
[--scheduler tcp://...] [--sensitivity] [--no-reuse]``: run an uncertainty study (docs/uncertainty.md)."""

from __future__ import annotations

import argparse
import sys


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m tetherlab.uncertainty", description=__doc__)
    ap.add_argument("study")
    ap.add_argument("--out", required=True)
    ap.add_argument("--samples", type=int, help="override sampling.samples (an extension reuses the cache)")
    ap.add_argument("--workers", type=int)
    ap.add_argument("--scheduler", help="Dask scheduler address; default: local processes")
    ap.add_argument("--sensitivity", action="store_true", help="run the [sensitivity] design instead")
    ap.add_argument("--no-reuse", action="store_true",
                    help="run every sample the full way (replace + prepare) even when only parameters change")
    ap.add_argument("--quiet", action="store_true")
    args = ap.parse_args(argv)
    from .study import load_uncertainty_study

    study = load_uncertainty_study(args.study, samples=args.samples)
    if args.sensitivity:
        from .sensitivity import run_sensitivity

        idx = run_sensitivity(study, args.out, scheduler=args.scheduler, workers=args.workers, progress=not args.quiet)
        for q, rows in idx.items():
            for k, v in rows.items():
                print(q, k, " ".join(f"{a}={b:.4g}" for a, b in v.items()))
        return 0
    from .runner import run_study

    try:
        res = run_study(study, args.out, scheduler=args.scheduler, workers=args.workers, progress=not args.quiet,
                        reuse=not args.no_reuse)
    except KeyboardInterrupt:
        print(f"interrupted: every finished sample is in {args.out}/cache; run the same command again to "
              f"continue", file=sys.stderr)
        return 130
    print(f"{study.name}: {len(res.records)} samples ({res.n_run} run now, {res.n_cached} cached), "
          f"{len(res.failed)} failed, {res.wall_s:.1f} s -> {args.out} (samples: {res.path})")
    for q, st in res.stats.items():
        for name, v in st.items():
            print(f"  {q} {name}: {v['value']:.6g}  [{v['low']:.6g}, {v['high']:.6g}]")
    for i, r in res.failed:
        print(f"  FAILED sample {i}: {r.error}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
