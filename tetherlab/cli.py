"""Command line: ``tetherlab run SCENE.toml --out DIR`` and ``tetherlab plot DIR``."""

from __future__ import annotations

import argparse
import sys
import time


def _run(args) -> int:
    t0 = time.perf_counter()
    from .errors import SceneError
    from .scene import load_scene
    from .pipeline import SimulationError, simulate

    try:
        scene = load_scene(args.scene)
    except (SceneError, FileNotFoundError) as exc:
        print(f"tetherlab: {exc}", file=sys.stderr)
        return 2
    changes = {}
    if args.method:
        changes["method"] = args.method
    if changes:
        scene = scene.replace(**{f"integrator.{k}": v for k, v in changes.items()})
    try:
        result = simulate(scene, progress=None if not args.quiet else False)
        code = 0
    except SimulationError as exc:
        result = exc.result
        print(f"tetherlab: {exc}", file=sys.stderr)
        code = 1
    except SceneError as exc:
        print(f"tetherlab: {exc}", file=sys.stderr)
        return 2
    out = result.save(args.out)
    s = result.stats
    if not args.quiet:
        print(
            f"{scene.name}: {len(result.timeseries)} outputs to {out}/ | "
            f"steps {s.get('n_accepted')} (+{s.get('n_rejected')} rejected), rhs {s.get('n_rhs')}, "
            f"jac {s.get('n_jac')} | integrate {s.get('wall_s', 0):.3f} s, compile {s.get('compile_s', 0):.3f} s, "
            f"total {time.perf_counter() - t0:.2f} s"
        )
    return code


def _plot(args) -> int:
    from .plots import plot_run

    files = plot_run(args.dir, out_dir=args.out)
    for f in files:
        print(f)
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="tetherlab", description=__doc__)
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run", help="integrate a scene and write its results")
    r.add_argument("scene", help="scene file (TOML)")
    r.add_argument("--out", required=True, help="output directory")
    r.add_argument("--method", help="override the scene's integrator method")
    r.add_argument("--quiet", action="store_true", help="no progress bar, no summary")
    r.set_defaults(func=_run)
    p = sub.add_parser("plot", help="draw PNG figures of a run directory")
    p.add_argument("dir", help="a directory written by `tetherlab run`")
    p.add_argument("--out", help="where to put the PNGs (default: DIR)")
    p.set_defaults(func=_plot)
    args = ap.parse_args(argv)
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
