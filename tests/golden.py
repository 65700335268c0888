"""Bit-for-bit regression of every shipped scene: record the outputs once, check them after a change.

A developer's tool, not a CI gate: machine code (and so the last bit) may differ between CPU
generations, so the record lives outside the repository and is compared on the machine that made it.

    python tests/golden.py record /tmp/golden.npz     # before the change
    python tests/golden.py check  /tmp/golden.npz     # after it: every column of every scene
    python tests/golden.py check  /tmp/golden.npz reel-hub-spoke catenary   # those scenes only

Scene names (file stems of studies/scenes/*.toml) after the file restrict either mode to those
scenes; an unknown name is an error (exit 2) before anything runs.  A check of named scenes
compares only their columns, so a record of every scene serves any subset.

Each scene runs for a short stretch (``SHORT``: a few outputs, capped duration) so the whole set
takes a minute or two once compiled; the stretch is the same in both runs, which is all a
bit-for-bit comparison needs.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
# Run as a script, Python puts tests/ first on the path, not the checkout: an environment
# installed from another checkout (a git worktree's shared venv) would then compare that
# checkout's package with itself.  The package beside this file is the one under test.
if str(ROOT) not in sys.path[:1]:
    sys.path.insert(0, str(ROOT))
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


def _difference(a: np.ndarray, b: np.ndarray) -> str:
    """How two differing columns differ: shapes, values that became or stopped being NaN, and the
    largest difference of the values finite in both (no warning when there is none)."""
    if a.shape != b.shape:
        return f"shape {a.shape} -> {b.shape}"
    both = np.isfinite(a) & np.isfinite(b)
    out = []
    flips = int(np.count_nonzero(np.isnan(a) != np.isnan(b)))
    if flips:
        out.append(f"{flips} of {a.size} values NaN in one only")
    if both.any():
        out.append(f"max |diff| {np.abs(a[both] - b[both]).max():.3g}, max |value| {np.abs(a[both]).max():.3g}")
    return "; ".join(out) or "infinities differ"


def select(names: list[str]) -> list[Path]:
    """The scene files named (all of them when none is); an unknown name is a ValueError naming
    it and the known ones."""
    if not names:
        return list(SCENES)
    known = {p.stem: p for p in SCENES}
    unknown = [n for n in names if n not in known]
    if unknown:
        raise ValueError(f"unknown scene name(s) {', '.join(map(repr, unknown))}: expected file stems of "
                         f"studies/scenes/*.toml ({', '.join(sorted(known))})")
    return [known[n] for n in dict.fromkeys(names)]


def main(argv: list[str]) -> int:
    if len(argv) < 3 or argv[1] not in ("record", "check"):
        print(__doc__)
        return 2
    mode, target = argv[1], Path(argv[2])
    try:
        paths = select(argv[3:])
    except ValueError as exc:
        print(f"golden.py: {exc}")
        return 2
    got: dict[str, np.ndarray] = {}
    for path in paths:
        try:
            got.update(_run(path))
        except Exception as exc:  # a scene that no longer runs is a difference too
            got[f"{path.stem}|error"] = np.array([0.0])
            print(f"{path.stem}: {type(exc).__name__}: {exc}")
    if mode == "record":
        np.savez(target, **got)
        print(f"recorded {len(got)} columns of {len(paths)} scenes into {target}")
        return 0
    # rhs-call counts are not compared: the driver sizes its progress chunks from the wall clock,
    # and a chunk boundary may cost an evaluation without changing a bit of the solution
    stems = {p.stem for p in paths}
    ref = {k: v for k, v in np.load(target).items() if "|stats|" not in k and k.split("|")[0] in stems}
    bad = 0
    for key in sorted(set(ref) | set(got)):
        a, b = ref.get(key), got.get(key)
        if a is None or b is None:
            print(f"{key}: {'new' if a is None else 'missing'}")
            bad += 1
            continue
        if a.shape != b.shape or not np.array_equal(a, b, equal_nan=True):
            print(f"{key}: differs ({_difference(a, b)})")
            bad += 1
    print(f"{len(ref)} recorded columns of {len(paths)} scenes, {bad} differ")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
