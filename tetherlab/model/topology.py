"""The scene's graph, computed once when the scene is loaded and read by every layer.

Bodies are the nodes, tethers the edges.  :func:`build` takes the bodies and tethers in file order
and returns a :class:`Graph`: a spanning forest (each tether of it oriented away from the root of
its connected component) plus the tethers left out of the forest because they join two bodies
already joined (``cut``: each closes a loop).  Everything the other layers need about the shape of
the system is read from it:

* the scene checks (tetherlab/scene/checks.py): loops (a cut tether), one fixed body per component, the
  layout plan and the bodies it cannot place;
* the kernel (tetherlab/system.py, build_model): the body order, each tether's parent and child
  and the elimination order (leaves first);
* the initial layout (tetherlab/initial/): roots, components, orientation, the order in which to
  lay the tethers (parents first).

Rules (docs/scenes.md, "Body order in the kernel"):

* components are numbered by their first body in file order;
* the root of a component is its fixed body, else the ``from`` body of its first tether in file
  order, else (no tether) the body itself;
* kernel body order: the root of component 0, then the child end of every tether in file order
  (kernel body 1 + k ends tether k), then the roots of the other components;
* elimination order: deepest child first, ties in file order (``sorted(k, key=(-depth, k))``).

Loops: the kernel solves trees, so scene load refuses a graph with a cut tether today.  A loop
solver plugs in here: a cut tether keeps its two ends, and the spanning forest is what the
elimination walks; the cut tether adds one closure constraint between the ends it names.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

CENTER_OF_MASS = "center_of_mass"


@dataclass(frozen=True)
class LayoutStep:
    """One step of the initial layout: lay ``tether`` from its already placed end ``start``.

    ``end`` is the body the step places (the tether's other end, put there by its initial
    shape), or None when both ends are already placed and the tether starts straight between
    them.
    """

    tether: str
    start: str
    end: str | None


@dataclass(frozen=True)
class OrientedTether:
    """A tether of the spanning forest, oriented from its root side (``parent``) to ``child``.

    ``index``: its position in the file (and in the kernel: kernel body 1 + index is ``child``);
    ``reversed``: the scene writes it child -> parent (``from`` is the child)."""

    index: int
    name: str
    parent: str
    child: str
    reversed: bool


@dataclass(frozen=True)
class CutTether:
    """A tether left out of the spanning forest: its ends were already joined, so it closes a loop."""

    index: int  # position in the file
    name: str
    from_body: str
    to_body: str


@dataclass(frozen=True)
class Graph:
    bodies: tuple[str, ...]  # body names, file order
    tethers: tuple[OrientedTether, ...]  # the spanning forest, file order (kernel tether k)
    cut: tuple[CutTether, ...]  # tethers closing loops (refused at load until loops are solved)
    component: dict[str, int]  # body -> its component (numbered by first body in file order)
    roots: tuple[str, ...]  # the root of every component, component order (roots[0]: kernel body 0)
    fixed: tuple[tuple[str, ...], ...]  # the fixed bodies of every component, file order
    kernel_bodies: tuple[str, ...]  # body names in kernel order
    depth: tuple[int, ...]  # per kernel body: tethers between it and its root
    elimination_order: tuple[int, ...]  # kernel tether indices, leaves first
    children: dict[str, tuple[int, ...]]  # body -> the forest tethers it is the parent of
    simple: bool  # a star of point masses around kernel body 0, every tether written from it
    layout: tuple[LayoutStep, ...] = ()  # the layout plan (set once the [orbit] is known)
    unplaced: tuple[str, ...] = ()  # bodies the layout plan cannot place

    @property
    def placement_order(self) -> tuple[int, ...]:
        """Kernel tether indices with every parent placed before its children (shallow first)."""
        return tuple(sorted(range(len(self.tethers)), key=lambda k: (self.depth[1 + k], k)))

    @property
    def parents(self) -> list[str]:
        return [t.parent for t in self.tethers]

    @property
    def child_names(self) -> list[str]:
        return [t.child for t in self.tethers]

    @property
    def reversed(self) -> list[bool]:
        return [t.reversed for t in self.tethers]

    def with_layout(self, bodies, tethers, orbit) -> "Graph":
        """This graph with the layout plan of the scene's [orbit] (None: every body is placed)."""
        steps, unplaced = layout_plan(bodies, tethers, orbit)
        return dataclasses.replace(self, layout=tuple(steps), unplaced=tuple(unplaced))


def depths_and_order(nbody: int, parent_index: list[int]) -> tuple[list[int], list[int]]:
    """Depths of the kernel bodies and the elimination order (leaves first, ties in tether order)
    of a forest in kernel order: tether k joins body ``parent_index[k]`` to its child 1 + k."""
    nteth = len(parent_index)
    depth: list[int | None] = [None] * nbody
    for b in [0] + list(range(1 + nteth, nbody)):
        depth[b] = 0
    for k in range(nteth):
        chain = []
        b = 1 + k
        while depth[b] is None:
            chain.append(b)
            b = parent_index[b - 1]
            if len(chain) > nteth:
                raise ValueError("tethers: the parents form a loop (the kernel solves trees)")
        for c in reversed(chain):
            depth[c] = depth[parent_index[c - 1]] + 1
    order = sorted(range(nteth), key=lambda k: (-depth[1 + k], k))
    return [int(d) for d in depth], order


