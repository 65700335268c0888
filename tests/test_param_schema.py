"""The declared parameter schema (tetherlab/kernel/schema.py), the layout constants generated from
it (tetherlab/kernel/layout.py) and the typed view (tetherlab/model/params.py).

* the boundary: outside tetherlab/kernel/ and tetherlab/model/, only a module that defines compiled
  kernels (``@njit``/``cfunc``) imports the layout constants or the schema; everything else reads
  the block through ParamView;
* the schema lays out: no two fields overlap, every region is contiguous and the regions tile the
  block, every record's fields fit its size, the constants are plain ints;
* build_model writes exactly the offsets and the length the schema computes, on shipped scenes with
  rigid bodies, wheels and a forest;
* a declaration that does not lay out is refused with a clear error (the negative controls);
* the view reads every field of a built model as the raw slots hold it, and writes go to the block.
"""

from __future__ import annotations

import ast
import dataclasses
import re
from pathlib import Path

import numpy as np
import pytest

from tetherlab.kernel import layout as L  # the schema's own test: allowed (see _EXEMPT)
from tetherlab.kernel import schema as S
from tetherlab.model.params import ParamView
from tetherlab.pipeline import prepare
from tetherlab.scene import load_scene

from .helpers import ROOT, SCENES, call_cfunc
from .test_newton_forest import forest_scene

_GUARDED = ("tetherlab.kernel.layout", "tetherlab.kernel.schema")
_COMPILED = re.compile(r"@\s*(numba\.)?(njit|cfunc|jit|rhs_cfunc|intrinsic)\b|\b(njit|cfunc)\(")
_EXEMPT = {
    "tests/test_param_schema.py": "this file checks the schema against the raw slots",
    "tests/test_radau5_boundary.py": "reads the constants' names only, to forbid them in integrators/",
}


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(path: Path, module: str) -> set[str]:
    """Every module (and module.name for ``from m import name``) the file imports, relative
    imports resolved against the package of ``module``."""
    tree = ast.parse(path.read_text(), str(path))
    pkg = module.split(".") if path.name == "__init__.py" else module.split(".")[:-1]
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = pkg[: len(pkg) - node.level + 1]
                base = ".".join(anchor + ([base] if base else []))
            out.add(base)
            out.update(f"{base}.{a.name}" for a in node.names)
    return out


def _offends(path: Path, rel: str, module: str) -> list[str]:
    if rel.startswith(("tetherlab/kernel/", "tetherlab/model/")) or rel in _EXEMPT:
        return []
    hits = sorted(m for m in _imports(path, module) if m.startswith(_GUARDED))
    return hits if hits and not _COMPILED.search(path.read_text()) else []


def _scanned():
    for top in ("tetherlab", "studies", "references", "tests"):
        yield from sorted((ROOT / top).rglob("*.py"))


def test_only_kernels_and_the_model_package_import_the_layout():
    offenders = []
    for path in _scanned():
        rel = path.relative_to(ROOT).as_posix()
        hits = _offends(path, rel, _module_name(path))
        if hits:
            offenders.append(f"{rel}: {', '.join(hits)}")
    assert not offenders, (
        "modules without compiled kernels read the parameter block by layout constant; use "
        "tetherlab.model.params.ParamView instead:\n  " + "\n  ".join(offenders)
    )


@pytest.mark.parametrize("src", ["from .kernel import layout", "from .kernel.layout import H_NRODS",
                                 "import tetherlab.kernel.layout", "from tetherlab.kernel.schema import BLOCK",
                                 "from tetherlab.kernel import layout as L"])
def test_the_boundary_scan_catches_every_import_form(tmp_path, src):
    # negative control of the scan: each spelling is caught in a plain module, allowed in a kernel
    f = tmp_path / "x.py"
    f.write_text(src + "\n")
    assert _offends(f, "tetherlab/x.py", "tetherlab.x"), src
    f.write_text(src + "\n\n@njit(cache=True)\ndef k(p):\n    return p[0]\n")
    assert not _offends(f, "tetherlab/x.py", "tetherlab.x"), src
    f.write_text(src + "\n")
    assert not _offends(f, "tetherlab/model/x.py", "tetherlab.model.x")


