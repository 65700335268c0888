"""Command line: ``tetherlab run``, ``validate``, ``plot`` and ``sweep``.

Exit codes of every command: 0 done, 1 the run (or a run of a sweep) failed, 2 bad input (a scene,
a command-line option, an output or run directory), 130 interrupted.
"""

from __future__ import annotations

import argparse
import logging
import math
import sys
import time
from pathlib import Path

#: what ``tetherlab --help`` prints (plain text: argparse shows it as written)
DESCRIPTION = (
    "tetherlab: space tether dynamics (TMED rod model). Commands: run a scene and write its outputs; "
    "validate a scene without running it; plot a run directory; sweep a study file."
)
EPILOG = "Scene reference: docs/scenes.md. Run directories and resuming: docs/runs.md."


class CommandLineError(Exception):
    """A command-line option is wrong (reported as such, not as a scene-file error)."""


def _say(text: str) -> None:
    print(f"tetherlab: {text}", file=sys.stderr)


def _enable_notices(quiet: bool) -> None:
    """Long silent steps (compiling the kernels, building the NRLMSIS table) say what they do."""
    log = logging.getLogger("tetherlab")
    if quiet or any(getattr(h, "_tetherlab_cli", False) for h in log.handlers):
        return
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter("tetherlab: %(message)s"))
    handler._tetherlab_cli = True  # type: ignore[attr-defined]
    log.addHandler(handler)
    log.setLevel(logging.INFO)


def _check_method(method: str) -> None:
    from .scene.data import INTEGRATOR_METHODS

    if method not in INTEGRATOR_METHODS:
        from .scene.keys import _suggest

        hint = _suggest(method, INTEGRATOR_METHODS)
        raise CommandLineError(
            f"argument --method: expected one of {', '.join(INTEGRATOR_METHODS)}; got {method!r}"
            + (f"; {hint}" if hint else "")
        )


def _scene_from(source: str):
    """A scene from a scene file, a run directory or its run.json (the scene the run stored)."""
    from .errors import SceneError
    from .scene import Scene, load_scene

    path = Path(source)
    run_json = path / "run.json" if path.is_dir() else path
    if path.is_dir() and not run_json.is_file():
        raise FileNotFoundError(f"{source!r} is a directory without a run.json: give a scene file (TOML), "
                                f"a run directory or its run.json")  # fmt: skip
    if run_json.name.endswith(".json") and run_json.is_file():
        import json

        try:
            record = json.loads(run_json.read_text())
        except ValueError as exc:
            raise SceneError("", "a run.json written by `tetherlab run`", f"not JSON ({exc})", source=str(run_json)) from None
        if not isinstance(record, dict) or not isinstance(record.get("scene"), dict):
            raise SceneError("", "a run.json written by `tetherlab run` (with its 'scene')", "no scene in it",
                             source=str(run_json))  # fmt: skip
        return Scene.from_dict(record["scene"], source=str(run_json))
    return load_scene(path)


def _default_out(scene) -> Path:
    """runs/<scene name>, or runs/<scene name>-2, -3 ... when that directory already holds a run."""
    base = Path("runs") / scene.name
    out, k = base, 1
    while (out / "run.json").exists():
        k += 1
        out = base.with_name(f"{scene.name}-{k}")
    return out


def _fmt_time(t_s: float) -> str:
    from .regime import format_time

    return format_time(t_s)


def stop_reason(record: dict) -> str:
    """Why a run ended, in words ("200 km reached at 38.4 d", "end of the duration at 10 orbits")."""
    s = record.get("stats", {}) or {}
    t_end = record.get("t_s")
    by = s.get("stopped_by")
    scene = record.get("scene", {}) or {}
    if not record.get("ok", record.get("status") == 0):
        return f"failed: {record.get('message', '')}"
    if by == "stop.altitude":
        alt = (scene.get("stop") or {}).get("altitude", "the stop altitude")
        try:  # the stored scene says "200000.0 m": a reader thinks in km
            value, unit = str(alt).split()
            if unit == "m":
                alt = f"{float(value) / 1e3:.6g} km"
        except ValueError:
            pass
        when = f" at {_fmt_time(float(t_end))}" if t_end is not None else ""
        return f"stop altitude {alt} reached{when}"
    if by and by.startswith("inextensible."):
        from .pipeline import inextensible_stop_text

        return inextensible_stop_text(by, float(t_end) if t_end is not None else float("nan"))
    if by:
        return f"stopped by event {by}" + (f" at {_fmt_time(float(t_end))}" if t_end is not None else "")
    return f"end of the duration ({scene.get('duration', '?')})" + (
        f" at {_fmt_time(float(t_end))}" if t_end is not None else ""
    )


