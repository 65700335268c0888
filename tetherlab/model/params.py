"""The typed view of the parameter block: Python reads and writes ``p`` by the schema's names.

The kernels index ``p`` with the integer constants of :mod:`tetherlab.kernel.layout`; every other
module reads it through :class:`ParamView` (tests/test_param_schema.py enforces it), whose
attributes are the fields declared in :mod:`tetherlab.kernel.schema`::

    v = ParamView(model.p)
    v.n_rods, v.root_mass_kg, v.stop_radius_m        # header fields (int or float)
    v.stop_radius_m = 6.5e6                          # a write goes to the block
    v.tether(0).parent, v.body(2).js_kg_m2           # one record (vectors are views of p)
    v.rods.mass_kg                                   # a column: a numpy view (writable)
    v.report.fail_code, v.counters, v.defect = code  # run reports, the negative controls' defect

A view holds no copy: it reads the block as it is now (the kernel's scratch and reports included).
The codes stored in the block (FORM_*, MODEL_*, FAIL_*, MUT_*/DEFECT_*, CTRL_*, WMODE_*) are
re-exported here for the same callers.
"""

from __future__ import annotations

import numpy as np

from ..kernel import layout as _L
from ..kernel import schema as S
from ..kernel.schema import block_offsets, dims_of  # noqa: F401  (build_model sizes the block with these)

_CODE_PREFIXES = ("FORM_", "MODEL_", "FAIL_", "MUT_", "DEFECT_", "CTRL_", "WMODE_", "REEL_")
globals().update({k: v for k, v in vars(_L).items() if k.startswith(_CODE_PREFIXES)})
N_EFFECT_CODES = S.N_EFFECT_CODES

_FIELDS = S.header_fields()


def _scalar_property(index: int, f: S.Field, base_attr: str | None = None):
    """A property for a field at ``index`` (in the block, or in a record when ``base_attr`` names
    the instance's record offset)."""
    n = f.count
    cast = int if f.kind == "int" else float

    if base_attr is None:
        def get(self):
            return cast(self.p[index]) if n == 1 else self.p[index : index + n]

        def put(self, value):
            if n == 1:
                self.p[index] = value
            else:
                self.p[index : index + n] = value
    else:
        def get(self):
            i = getattr(self, base_attr) + index
            return cast(self.p[i]) if n == 1 else self.p[i : i + n]

        def put(self, value):
            i = getattr(self, base_attr) + index
            if n == 1:
                self.p[i] = value
            else:
                self.p[i : i + n] = value

    unit = f" [{f.unit}]" if f.unit else ""
    return property(get, put, doc=f"{f.doc}{unit}")


class _View:
    __slots__ = ("p",)

    def __init__(self, p: np.ndarray):
        self.p = p

    def __setattr__(self, name, value):
        # a misspelt field must not silently become a Python attribute
        if not hasattr(type(self), name):
            raise AttributeError(f"{type(self).__name__} has no field {name!r}")
        object.__setattr__(self, name, value)


def _region_class(name: str, regions: tuple) -> type:
    ns = {"__slots__": ()}
    for fname, (region, f) in _FIELDS.items():
        if region in regions:
            ns[fname] = _scalar_property(S.CONSTANTS[f.const], f)
    return type(name, (_View,), ns)


class RecordView:
    """One row of a table: its fields by name (vectors and matrices are views of the block)."""

    __slots__ = ("p", "base")
    record: S.Record

    def __init__(self, p, base):
        object.__setattr__(self, "p", p)
        object.__setattr__(self, "base", base)

    def __setattr__(self, name, value):
        if not hasattr(type(self), name):
            raise AttributeError(f"{type(self).__name__} has no field {name!r}")
        object.__setattr__(self, name, value)

    def __repr__(self):
        vals = ", ".join(f"{f.name}={getattr(self, f.name)!r}" for f in self.record.fields)
        return f"{self.record.name}({vals})"