# -- the schema lays out ----------------------------------------------------------------------------
def _dims(**over):
    d = dict(n_rods=5, n_tethers=2, n_bodies=4, n_wheels=3, n_effects=3, n_effect_pars=17, n_quadrature=2,
             n_roots=2, n_rest=1, n_wheel_table_floats=8)
    d.update(over)
    return S.dims_of(**d)


def _coverage(dims):
    """Owner of every slot of the block: (region, item, part) from walking the declaration."""
    offs, length = S.block_offsets(dims)
    owner = [None] * length
    pos = 0
    for region, items in S.BLOCK.items():
        for it in items:
            if isinstance(it, S.Field):
                spans = [(S.CONSTANTS[it.const], it.count, it.name)]
                assert S.CONSTANTS[it.const] == pos
            else:
                assert offs[it.name] == pos
                po = S.part_offsets(it, dims)
                spans = [(pos + po[pt.name], S._part_size(pt, dims), f"{it.name}.{pt.name}") for pt in it.parts]
            for start, n, name in spans:
                for i in range(start, start + n):
                    assert owner[i] is None, f"slot {i}: {name} overlaps {owner[i]}"
                    owner[i] = (region, name)
                pos = max(pos, start + n)
    return owner, length


@pytest.mark.parametrize("dims", [_dims(), _dims(n_wheels=0, n_rest=0, n_wheel_table_floats=0, n_bodies=2, n_tethers=1),
                                  _dims(n_rods=128, n_effects=0, n_effect_pars=0)])
def test_no_two_fields_overlap_and_the_regions_tile_the_block(dims):
    owner, length = _coverage(dims)
    assert all(o is not None for o in owner), "a gap in the block"
    spans = S.region_spans(dims)
    assert list(spans) == list(S.REGIONS)
    pos = 0
    for region, (start, stop) in spans.items():
        assert start == pos and stop >= start
        assert {o[0] for o in owner[start:stop]} <= {region}, region  # contiguous: nothing else inside
        pos = stop
    assert pos == length


def test_records_fit_their_size_and_the_constants_are_plain_ints():
    for rec in S.RECORDS:
        used = np.zeros(rec.size, int)
        for f in rec.fields:
            i = getattr(L, f.const)
            assert type(i) is int and 0 <= i and i + f.count <= rec.size, (rec.name, f.name)
            used[i : i + f.count] += 1
        assert used.max() == 1, rec.name
        assert getattr(L, rec.prefix + "SIZE") == rec.size
    for name, value in S.CONSTANTS.items():
        assert type(getattr(L, name)) is int and getattr(L, name) == value, name
    assert L.H_MUTANT == L.H_DEFECT
    # every fixed slot sits before the first model-sized table (its index is a constant)
    assert max(S.CONSTANTS[f.const] + f.count for _, f in S.header_fields().values()) <= L.H_SIZE


# -- build_model writes what the schema computes -----------------------------------------------------
_SHIPPED = ["deorbit-ed-rigid.toml", "rigid-wheels-control.toml", "rigid-example.toml", "hub-spoke-spin.toml",
            "deorbit-ed-fullenv.toml", "stiefel-scheifele.toml"]


def _prepared(name):
    if name == "forest":
        return prepare(forest_scene())
    return prepare(load_scene(SCENES / name))


@pytest.fixture(scope="module", params=_SHIPPED + ["forest"])
def prep(request):
    return _prepared(request.param)


def test_build_model_writes_the_offsets_and_length_the_schema_computes(prep):
    model = prep.model
    v = ParamView(model.p)
    offs, length = S.block_offsets(v.dims())
    assert length == v.block_length == model.p.size
    for items in S.BLOCK.values():
        for it in items:
            if isinstance(it, S.Table):
                assert int(model.p[S.CONSTANTS[it.offset]]) == offs[it.name], it.name
    # the model's shape, as the view reads it
    assert v.n_rods == model.n_rods == sum(t.rods for t in model.tethers)
    assert v.n_tethers == len(model.tethers) and v.n_bodies == len(model.bodies)
    assert v.n_rigid == len(model.rigid_index) and v.n_wheels == len(model.wheel_index)
    assert v.n_effects == len(model.effect_codes) and [e.code for e in v.effects] == model.effect_codes
    assert list(v.roots.astype(int)) == model.roots
    assert v.defect == 0 and v.report.fail_code == 0 and v.report.fail_rod == -1