def _run(args) -> int:
    """``tetherlab run SCENE [--out DIR]`` or ``tetherlab run --resume DIR``."""
    t0 = time.perf_counter()
    _enable_notices(args.quiet)
    from . import _jit
    from .errors import SceneError
    from .runstore import Interrupted, RunDirError, resume_dir, run_to_dir

    progress = None if not args.quiet else False
    try:
        if args.method:
            _check_method(args.method)
        if args.resume:
            if args.scene or args.out or args.method or args.from_run:
                raise CommandLineError("--resume DIR continues the run stored in DIR: give no scene, --out, --method or --from")
            out = Path(args.resume)
            _jit.announce_compilation()
            record = resume_dir(out, progress=progress, checkpoint_s=args.checkpoint_every)
        else:
            if not args.scene:
                raise CommandLineError("give a scene file (or a run directory or run.json to run again), or --resume DIR")
            scene = _scene_from(args.scene)
            if args.method:
                scene = scene.replace(**{"integrator.method": args.method})
            out = Path(args.out) if args.out else _default_out(scene)
            if args.from_run:
                if Path(args.from_run).resolve() == out.resolve():
                    raise CommandLineError(f"--from {args.from_run} and --out {out} are one directory: the new phase "
                                           "would overwrite the run it starts from; give it a directory of its own")
                # the scene's inputs from the final state and time of the finished run in DIR
                scene = scene.replace(continue_from=args.from_run)
            _jit.announce_compilation()
            record = run_to_dir(scene, out, progress=progress, checkpoint_s=args.checkpoint_every,
                                part_rows=args.part_rows)  # fmt: skip
    except CommandLineError as exc:
        _say(str(exc))
        return 2
    except (SceneError, FileNotFoundError, RunDirError) as exc:
        _say(str(exc))
        return 2
    except Interrupted as exc:
        print(f"\ntetherlab: {exc}", file=sys.stderr)
        return 130
    except KeyboardInterrupt:  # before the integration started: nothing was computed
        print("\ntetherlab: interrupted before the integration started; nothing was computed", file=sys.stderr)
        return 130
    if not record.get("ok"):
        _say(str(record.get("message")))
    warnings = record.get("warnings", [])
    if not args.quiet:
        print(run_summary(record, out, time.perf_counter() - t0))
    for w in warnings:
        _say(f"warning: {w['text']}")
    return 0 if record.get("ok") else 1


def run_summary(record: dict, out, total_s: float) -> str:
    """The lines printed after a run: outputs, why it stopped, the work and where the time went.

    The times add up: total = set-up (imports, loading, the initial state; on a resume reading the
    checkpoint) + compiling the integrator kernel + integrating and writing, all of this session.
    """
    s = record.get("stats", {}) or {}
    name = record.get("scene", {}).get("name", "run")
    session = float(s.get("session_wall_s", s.get("wall_s", 0.0)))
    compile_s = float(s.get("compile_s", 0.0))
    setup = max(total_s - session, 0.0)
    lines = [
        f"{name}: {record.get('rows_done')} outputs to {out}/; {stop_reason(record)}",
        f"  steps {s.get('n_accepted')} (+{s.get('n_rejected')} rejected), rhs {s.get('n_rhs')}, jac {s.get('n_jac')}",
        f"  time: set-up {setup:.2f} s + compile {compile_s:.2f} s + integrate and write {session - compile_s:.2f} s"
        f" = total {setup + session:.2f} s",
    ]
    if record.get("reel"):  # a deployment: its phases between births and retirements (reelstore.py)
        kinds = [c["change"] for c in record.get("changes", [])]
        lines.insert(1, f"  {len(record.get('phases', []))} phases: {kinds.count('birth')} births, "
                        f"{kinds.count('retire')} retirements" + ("; the whole tether retrieved" if "retrieved" in kinds
                                                                   else ""))  # fmt: skip
    if int(record.get("segments", 1) or 1) > 1:  # a resumed run: the sessions before this one count too
        lines.append(f"  (integration over every session of this run so far, {record['segments']} sessions: "
                     f"{float(s.get('wall_s', 0.0)):.2f} s)")  # fmt: skip
    return "\n".join(lines)


