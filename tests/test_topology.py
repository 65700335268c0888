"""The scene's graph (tetherlab/model/topology.py): built once at load, read by every layer.

Every expected value below is derived by hand from the rules in the module docstring (docs/scenes.md,
"Body order in the kernel"): components numbered by their first body in file order; a component's
root is its fixed body, else the ``from`` body of its first tether, else the body itself; kernel
order = root 0, the child of every tether in file order, the other roots; elimination order =
deepest child first, ties in file order.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import pytest

from tetherlab.errors import SceneError
from tetherlab.model import topology
from tetherlab.model.topology import CutTether, LayoutStep
from tetherlab.scene import Scene


@dataclass(frozen=True)
class _B:  # the fields of scene.Body the graph reads
    name: str
    fixed: bool = False
    rigid: object = None
    has_state: bool = False


@dataclass(frozen=True)
class _T:  # the fields of scene.Tether the graph reads
    name: str
    from_body: str
    to_body: str


def graph(bodies, tethers):
    return topology.build([b if isinstance(b, _B) else _B(b) for b in bodies], [_T(*t) for t in tethers])


def test_star_written_from_its_root():
    # m0 -> a, m0 -> b: one component, root m0 (from of the first tether); both children at depth
    # 1, so the elimination keeps file order; a star of point masses written from its root
    g = graph(["m0", "a", "b"], [("t1", "m0", "a"), ("t2", "m0", "b")])
    assert g.roots == ("m0",)
    assert g.kernel_bodies == ("m0", "a", "b")
    assert g.depth == (0, 1, 1)
    assert g.elimination_order == (0, 1)
    assert g.parents == ["m0", "m0"] and g.child_names == ["a", "b"] and g.reversed == [False, False]
    assert g.children == {"m0": (0, 1), "a": (), "b": ()}
    assert g.simple and g.cut == ()


def test_chain_eliminates_its_leaf_first():
    # m0 -> m1 -> m2: depths 0, 1, 2; the leaf's tether (1) is eliminated before the one at the root
    g = graph(["m0", "m1", "m2"], [("t1", "m0", "m1"), ("t2", "m1", "m2")])
    assert g.kernel_bodies == ("m0", "m1", "m2")
    assert g.depth == (0, 1, 2)
    assert g.elimination_order == (1, 0)
    assert g.placement_order == (0, 1)
    assert not g.simple  # t2 hangs from m1, not from the root


def test_tether_written_towards_its_parent_is_reversed():
    # m0 -> mf <- m2: root m0 (from of t1); t2 is written from m2 but hangs from mf, so it is
    # oriented mf -> m2 and reversed; kernel body 2 (child of t2) is m2
    g = graph(["m0", "mf", "m2"], [("t1", "m0", "mf"), ("t2", "m2", "mf")])
    assert g.roots == ("m0",)
    assert [(t.parent, t.child, t.reversed) for t in g.tethers] == [("m0", "mf", False), ("mf", "m2", True)]
    assert g.kernel_bodies == ("m0", "mf", "m2")
    assert g.depth == (0, 1, 2) and g.elimination_order == (1, 0)
    assert not g.simple


def test_forest_with_several_roots_and_a_body_without_tether():
    # components in order of their first body: {a, b} (0), {c, d} (1), {e} (2); roots a, c (from of
    # their first tethers) and e (no tether: the body itself).  Kernel order: root 0 (a), the
    # children of t1, t2 (b, d), then the other roots (c, e); depths 0 1 1 0 0
    g = graph(["a", "b", "c", "d", "e"], [("t1", "a", "b"), ("t2", "c", "d")])
    assert g.component == {"a": 0, "b": 0, "c": 1, "d": 1, "e": 2}
    assert g.roots == ("a", "c", "e")
    assert g.kernel_bodies == ("a", "b", "d", "c", "e")
    assert g.depth == (0, 1, 1, 0, 0)
    assert g.elimination_order == (0, 1)
    assert not g.simple  # several roots


def test_the_root_of_a_chain_in_the_other_component_is_from_of_its_first_tether():
    # second component written c <- d: its first tether's from body is d, so d is its root and
    # the tether is not reversed (it is written from d)
    g = graph(["a", "c", "d"], [("t1", "d", "c")])
    assert g.component == {"a": 0, "c": 1, "d": 1}
    assert g.roots == ("a", "d")
    assert g.kernel_bodies == ("a", "c", "d")  # a, child of t1 (c), the other root (d)
    assert [(t.parent, t.child, t.reversed) for t in g.tethers] == [("d", "c", False)]


def test_fixed_body_not_first_is_the_root():
    # a -> nail -> b with nail fixed: the fixed body is the root, so t1 (written from a) is
    # oriented nail -> a and reversed; both children at depth 1
    g = graph(["a", _B("nail", fixed=True), "b"], [("t1", "a", "nail"), ("t2", "nail", "b")])
    assert g.roots == ("nail",)
    assert g.fixed == (("nail",),)
    assert [(t.parent, t.child, t.reversed) for t in g.tethers] == [("nail", "a", True), ("nail", "b", False)]
    assert g.kernel_bodies == ("nail", "a", "b")
    assert g.depth == (0, 1, 1) and g.elimination_order == (0, 1)
    assert not g.simple  # t1 reversed


def test_rigid_body_makes_the_star_not_simple():
    g = graph([_B("sat", rigid=object()), "tip"], [("t1", "sat", "tip")])
    assert g.kernel_bodies == ("sat", "tip") and not g.simple


def test_elimination_order_leaves_first_on_a_branched_tree():
    # r -> a -> b -> d and r -> c: children depths a 1, b 2, c 1, d 3 (tethers t1 t2 t3 t4);
    # sorted by (-depth, k): t4 (3), t2 (2), t1 (1, k = 0), t3 (1, k = 2)
    g = graph(["r", "a", "b", "c", "d"], [("t1", "r", "a"), ("t2", "a", "b"), ("t3", "r", "c"), ("t4", "b", "d")])
    assert g.depth == (0, 1, 2, 1, 3)
    assert g.elimination_order == (3, 1, 0, 2)
    assert g.placement_order == (0, 2, 1, 3)  # every parent before its children
    # the kernel-level derivation build_model uses without a graph gives the same (parents by
    # kernel index: t1 -> 0 (r), t2 -> 1 (a), t3 -> 0, t4 -> 2 (b))
    assert topology.depths_and_order(5, [0, 1, 0, 2]) == ([0, 1, 2, 1, 3], [3, 1, 0, 2])


def test_cut_tether_of_a_loop_is_held():
    # a -> b -> c -> a: t1 and t2 join a, b, c; t3 joins c and a, already joined, so it is cut and
    # the spanning forest is the chain a -> b -> c
    g = graph(["a", "b", "c"], [("t1", "a", "b"), ("t2", "b", "c"), ("t3", "c", "a")])
    assert g.cut == (CutTether(2, "t3", "c", "a"),)
    assert [(t.parent, t.child) for t in g.tethers] == [("a", "b"), ("b", "c")]
    assert g.kernel_bodies == ("a", "b", "c") and g.elimination_order == (1, 0)


# -- the scene layer reads the graph ------------------------------------------------------------

BASE = {
    "duration": "6000 s",
    "effects": {"central_gravity": {}},
    "bodies": {"m0": {"mass": "1000 kg"}, "mf": {"mass": "10 kg"}},
    "tethers": {"main": {"from": "m0", "to": "mf", "rods": 2, "length": "5 km", "EA": "5e4 N", "mass": "10 kg"}},
    "orbit": {"elements": {"a": "7400 km", "e": 0.0, "i": "35 deg", "raan": "0 deg", "argp": "0 deg", "nu": "0 deg"}},
    "output": {"step": "60 s"},
}
TETHER = {"rods": 1, "length": "1 km", "EA": "1e4 N", "mass": "1 kg"}


def _scene(**tethers_and_bodies) -> dict:
    d = copy.deepcopy(BASE)
    for key, value in tethers_and_bodies.items():
        kind, name = key.split("__")
        d[kind][name] = value
    return d


def _refused(d: dict, key: str, fragment: str) -> None:
    with pytest.raises(SceneError) as info:
        Scene.from_dict(d)
    assert info.value.key == key, str(info.value)
    assert fragment in str(info.value), str(info.value)


def test_the_scene_keeps_its_graph_out_of_its_value():
    scene = Scene.from_dict(BASE)
    assert scene.graph.kernel_bodies == ("m0", "mf") and scene.graph.simple
    assert scene.layout_plan() == (LayoutStep("main", "m0", "mf"),)
    again = Scene.from_dict(scene.to_dict())
    assert again == scene and "graph" not in scene.to_dict()


def test_loop_is_refused_at_load_from_the_cut_tether():
    # m0 -> mf, mf -> m2, m2 -> m0: the third tether is the cut one
    d = _scene(bodies__m2={"mass": "1 kg"}, tethers__second={"from": "mf", "to": "m2", **TETHER},
               tethers__third={"from": "m2", "to": "m0", **TETHER})  # fmt: skip
    _refused(d, "tethers.third", "tether 'third' closes a loop between 'm2' and 'm0'")


def test_two_fixed_bodies_in_one_group_are_refused_at_load():
    d = _scene(bodies__n1={"mass": "1 kg", "fixed": True, "position": ["7000 km", "0 km", "0 km"]},
               bodies__n2={"mass": "1 kg", "fixed": True, "position": ["7001 km", "0 km", "0 km"]},
               tethers__joint={"from": "n1", "to": "n2", **TETHER})  # fmt: skip
    d["orbit"]["reference"] = "m0"  # (a centre-of-mass reference would refuse the explicit states)
    _refused(d, "bodies.n2.fixed", "at most one fixed body")


def test_quadratures_that_differ_are_refused_at_load():
    d = _scene(bodies__m2={"mass": "1 kg"}, tethers__second={"from": "m0", "to": "m2", "quadrature": 3, **TETHER})
    _refused(d, "tethers.*.quadrature", "the same quadrature for every tether")


def test_scipy_method_with_events_is_refused_at_load():
    d = copy.deepcopy(BASE)
    d["tethers"]["main"]["tension_only"] = True
    d["integrator"] = {"method": "scipy:DOP853"}
    _refused(d, "integrator.method", "this scene has events (slack) that only they locate")


def test_equilibrium_motion_in_a_tree_other_than_a_star_is_refused_at_load():
    # m0 -> mf -> m2 is a chain, not a star
    d = _scene(bodies__m2={"mass": "1 kg"}, tethers__second={"from": "mf", "to": "m2", **TETHER})
    d["orbit"]["motion"] = "equilibrium"
    _refused(d, "orbit.motion", "'corotating' or 'translating'")
