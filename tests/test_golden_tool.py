"""tests/golden.py, the bit-for-bit regression tool: scene names after the file restrict record
and check to those scenes, an unknown name is refused before anything runs.  The scenes' runs are
replaced by a stand-in (the tool's selection and comparison are under test, not the simulator)."""

from __future__ import annotations

import numpy as np
import pytest

from . import golden


@pytest.fixture
def fake_runs(monkeypatch):
    ran = []
    values = {}

    def run(path):
        ran.append(path.stem)
        return {f"{path.stem}|ts|x": values.get(path.stem, np.array([1.0, 2.0]))}

    monkeypatch.setattr(golden, "_run", run)
    return ran, values


def test_check_runs_and_compares_only_the_named_scenes(tmp_path, fake_runs, capsys):
    ran, values = fake_runs
    rec = tmp_path / "g.npz"
    assert golden.main(["golden.py", "record", str(rec)]) == 0
    assert ran == [p.stem for p in golden.SCENES] and len(ran) > 2
    a, b, c = ran[:3]
    ran.clear()
    values[c] = np.array([1.0, 3.0])  # a scene not named differs: not reported
    assert golden.main(["golden.py", "check", str(rec), b, a]) == 0
    assert ran == [b, a]
    assert "2 recorded columns of 2 scenes, 0 differ" in capsys.readouterr().out
    values[a] = np.array([1.0, np.nan])  # a named one differs: reported, exit 1
    assert golden.main(["golden.py", "check", str(rec), a]) == 1
    out = capsys.readouterr().out
    assert f"{a}|ts|x: differs (1 of 2 values NaN in one only; max |diff| 0, max |value| 1)" in out
    assert "1 recorded columns of 1 scenes, 1 differ" in out


def test_an_unknown_scene_name_is_refused_before_anything_runs(tmp_path, fake_runs, capsys):
    ran, _ = fake_runs
    assert golden.main(["golden.py", "check", str(tmp_path / "g.npz"), "reel-hub-spoke", "no-such-scene"]) == 2
    assert ran == []
    out = capsys.readouterr().out
    assert "unknown scene name(s) 'no-such-scene': expected file stems of studies/scenes/*.toml" in out


def test_run_as_a_script_it_imports_the_package_beside_it():
    # a worktree sharing another checkout's venv: without its own root first on the path, the
    # tool imported the installed checkout's tetherlab and compared that one with itself
    import subprocess
    import sys

    code = (f"import runpy; runpy.run_path({str(golden.ROOT / 'tests' / 'golden.py')!r}, run_name='golden'); "
            "import tetherlab; print(tetherlab.__file__)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd="/")
    assert out.stdout.strip() == str(golden.ROOT / "tetherlab" / "__init__.py")