def _validate(args) -> int:
    """``tetherlab validate SCENE``: load and check, estimate memory and disk, exit."""
    from .errors import SceneError
    from .resources import GiB, available_memory_bytes, check_scene, estimate

    try:
        if args.method:
            _check_method(args.method)
        scene = _scene_from(args.scene)
        if args.method:
            scene = scene.replace(**{"integrator.method": args.method})
        check_scene(scene, outputs_in_memory=False, out_dir=args.out or Path("runs") / scene.name)
    except CommandLineError as exc:
        _say(str(exc))
        return 2
    except (SceneError, FileNotFoundError) as exc:
        _say(str(exc))
        return 2
    need = estimate(scene)
    try:
        duration = f"{scene.duration_seconds():.6g} s"
    except ValueError:
        duration = "resolved when the initial state is laid out"
    rods = sum(t.rods for t in scene.tethers)
    lines = [
        f"{scene.name}: valid scene ({scene.source})",
        f"  {len(scene.bodies)} bodies, {len(scene.tethers)} tethers, {rods} rods; effects: "
        + (", ".join(e.name for e in scene.effects) or "none (free space)"),
        f"  duration {duration}; integrator {scene.integrator.method}, rtol {scene.integrator.rtol:g}, "
        f"formulation {scene.integrator.formulation}"
        + (f", error scale {scene.integrator.error_scale}" if scene.integrator.error_scale != "rod" else ""),
    ]
    if need is not None:
        mem = need.rows * need.row_bytes_memory + need.fixed_bytes
        disk = need.rows * need.row_bytes_disk
        lines += [
            f"  state: {need.state_len} floats; outputs: {need.rows} rows ({need.output_key})",
            f"  memory: {mem / GiB:.3g} GiB with every output in memory (tetherlab.simulate), of "
            f"{available_memory_bytes() / GiB:.3g} GiB available; disk: {disk / GiB:.3g} GiB for 'tetherlab run'",
            f"  cost per right-hand side grows linearly with the rods ({rods}); the number of steps is "
            f"known only by running: --probe SECONDS measures the rate on the start of the run",
        ]
    lines += reel_lines(scene, need)
    from .regime import light_rods

    lines += [f"  warning: {w['text']}" for w in light_rods(scene)]
    print("\n".join(lines), flush=True)
    if args.probe:
        _enable_notices(False)
        try:
            print(probe_cost(scene, args.probe))
        except (SceneError, ValueError) as exc:
            _say(f"the probe run failed: {exc}")
            return 2
    return 0


def _longest_deployed_m(tether, duration_s: float | None, from_s: float = 0.0) -> float:
    """The most line a reel tether has out from ``from_s`` to the end of the run: the whole line
    under a spool law (its length is state, known only by running), else the prescribed law's
    largest length."""
    from .scene.reels import length_at

    r = tether.reel
    line = tether.length_m + r.stored_length_m
    if r.spool is not None or duration_s is None:
        return line
    # the laws are monotone except a table, whose spline is sampled (as deployment.check_law does)
    ts = ([from_s + (duration_s - from_s) * k / 200 for k in range(201)] if r.law == "table"
          else [from_s, duration_s])  # fmt: skip
    return min(line, max(length_at(r, tether.length_m, t) for t in ts))


def reel_lines(scene, need) -> list[str]:
    """What ``validate`` says of a scene with reels: per reel its law and rods now and at most, and
    the memory and disk of the largest layout (the rod count, so the state, changes at each birth;
    the other lines of ``validate`` describe the first phase's)."""
    reels = [t for t in scene.tethers if t.reel is not None]
    if not reels:
        return []
    from .resources import GiB, estimate

    try:
        duration_s = scene.duration_seconds()
    except ValueError:
        duration_s = None
    lines, changes = [], {}
    for t in reels:
        r = t.reel
        most = _longest_deployed_m(t, duration_s)
        rods_most = max(t.rods, 1 + max(0, math.ceil((most - r.birth_length_m) / r.rod_length_m)))
        how = "by events of the run (a spool law)" if r.spool is not None else "at times the law gives"
        lines.append(f"  reel {t.name}: law {r.law}, exit {r.exit}; {t.length_m:.6g} m out of a "
                     f"{t.length_m + r.stored_length_m:.6g} m line, rods of {r.rod_length_m:.6g} m: {t.rods} rods "
                     f"now, up to {rods_most} with {most:.6g} m out (births and retirements {how})")  # fmt: skip
        if rods_most > t.rods:
            changes[f"tethers.{t.name}.length"] = f"{most!r} m"
    if need is not None and changes:
        try:
            big = estimate(scene.replace(**changes))
        except Exception:  # noqa: BLE001 -- an estimate only: the scene itself was checked above
            big = None
        if big is not None:
            lines.append(f"  with the most rods: state {big.state_len} floats; memory "
                         f"{(big.rows * big.row_bytes_memory + big.fixed_bytes) / GiB:.3g} GiB, disk "
                         f"{big.rows * big.row_bytes_disk / GiB:.3g} GiB at most (each phase adds a row at its start)")
    return lines