def test_the_shipped_set_covers_rigid_bodies_wheels_and_a_forest():
    vs = [ParamView(_prepared(n).model.p) for n in ("rigid-wheels-control.toml", "forest")]
    assert vs[0].n_rigid >= 1 and vs[0].n_wheels >= 1 and vs[1].n_roots >= 2


# -- declarations that do not lay out are refused -----------------------------------------------------
def test_an_overlapping_record_is_refused():
    bad = dataclasses.replace(S.TETHER, fields=S.TETHER.fields + (S.Field("again", "TT_PARENT"),))
    with pytest.raises(S.SchemaError, match=r"TT_PARENT.*declared twice"):
        S.layout_constants(records=(bad,) + S.RECORDS[1:])


def test_a_record_larger_than_its_size_is_refused():
    bad = dataclasses.replace(S.ROD, size=5)
    with pytest.raises(S.SchemaError, match=r"record 'rod': its fields need 6 slots, more than its size 5"):
        S.layout_constants(records=tuple(bad if r is S.ROD else r for r in S.RECORDS))


def test_a_header_slot_declared_twice_is_refused():
    block = dict(S.BLOCK)
    block["report"] = block["report"] + (S.Field("fail_code_again", "H_FAIL_CODE"),)
    with pytest.raises(S.SchemaError, match=r"H_FAIL_CODE.*declared twice.*overlap"):
        S.layout_constants(block=block)


def test_a_fixed_field_after_a_model_sized_table_is_refused():
    block = dict(S.BLOCK)
    block["scratch"] = block["scratch"] + (S.Field("late", "H_LATE"),)
    with pytest.raises(S.SchemaError, match=r"field 'late' comes after a model-sized table"):
        S.layout_constants(block=block)


def test_regions_out_of_order_are_refused():
    block = {k: S.BLOCK[k] for k in ("params", "report", "defect", "scratch")}
    with pytest.raises(S.SchemaError, match=r"block regions: expected"):
        S.layout_constants(block=block)


# -- the typed view -------------------------------------------------------------------------------
_TABLES = {  # view attribute -> (header slot of its offset, count attribute, record)
    "tethers": (L.H_OFF_TETH, "n_tethers", S.TETHER),
    "rods": (L.H_OFF_ROD, "n_rods", S.ROD),
    "bodies": (L.H_OFF_BODY, "n_bodies", S.BODY),
    "wheels": (L.H_OFF_WT, "n_wheels", S.WHEEL),
    "effects": (L.H_OFF_EFF, "n_effects", S.EFFECT),
    "rod_scratch": (L.H_OFF_SCR, "n_rods", S.ROD_SCRATCH),
    "body_scratch": (L.H_OFF_BSCR, "n_bodies", S.BODY_SCRATCH),
}


def _raw_base(p, name):
    off, _, _ = _TABLES.get(name, (None, None, None))
    if off is not None:
        return int(p[off])
    nr, nt, nb = int(p[L.H_NRODS]), int(p[L.H_NTETH]), int(p[L.H_NBODY])
    return {
        "joint_scratch": int(p[L.H_OFF_SCR]) + nr * L.SR_SIZE,
        "tether_scratch": int(p[L.H_OFF_BSCR]) + nb * L.BS_SIZE,
        "wheel_scratch": int(p[L.H_OFF_BSCR]) + nb * L.BS_SIZE + nt * L.TS_SIZE,
    }[name]


_ALL_TABLES = dict(
    _TABLES, joint_scratch=(None, "n_joints", S.JOINT_SCRATCH), tether_scratch=(None, "n_tethers", S.TETHER_SCRATCH),
    wheel_scratch=(None, "n_wheels", S.WHEEL_SCRATCH),
)


