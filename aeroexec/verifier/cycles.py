"""The cycle and reachability questions the rules ask of their graphs, answered by networkx.

Every answer is a networkx algorithm (strongly connected components, breadth-first
search); what this module adds is the order in which findings name things: a cycle
starts at the first node of its strongly connected set by the rule's key (catalog
order), its search follows each node's successors in the order the catalog imposed them
(the graph's insertion order, never a set's), and among equally short cycles the one
closing through the first predecessor by the key wins. So a finding names the same
cycle on every run, whatever the hash seed.

networkx's algorithms are iterative: a chain of 100,000 capabilities does not reach
Python's recursion limit. networkx is imported by the functions (only `verify` builds
graphs, and no other command should pay for the import).
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Hashable, Iterable, Iterator
from itertools import pairwise
from typing import TYPE_CHECKING, Any, TypeVar

if TYPE_CHECKING:
    import networkx as nx

N = TypeVar("N", bound=Hashable)

__all__ = ["cycle_edges", "cyclic_components", "reaching", "shortest_cycle"]


def cyclic_components(graph: nx.DiGraph) -> list[set[Any]]:
    """The strongly connected sets that hold a cycle: more than one node, or a node
    with an edge to itself. In no particular order: callers sort them by their key."""
    import networkx as nx

    looped = set(nx.nodes_with_selfloops(graph))
    return [
        component
        for component in nx.strongly_connected_components(graph)
        if len(component) > 1 or not looped.isdisjoint(component)
    ]


def reaching(graph: nx.DiGraph, targets: Iterable[Any]) -> set[Any]:
    """`targets` and every node with a path to one of them (one breadth-first search
    from all of them at once on the reversed graph, however many they are)."""
    import networkx as nx

    return set().union(*nx.bfs_layers(graph.reverse(copy=False), list(targets)))


def shortest_cycle(graph: nx.DiGraph, nodes: Collection[N], key: Callable[[N], Any]) -> list[N]:
    """The shortest cycle through the first (by `key`) node of a strongly connected set,
    as [start, ..., start]: networkx's breadth-first search from `start` in the set's
    subgraph, each node's successors in the graph's order (a subgraph view keeps it);
    ties go to the cycle closing through the predecessor of `start` first by `key`."""
    import networkx as nx

    members = nodes if isinstance(nodes, (set, frozenset)) else set(nodes)
    start = min(members, key=key)
    if graph.has_edge(start, start):
        return [start, start]
    inside = graph.subgraph(members)
    # Per node reached: the nodes it is first reached from (the first is the search
    # tree's parent), and its distance from `start`.
    parents, distance = nx.predecessor(inside, start, return_seen=True)
    closing = [p for p in inside.predecessors(start) if p in distance]
    if not closing:
        raise ValueError("the nodes are not strongly connected")
    path = [min(closing, key=lambda p: (distance[p], key(p)))]
    while path[-1] != start:
        path.append(parents[path[-1]][0])
    path.reverse()
    return [*path, start]


def cycle_edges(cycle: list[N]) -> Iterator[tuple[N, N]]:
    return pairwise(cycle)