class _ProbeDone(Exception):
    pass


def probe_cost(scene, wall_budget_s: float) -> str:
    """Integrate ``scene`` for about ``wall_budget_s`` seconds of wall-clock time (after the
    kernels are compiled), then extrapolate: simulated seconds per wall-clock second, and the
    whole run's integration time at that rate. Stiffness that appears later in the run (a tether
    going slack, a collapse, a lower orbit) is not seen by the probe."""
    from . import _jit
    from .pipeline import integrate_prepared, prepare

    _jit.announce_compilation()
    prep = prepare(scene)
    p = prep.model.fresh_params()
    t_end = float(prep.t_out[-1])
    reel = any(t.reel is not None for t in scene.tethers)
    sink = None
    if reel:  # the tables each phase ends with compile at the first birth: before the clock starts
        import numpy as np

        from .deployment import _rows

        _rows(prep.model, np.array([float(prep.t0_s)]), np.asarray(prep.y0, float)[None, :])
    seen: list[tuple[float, float]] = []
    start = [None]

    def progress(t: float) -> None:
        now = time.perf_counter()
        if start[0] is None:  # the first chunk ends after the compilation: measure from there
            start[0] = (now, float(t))
            return
        seen.append((now, float(t)))
        if now - start[0][0] >= wall_budget_s:
            raise _ProbeDone

    try:
        if reel:  # the phase loop itself: births and retirements (a model rebuilt, a remap) count in the rate
            from .deployment import MemoryPhases, run_phases

            class _Probe(MemoryPhases):  # keeps the loop's state: the rods and changes so far
                loop = None

                def start_phase(self, loop: dict) -> None:
                    self.loop = loop

            sink = _Probe(scene)
            status, message, _, _ = run_phases(scene, sink, progress=progress)
            if status != 0:
                raise ValueError(message)
        else:
            integrate_prepared(prep, p, progress)
        finished = True
    except _ProbeDone:
        finished = False
    if finished or not seen:
        return f"  probe: the whole run ({_fmt_time(t_end)} simulated) took less than the probe's {wall_budget_s:g} s"
    (w0, t0), (w1, t1) = start[0], seen[-1]
    rate = (t1 - t0) / (w1 - w0)
    left = (t_end - t1) / rate if rate > 0 else float("inf")
    total = (w1 - w0) + left
    text = (f"  probe: {_fmt_time(t1 - t0)} simulated in {w1 - w0:.1f} s of wall time ({rate:.4g} s simulated per "
            f"second); the whole run ({_fmt_time(t_end)}) would integrate in about {_fmt_time(total)} at this rate "
            f"(stiffness later in the run is not seen by the probe)")
    if reel and sink.loop is not None:
        # a step's cost grows with the rods (the right-hand side linearly): the rest of the run at the
        # most rods it can reach bounds what the births still to come add (more steps are not seen)
        kinds = [c["change"] for c in sink.loop["changes"]]
        now = sum(sink.loop["rods"].values())
        try:
            duration_s = scene.duration_seconds()
        except ValueError:
            duration_s = None
        # (a reel's rods now are not known here: the count at the longest line from t1 on, at least one)
        most = sum(1 + max(0, math.ceil((_longest_deployed_m(t, duration_s, t1) - t.reel.birth_length_m)
                                        / t.reel.rod_length_m)) for t in scene.tethers if t.reel)
        most += sum(t.rods for t in scene.tethers if t.reel is None)
        now += sum(t.rods for t in scene.tethers if t.reel is None)
        text += (f"; within the probe {kinds.count('birth')} births and {kinds.count('retire')} retirements, "
                 f"their cost counted, {now} rods at its end")
        if most > now:
            upper = (w1 - w0) + left * most / now
            text += (f"; with up to {most} rods later, each step dearer in proportion: up to about "
                     f"{_fmt_time(upper)}")
    return text


