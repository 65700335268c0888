"""Starting a scene from the final state of a finished run (``continue_from``, ``tetherlab run
--from DIR``): a mission in phases, each with its own inputs (a commanded torque, a new effect).

The run directory (docs/runs.md) holds every output row as a Cowell state in ``states.npy``, the
names of its blocks in ``run.json`` (``state_blocks``) and the time its last row was reached
(``t_s``).  The new scene starts there: time continues from that t (its ``duration`` and output
step count from it), its state is that row, bit for bit, and the scene's own initial-state keys
(``[orbit]``, tether shapes, attitudes, wheel speeds) are checked as usual but not used.  A run
split in two phases with the same inputs therefore continues exactly as one run that lands a
step on the split time and restarts there, which is what a breakpoint does (the corner or jump of
a time table, docs/integrators.md section 14): tests/test_continuation.py compares them bit for
bit.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import SceneError

KEY = "continue_from"


@dataclass(frozen=True)
class FinalState:
    """The last output row of a run: its time, its Cowell state and the state's named blocks."""

    run_dir: str
    t_s: float
    y: np.ndarray
    blocks: tuple  # ((name, start, stop), ...) as run.json's state_blocks


def final_state(run_dir: str) -> FinalState:
    """The final state of the finished run in ``run_dir``; a SceneError naming ``continue_from``
    when it is not a run directory, the run did not end (interrupted: resume it; failed: its last
    state is not one to continue from) or its files disagree."""
    d = Path(run_dir)
    rec_path = d / "run.json"
    if not rec_path.is_file():
        raise SceneError(KEY, "a directory written by `tetherlab run` (with run.json and states.npy)",
                         f"{str(d)!r} ({'no such directory' if not d.is_dir() else 'no run.json in it'})")  # fmt: skip
    try:
        rec = json.loads(rec_path.read_text())
    except (OSError, ValueError) as exc:
        raise SceneError(KEY, "a readable run.json", f"{str(rec_path)!r} ({exc})") from None
    state = rec.get("state")
    if state != "complete":
        why = {
            "interrupted": "an interrupted run: finish it first with `tetherlab run --resume DIR`",
            "running": "a run still running (or killed: `tetherlab run --resume DIR` finishes it)",
            "failed": "a failed run: its last state is where it broke down, not one to continue from",
        }.get(state, f"state {state!r}")
        raise SceneError(KEY, "a complete run", f"{str(d)!r}: {why}")
    rows = int(rec.get("rows_done", 0))
    blocks = tuple((str(n), int(a), int(b)) for n, a, b in rec.get("state_blocks", []))
    try:
        states = np.load(d / "states.npy", mmap_mode="r")
    except (OSError, ValueError) as exc:
        raise SceneError(KEY, "a run directory with its states.npy", f"{str(d)!r} ({exc})") from None
    if rows < 1 or states.ndim != 2 or states.shape[0] < rows or states.shape[1] != int(rec.get("state_length", -1)):
        raise SceneError(KEY, "a run whose states.npy holds the rows run.json counts",
                         f"{str(d)!r}: states {states.shape}, rows_done {rows}, state_length {rec.get('state_length')}")  # fmt: skip
    y = np.array(states[rows - 1], dtype=np.float64)
    if not np.all(np.isfinite(y)):
        raise SceneError(KEY, "a run whose final state is finite", f"{str(d)!r}: non-finite values in its last row")
    return FinalState(str(d), float(rec["t_s"]), y, blocks)


def check_layout(fs: FinalState, layout) -> None:
    """The run's state blocks must be the scene's (model/state.py::StateLayout.blocks): the same
    names, in the same places; otherwise a SceneError listing the first difference."""
    mine = tuple((b.name, int(b.start), int(b.stop)) for b in layout.blocks())
    if mine == fs.blocks:
        return
    diff = next(((a, b) for a, b in zip(mine, fs.blocks) if a != b), None)
    if diff is None:
        detail = f"{len(mine)} blocks in the scene, {len(fs.blocks)} in the run"
    else:
        (n1, a1, b1), (n2, a2, b2) = diff
        detail = f"the scene's {n1} [{a1}:{b1}] against the run's {n2} [{a2}:{b2}]"
    raise SceneError(
        KEY,
        f"a run with this scene's state layout ({layout.size} values: "
        + ", ".join(f"{n} [{a}:{b}]" for n, a, b in mine) + ")",
        f"{fs.run_dir!r}, whose states have {fs.blocks[-1][2] if fs.blocks else 0} values ({detail}): the bodies, "
        "tethers, rod counts, rigid bodies and wheels must be those of the run continued",
    )
