"""Only the StateLayout (tetherlab/model/state.py) slices a Cowell state.

A Cowell state is ``[q, q', attitude, wheels]`` with ``q = (r0, d_1 .. d_N, other roots)``; its
offsets are arithmetic (``3 + 3 g`` for rod g, ``3 (1 + N)`` for the other roots, half the length
for q', ``2 n_qt`` for the attitude).  Written out by hand in Python they go wrong silently the day
the layout changes (a rigid body's attitude block, a reel's rods), so outside the layout every
module asks ``model.state`` for a named block.

How the scan tells kernels apart: a function decorated as compiled (``@njit``, ``cfunc``,
``rhs_cfunc``, ``jit``, ``intrinsic``), and everything nested in it, is a kernel.  Kernels read the
same offsets from the parameter block's header (H_NQT, BT_QOFF ...) by design (numba has no objects
to carry a layout), and StateLayout.agrees_with checks that the two say the same.  Everything else,
plain Python in a kernel module included, is scanned.  Tests are not scanned: they may rebuild an
offset by hand to check the layout against it.

The spellings caught (each has a negative control below, planted in a temporary file):

* half the state length: ``y.size // 2``, ``len(y) // 2``, ``Y.shape[1] // 2``;
* a rod's offset: ``3 + 3 * g`` (and ``4 ..``, ``5 ..``, ``6 + 3 * g``, either order);
* the length of q: ``3 * (1 + n)``;
* the q' block or what follows it: ``2 * n_qt`` (any spelling ``nqt``, ``n_qt``, ``n_qtrans``);
* any subscript whose bounds are computed from ``n_qt``: ``y[:nqt]``, ``y[nqt : nqt + 3]``.

A statement that computes such a number for something that is not a state index carries the
comment ``# not a state index: <why>`` on one of its lines.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

from .helpers import ROOT

_COMPILED = {"njit", "jit", "cfunc", "rhs_cfunc", "intrinsic", "generated_jit", "vectorize"}
_QT = re.compile(r"^(n_?qt|n_qtrans)$")
_MARK = "# not a state index:"
_SCANNED = ("tetherlab", "studies", "references")
_EXEMPT = {
    "tetherlab/model/state.py": "the layout itself",
    "tetherlab/oracles/bead_scene.py": "the lumped-mass oracle's own state, not a Cowell state",
}
# Modules that still slice by hand; each entry must still offend (so the list only shrinks).
_PENDING = {
    "tetherlab/statics.py": "the static solver's q of a single tether; reworked in parallel, convert after",
}


def _decorator_name(d) -> str:
    if isinstance(d, ast.Call):
        d = d.func
    if isinstance(d, ast.Attribute):
        return d.attr
    return d.id if isinstance(d, ast.Name) else ""


def _int(node, values) -> bool:
    return isinstance(node, ast.Constant) and type(node.value) is int and node.value in values


def _name(node) -> str:
    if isinstance(node, ast.Name):
        return node.id
    return node.attr if isinstance(node, ast.Attribute) else ""


def _mentions_qt(node) -> bool:
    return node is not None and any(_QT.match(_name(n)) for n in ast.walk(node))


def _spelling(node) -> str | None:
    """The name of the hand-made state offset ``node`` is, or None."""
    if isinstance(node, ast.Subscript):
        sl = node.slice
        bounds = [sl.lower, sl.upper] if isinstance(sl, ast.Slice) else [sl]
        if any(_mentions_qt(b) for b in bounds):
            return "a slice computed from n_qt"
        return None
    if not isinstance(node, ast.BinOp):
        return None
    left, right, op = node.left, node.right, node.op
    if isinstance(op, ast.FloorDiv) and _int(right, {2}):
        if (isinstance(left, ast.Attribute) and left.attr == "size") or isinstance(left, ast.Subscript) or (
            isinstance(left, ast.Call) and _name(left.func) == "len"
        ):
            return "half the state length (// 2)"
    for a, b in ((left, right), (right, left)):
        if isinstance(op, ast.Add) and _int(a, {3, 4, 5, 6}) and isinstance(b, ast.BinOp) and isinstance(b.op, ast.Mult):
            if _int(b.left, {3}) or _int(b.right, {3}):
                return "a rod offset (3 + 3 g)"
        if isinstance(op, ast.Mult) and _int(a, {3}) and isinstance(b, ast.BinOp) and isinstance(b.op, ast.Add):
            if _int(b.left, {1}) or _int(b.right, {1}):
                return "the length of q (3 (1 + n))"
        if isinstance(op, ast.Mult) and _int(a, {2}) and _QT.match(_name(b)):
            return "the end of q' (2 n_qt)"
    return None


def hand_slicing(source: str) -> list[tuple[int, str, str]]:
    """(line, spelling, expression) of every hand-made state offset outside compiled kernels."""
    tree = ast.parse(source)
    lines = source.splitlines()
    hits = []

    def marked(stmt) -> bool:
        return any(_MARK in line for line in lines[stmt.lineno - 1 : stmt.end_lineno])

    def visit(node, in_kernel, stmt):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            in_kernel = in_kernel or any(_decorator_name(d) in _COMPILED for d in node.decorator_list)
        if isinstance(node, ast.stmt):
            stmt = node
        what = None if in_kernel else _spelling(node)
        if what and not (stmt is not None and marked(stmt)):
            hits.append((node.lineno, what, ast.unparse(node)))
            return  # one report per expression, not one per sub-expression
        for child in ast.iter_child_nodes(node):
            visit(child, in_kernel, stmt)

    visit(tree, False, None)
    return hits


def _offenders() -> dict[str, list[str]]:
    out = {}
    for top in _SCANNED:
        for path in sorted((ROOT / top).rglob("*.py")):
            rel = path.relative_to(ROOT).as_posix()
            if rel in _EXEMPT:
                continue
            hits = hand_slicing(path.read_text())
            if hits:
                out[rel] = [f"{rel}:{line}: {what}: {expr}" for line, what, expr in hits]
    return out


def test_only_the_state_layout_slices_a_state():
    found = _offenders()
    bad = [h for rel, hits in found.items() if rel not in _PENDING for h in hits]
    assert not bad, (
        "a Cowell state sliced by hand; ask model.state (tetherlab/model/state.py) for the block "
        "instead:\n  " + "\n  ".join(bad)
    )
    stale = sorted(set(_PENDING) - set(found))
    assert not stale, f"no longer slice by hand, drop them from _PENDING: {stale}"


_PLANTED = [
    ("h = y.size // 2", "half"),
    ("h = len(y) // 2", "half"),
    ("h = Y.shape[1] // 2", "half"),
    ("d = y[3 + 3 * g : 6 + 3 * g]", "rod offset"),
    ("d = y[3 * g + 3 : 3 * g + 6]", "rod offset"),
    ("o = 3 * (1 + nrods)", "length of q"),
    ("o = 3 * (n + 1)", "length of q"),
    ("n_first = y.size - 2 * nqt", "2 n_qt"),
    ("att = y[2 * nqt :]", "n_qt"),
    ("att = y[2 * model.n_qt :]", "n_qt"),
    ("q = y[:nqt]", "from n_qt"),
    ("v = y[n_qt : n_qt + 3]", "from n_qt"),
    ("v = Y[:, lay.n_qt + 3]", "from n_qt"),
]


@pytest.mark.parametrize("src,what", _PLANTED)
def test_the_scan_catches_each_spelling(tmp_path, src, what):
    # negative control: each hand-made offset is caught in plain Python (module level and inside a
    # function), left alone inside a compiled kernel and on a line that says why it is no state index
    f = tmp_path / "planted.py"
    f.write_text(src + "\n")
    hits = hand_slicing(f.read_text())
    assert hits and what in hits[0][1], (src, hits)
    assert hand_slicing(f"def f(y, g, nrods, nqt, n, model, lay, Y):\n    {src}\n")
    assert not hand_slicing(f"@njit(cache=True)\ndef f(y, g, nrods, nqt, n, model, lay, Y):\n    {src}\n")
    assert not hand_slicing(f"@numba.cfunc(SIG)\ndef f(y):\n    def g():\n        {src}\n")
    assert not hand_slicing(f"{src}  {_MARK} a column count\n")


@pytest.mark.parametrize("src", ["a = y[lay.rod(g)]", "a = y[model.state.qd]", "n = 3 * g", "k = len(x) // 3",
                                 "h = a // 2 + 1", "c = 2 * n_rods", "x = y[3:6]"])
def test_the_scan_leaves_layout_use_alone(src):
    assert not hand_slicing(src + "\n"), src
