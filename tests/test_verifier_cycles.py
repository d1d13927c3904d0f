"""The cycles findings name: networkx's searches, in the catalog's order, and iterative."""

from __future__ import annotations

import networkx as nx

from aeroexec.catalog.loader import parse_catalog
from aeroexec.verifier import CatalogGraphs, check_catalog
from aeroexec.verifier.cycles import cyclic_components, reaching, shortest_cycle


def test_a_cycle_of_100_000_needs_no_recursion_and_no_quadratic_memory() -> None:
    """A recursive search stops at Python's recursion limit (1,000); one that keeps
    every shortest path (as `single_source_shortest_path` does) holds 5e9 list items."""
    size = 100_000
    graph = nx.DiGraph()
    graph.add_edges_from((n, n + 1) for n in range(size))
    graph.add_edge(size, 0)
    graph.add_edge(size, "tail")
    [component] = cyclic_components(graph)
    assert len(component) == size + 1
    cycle = shortest_cycle(graph, component, key=lambda n: n)
    assert cycle == [*range(size + 1), 0]
    assert reaching(graph, ["tail"]) == {*range(size + 1), "tail"}


def fan() -> nx.DiGraph:
    """0 -> 5 -> 9 -> 0 and 0 -> 3 -> 9 -> 0, equally short; 5 is 0's first successor
    (by key and in a set of small ints, 3 comes first). 0 also has successors outside
    the cycle, which the search must not enter."""
    graph = nx.DiGraph()
    graph.add_edges_from([(0, 5), (0, 3), *((0, 100 + i) for i in range(12))])
    graph.add_edges_from([(5, 9), (3, 9), (9, 0)])
    return graph


def test_the_search_follows_the_order_the_edges_were_imposed_in() -> None:
    graph = fan()
    [component] = cyclic_components(graph)
    assert component == {0, 3, 5, 9}
    assert shortest_cycle(graph, component, key=lambda n: n) == [0, 5, 9, 0]


def test_equally_short_cycles_close_through_the_first_predecessor_by_key() -> None:
    graph = nx.DiGraph([(0, 7), (7, 0), (0, 4), (4, 0), (0, 2), (2, 6), (6, 0)])
    [component] = cyclic_components(graph)
    assert shortest_cycle(graph, component, key=lambda n: n) == [0, 4, 0]
    # The start is the first by key too; from 7, the shortest cycle goes through 0.
    assert shortest_cycle(graph, component, key=lambda n: -n) == [7, 0, 7]


def test_self_loops_are_cycles_and_lone_nodes_are_not() -> None:
    graph = nx.DiGraph([("a", "a"), ("a", "b"), ("b", "c")])
    assert cyclic_components(graph) == [{"a"}]
    assert shortest_cycle(graph, {"a"}, key=str) == ["a", "a"]


def chain_catalog(length: int, cyclic: bool) -> str:
    """Capabilities C00000 <- C00001 <- ... (each requires the one before), used by one
    behavior; with `cyclic`, the first requires the last."""
    lines = [
        "behavior_descriptors:",
        f"  - {{behavior: TOP, timeout: 1, recurrent: no, capabilities: [C{length - 1:05d}]}}",
        "behavior_lists: []",
        "capability_descriptors:",
    ]
    for i in range(length):
        required = f"C{i - 1:05d}" if i else (f"C{length - 1:05d}" if cyclic else "")
        lines.append(
            f"  - {{capability: C{i:05d}, active_by_default: no, processes: [p{i}], "
            f"required_capabilities: [{required}]}}"
        )
    return "\n".join(lines) + "\n"


def test_a_long_requirement_chain_expands_in_order() -> None:
    graphs = CatalogGraphs(parse_catalog(chain_catalog(2_000, cyclic=False), "chain.yaml"))
    assert graphs.expansion("TOP") == tuple(f"C{i:05d}" for i in range(2_000))
    assert graphs.broken_capabilities == frozenset()


def test_a_long_requirement_cycle_is_named_from_its_first_capability() -> None:
    catalog = parse_catalog(chain_catalog(2_000, cyclic=True), "chain.yaml")
    [finding] = [f for f in check_catalog(catalog) if f.rule == "AX502"]
    names = [f"C{i:05d}" for i in range(2_000)]
    # C00000 requires C02999, which requires C02998, ... back to C00000.
    shown = " -> ".join(["C00000", *reversed(names[1:]), "C00000"])
    assert finding.message.startswith(f"capabilities require each other in a cycle: {shown};")
    assert finding.message.endswith("behaviors using them are rejected: TOP")
