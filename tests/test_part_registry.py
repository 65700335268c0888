"""The part registries (tetherlab/bodies/registry.py, tetherlab/tether/registry.py) and their
generated dispatchers (tetherlab/model/dispatch.py).

* bodies/parts.py and tether/parts.py are what the generator makes of the registries today (so a
  part table edited without regenerating fails here, naming the command);
* the generator refuses a table or a part module it cannot dispatch, naming what is wrong;
* a new part type is its own module plus one registration line: a toy part (a point body whose
  mass counts twice, written as its own module) is added to a copy of the package that way,
  regenerated, and run; its right-hand side and energy shares are bit for bit those of a point
  body of twice the mass, and differ from a point body of the same mass (so the dispatch reached
  the toy's functions, not the default's).
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from tetherlab.bodies import registry
from tetherlab.bodies.registry import PartType
from tetherlab.model import dispatch
from tetherlab.tether import registry as tether_registry

from .helpers import ROOT


@pytest.mark.parametrize("family", dispatch.FAMILIES, ids=lambda f: f.name)
def test_the_dispatcher_is_generated_from_the_registry(family):
    assert family.target.read_text() == dispatch.render(family), (
        f"{family.target} is out of date with its registry: run python -m tetherlab.model.dispatch"
    )


def test_the_check_command_passes_on_the_checked_in_dispatchers():
    assert dispatch.out_of_date() == [] and dispatch.main(["--check"]) == 0


def test_one_tether_part_is_a_direct_call_and_each_more_adds_branches(tmp_path):
    # with the rod chain alone no kind is read; the inextensible chain (code 1) is a branch in each
    # tether dispatcher, the chain staying the default, and one more part type (a reel, say) adds
    # another
    folder = tmp_path / "tether"
    shutil.copytree(ROOT / "tetherlab" / "tether", folder)
    one = dispatch.render(dispatch.TETHER, tether_registry.PARTS[:1], folder)
    assert "kind ==" not in one and "return _chain_walk(t, q, qd, p, k" in one
    text = dispatch.render(dispatch.TETHER)
    assert text.count("kind == 1:") == len(tether_registry.INTERFACE) and "return _chain_walk(t, q, qd, p, k" in text
    (folder / "reel.py").write_text("".join(f"def {v}({sig}):\n    pass\n" for v, sig in tether_registry.INTERFACE.items()))
    more = dispatch.render(dispatch.TETHER, tether_registry.PARTS + (PartType(2, "reel", "reel"),), folder)
    assert more.count("kind == 2:") == len(tether_registry.INTERFACE) and "from .reel import (" in more


def test_one_more_line_adds_a_branch_to_every_dispatcher(tmp_path):
    # negative control of the up-to-date check: the table with one more part renders another file,
    # with one more branch in each of the interface's dispatchers
    bodies = tmp_path / "bodies"
    shutil.copytree(ROOT / "tetherlab" / "bodies", bodies)
    (bodies / "toy.py").write_text("from .point import *  # noqa\n" + "".join(
        f"def {v}({sig}):\n    pass\n" for v, sig in registry.INTERFACE.items()))
    parts = registry.PARTS + (PartType(7, "toy", "toy"),)
    text = dispatch.render(dispatch.BODY, parts, bodies)
    assert text != dispatch.render(dispatch.BODY, registry.PARTS, bodies)
    assert text.count("kind == 7:") == len(registry.INTERFACE)
    assert "from .toy import (" in text


@pytest.mark.parametrize("parts,what", [
    (registry.PARTS + (PartType(1, "twice", "point"),), "code 1 is already 'rigid'"),
    (registry.PARTS + (PartType(5, "point", "point"),), "'point': the name is already taken"),
    (registry.PARTS + (PartType(-1, "neg", "point"),), "expected an int >= 0"),
    (registry.PARTS + (PartType(5, "gone", "no_such_module"),), "no_such_module.py: no such module"),
    ((), "at least one part type"),
    ((PartType(0, "point", "point"), PartType(1, "rigid", "rigid_body"), PartType(2, "x", "point"),
      PartType(3, "x", "rigid_body")), "'x': the name is already taken"),
])
def test_a_table_that_cannot_dispatch_is_refused(parts, what):
    with pytest.raises(ValueError, match=what):
        dispatch.render(dispatch.BODY, parts)


def test_a_part_module_without_the_interface_is_refused(tmp_path):
    bodies = tmp_path / "bodies"
    shutil.copytree(ROOT / "tetherlab" / "bodies", bodies)
    sigs = dict(registry.INTERFACE)
    sigs.pop("share")
    sigs["setup"] = "t, p, b"
    (bodies / "half.py").write_text("".join(f"def {v}({sig}):\n    pass\n" for v, sig in sigs.items()))
    with pytest.raises(ValueError) as err:
        dispatch.render(dispatch.BODY, registry.PARTS + (PartType(3, "half", "half"),), bodies)
    assert "half.py: expected a function share(t, att, p, b, sh), found none" in str(err.value)
    assert "half.py: setup: expected arguments (t, att, p, b, datt), got (t, p, b)" in str(err.value)


def test_a_body_or_tether_names_a_part_type_that_exists():
    from tetherlab.system import BodySpec, TetherSpec

    assert registry.part_of(BodySpec("a", 1.0)).name == "point"
    with pytest.raises(ValueError, match="part: expected one of .*'point', 'rigid'.*got 'reel'"):
        registry.part_of(BodySpec("a", 1.0, part="reel"))
    t = TetherSpec("t", 2, 10.0, 1e4, 1.0)
    assert tether_registry.part_of(t).name == "chain"
    assert tether_registry.part_of(TetherSpec("t", 2, 10.0, 1e4, 1.0, part="inextensible")).name == "inextensible"
    with pytest.raises(ValueError, match="part: expected one of \\['chain', 'inextensible'\\], got 'rope'"):
        tether_registry.part_of(TetherSpec("t", 2, 10.0, 1e4, 1.0, part="rope"))


# -- a toy part type, added the way the registry says ----------------------------------------------
_TOY = '''
"""A point body whose mass counts twice (the registry's test part type)."""

from .._jit import njit
from ..kernel.effects import body_force, potential_per_mass
from ..kernel.layout import BS_C, BS_CF, BS_F, BS_M, BS_R, BS_SIZE, BS_V, BT_INV_M, BT_M, BT_NCHILD, BT_SIZE, H_OFF_BODY, H_OFF_BSCR
from ..kernel.shares import SH_HX, SH_HY, SH_HZ, SH_KE, SH_PX, SH_PY, SH_PZ, SH_VG
from .point import add_child, attach, back_substitute, derivatives, end_state, point_acceleration, root_solve, root_state
from .point import compliance as _point_compliance


@njit(cache=True, inline="always")
def setup(t, att, p, b, datt):
    bt = int(p[H_OFF_BODY]) + b * BT_SIZE
    bs = int(p[H_OFF_BSCR]) + b * BS_SIZE
    m = 2.0 * p[bt + BT_M]
    fx, fy, fz = body_force(p, t, b, p[bs + BS_R], p[bs + BS_R + 1], p[bs + BS_R + 2],
                            p[bs + BS_V], p[bs + BS_V + 1], p[bs + BS_V + 2], m)
    for c in range(9):
        p[bs + BS_M + c] = 0.0
    p[bs + BS_M] = m
    p[bs + BS_M + 4] = m
    p[bs + BS_M + 8] = m
    p[bs + BS_F] = fx
    p[bs + BS_F + 1] = fy
    p[bs + BS_F + 2] = fz


@njit(cache=True, inline="always")
def compliance(p, c, work):
    bt = int(p[H_OFF_BODY]) + c * BT_SIZE
    if p[bt + BT_NCHILD] != 0.0:
        return _point_compliance(p, c, work)
    bs = int(p[H_OFF_BSCR]) + c * BS_SIZE
    inv_m = 0.5 * p[bt + BT_INV_M]
    for a in range(9):
        p[bs + BS_C + a] = 0.0
    p[bs + BS_C] = inv_m
    p[bs + BS_C + 4] = inv_m
    p[bs + BS_C + 8] = inv_m
    for a in range(3):
        p[bs + BS_CF + a] = p[bs + BS_F + a] * inv_m
    return 1.0


@njit(cache=True, inline="always")
def share(t, att, p, b, sh):
    bt = int(p[H_OFF_BODY]) + b * BT_SIZE
    bs = int(p[H_OFF_BSCR]) + b * BS_SIZE
    m = 2.0 * p[bt + BT_M]
    rx, ry, rz = p[bs + BS_R], p[bs + BS_R + 1], p[bs + BS_R + 2]
    vx, vy, vz = p[bs + BS_V], p[bs + BS_V + 1], p[bs + BS_V + 2]
    sh[SH_PX] += m * vx
    sh[SH_PY] += m * vy
    sh[SH_PZ] += m * vz
    sh[SH_HX] += m * (ry * vz - rz * vy)
    sh[SH_HY] += m * (rz * vx - rx * vz)
    sh[SH_HZ] += m * (rx * vy - ry * vx)
    sh[SH_KE] += 0.5 * m * (vx * vx + vy * vy + vz * vz)
    sh[SH_VG] += m * potential_per_mass(p, t, rx, ry, rz)
'''

_RUN = '''
import json, sys
import numpy as np
import tetherlab
from tetherlab.diagnostics import shares
from tetherlab.forces.registry import EFFECTS
from tetherlab.formulations.cowell import cowell_rhs_py
from tetherlab.system import BodySpec, TetherSpec, build_model, chain_state

assert tetherlab.__file__.startswith(sys.argv[1]), tetherlab.__file__

def run(mass, part):
    m = build_model(root_mass_kg=500.0, tethers=[TetherSpec("t", 4, 2000.0, 5e4, 10.0, 0.0, "paper", mass, "tip", parent="m0")],
                    effects=[(EFFECTS["central_gravity"], {})], central={"mu_m3_s2": 3.986004418e14},
                    bodies=[BodySpec("m0", 500.0), BodySpec("tip", mass, part=part)])
    r0, v0 = np.array([7.0e6, 0.0, 0.0]), np.array([0.0, 7.546e3, 0.0])
    y = chain_state(m, r0, v0, [np.tile([1.0, 0.1, 0.0], (4, 1))], [1e-4], None)
    return cowell_rhs_py(m, y, 0.0), shares(m, 0.0, y)

toy, twice, same = run(20.0, "double"), run(40.0, "point"), run(20.0, "point")
print(json.dumps({
    "rhs_equal": bool(np.array_equal(toy[0], twice[0])), "shares_equal": bool(np.array_equal(toy[1], twice[1])),
    "rhs_differs_from_same_mass": bool(np.max(np.abs(toy[0] - same[0])) > 0.0),
    "shares_differ_from_same_mass": bool(np.max(np.abs(toy[1] - same[1])) > 0.0),
}))
'''


@pytest.mark.slow
def test_a_toy_part_type_is_one_module_and_one_line(tmp_path):
    pkg = tmp_path / "tetherlab"
    shutil.copytree(ROOT / "tetherlab", pkg, ignore=shutil.ignore_patterns("__pycache__"))
    (pkg / "bodies" / "double.py").write_text(textwrap.dedent(_TOY))
    reg = pkg / "bodies" / "registry.py"
    text = reg.read_text()
    last = '    PartType(1, "rigid", "rigid_body"),\n'
    assert last in text
    reg.write_text(text.replace(last, last + '    PartType(2, "double", "double"),\n'))  # the one line
    env = dict(os.environ, PYTHONPATH=str(tmp_path), TETHERLAB_CACHE_DIR=str(tmp_path / "cache"))
    gen = subprocess.run([sys.executable, "-m", "tetherlab.model.dispatch"], cwd=tmp_path, env=env,
                         capture_output=True, text=True)
    assert gen.returncode == 0, gen.stderr
    assert "kind == 2:" in (pkg / "bodies" / "parts.py").read_text()
    out = subprocess.run([sys.executable, "-c", _RUN, str(pkg)], cwd=tmp_path, env=env, capture_output=True,
                         text=True, timeout=900)
    assert out.returncode == 0, out.stderr[-3000:]
    got = json.loads(out.stdout.strip().splitlines()[-1])
    # bit for bit: 2 m and 0.5 / m are exact in binary, so the toy's arithmetic is the point's at 2 m
    assert got == {"rhs_equal": True, "shares_equal": True, "rhs_differs_from_same_mass": True,
                   "shares_differ_from_same_mass": True}, got
