"""The integrators import nothing of the model (tetherlab/integrators/linear_solver.py).

RADAU5 is handed its structured Newton solver by the caller, as scipy's solvers are handed a
``jac``: no module under tetherlab/integrators/ may import a tetherlab module outside that package
other than tetherlab._jit (the cfunc ABI), nor name a constant of the parameter-block layout
(tetherlab/kernel/layout.py).  Imports are read from the syntax tree, relative ones resolved, so
a docstring that mentions tether/newton.py is not an import and an import inside a function is.

Negative control: the same checker, applied to a module holding the imports RADAU5 and its driver
used to have (``from ..tether import newton as _nw``, ``from ..kernel.layout import H_NRIGID,
H_NRODS``, a function-local ``from ..tether.newton import structure_supported``), must report
each of them.
"""

from __future__ import annotations

import ast
from pathlib import Path

import tetherlab.kernel.layout as layout

PKG = Path(__file__).resolve().parents[1] / "tetherlab"
INTEGRATORS = PKG / "integrators"
ALLOWED = ("tetherlab._jit", "tetherlab.integrators")
LAYOUT_NAMES = {n for n in vars(layout) if n.isupper() and not n.startswith("_")}


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(PKG.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def violations(source: str, module: str, is_package: bool = False) -> list[str]:
    """Imports of model modules and uses of layout constants in ``source`` (module ``module``)."""
    tree = ast.parse(source)
    base = module.split(".") if is_package else module.split(".")[:-1]
    out = []
    for node in ast.walk(tree):
        names = []
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                up = base[: len(base) - (node.level - 1)]
                target = ".".join(up + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            names = [target]
            out += [f"line {node.lineno}: imports layout constant {a.name}" for a in node.names
                    if a.name in LAYOUT_NAMES]  # fmt: skip
        elif isinstance(node, (ast.Name, ast.Attribute)):
            ident = node.id if isinstance(node, ast.Name) else node.attr
            if ident in LAYOUT_NAMES:
                out.append(f"line {node.lineno}: names layout constant {ident}")
        for name in names:
            if name.split(".")[0] == "tetherlab" and not any(name == a or name.startswith(a + ".") for a in ALLOWED):
                out.append(f"line {node.lineno}: imports {name}")
    return out


def test_no_module_of_the_integrators_imports_the_model():
    files = sorted(INTEGRATORS.rglob("*.py"))
    assert len(files) >= 10  # the radau5 package is walked too
    found = {}
    for path in files:
        v = violations(path.read_text(), _module_name(path), path.name == "__init__.py")
        if v:
            found[str(path.relative_to(PKG.parent))] = v
    assert found == {}


def test_negative_control_the_old_imports_are_reported():
    old = (
        "from ..tether import newton as _nw\n"
        "from ..kernel.layout import H_NRIGID, H_NRODS\n"
        "def _newton_choice(p):\n"
        "    from ..tether.newton import structure_supported\n"
        "    return structure_supported(p) or int(p[H_NRODS])\n"
    )
    v = violations(old, "tetherlab.integrators.radau5")  # the module radau5.py was
    assert any("imports tetherlab.tether" in x and x.startswith("line 1") for x in v)
    assert any("imports tetherlab.kernel.layout" in x for x in v)
    assert any("layout constant H_NRIGID" in x for x in v)
    assert any(x.startswith("line 4") and "tetherlab.tether.newton" in x for x in v)
    assert any(x.startswith("line 5") and "H_NRODS" in x for x in v)
    # the same import from a file of the radau5 package is one level deeper
    v = violations("from ...tether import newton as _nw\n", "tetherlab.integrators.radau5.core")
    assert v == ["line 1: imports tetherlab.tether"]
    # and an absolute import is caught as well
    assert violations("import tetherlab.system\n", "tetherlab.integrators.driver") == ["line 1: imports tetherlab.system"]