def build(bodies, tethers) -> Graph:
    """The graph of ``bodies`` (scene.Body, file order) and ``tethers`` (scene.Tether, file order)."""
    names = [b.name for b in bodies]
    # spanning forest in file order: a tether whose ends are already joined closes a loop
    uf = {n: n for n in names}

    def find(x):
        while uf[x] != x:
            uf[x] = uf[uf[x]]
            x = uf[x]
        return x

    forest, cut = [], []
    for k, t in enumerate(tethers):
        a, b = find(t.from_body), find(t.to_body)
        if a == b:
            cut.append(CutTether(k, t.name, t.from_body, t.to_body))
            continue
        uf[a] = b
        forest.append(t)
    adj: dict[str, list] = {n: [] for n in names}
    for k, t in enumerate(forest):
        adj[t.from_body].append((k, t.to_body))
        adj[t.to_body].append((k, t.from_body))
    comp: dict[str, int] = {}
    members: list[list[str]] = []
    for n in names:
        if n in comp:
            continue
        comp[n] = len(members)
        group, stack = [], [n]
        while stack:
            x = stack.pop()
            group.append(x)
            for _, y in adj[x]:
                if y not in comp:
                    comp[y] = comp[n]
                    stack.append(y)
        members.append(group)
    roots, fixed = [], []
    for c, group in enumerate(members):
        fx = tuple(b.name for b in bodies if comp[b.name] == c and b.fixed)
        first = next((t for t in tethers if comp[t.from_body] == c), None)
        alone = next(n for n in names if comp[n] == c)
        roots.append(fx[0] if fx else (first.from_body if first is not None else alone))
        fixed.append(fx)
    # orient every forest tether away from its component's root (unique in a tree)
    parent = [None] * len(forest)
    child = [None] * len(forest)
    for root in roots:
        stack, seen = [root], {root}
        while stack:
            x = stack.pop()
            for k, y in adj[x]:
                if y in seen:
                    continue
                seen.add(y)
                parent[k], child[k] = x, y
                stack.append(y)
    oriented = tuple(
        OrientedTether(k, t.name, parent[k], child[k], parent[k] != t.from_body) for k, t in enumerate(forest)
    )
    kernel = [roots[0]] + list(child) + roots[1:]
    kindex = {n: i for i, n in enumerate(kernel)}
    parent_index = [kindex[p] for p in parent]
    depth, order = depths_and_order(len(kernel), parent_index)
    children = {n: tuple(k for k in range(len(forest)) if parent[k] == n) for n in names}
    rigid = any(b.rigid is not None for b in bodies)
    simple = (
        len(roots) == 1 and not any(t.reversed for t in oriented) and all(p == roots[0] for p in parent) and not rigid
    )
    return Graph(
        bodies=tuple(names),
        tethers=oriented,
        cut=tuple(cut),
        component=comp,
        roots=tuple(roots),
        fixed=tuple(fixed),
        kernel_bodies=tuple(kernel),
        depth=tuple(depth),
        elimination_order=tuple(order),
        children=children,
        simple=simple,
    )


def layout_plan(bodies, tethers, orbit) -> tuple[list[LayoutStep], list[str]]:
    """Layout order and the bodies it cannot place.

    Start from the placed bodies (every body without [orbit]; with a body reference, it and the
    bodies with explicit states; with the centre of mass, the first body, the whole layout being
    shifted afterwards to put the centre of mass on the orbit).  Sweep the tethers in file order,
    laying each that has exactly one placed end, until nothing changes; the tethers left with both
    ends placed start straight between their ends.
    """
    if orbit is None:
        placed = {b.name for b in bodies}
    elif orbit.reference == CENTER_OF_MASS:
        placed = {bodies[0].name}
    else:
        placed = {orbit.reference} | {b.name for b in bodies if b.has_state}
    steps: list[LayoutStep] = []
    laid: set[str] = set()
    progress = True
    while progress:
        progress = False
        for t in tethers:
            if t.name in laid:
                continue
            if (t.from_body in placed) != (t.to_body in placed):
                start, end = (t.from_body, t.to_body) if t.from_body in placed else (t.to_body, t.from_body)
                steps.append(LayoutStep(t.name, start, end))
                placed.add(end)
                laid.add(t.name)
                progress = True
    steps.extend(
        LayoutStep(t.name, t.from_body, None)
        for t in tethers
        if t.name not in laid and t.from_body in placed and t.to_body in placed
    )
    return steps, [b.name for b in bodies if b.name not in placed]
