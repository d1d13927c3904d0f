"""AX5xx: start order — the order constraints of capability and process lists, and
capabilities that require each other."""

from __future__ import annotations

from collections.abc import Iterator

from aeroexec.catalog.model import Severity
from aeroexec.verifier.cycles import cycle_edges, cyclic_components, reaching, shortest_cycle
from aeroexec.verifier.findings import Finding
from aeroexec.verifier.graphs import CatalogGraphs, OrderEdge, node_label
from aeroexec.verifier.registry import catalog_rule
from aeroexec.verifier.witness import rejection_witness

E, W = Severity.ERROR, Severity.WARNING


@catalog_rule(
    "AX501",
    "start-order-cycle",
    W,
    """The order constraints of the catalog admit no global start order. The resource
    manager starts a behavior's capabilities in the order the behavior lists them, each
    capability's processes in the order of its `processes` (`process_sequence`), and
    required capabilities before the ones that require them; those orders are there
    because the processes depend on each other. A cycle (e.g. one behavior lists
    A before B and another B before A, or two capabilities share processes in opposite
    orders) means at least one behavior starts its processes in an order its author
    said is wrong. In flight: a controller can start before the estimator it reads
    from. Fix: make the lists agree; the finding names every behavior and capability
    imposing an edge of the cycle.""",
)
def start_order_cycle(graphs: CatalogGraphs) -> Iterator[Finding]:
    graph = graphs.start_order_graph
    components = [c for c in cyclic_components(graph) if len(c) > 1]
    components.sort(key=lambda c: min(graphs.node_order(n) for n in c))
    for component in components:
        cycle = shortest_cycle(graph, component, graphs.node_order)
        reasons: list[OrderEdge] = [graph.edges[u, v]["why"][0] for u, v in cycle_edges(cycle)]
        shown = " -> ".join(node_label(n) for n in cycle)
        because = "; ".join(dict.fromkeys(r.reason for r in reasons if not r.implied))
        # Everyone imposing an edge inside the strongly connected set takes part, not
        # only those on the cycle shown (which depends on where the search starts).
        inside = graph.subgraph(component)
        imposers = sorted(
            {why.by for _, _, whys in inside.edges(data="why") for why in whys if not why.implied}
        )
        members = sorted(name for _, name in component)
        # The edge a behavior imposes is the most likely to be "the wrong one".
        anchor = next((r for r in reasons if r.by_kind == "behavior"), reasons[0])
        yield graphs.finding(
            "AX501",
            W,
            f"no start order satisfies every list: {shown} (because {because})",
            anchor.mark,
            [*imposers, *members],
        )


@catalog_rule(
    "AX502",
    "required-capability-cycle",
    E,
    """Capabilities that require each other (directly or through others), or a
    capability that requires itself. The executive starts required capabilities first,
    so it cannot order them. In flight: every behavior using one of them is rejected
    at activation. Fix: break the cycle; a requirement is "must already run", so it
    must point one way.""",
    witness=True,
)
def required_capability_cycle(graphs: CatalogGraphs) -> Iterator[Finding]:
    requires = graphs.requires_graph
    order = graphs.capability_order
    for component in graphs.requires_cycles:
        cycle = shortest_cycle(requires, component, lambda n: order.get(n, len(order)))
        first = graphs.catalog.capabilities[cycle[0]]
        index = first.required_capabilities.index(cycle[1])
        users = reaching(requires, component)
        affected = [
            b
            for b in graphs.catalog.behaviors
            if any(c in users for c in graphs.catalog.behaviors[b].capabilities)
        ]
        if affected:
            consequence = f"; behaviors using them are rejected: {', '.join(affected)}"
            witness = rejection_witness(graphs.model, affected[:1], affected[0])
        else:
            consequence = ""
            witness = None
        shown = " -> ".join(cycle)
        yield graphs.finding(
            "AX502",
            E,
            f"capabilities require each other in a cycle: {shown}{consequence}",
            first.mark_of(f"required_capabilities.{index}"),
            [*sorted(component, key=order.__getitem__), *affected],
            witness,
        )
