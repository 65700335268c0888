"""Command line: ``tetherlab run SCENE.toml --out DIR``, ``tetherlab run --resume DIR`` and
``tetherlab plot DIR``."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path


def _run(args) -> int:
    """``tetherlab run SCENE --out DIR`` or ``tetherlab run --resume DIR``.

    Exit codes: 0 done, 1 the run failed (its message says when, where and why; outputs so far
    are in DIR), 2 bad input (scene, output directory), 130 interrupted (Ctrl-C / SIGTERM: what
    was computed is saved and the command to continue is printed).
    """
    t0 = time.perf_counter()
    from .errors import SceneError
    from .runstore import Interrupted, RunDirError, resume_dir, run_to_dir
    from .scene import load_scene

    progress = None if not args.quiet else False
    try:
        if args.resume:
            if args.scene or args.out or args.method or args.from_run:
                print("tetherlab: --resume DIR continues the run stored in DIR: give no scene, --out, --method or --from",
                      file=sys.stderr)  # fmt: skip
                return 2
            out = args.resume
            record = resume_dir(out, progress=progress, checkpoint_s=args.checkpoint_every)
        else:
            if not args.scene or not args.out:
                print("tetherlab: give a scene and --out DIR (or --resume DIR)", file=sys.stderr)
                return 2
            out = args.out
            scene = load_scene(args.scene)
            if args.method:
                scene = scene.replace(**{"integrator.method": args.method})
            if args.from_run:
                if Path(args.from_run).resolve() == Path(args.out).resolve():
                    print(f"tetherlab: --from {args.from_run} and --out {args.out} are one directory: the new phase "
                          "would overwrite the run it starts from; give it a directory of its own", file=sys.stderr)
                    return 2
                # the scene's inputs from the final state and time of the finished run in DIR
                scene = scene.replace(continue_from=args.from_run)
            record = run_to_dir(scene, out, progress=progress, checkpoint_s=args.checkpoint_every,
                                part_rows=args.part_rows)  # fmt: skip
    except (SceneError, FileNotFoundError, RunDirError) as exc:
        print(f"tetherlab: {exc}", file=sys.stderr)
        return 2
    except Interrupted as exc:
        print(f"\ntetherlab: {exc}", file=sys.stderr)
        return 130
    except KeyboardInterrupt:  # before the integration started: nothing was computed
        print("\ntetherlab: interrupted before the integration started; nothing was computed", file=sys.stderr)
        return 130
    s = record.get("stats", {})
    if not record.get("ok"):
        print(f"tetherlab: {record.get('message')}", file=sys.stderr)
    if not args.quiet:
        name = record.get("scene", {}).get("name", "run")
        print(
            f"{name}: {record.get('rows_done')} outputs to {out}/ | "
            f"steps {s.get('n_accepted')} (+{s.get('n_rejected')} rejected), rhs {s.get('n_rhs')}, "
            f"jac {s.get('n_jac')} | integrate {s.get('wall_s', 0):.3f} s, compile {s.get('compile_s', 0):.3f} s, "
            f"total {time.perf_counter() - t0:.2f} s"
        )
    return 0 if record.get("ok") else 1


def _plot(args) -> int:
    from .plots import plot_run

    files = plot_run(args.dir, out_dir=args.out)
    for f in files:
        print(f)
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="tetherlab", description=__doc__)
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run", help="integrate a scene and write its results as it goes")
    r.add_argument("scene", nargs="?", help="scene file (TOML)")
    r.add_argument("--out", help="output directory (Parquet datasets timeseries/ and diagnostics/, run.json)")
    r.add_argument("--resume", metavar="DIR", help="continue the interrupted run stored in DIR")
    r.add_argument("--from", dest="from_run", metavar="DIR",
                   help="start from the final state and time of the finished run in DIR (a mission in phases; "
                        "sets the scene's continue_from)")
    r.add_argument("--method", help="override the scene's integrator method")
    r.add_argument("--quiet", action="store_true", help="no progress bar, no summary")
    r.add_argument("--checkpoint-every", type=float, default=5.0, metavar="SECONDS",
                   help="wall-clock seconds between checkpoints (default 5)")
    r.add_argument("--part-rows", type=int, default=None, metavar="N",
                   help="output rows per Parquet part (default: about 64 MiB of columns)")
    r.set_defaults(func=_run)
    p = sub.add_parser("plot", help="draw PNG figures of a run directory")
    p.add_argument("dir", help="a directory written by `tetherlab run`")
    p.add_argument("--out", help="where to put the PNGs (default: DIR)")
    p.set_defaults(func=_plot)
    args = ap.parse_args(argv)
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
