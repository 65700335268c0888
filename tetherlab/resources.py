"""Will a run fit this machine?  Memory and disk a scene needs, estimated before anything is built.

A valid scene can ask for more than the machine has (``output.count = 200000000``, ``rods =
200000``).  Without a check, numpy fails deep inside the pipeline with a bare MemoryError (or the
machine starts to swap).  :func:`check_scene` estimates the dominant allocations from the scene
alone -- no model, no initial state, no output-time array is built first -- and refuses with a
:class:`~tetherlab.errors.SceneError` that names the key to change, what the run needs and what
the machine has.

What is counted (8 bytes a float; n = 6 (1 + rods) is the Cowell state length):

* per output row, all outputs in memory (``simulate``): the integrator's output buffer (n), the
  diagnostics arrays (2 per rod, 3 per joint, 16 global), node positions and velocities
  (6 per joint), the time-series and diagnostics columns twice (the column arrays and the
  DataFrame built from them) and three copies of the output times;
* per output row, streamed to a directory (``tetherlab run``, tetherlab/runstore.py): in memory
  only the three copies of the output times; on disk the raw state (n), the time-series and the
  diagnostics columns (Parquet, counted uncompressed: an upper bound);
* once: RADAU5's Jacobian and its two LU factors (n^2 + (n/2)^2 + 2 (n/2)^2 floats, the
  complex one counted twice) and the dense Jacobian of the relative-equilibrium Newton solve
  (``orbit.motion = "equilibrium"``: (rods + 1)^2, twice).

It is an estimate of the largest terms, not of every temporary: a refusal is certain to be
right when the need is well above what the machine has; a run near the limit may still fail.
"""

from __future__ import annotations

import math
import os
import shutil
from dataclasses import dataclass
from pathlib import Path

from .errors import SceneError

GiB = float(2**30)
#: Rows of derived output (time series, diagnostics) converted and written at once by a streamed
#: run, at most (tetherlab/runstore.py); their memory is counted once, not per output.
STREAM_BATCH_BYTES = 64 * 2**20


@dataclass(frozen=True)
class Need:
    rows: int  # output rows
    output_key: str  # the scene key that sets the number of outputs
    state_len: int  # n
    row_bytes_memory: int  # per output row held in memory when outputs are kept in memory
    row_bytes_disk: int  # per output row written to disk by a streamed run
    fixed_bytes: int  # independent of the number of outputs


def available_memory_bytes() -> int:
    """Memory a new allocation can get without swapping (psutil's 'available'; the free pages
    if psutil is missing)."""
    try:
        import psutil

        return int(psutil.virtual_memory().available)
    except ImportError:  # pragma: no cover - psutil comes with dask[distributed]
        return int(os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))


def free_disk_bytes(path) -> int:
    """Free space on the file system that holds ``path`` (or its nearest existing parent)."""
    p = Path(path).resolve()
    while not p.exists():
        p = p.parent
    return int(shutil.disk_usage(p).free)


def output_rows(scene) -> tuple[int, str] | None:
    """Number of output rows the scene asks for and the key that sets it, without building the
    output times (None when the duration cannot be resolved yet: prepare() says why)."""
    out = scene.output
    if out.count is not None:
        return int(out.count), "output.count"
    if out.times_s is not None:
        return len(out.times_s) + 1, "output.times"
    try:
        duration = scene.duration_seconds()
    except ValueError:
        return None
    if not (math.isfinite(duration) and duration >= 0):
        return None
    return int(math.floor(duration / out.step_s + 1e-9)) + 2, "output.step"


def scene_layout(scene):
    """The StateLayout (model/state.py) the scene's model will have, from the scene's counts alone
    (the model is built after this check): rods per tether, the other roots of a forest (one per
    group of bodies joined by tethers, past the first), each rigid body with its wheels."""
    from .model.state import StateLayout

    tethers = list(scene.tethers)
    other = tuple(range(1 + len(tethers), len(scene.bodies)))  # kernel order: root 0, the tethers' ends, the rest
    # (the rigid bodies in file order: the same sizes as the kernel's order)
    rigid = tuple((b, len(body.rigid.wheels)) for b, body in enumerate(scene.bodies) if body.rigid is not None)
    return StateLayout(rods=tuple(t.rods for t in tethers), other_roots=other, rigid=rigid)


