"""The graphs the rules ask questions of, on the thesis' Appendix A catalog."""

from __future__ import annotations

from aeroexec.catalog import THESIS_CATALOG, read_catalog
from aeroexec.catalog.loader import parse_catalog
from aeroexec.verifier import CatalogGraphs
from aeroexec.verifier.suggest import Suggester


def graphs_of(text: str) -> CatalogGraphs:
    return CatalogGraphs(parse_catalog(text, "g.yaml"))


def test_thesis_graphs() -> None:
    graphs = CatalogGraphs(read_catalog(THESIS_CATALOG))
    conflicts = graphs.conflict_graph
    assert set(map(frozenset, conflicts.edges())) == {
        frozenset({"SETPOINT_BASED_FLIGHT_CONTROL", "VISUAL_SERVOING"})
    }
    preemption = graphs.preemption_graph
    assert preemption.has_edge("TAKE_OFF", "ROTATE") and preemption.has_edge("ROTATE", "TAKE_OFF")
    assert not preemption.has_node("LOOK_AT_POINT")  # only defined behaviors
    assert not any(preemption.has_edge("PAY_ATTENTION", b) for b in preemption)
    assert graphs.incompatibility_graph.has_edge("GO_TO_POINT", "FLIP")
    assert graphs.asymmetric_preemption == {}
    assert graphs.expansion("GO_TO_POINT") == ("SETPOINT_BASED_FLIGHT_CONTROL", "PATH_PLANNING")
    assert graphs.holders["VISUAL_SERVOING"] == ("FOLLOW_OBJECT_IMAGE",)
    assert graphs.defaults == ("SELF_LOCALIZATION_BY_ODOMETRY",)
    order = graphs.start_order_graph
    assert order.has_edge(("process", "droneTrajectoryPlanner"), ("process", "droneYawPlanner"))
    # GO_TO_POINT lists flight control before path planning.
    assert order.has_edge(
        ("capability", "SETPOINT_BASED_FLIGHT_CONTROL"), ("process", "droneTrajectoryPlanner")
    )


CATALOG = """
behavior_descriptors:
  - {behavior: X, timeout: 1, recurrent: no, capabilities: [A, B]}
  - {behavior: Y, timeout: 1, recurrent: no, capabilities: [C]}
behavior_lists: []
capability_descriptors:
  - {capability: A, active_by_default: no, processes: [p]}
  - {capability: B, active_by_default: no, processes: [p, q]}
  - {capability: C, active_by_default: no, processes: [r], required_capabilities: [D]}
  - {capability: D, active_by_default: no, processes: [s], required_capabilities: [E]}
  - {capability: E, active_by_default: no, processes: [t]}
"""


def test_shared_processes_are_not_a_start_order_cycle() -> None:
    """B starts p (already running for A) and q: no edge back into p."""
    import networkx as nx

    graphs = graphs_of(CATALOG)
    assert nx.is_directed_acyclic_graph(graphs.start_order_graph)
    assert graphs.start_order_graph.has_edge(("capability", "A"), ("process", "q"))


def test_expansion_puts_required_capabilities_first() -> None:
    graphs = graphs_of(CATALOG)
    assert graphs.expansion("Y") == ("E", "D", "C")
    assert graphs.closure("D") == ("E", "D")
    assert graphs.holders["E"] == ("Y",)


def test_suggester_large_pool_finds_the_misspelling() -> None:
    names = [f"BEHAVIOR_{i:05d}" for i in range(5000)] + ["SELF_LOCALIZE_BY_VISUAL_MARKER"]
    suggester = Suggester(names)
    assert suggester.best("SELF_LOCALIZE_BY_VISUAL_MARKERS") == "SELF_LOCALIZE_BY_VISUAL_MARKER"
    assert suggester.best("BEHAVIOR_0123X") is not None
    assert suggester.best("COMPLETELY_DIFFERENT") is None
    assert suggester.hint("behavior_00042") == " (did you mean 'BEHAVIOR_00042'?)"