def test_the_view_reads_every_field_as_the_raw_slots_hold_it(prep):
    from tetherlab.formulations.cowell import cowell_rhs

    model = prep.model
    p = model.fresh_params()
    status, _ = call_cfunc(cowell_rhs, 0.0, prep.y0, p)  # fills the scratch and the counters
    assert status == 0
    v = ParamView(p)
    for name, (region, f) in S.header_fields().items():
        i = getattr(L, f.const)
        got = getattr(v, name)
        if f.count == 1:
            assert got == p[i] and type(got) is (int if f.kind == "int" else float), name
        else:
            np.testing.assert_array_equal(got, p[i : i + f.count], err_msg=name)
        if region == "report":
            assert getattr(v.report, name) == got
    for tname, (_, count, rec) in _ALL_TABLES.items():
        n = v.n_rods + v.n_tethers if count == "n_joints" else getattr(v, count)
        table = getattr(v, tname)
        assert len(table) == n
        base = _raw_base(p, tname)
        for k in range(n):
            row = table[k]
            for f in rec.fields:
                i = base + k * rec.size + getattr(L, f.const)
                if f.count == 1:
                    assert getattr(row, f.name) == p[i], (tname, k, f.name)
                    assert getattr(table, f.name)[k] == p[i]
                else:
                    np.testing.assert_array_equal(getattr(row, f.name), p[i : i + f.count])
                    np.testing.assert_array_equal(getattr(table, f.name)[k], p[i : i + f.count])
    cnt = int(p[L.H_OFF_CNT])
    np.testing.assert_array_equal(v.counters, p[cnt : cnt + L.N_EFFECT_CODES])
    assert v.counters.sum() > 0 or not model.effect_codes
    q = int(p[L.H_OFF_QUAD])
    nq = int(p[L.H_NQ])
    np.testing.assert_array_equal(v.quadrature_nodes, p[q : q + 2 * nq])
    np.testing.assert_array_equal(v.quadrature_weights, p[q + 2 * nq : q + 4 * nq])
    np.testing.assert_array_equal(v.order, p[int(p[L.H_OFF_ORDER]) : int(p[L.H_OFF_ORDER]) + v.n_tethers])
    rest = int(p[L.H_OFF_REST])
    np.testing.assert_array_equal(v.rest.ravel(), p[rest : rest + 2 * int(p[L.H_NREST])])
    for e in range(v.n_effects):
        par = int(p[int(p[L.H_OFF_EFF]) + e * L.ET_SIZE + L.ET_OFF_PAR])
        npar = int(p[int(p[L.H_OFF_EFF]) + e * L.ET_SIZE + L.ET_NPAR])
        np.testing.assert_array_equal(v.effect_params(e), p[par : par + npar])


def test_writes_through_the_view_go_to_the_block():
    model = _prepared("rigid-wheels-control.toml").model
    p = model.fresh_params()
    v = ParamView(p)
    v.stop_radius_m = 6.5e6
    v.defect = L.DEFECT_NO_CENTRIPETAL
    v.tether(0).parent_point_m = (1.0, 2.0, 3.0)
    v.rods.mass_kg = 2.5
    v.body(0).js_kg_m2[4] = 7.0
    assert p[L.H_EV_STOP_R] == 6.5e6 and p[L.H_DEFECT] == L.DEFECT_NO_CENTRIPETAL
    tb = int(p[L.H_OFF_TETH])
    assert list(p[tb + L.TT_PA : tb + L.TT_PA + 3]) == [1.0, 2.0, 3.0]
    rb = int(p[L.H_OFF_ROD])
    assert (p[rb + L.RT_M : rb + v.n_rods * L.RT_SIZE : L.RT_SIZE] == 2.5).all()
    assert p[int(p[L.H_OFF_BODY]) + L.BT_JS + 4] == 7.0
    assert (model.p[L.H_DEFECT], model.p[L.H_EV_STOP_R]) != (p[L.H_DEFECT], 6.5e6)  # the model's own block untouched
    with pytest.raises(AttributeError, match="stop_radius"):
        v.stop_radius = 1.0  # a misspelt field is an error, not a new attribute
    with pytest.raises(IndexError):
        v.tether(v.n_tethers)
