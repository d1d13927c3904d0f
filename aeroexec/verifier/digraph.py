"""A small directed graph and the few algorithms the rules need, in linear time.

The rules ask a handful of questions of graphs as large as the catalog (strongly
connected sets, what a node reaches, a shortest cycle, an order with requirements
first). A dict of dicts answers them with less memory and time than networkx, and
without importing it: `CatalogGraphs` still offers networkx views of its graphs for
callers who want them (built on request, importing networkx then).

Every algorithm is iterative: a chain of 100,000 capabilities must not reach Python's
recursion limit.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Hashable, Iterable, Iterator
from typing import Any, Generic, TypeVar

N = TypeVar("N", bound=Hashable)


class Digraph(Generic[N]):
    """Nodes in insertion order; each edge carries one value (`data`)."""

    __slots__ = ("succ",)

    def __init__(self) -> None:
        self.succ: dict[N, dict[N, Any]] = {}

    def add_node(self, node: N) -> None:
        self.succ.setdefault(node, {})

    def add_edge(self, u: N, v: N, data: Any = None) -> None:
        self.succ.setdefault(v, {})
        self.succ.setdefault(u, {})[v] = data

    def has_edge(self, u: N, v: N) -> bool:
        return v in self.succ.get(u, {})

    def edge(self, u: N, v: N) -> Any:
        return self.succ[u][v]

    def successors(self, node: N) -> Iterable[N]:
        return self.succ.get(node, {})

    def __contains__(self, node: object) -> bool:
        return node in self.succ

    def __iter__(self) -> Iterator[N]:
        return iter(self.succ)

    def __len__(self) -> int:
        return len(self.succ)

    def edges(self) -> Iterator[tuple[N, N, Any]]:
        for u, targets in self.succ.items():
            for v, data in targets.items():
                yield u, v, data

    def reverse(self) -> Digraph[N]:
        reversed_graph: Digraph[N] = Digraph()
        for node in self.succ:
            reversed_graph.add_node(node)
        for u, v, data in self.edges():
            reversed_graph.add_edge(v, u, data)
        return reversed_graph

    def to_networkx(self, directed: bool = True, attribute: str | None = None) -> Any:
        """The same graph as a networkx (Di)Graph; edge data under `attribute`."""
        import networkx as nx  # only for callers who ask for a networkx view

        graph = nx.DiGraph() if directed else nx.Graph()
        graph.add_nodes_from(self.succ)
        for u, v, data in self.edges():
            if attribute is None:
                graph.add_edge(u, v)
            else:
                graph.add_edge(u, v, **{attribute: data})
        return graph


def strongly_connected_components(graph: Digraph[N]) -> list[set[N]]:
    """Tarjan's algorithm, iteratively; components in reverse topological order."""
    index: dict[N, int] = {}
    low: dict[N, int] = {}
    on_stack: set[N] = set()
    stack: list[N] = []
    components: list[set[N]] = []
    counter = 0
    for root in graph.succ:
        if root in index:
            continue
        work: list[tuple[N, Iterator[N]]] = [(root, iter(graph.succ[root]))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            advanced = False
            for child in children:
                if child not in index:
                    index[child] = low[child] = counter
                    counter += 1
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(graph.succ[child])))
                    advanced = True
                    break
                if child in on_stack:
                    low[node] = min(low[node], index[child])
            if advanced:
                continue
            work.pop()
            if work:
                parent = work[-1][0]
                low[parent] = min(low[parent], low[node])
            if low[node] == index[node]:
                component: set[N] = set()
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.add(member)
                    if member == node:
                        break
                components.append(component)
    return components


def cyclic_components(graph: Digraph[N]) -> list[set[N]]:
    """Strongly connected sets that contain a cycle (a self-loop counts)."""
    return [
        c
        for c in strongly_connected_components(graph)
        if len(c) > 1 or graph.has_edge(next(iter(c)), next(iter(c)))
    ]


def descendants(graph: Digraph[N], start: N) -> set[N]:
    """Every node reachable from `start`, without `start` itself (as networkx says)."""
    seen: set[N] = set()
    queue = deque(graph.successors(start))
    while queue:
        node = queue.popleft()
        if node in seen:
            continue
        seen.add(node)
        queue.extend(graph.successors(node))
    seen.discard(start)
    return seen


def shortest_cycle(graph: Digraph[N], nodes: Iterable[N], key: Callable[[N], Any]) -> list[N]:
    """The shortest cycle through the first (by `key`) node of a strongly connected set:
    [start, ..., start]. Ties go to the predecessor first by `key`."""
    members = set(nodes)
    start = min(members, key=key)
    parents: dict[N, N | None] = {start: None}
    queue = deque([start])
    while queue:
        node = queue.popleft()
        for child in graph.successors(node):
            if child in members and child not in parents:
                parents[child] = node
                queue.append(child)
    best: list[N] | None = None
    for pred in sorted((m for m in members if graph.has_edge(m, start)), key=key):
        if pred not in parents:
            continue
        path = [pred]
        while parents[path[-1]] is not None:
            path.append(parents[path[-1]])  # type: ignore[arg-type]
        path.reverse()
        if best is None or len(path) < len(best):
            best = path
    if best is None:
        raise ValueError("the nodes are not strongly connected")
    return [*best, start]


def dependencies_first(graph: Digraph[N], nodes: Iterable[N]) -> list[N]:
    """`nodes` ordered so that every node comes after the nodes it points to (among
    `nodes`); the subgraph must be acyclic."""
    members = set(nodes)
    pending = {n: sum(1 for s in graph.successors(n) if s in members) for n in members}
    predecessors: dict[N, list[N]] = {n: [] for n in members}
    for node in members:
        for child in graph.successors(node):
            if child in members:
                predecessors[child].append(node)
    ready = deque(n for n in graph.succ if n in members and pending[n] == 0)
    order: list[N] = []
    while ready:
        node = ready.popleft()
        order.append(node)
        for parent in predecessors[node]:
            pending[parent] -= 1
            if pending[parent] == 0:
                ready.append(parent)
    if len(order) != len(members):
        raise ValueError("the subgraph has a cycle")
    return order