class TableView:
    """``count`` rows of one record from ``base``: ``t[k]`` a row, ``t.<field>`` a column (a numpy
    view of the block: shape (count,) for a scalar field, (count, n) for a vector field)."""

    __slots__ = ("p", "base", "count", "_row")

    def __init__(self, p, base, count, row_cls):
        object.__setattr__(self, "p", p)
        object.__setattr__(self, "base", base)
        object.__setattr__(self, "count", count)
        object.__setattr__(self, "_row", row_cls)

    def __len__(self):
        return self.count

    def __getitem__(self, k: int) -> RecordView:
        if not -self.count <= k < self.count:
            raise IndexError(f"{self._row.record.name} {k}: the table has {self.count} rows")
        k %= self.count
        return self._row(self.p, self.base + k * self._row.record.size)

    def __iter__(self):
        return (self[k] for k in range(self.count))

    def rows(self) -> np.ndarray:
        """The table as a (count, record size) view."""
        size = self._row.record.size
        return self.p[self.base : self.base + self.count * size].reshape(self.count, size)

    def __getattr__(self, name):
        f = self._row.fields.get(name)
        if f is None:
            raise AttributeError(f"{self._row.record.name} has no field {name!r}")
        i = S.CONSTANTS[f.const]
        col = self.rows()[:, i : i + f.count]
        return col[:, 0] if f.count == 1 else col

    def __setattr__(self, name, value):
        col = self.__getattr__(name)
        col[...] = value


def _record_class(rec: S.Record) -> type:
    ns = {"__slots__": (), "record": rec, "fields": {f.name: f for f in rec.fields}}
    for f in rec.fields:
        ns[f.name] = _scalar_property(S.CONSTANTS[f.const], f, base_attr="base")
    return type(rec.name.title().replace("_", "") + "Record", (RecordView,), ns)


_ROWS = {rec.name: _record_class(rec) for rec in S.RECORDS}

ReportView = _region_class("ReportView", ("report",))
_Header = _region_class("_Header", S.REGIONS)