def _plot(args) -> int:
    from .plots import PlotError, plot_run

    try:
        files = plot_run(args.dir, out_dir=args.out)
    except PlotError as exc:
        _say(str(exc))
        return 2
    for f in files:
        print(f)
    return 0


def _sweep(args) -> int:
    from .sweep import main as sweep_main

    argv = [args.study, "--out", args.out]
    if args.scheduler:
        argv += ["--scheduler", args.scheduler]
    if args.workers is not None:
        argv += ["--workers", str(args.workers)]
    if args.quiet:
        argv.append("--quiet")
    try:
        return sweep_main(argv)
    except (FileNotFoundError, ValueError) as exc:
        _say(str(exc))
        return 2


def parser() -> argparse.ArgumentParser:
    from . import __version__

    ap = argparse.ArgumentParser(prog="tetherlab", description=DESCRIPTION, epilog=EPILOG)
    ap.add_argument("--version", action="version", version=f"tetherlab {__version__}")
    sub = ap.add_subparsers(dest="cmd", required=True, metavar="{run,validate,plot,sweep}")
    r = sub.add_parser("run", help="integrate a scene and write its results as it goes",
                       description="Integrate a scene and write its results as it goes. SCENE is a scene file "
                       "(TOML), or a run directory or its run.json to run that scene again.")  # fmt: skip
    r.add_argument("scene", nargs="?", help="scene file (TOML), or a run directory / run.json to run again")
    r.add_argument("--out", help="output directory (Parquet datasets timeseries/ and diagnostics/, run.json); "
                   "default runs/NAME, NAME the scene's name (runs/NAME-2 ... when taken)")  # fmt: skip
    r.add_argument("--resume", metavar="DIR", help="continue the interrupted run stored in DIR")
    r.add_argument("--from", dest="from_run", metavar="DIR",
                   help="start from the final state and time of the finished run in DIR (a mission in phases; "
                        "sets the scene's continue_from)")
    r.add_argument("--method", help="override the scene's integrator method (dop853, vern9, radau5, abm, "
                   "scipy:DOP853, scipy:Radau, scipy:LSODA, scipy:BDF)")  # fmt: skip
    r.add_argument("--quiet", action="store_true", help="no progress bar, no summary")
    r.add_argument("--checkpoint-every", type=float, default=5.0, metavar="SECONDS",
                   help="wall-clock seconds between checkpoints (default 5)")
    r.add_argument("--part-rows", type=int, default=None, metavar="N",
                   help="output rows per Parquet part (default: about 64 MiB of columns)")
    r.set_defaults(func=_run)
    v = sub.add_parser("validate", help="load and check a scene, estimate the memory and disk it needs, and exit")
    v.add_argument("scene", help="scene file (TOML), or a run directory / run.json")
    v.add_argument("--method", help="check with this integrator method instead of the scene's")
    v.add_argument("--out", help="the output directory whose free disk space is checked (default runs/NAME)")
    v.add_argument("--probe", type=float, default=0.0, metavar="SECONDS",
                   help="also integrate for about SECONDS of wall-clock time and extrapolate the run's integration "
                   "time (compiles the kernels first if needed)")  # fmt: skip
    v.set_defaults(func=_validate)
    p = sub.add_parser("plot", help="draw PNG figures of a run directory")
    p.add_argument("dir", help="a directory written by 'tetherlab run'")
    p.add_argument("--out", help="where to put the PNGs (default: DIR)")
    p.set_defaults(func=_plot)
    s = sub.add_parser("sweep", help="run a study file (grids of scene changes) in parallel, resumable",
                       description="Run a study file: each case is a scene, a summary function and a grid of "
                       "scene changes; results are cached by scene hash, so an interrupted sweep resumes. "
                       "The study format is in docs/studies.md.")  # fmt: skip
    s.add_argument("study", help="study file (TOML, docs/studies.md)")
    s.add_argument("--out", required=True, help="output directory (one CSV per case, the run cache under cache/)")
    s.add_argument("--scheduler", help="Dask scheduler address (tcp://host:8786); default: local processes")
    s.add_argument("--workers", type=int, help="local worker processes (default: all cores)")
    s.add_argument("--quiet", action="store_true", help="no progress bars")
    s.set_defaults(func=_sweep)
    return ap


def main(argv=None) -> int:
    args = parser().parse_args(argv)
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
