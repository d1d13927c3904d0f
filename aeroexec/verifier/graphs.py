"""A loaded catalog with the indexes and graphs the rules ask questions of.

Everything is computed lazily and once per catalog, in time linear in the catalog (plus
the size of the answers): rules never loop over all pairs of behaviors.

Graphs are networkx graphs, built on first use (networkx is imported then: only the
rules that ask a graph question pay for it, and no command but `verify` does); their
questions (strongly connected sets, reachability, shortest cycles, dependency order)
are networkx algorithms (`aeroexec.verifier.cycles`). Pair questions that need no graph
use `conflict_pairs`, the declared pairs in file order.

* `conflict_graph` — undirected, capabilities, an edge per declared
  `incompatible_capabilities` pair (symmetric, as the executive reads it);
* `requires_graph` — directed, capability -> each capability it requires;
* `start_order_graph` — directed, what must start before what: process -> process
  (a capability's process order), last process -> "capability up", "capability up" ->
  the first not-yet-running process of the next capability in a behavior's list or of
  a capability that requires it; every edge says which behaviors or capabilities
  impose it;
* `preemption_graph` — directed, A -> B when activating A stops B (built on demand:
  it is quadratic in the size of a list, so no rule needs it);
* `incompatibility_graph` — its undirected version (A and B cannot run together);
* `asymmetric_preemption_graph` — the edges A -> B of the preemption digraph whose
  reverse B -> A is missing (built from set differences, linear in the relation).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING, Generic, TypeVar

from aeroexec.behaviors import STANDARD_LIBRARY
from aeroexec.catalog.model import (
    BehaviorDescriptor,
    BehaviorList,
    CapabilityDescriptor,
    Catalog,
    Severity,
)
from aeroexec.errors import Mark
from aeroexec.executive.behavior import Behavior
from aeroexec.vehicles.world import World, default_world
from aeroexec.verifier.cycles import cyclic_components, reaching
from aeroexec.verifier.findings import Finding, Witness
from aeroexec.verifier.suggest import Suggester

if TYPE_CHECKING:
    import networkx as nx

    from aeroexec.verifier.witness import ActivationModel

T = TypeVar("T", BehaviorDescriptor, BehaviorList, CapabilityDescriptor)

#: Start-order graph nodes: ("capability", name) or ("process", name).
Node = tuple[str, str]
#: A behavior's capability k must follow this many earlier ones directly (all of them in
#: any real catalog); beyond that the order is implied through the chain.
_PAIRWISE_LIMIT = 16


@dataclass(frozen=True, slots=True)
class Definition(Generic[T]):
    """One definition in file order; `effective` is False for one a later duplicate
    replaces (the executive never sees it, the verifier still checks it)."""

    item: T
    effective: bool
    replaced_at: int = 0  # line of the definition that replaces it


class OrderEdge:
    """Why one thing must start before another: imposed by `by` (a behavior or a
    capability, `by_kind`) through item `index` of its list `field`.

    Its `reason` and `mark` are written only when asked for: a large catalog imposes
    tens of thousands of edges, and only those of a cycle are ever reported. Treat
    instances as immutable."""

    __slots__ = ("_owner", "by", "by_kind", "field", "implied", "index", "other", "why")

    def __init__(
        self,
        by_kind: str,
        owner: BehaviorDescriptor | CapabilityDescriptor,
        why: str,
        field: str,
        index: int,
        other: str = "",
        *,
        implied: bool = False,
    ) -> None:
        self.by_kind = by_kind  # "behavior" or "capability"
        self.by = owner.name
        self._owner = owner
        #: The reason, its names still to be filled in: `{by}`, `{item}` (item `index`
        #: of the list `field`) and `{other}`.
        self.why = why
        self.field = field
        self.index = index
        self.other = other
        #: True for "a capability is up once its last process runs": implied, not authored.
        self.implied = implied

    @property
    def reason(self) -> str:
        item = getattr(self._owner, self.field)[self.index]
        return self.why.format(by=self.by, item=item, other=self.other)

    @property
    def mark(self) -> Mark:
        return self._owner.item_mark(self.field, self.index)

    def __repr__(self) -> str:
        return f"OrderEdge({self.reason!r}, {self.mark})"


def node_label(node: Node) -> str:
    return f"{node[0]} {node[1]}"


class CatalogGraphs:
    """The context every catalog rule receives: the catalog, and the world and behavior
    library it is meant to fly with (the vehicle's limits; what implementations declare)."""

    def __init__(
        self,
        catalog: Catalog,
        world: World | None = None,
        library: Mapping[str, type[Behavior]] | None = None,
    ) -> None:
        self.catalog = catalog
        self.file = catalog.source
        self._world = world
        self._library = library

    @cached_property
    def world(self) -> World:
        return self._world or default_world()

    @cached_property
    def library(self) -> Mapping[str, type[Behavior]]:
        return STANDARD_LIBRARY if self._library is None else self._library

    # -- findings ------------------------------------------------------------------------
    def finding(
        self,
        rule: str,
        severity: Severity,
        message: str,
        mark: Mark,
        subjects: Iterable[str] = (),
        witness: Witness | None = None,
    ) -> Finding:
        return Finding.in_file(self.file, rule, severity, message, mark, subjects, witness)

    @property
    def top_mark(self) -> Mark:
        return Mark(self.file, 1, 1) if self.catalog.text else Mark(self.file)

    # -- definitions (duplicates included) -----------------------------------------------
    @cached_property
    def behavior_defs(self) -> tuple[Definition[BehaviorDescriptor], ...]:
        return _definitions(self.catalog.all_behaviors, self.catalog.behaviors)

    @cached_property
    def list_defs(self) -> tuple[Definition[BehaviorList], ...]:
        return _definitions(self.catalog.all_lists, self.catalog.lists)

    @cached_property
    def capability_defs(self) -> tuple[Definition[CapabilityDescriptor], ...]:
        return _definitions(self.catalog.all_capabilities, self.catalog.capabilities)

    # -- suggestions ---------------------------------------------------------------------
    @cached_property
    def behavior_names(self) -> Suggester:
        return Suggester(self.catalog.behaviors)

    @cached_property
    def list_names(self) -> Suggester:
        return Suggester(self.catalog.lists)

    @cached_property
    def capability_names(self) -> Suggester:
        return Suggester(self.catalog.capabilities)

    # -- capability expansion (mirrors the specialist: required capabilities first) ------
    @cached_property
    def requires_graph(self) -> nx.DiGraph:
        """Capability -> each capability it requires (undefined ones included)."""
        import networkx as nx

        capabilities = self.catalog.capabilities
        graph = nx.DiGraph()
        graph.add_nodes_from(capabilities)
        graph.add_edges_from(
            (name, required)
            for name, capability in capabilities.items()
            for required in capability.required_capabilities
        )
        return graph

    @cached_property
    def requires_cycles(self) -> tuple[frozenset[str], ...]:
        """Strongly connected sets of capabilities that require each other (self-loops
        included), in catalog order."""
        found = [frozenset(scc) for scc in cyclic_components(self.requires_graph)]
        order = self.capability_order
        return tuple(sorted(found, key=lambda s: min(order.get(n, len(order)) for n in s)))

    @cached_property
    def capability_order(self) -> dict[str, int]:
        return {name: i for i, name in enumerate(self.catalog.capabilities)}

    @cached_property
    def broken_capabilities(self) -> frozenset[str]:
        """Capabilities that cannot be expanded: undefined, in a requires-cycle, or
        requiring (transitively) one of those."""
        graph = self.requires_graph
        bad = {n for n in graph if n not in self.catalog.capabilities}
        for scc in self.requires_cycles:
            bad |= scc
        return frozenset(reaching(graph, bad))

    @cached_property
    def _closures(self) -> dict[str, tuple[str, ...]]:
        """Per good capability: it and everything it requires, required ones first."""
        import networkx as nx

        broken = self.broken_capabilities
        closures: dict[str, tuple[str, ...]] = {}
        # A depth-first postorder lists a node after every node it points to, except
        # along an edge closing a cycle; a good capability requires only good ones and is
        # on no cycle, so in the postorder its requirements come first. (Cheaper than a
        # topological sort of a view that hides the broken ones.)
        for name in nx.dfs_postorder_nodes(self.requires_graph):
            if name in broken:
                continue
            required = self.catalog.capabilities[name].required_capabilities
            if not required:
                closures[name] = (name,)
                continue
            merged: dict[str, None] = {}
            for r in required:
                merged.update(dict.fromkeys(closures[r]))
            merged[name] = None
            closures[name] = tuple(merged)
        return closures

    def closure(self, capability: str) -> tuple[str, ...] | None:
        return self._closures.get(capability)

    def expansion(self, behavior: str) -> tuple[str, ...] | None:
        """The capabilities `behavior` references, in start order; None if one of them
        cannot be expanded (the activation then fails)."""
        cache = self._expansions
        if behavior in cache:
            return cache[behavior]
        descriptor = self.catalog.behaviors.get(behavior)
        result: tuple[str, ...] | None
        if descriptor is None:
            result = None
        elif len(descriptor.capabilities) == 1:
            result = self._closures.get(descriptor.capabilities[0])
        else:
            merged: dict[str, None] = {}
            result = ()
            for capability in descriptor.capabilities:
                closure = self._closures.get(capability)
                if closure is None:
                    result = None
                    break
                merged.update(dict.fromkeys(closure))
            if result is not None:
                result = tuple(merged)
        cache[behavior] = result
        return result

    @cached_property
    def _expansions(self) -> dict[str, tuple[str, ...] | None]:
        return {}

    @cached_property
    def defaults(self) -> tuple[str, ...]:
        """Capabilities referenced at initiation: the default ones and those they require
        (empty when that expansion fails, since initiation then fails)."""
        return self._default_expansion or ()

    @cached_property
    def defaults_broken(self) -> bool:
        """A default capability requires an undefined capability, or itself."""
        return self._default_expansion is None

    @cached_property
    def _default_expansion(self) -> tuple[str, ...] | None:
        merged: dict[str, None] = {}
        for capability in self.catalog.default_capabilities:
            closure = self._closures.get(capability)
            if closure is None:
                return None
            merged.update(dict.fromkeys(closure))
        return tuple(merged)

    @cached_property
    def holders(self) -> dict[str, tuple[str, ...]]:
        """Capability -> behaviors (catalog order) whose expansion references it."""
        result: dict[str, list[str]] = {}
        for name in self.catalog.behaviors:
            expansion = self.expansion(name)
            if expansion:
                for capability in expansion:
                    result.setdefault(capability, []).append(name)
        return {k: tuple(v) for k, v in result.items()}

    @property
    def model(self) -> ActivationModel:
        """The activation model of these graphs. Made on each use (it keeps nothing of
        its own), not cached: a cached one pointing back at the graphs would make a
        reference cycle, and the whole catalog would outlive the run as garbage that only
        the cyclic collector frees (after verify: ~1.4 s at exit for 30,000 behaviors)."""
        from aeroexec.verifier.witness import ActivationModel

        return ActivationModel(self)

    # -- capability conflicts ------------------------------------------------------------
    @cached_property
    def conflict_pairs(self) -> tuple[tuple[str, str], ...]:
        """Each declared pair of incompatible capabilities once (no self-pairs), in
        declaration order."""
        seen: set[frozenset[str]] = set()
        pairs: list[tuple[str, str]] = []
        for name, capability in self.catalog.capabilities.items():
            for other in capability.incompatible_capabilities:
                pair = frozenset((name, other))
                if other != name and pair not in seen:
                    seen.add(pair)
                    pairs.append((name, other))
        return tuple(pairs)

    @cached_property
    def conflict_graph(self) -> nx.Graph:
        import networkx as nx

        graph = nx.Graph()
        graph.add_nodes_from(self.catalog.capabilities)
        graph.add_edges_from(self.conflict_pairs)
        return graph

    def conflict_mark(self, a: str, b: str) -> Mark:
        """Where the conflict a-b is declared (a's entry naming b, else b's naming a)."""
        for first, second in ((a, b), (b, a)):
            spec = self.catalog.capabilities.get(first)
            if spec is not None and second in spec.incompatible_capabilities:
                index = spec.incompatible_capabilities.index(second)
                return spec.mark_of(f"incompatible_capabilities.{index}")
        spec = self.catalog.capabilities.get(a) or self.catalog.capabilities.get(b)
        return spec.mark if spec is not None else self.top_mark

    def own_conflict(self, behavior: str) -> tuple[str, str] | None:
        """A pair of conflicting capabilities in the behavior's own expansion, as the
        executive finds it (new capabilities only: defaults are already referenced)."""
        expansion = self.expansion(behavior)
        if not expansion or len(expansion) < 2:
            return None
        defaults = self.default_set
        new = [c for c in expansion if c not in defaults]
        seen: set[str] = set()
        for capability in new:
            conflicts = self.catalog.conflicts_of(capability)
            if conflicts:
                for other in new:
                    if other in seen and other in conflicts:
                        return other, capability
            seen.add(capability)
        return None

    def default_conflict(self, behavior: str) -> tuple[str, str] | None:
        """(capability, default capability) of the behavior that conflict."""
        expansion = self.expansion(behavior)
        if not expansion or not self.defaults:
            return None
        if self.default_clashes.isdisjoint(expansion):
            return None  # the usual behavior: one set look-up per capability
        defaults = self.default_set
        conflicts_of = self.catalog.conflicts_of
        for capability in expansion:
            if capability in defaults:
                continue
            conflicts = conflicts_of(capability)
            if conflicts and not conflicts.isdisjoint(defaults):
                return capability, min(conflicts & defaults)
        return None

    @cached_property
    def default_set(self) -> frozenset[str]:
        """`defaults` as a set (asked about once per behavior)."""
        return frozenset(self.defaults)

    @cached_property
    def default_clashes(self) -> frozenset[str]:
        """Capabilities, not default ones, incompatible with a default capability
        (incompatibility is symmetric: those the defaults name)."""
        clashes: set[str] = set()
        for default in self.defaults:
            clashes |= self.catalog.conflicts_of(default)
        return frozenset(clashes - self.default_set)

    @cached_property
    def activatable(self) -> frozenset[str]:
        """Behaviors whose activation from a freshly initiated executive succeeds (as far
        as the catalog decides it)."""
        initiated = not (self.default_pairs_in_conflict or self.defaults_broken)
        return frozenset(
            name
            for name in self.catalog.behaviors
            if self.expansion(name) is not None
            and self.own_conflict(name) is None
            and (not initiated or self.default_conflict(name) is None)
        )

    @cached_property
    def default_pairs_in_conflict(self) -> tuple[tuple[str, str], ...]:
        defaults = self.defaults
        pairs = []
        for i, capability in enumerate(defaults):
            conflicts = self.catalog.conflicts_of(capability)
            for other in defaults[:i]:
                if other in conflicts:
                    pairs.append((other, capability))
        return tuple(pairs)

    # -- lists and preemption ------------------------------------------------------------
    @cached_property
    def list_namers(self) -> dict[str, tuple[str, ...]]:
        """Defined list -> behaviors (catalog order) that name it in incompatible_lists.
        Undefined names are left out: a hostile catalog names a million of them, each an
        entry here for nothing (AX201 reports them from the descriptors)."""
        lists = self.catalog.lists
        result: dict[str, list[str]] = {}
        for name, behavior in self.catalog.behaviors.items():
            # Deduplicated among the defined lists only: no set of every name written.
            named = {n for n in behavior.incompatible_lists if n in lists}
            for list_name in behavior.incompatible_lists:
                if list_name in named:
                    named.discard(list_name)
                    result.setdefault(list_name, []).append(name)
        return {k: tuple(v) for k, v in result.items()}

    def preempts(self, a: str, b: str) -> bool:
        return b in self.catalog.preempted_by(a)

    @cached_property
    def preemptors(self) -> dict[str, frozenset[str]]:
        """Defined behavior B -> behaviors whose activation stops B (they name a list
        that contains B)."""
        catalog = self.catalog
        result: dict[str, set[str]] = {}
        for list_name, namers in self.list_namers.items():
            members = catalog.lists.get(list_name)
            if members is None:
                continue
            for member in members.behaviors:
                if member in catalog.behaviors:
                    result.setdefault(member, set()).update(namers)
        return {k: frozenset(v) for k, v in result.items()}

    def mutual(self, behavior: str) -> frozenset[str]:
        """Behaviors that `behavior` preempts and that preempt it back."""
        return self.catalog.preempted_by(behavior) & self.preemptors.get(behavior, frozenset())

    @cached_property
    def asymmetric_preemption(self) -> dict[str, tuple[str, ...]]:
        """A -> defined behaviors B (catalog order) that A preempts but that do not
        preempt A. Cost: the size of the preemption relation, in set operations."""
        catalog = self.catalog
        order = catalog.order_of
        result: dict[str, list[str]] = {}
        for b, attackers in self.preemptors.items():
            one_sided = attackers - catalog.preempted_by(b)
            for a in one_sided:
                if a != b:
                    result.setdefault(a, []).append(b)
        return {
            a: tuple(sorted(bs, key=order))
            for a, bs in sorted(result.items(), key=lambda item: order(item[0]))
        }

    @cached_property
    def asymmetric_preemption_graph(self) -> nx.DiGraph:
        """A -> B for each one-sided preemption; each node's edges in catalog order."""
        import networkx as nx

        graph = nx.DiGraph()
        graph.add_edges_from(
            (a, b) for a, victims in self.asymmetric_preemption.items() for b in victims
        )
        return graph

    @cached_property
    def preemption_graph(self) -> nx.DiGraph:
        import networkx as nx

        behaviors = self.catalog.behaviors
        graph = nx.DiGraph()
        graph.add_nodes_from(behaviors)
        graph.add_edges_from(
            (name, victim)
            for name in behaviors
            for victim in self.catalog.preempted_by(name)
            if victim in behaviors
        )
        return graph

    @cached_property
    def incompatibility_graph(self) -> nx.Graph:
        return self.preemption_graph.to_undirected(as_view=False)

    def preempting_list(self, a: str, b: str) -> tuple[int, str] | None:
        """(index in A's incompatible_lists, list name) through which A preempts B."""
        descriptor = self.catalog.behaviors[a]
        for index, list_name in enumerate(descriptor.incompatible_lists):
            members = self.catalog.lists.get(list_name)
            if members is not None and b in members.behaviors:
                return index, list_name
        return None

    # -- start order ---------------------------------------------------------------------
    @cached_property
    def start_order_graph(self) -> nx.DiGraph:
        """What must start before what. Nodes: ("process", p), and ("capability", C)
        meaning "C is up" (all its processes run). Edges carry `why`: the OrderEdges
        (catalog order) that impose them:

        * a capability's processes in their order, the last one before the capability
          is up;
        * a behavior's capabilities in their order: the previous capability is up
          before the next one's first process *that is not already running* (processes
          shared with earlier capabilities start only once);
        * a required capability is up before the first (not yet running) process of the
          capability that requires it.
        """
        import networkx as nx

        # Collected in plain dicts first (an edge is imposed again and again: appending
        # to a list is cheaper than asking the graph), then given to networkx at once.
        # Each node's successors keep the order the catalog imposed them in.
        successors: dict[Node, dict[Node, list[OrderEdge]]] = {}
        capabilities = self.catalog.capabilities
        requires_scc: dict[str, frozenset[str]] = {}
        for scc in self.requires_cycles:
            for name in scc:
                requires_scc[name] = scc

        def add(u: Node, v: Node, why: OrderEdge) -> None:
            if u == v:
                return
            imposed = successors.setdefault(u, {})
            if v in imposed:
                imposed[v].append(why)
            else:
                imposed[v] = [why]

        unique_processes: dict[str, tuple[str, ...]] = {}
        up_with: dict[str, frozenset[str]] = {}

        def processes(name: str) -> tuple[str, ...]:
            found = unique_processes.get(name)
            if found is None:
                found = unique_processes[name] = tuple(dict.fromkeys(capabilities[name].processes))
            return found

        def running_after(name: str) -> frozenset[str]:
            """Processes running once `name` is up (with what it requires); once per
            capability, however many behaviors list it."""
            found = up_with.get(name)
            if found is None:
                running: set[str] = set()
                for capability in self.closure(name) or (name,):
                    running.update(processes(capability))
                found = up_with[name] = frozenset(running)
            return found

        def entry(name: str, running: set[str] | frozenset[str]) -> Node:
            for process in processes(name):
                if process not in running:
                    return ("process", process)
            return ("capability", name)

        for name, spec in capabilities.items():
            up: Node = ("capability", name)
            previous: str | None = None
            for index, process in enumerate(spec.processes):
                if process == previous or process in spec.processes[:index]:
                    continue
                if previous is not None:
                    add(
                        ("process", previous),
                        ("process", process),
                        OrderEdge(
                            "capability",
                            spec,
                            "capability {by} starts {other} before {item}",
                            "processes",
                            index,
                            previous,
                        ),
                    )
                previous = process
            if previous is not None:
                add(
                    ("process", previous),
                    up,
                    OrderEdge(
                        "capability",
                        spec,
                        "capability {by} is up once {item} runs",
                        "processes",
                        spec.processes.index(previous),
                        implied=True,
                    ),
                )
            for index, required in enumerate(spec.required_capabilities):
                if required not in capabilities:
                    continue
                if required in requires_scc.get(name, ()):
                    continue  # a requires-cycle is its own finding (AX502)
                add(
                    ("capability", required),
                    entry(name, running_after(required)),
                    OrderEdge(
                        "capability",
                        spec,
                        "capability {by} requires {item}",
                        "required_capabilities",
                        index,
                    ),
                )
        for behavior in self.catalog.behaviors.values():
            if len(behavior.capabilities) < 2:
                continue  # imposes no order
            # Every earlier capability before every later one (not only neighbours),
            # so that a reported cycle is as short as the contradiction itself.
            earlier: list[str] = []
            running: set[str] = set()
            for index, capability in enumerate(behavior.capabilities):
                if capability not in capabilities or capability in behavior.capabilities[:index]:
                    continue
                target = entry(capability, running)
                for before in earlier[-_PAIRWISE_LIMIT:]:
                    add(
                        ("capability", before),
                        target,
                        OrderEdge(
                            "behavior",
                            behavior,
                            "behavior {by} lists {other} before {item}",
                            "capabilities",
                            index,
                            before,
                        ),
                    )
                running |= running_after(capability)
                earlier.append(capability)
        graph = nx.DiGraph()
        graph.add_nodes_from(("capability", name) for name in capabilities)
        graph.add_edges_from(
            (u, v, {"why": whys})
            for u, targets in successors.items()
            for v, whys in targets.items()
        )
        return graph

    def node_order(self, node: Node) -> tuple[int, int, str]:
        kind, name = node
        if kind == "capability":
            return (0, self.capability_order.get(name, 0), name)
        return (1, 0, name)


def _pmark(spec: CapabilityDescriptor, index: int) -> Mark:
    return spec.mark_of(f"processes.{index}")


def _definitions(all_items: tuple[T, ...], effective: Mapping[str, T]) -> tuple[Definition[T], ...]:
    items: Iterable[T] = all_items or tuple(effective.values())
    out: list[Definition[T]] = []
    for item in items:
        winner = effective.get(item.name)
        if winner is item or winner is None:
            out.append(Definition(item, winner is item))
        else:
            out.append(Definition(item, False, winner.mark.line))
    return tuple(out)
