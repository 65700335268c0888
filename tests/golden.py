"""Bit-for-bit regression of every shipped scene: record the outputs once, check them after a change.

A developer's tool, not a CI gate: machine code (and so the last bit) may differ between CPU
generations, so the record lives outside the repository and is compared on the machine that made it.

    python tests/golden.py record /tmp/golden.npz     # before the change
    python tests/golden.py check  /tmp/golden.npz     # after it: every column of every scene

Each scene runs for a short stretch (``SHORT``: a few outputs, capped duration) so the whole set
takes a minute or two once compiled; the stretch is the same in both runs, which is all a
bit-for-bit comparison needs.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SCENES = sorted((ROOT / "studies" / "scenes").glob("*.toml"))

#: per-scene duration override for the short stretch (the scene's own when shorter)
SHORT_S = {"stiefel-scheifele": "20 d", "stiefel-example1": "20 d",
           # a reel law's stages must start within the run: the short stretch reaches the last one
           "reel-yes2-like": "2.05 orbits", "reel-retrieval-tension": "3.8 orbits"}
DEFAULT_S = 600.0


def _run(path: Path) -> dict[str, np.ndarray]:
    import tetherlab

    scene = tetherlab.load_scene(path)
    try:
        dur = scene.duration_seconds()
    except ValueError:
        dur = scene.duration_s
    changes = {"output": {"count": 6}}
    if scene.name in SHORT_S:
        changes["duration"] = SHORT_S[scene.name]
    elif dur is None or dur > DEFAULT_S:
        changes["duration"] = f"{DEFAULT_S} s"
    scene = scene.replace(**changes)
    res = tetherlab.simulate(scene, progress=False, raise_on_failure=False)
    if hasattr(res, "phases"):  # a scene with reels: its phases' rows in order, and the reel table
        import pandas as pd

        frames = ((pd.concat([ph.timeseries for ph in res.phases], ignore_index=True), "ts"),
                  (pd.concat([ph.diagnostics for ph in res.phases], ignore_index=True), "dg"), (res.reel, "reel"))
    else:
        frames = ((res.timeseries, "ts"), (res.diagnostics, "dg"))
    out = {}
    for frame, tag in frames:
        for col in frame.columns:
            vals = np.asarray(frame[col])
            if vals.dtype.kind in "fiub":
                out[f"{path.stem}|{tag}|{col}"] = vals.astype(float)
    return out


def main(argv: list[str]) -> int:
    if len(argv) != 3 or argv[1] not in ("record", "check"):
        print(__doc__)
        return 2
    mode, target = argv[1], Path(argv[2])
    names = [a for a in sys.argv[3:]] or None
    got: dict[str, np.ndarray] = {}
    for path in SCENES:
        try:
            got.update(_run(path))
        except Exception as exc:  # a scene that no longer runs is a difference too
            got[f"{path.stem}|error"] = np.array([0.0])
            print(f"{path.stem}: {type(exc).__name__}: {exc}")
    if mode == "record":
        np.savez(target, **got)
        print(f"recorded {len(got)} columns of {len(SCENES)} scenes into {target}")
        return 0
    # rhs-call counts are not compared: the driver sizes its progress chunks from the wall clock,
    # and a chunk boundary may cost an evaluation without changing a bit of the solution
    ref = {k: v for k, v in np.load(target).items() if "|stats|" not in k}
    bad = 0
    for key in sorted(set(ref) | set(got)):
        a, b = ref.get(key), got.get(key)
        if a is None or b is None:
            print(f"{key}: {'new' if a is None else 'missing'}")
            bad += 1
            continue
        if a.shape != b.shape or not np.array_equal(a, b, equal_nan=True):
            diff = np.nanmax(np.abs(a - b)) if a.shape == b.shape else float("nan")
            scale = np.nanmax(np.abs(a)) if a.size else 0.0
            print(f"{key}: differs (max |diff| {diff:.3g}, max |value| {scale:.3g})")
            bad += 1
    print(f"{len(ref)} recorded columns, {bad} differ")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
