"""The verifier's own graph algorithms agree with networkx, and stay iterative."""

from __future__ import annotations

import random
from itertools import pairwise

import networkx as nx
import pytest

from aeroexec.verifier.digraph import (
    Digraph,
    cyclic_components,
    dependencies_first,
    descendants,
    shortest_cycle,
    strongly_connected_components,
)


def random_graph(seed: int, nodes: int = 60, edges: int = 90) -> Digraph[int]:
    rng = random.Random(seed)
    graph: Digraph[int] = Digraph()
    for node in range(nodes):
        graph.add_node(node)
    for _ in range(edges):
        graph.add_edge(rng.randrange(nodes), rng.randrange(nodes))
    return graph


@pytest.mark.parametrize("seed", range(25))
def test_components_reachability_and_cycles_agree_with_networkx(seed: int) -> None:
    graph = random_graph(seed)
    reference = graph.to_networkx()
    ours = {frozenset(c) for c in strongly_connected_components(graph)}
    assert ours == {frozenset(c) for c in nx.strongly_connected_components(reference)}
    for node in (0, 7, 33):
        assert descendants(graph, node) == nx.descendants(reference, node)
    for component in cyclic_components(graph):
        cycle = shortest_cycle(graph, component, key=lambda n: n)
        assert cycle[0] == cycle[-1] == min(component)
        assert all(graph.has_edge(u, v) for u, v in pairwise(cycle))
        shortest = min(
            len(nx.shortest_path(reference, min(component), p))
            for p in component
            if graph.has_edge(p, min(component))
        )
        assert len(cycle) - 1 == shortest


def test_dependency_order_puts_what_is_pointed_to_first() -> None:
    graph: Digraph[str] = Digraph()
    for a, b in [("C", "B"), ("B", "A"), ("D", "A"), ("C", "D")]:
        graph.add_edge(a, b)
    order = dependencies_first(graph, "ABCD")
    assert all(order.index(b) < order.index(a) for a, b, _ in graph.edges())
    graph.add_edge("A", "C")
    with pytest.raises(ValueError):
        dependencies_first(graph, "ABCD")


def test_a_chain_of_100_000_needs_no_recursion() -> None:
    graph: Digraph[int] = Digraph()
    for node in range(100_000):
        graph.add_edge(node, node + 1)
    graph.add_edge(100_000, 0)
    [component] = strongly_connected_components(graph)
    assert len(component) == 100_001
    assert len(shortest_cycle(graph, component, key=lambda n: n)) == 100_002