class ParamView(_Header):
    """Typed access to a parameter block ``p`` (no copy: reads and writes go to ``p``)."""

    __slots__ = ()

    # -- dimensions and tables -----------------------------------------------------------------
    def dims(self) -> dict:
        """The model dimensions the tables are sized by, as far as the header knows them (the
        trailing effect parameters and wheel time tables: from their tables)."""
        return S.dims_of(
            n_rods=self.n_rods, n_tethers=self.n_tethers, n_bodies=self.n_bodies, n_wheels=self.n_wheels,
            n_effects=self.n_effects, n_effect_pars=sum(e.n_par for e in self.effects), n_quadrature=self.n_quadrature,
            n_roots=self.n_roots, n_rest=self.n_rest,
            n_wheel_table_floats=sum(2 * w.table_points for w in self.wheels if w.mode == WMODE_TABLE),  # noqa: F821
            n_reels=self.n_reels, n_reel_table_floats=sum(5 * r.table_intervals for r in self.reels),
        )

    def part_offset(self, table: str, part: str) -> int:
        """Offset of ``part`` of ``table`` (only the parts before it are sized)."""
        t = S.table(table)
        pos = int(self.p[S.CONSTANTS[t.offset]])
        for pt in t.parts:
            if pt.name == part:
                return pos
            n = pt.count if isinstance(pt.count, int) else self._count(pt.count)
            pos += n * (pt.record.size if pt.record is not None else pt.width)
        raise KeyError(f"table {table!r} has no part {part!r}")

    def _count(self, dim: str) -> int:
        if dim == "n_joints":
            return self.n_rods + self.n_tethers
        return int(getattr(self, dim))

    def _table(self, table: str, part: str, count: str, record: str) -> TableView:
        return TableView(self.p, self.part_offset(table, part), self._count(count), _ROWS[record])

    @property
    def tethers(self) -> TableView:
        return self._table("tethers", "rows", "n_tethers", "tether")

    @property
    def rods(self) -> TableView:
        return self._table("rods", "rows", "n_rods", "rod")

    @property
    def bodies(self) -> TableView:
        return self._table("bodies", "rows", "n_bodies", "body")

    @property
    def wheels(self) -> TableView:
        return self._table("wheels", "rows", "n_wheels", "wheel")

    @property
    def effects(self) -> TableView:
        return self._table("effects", "rows", "n_effects", "effect")

    @property
    def rod_scratch(self) -> TableView:
        return self._table("rod_scratch", "rods", "n_rods", "rod_scratch")

    @property
    def joint_scratch(self) -> TableView:
        """Per joint (n_k + 1 per tether, tether by tether): the reactions J and the Schur blocks."""
        return self._table("rod_scratch", "joints", "n_joints", "joint_scratch")

    @property
    def body_scratch(self) -> TableView:
        return self._table("body_scratch", "bodies", "n_bodies", "body_scratch")

    @property
    def tether_scratch(self) -> TableView:
        return self._table("body_scratch", "tethers", "n_tethers", "tether_scratch")

    @property
    def wheel_scratch(self) -> TableView:
        return self._table("body_scratch", "wheels", "n_wheels", "wheel_scratch")

    @property
    def reels(self) -> TableView:
        return self._table("reels", "rows", "n_reels", "reel")

    @property
    def reel_scratch(self) -> TableView:
        return self._table("reel_scratch", "reels", "n_reels", "reel_scratch")

    def reel(self, i: int) -> RecordView:
        return self.reels[i]

    def tether(self, k: int) -> RecordView:
        return self.tethers[k]

    def rod(self, g: int) -> RecordView:
        return self.rods[g]

    def body(self, b: int) -> RecordView:
        return self.bodies[b]

    def wheel(self, j: int) -> RecordView:
        return self.wheels[j]

    def effect(self, e: int) -> RecordView:
        return self.effects[e]

    def effect_params(self, e: int) -> np.ndarray:
        """The parameters effect ``e`` packed (a view of the block)."""
        row = self.effects[e]
        return self.p[row.par_offset : row.par_offset + row.n_par]

    def effects_with_code(self, *codes: int) -> list[int]:
        """Parameter offsets of the named effects whose code is in ``codes`` (scene order)."""
        return [e.par_offset for e in self.effects if e.code in codes]

    @property
    def quadrature_nodes(self) -> np.ndarray:
        off = self.part_offset("quadrature", "nodes")
        return self.p[off : off + 2 * self.n_quadrature]

    @property
    def quadrature_weights(self) -> np.ndarray:
        off = self.part_offset("quadrature", "weights")
        return self.p[off : off + 2 * self.n_quadrature]

    @property
    def order(self) -> np.ndarray:
        """The tethers, leaves first (the elimination order), as floats."""
        off = self.order_offset
        return self.p[off : off + self.n_tethers]

    @property
    def roots(self) -> np.ndarray:
        off = self.roots_offset
        return self.p[off : off + self.n_roots]

    @property
    def rest(self) -> np.ndarray:
        """(n_rest, 2): (code, parameter offset) of the effects the body-force slots do not name."""
        off = self.rest_offset
        return self.p[off : off + 2 * self.n_rest].reshape(self.n_rest, 2)

    # -- run reports ---------------------------------------------------------------------------
    @property
    def report(self):
        """The report region: the failure record and the non-finite effect record."""
        return ReportView(self.p)

    @property
    def counters(self) -> np.ndarray:
        """Effect evaluation counters, indexed by effect code (a view of the block)."""
        off = self.counters_offset
        return self.p[off : off + S.N_EFFECT_CODES]

    def region(self, name: str) -> np.ndarray:
        """The block's slice of region ``name`` (report, defect, params, scratch)."""
        start, stop = S.region_spans(self.dims())[name]
        return self.p[start:stop]


# The report view also carries the counters, so a caller holds one object for the run's reports.
ReportView.counters = property(lambda self: ParamView(self.p).counters, doc="effect evaluation counters")


def write_table_offsets(p: np.ndarray, offs: dict) -> None:
    """Write every table's offset (``schema.block_offsets``) into its header field."""
    for items in S.BLOCK.values():
        for it in items:
            if isinstance(it, S.Table):
                p[S.CONSTANTS[it.offset]] = offs[it.name]