def estimate(scene) -> Need | None:
    rows_key = output_rows(scene)
    if rows_key is None:
        return None
    rows, okey = rows_key
    tethers = list(scene.tethers)
    nr = sum(t.rods for t in tethers)
    nj = sum(t.rods + 1 for t in tethers)
    n = scene_layout(scene).size
    ts_cols = 1 + 6 + sum((6 if scene.body(t.to_body).mass_kg > 0 else 0) + 3 * (t.rods + 1) + 2 * t.rods
                          + (t.rods + 1) for t in tethers)  # fmt: skip  # not a state index: Result.from_run's columns
    dg_cols = 18 + 9 + 2 * len(tethers)  # (+ altitude, five elements, latitude, longitude, height)
    row_mem = 8 * (n + 2 * nr + 3 * nj + 16 + 6 * nj + 2 * ts_cols + 2 * dg_cols + 3)
    row_disk = 8 * (n + ts_cols + dg_cols)
    fixed = {}
    if scene.integrator.method == "radau5":
        half = n // 2
        fixed["integrator.method"] = 8 * (n * n + half * half + 4 * half * half)
    if scene.orbit is not None and scene.orbit.motion == "equilibrium":
        fixed["orbit.motion"] = 8 * 2 * (nr + 1) ** 2
    elif scene.orbit is not None and scene.orbit.motion == "quasi-static":
        fixed["orbit.motion"] = 8 * 2 * (3 * nr) ** 2  # the 3n x 3n finite-difference Jacobian, twice
    return Need(rows, okey, n, row_mem, row_disk, sum(fixed.values()))


def _gib(x: float) -> str:
    return f"{x / GiB:.3g} GiB"


def check_scene(scene, *, outputs_in_memory: bool = True, out_dir=None,
                available: int | None = None, free_disk: int | None = None) -> Need | None:  # fmt: skip
    """Refuse (SceneError) a run whose estimated memory, or disk when streamed to ``out_dir``,
    exceeds what the machine has.  Returns the estimate."""
    need = estimate(scene)
    if need is None:
        return None
    avail = available_memory_bytes() if available is None else int(available)
    value = _key_value(scene, need.output_key)
    tethers = list(scene.tethers)
    rods_key = f"tethers.{max(tethers, key=lambda t: t.rods).name}.rods" if tethers else None
    if outputs_in_memory:
        per_row = need.row_bytes_memory
        total = need.fixed_bytes + need.rows * per_row
        where = "in memory"
    else:
        per_row = 24  # the output times (three copies); the rows themselves stream to disk
        total = need.fixed_bytes + need.rows * per_row + min(need.rows, 1) * need.row_bytes_memory
        where = "in memory while streaming outputs to disk"
    if total > avail:
        # Blame the outputs when even the smallest row (one rod) would not fit that many times;
        # else the size of the system (the rods), whose every output row and fixed term grow.
        small_row = 8 * 40 if outputs_in_memory else 24
        if need.rows * small_row > avail or rods_key is None:
            key, got = need.output_key, f"{value}: {need.rows} output rows x {per_row} bytes"
        else:
            key = rods_key  # the rods set n, hence every per-row and fixed term
            got = (f"{_key_value(scene, key)} (state of {need.state_len} floats; {need.rows} output rows x "
                   f"{per_row} bytes + {_gib(need.fixed_bytes)} of solver workspace)")  # fmt: skip
        hint = (
            "fewer outputs (output.count/step/times) or fewer rods; `tetherlab run` streams outputs to "
            "disk instead of holding them in memory" if outputs_in_memory else "fewer outputs or fewer rods"
        )
        raise SceneError(
            key, f"a run that fits this machine: it needs about {_gib(total)} {where}, "
            f"the machine has {_gib(avail)} available", got, hint=hint,
        )  # fmt: skip
    if not outputs_in_memory and out_dir is not None:
        disk = need.rows * need.row_bytes_disk
        free = free_disk_bytes(out_dir) if free_disk is None else int(free_disk)
        if disk > free:
            raise SceneError(
                need.output_key, f"outputs that fit the disk of {out_dir}: they need about {_gib(disk)} "
                f"({need.rows} rows x {need.row_bytes_disk} bytes, uncompressed), the disk has {_gib(free)} free",
                str(value), hint="fewer outputs (output.count/step/times), or another --out",
            )  # fmt: skip
    return need


def _key_value(scene, key: str):
    if key == "output.count":
        return f"output.count = {scene.output.count}"
    if key == "output.step":
        return f"output.step = {scene.output.step_s} s over {scene.duration_seconds():.6g} s"
    if key == "output.times":
        return f"output.times with {len(scene.output.times_s)} times"
    if key.startswith("tethers.") and key.endswith(".rods"):
        return f"rods = {scene.tether(key.split('.')[1]).rods}"
    if key == "integrator.method":
        return repr(scene.integrator.method)
    if key == "orbit.motion":
        return repr(scene.orbit.motion)
    return key
