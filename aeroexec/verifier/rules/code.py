"""AX9xx: the catalog against the behavior implementations that would run it.

These rules run when the project declares its behaviors (`--behaviors`, a `behaviors`
key in `[tool.aeroexec]` / aeroexec.toml, or an installed `aeroexec.behaviors` entry
point): then `run` uses exactly that set, and a mismatch is a run-time failure found
before flight. Argument names are compared as behaviors declare them
(`Behavior.argument_names`) or, when a behavior declares none, as its hooks read them
(`args["TEMPERATURE"]`, found in the AST of its class's source: `code_reads`),
statically: no behavior code runs for these checks.
"""

from __future__ import annotations

import inspect
from collections.abc import Iterator

from aeroexec.catalog.model import BehaviorDescriptor, Severity
from aeroexec.plugins.discovery import BehaviorSet, Implementation
from aeroexec.verifier.code_reads import ArgumentsRead, arguments_read
from aeroexec.verifier.findings import Finding
from aeroexec.verifier.graphs import CatalogGraphs
from aeroexec.verifier.registry import code_rule
from aeroexec.verifier.suggest import Suggester

E = Severity.ERROR
W = Severity.WARNING
I = Severity.INFO  # noqa: E741  (the severities read as E, W, I)


def _where(implementation: Implementation) -> str:
    mark = implementation.mark
    return f"{mark.file}:{mark.line}" if mark.line else mark.file


def _implemented(
    graphs: CatalogGraphs, behaviors: BehaviorSet
) -> Iterator[tuple[BehaviorDescriptor, Implementation]]:
    for definition in graphs.behavior_defs:
        if not definition.effective:
            continue
        implementation = behaviors.implementations.get(definition.item.name)
        if implementation is not None and not implementation.stand_in:
            yield definition.item, implementation


def read_names(implementation: Implementation) -> ArgumentsRead | None:
    """The argument names the implementation reads: declared (`argument_names`, then
    complete), else found in its source's AST; None when neither can tell."""
    declared = implementation.cls.argument_names
    if declared is not None:
        return ArgumentsRead(tuple(declared), True)
    try:
        file = inspect.getsourcefile(implementation.cls)
    except TypeError:
        return None
    if file is None:
        return None
    return arguments_read(file, implementation.cls.__name__, implementation.mark.line)


def _how(implementation: Implementation) -> str:
    return "reads" if implementation.cls.argument_names is not None else "reads (in its code)"


@code_rule(
    "AX901",
    "no-implementation",
    E,
    """A catalog behavior has no implementation among the project's behaviors
    (`--behaviors`, `[tool.aeroexec] behaviors`, entry points, the standard library). In
    flight: `aeroexec run` and `aeroexec fly` refuse the catalog; with
    `--allow-unimplemented` the behavior is a stand-in that just succeeds after 1 s, so a
    typo in a name flies as a success. Fix: implement it (a `Behavior` subclass with this
    `name`), add the module to the project's behaviors, or correct the name.""",
)
def no_implementation(graphs: CatalogGraphs, behaviors: BehaviorSet) -> Iterator[Finding]:
    for definition in graphs.behavior_defs:
        behavior = definition.item
        if not definition.effective or behavior.name in behaviors.implementations:
            continue
        yield graphs.finding(
            "AX901",
            E,
            f"{behavior.name} has no implementation (looked in: {'; '.join(behaviors.searched)})",
            behavior.mark,
            (behavior.name,),
        )


@code_rule(
    "AX902",
    "implementation-not-in-catalog",
    W,
    """One of the project's own behavior classes (not the standard library's) implements
    a name the catalog does not define. In flight: nothing can activate it, and a mission
    asking for the catalog's spelling gets an unknown behavior or a stand-in. Usually a
    misspelt `name` or a catalog entry that was never written. Fix: correct the `name`
    or add the behavior to the catalog.""",
)
def implementation_not_in_catalog(
    graphs: CatalogGraphs, behaviors: BehaviorSet
) -> Iterator[Finding]:
    names = graphs.catalog.behaviors
    suggester = Suggester(names)
    section = graphs.catalog.section_marks.get("behavior_descriptors", graphs.top_mark)
    for implementation in behaviors.user():
        if implementation.name in names:
            continue
        yield graphs.finding(
            "AX902",
            W,
            f"{implementation.reference} ({_where(implementation)}) implements "
            f"{implementation.name}, which this catalog does not define"
            f"{suggester.hint(implementation.name)}",
            section,
            (implementation.name,),
        )


@code_rule(
    "AX903",
    "argument-not-read",
    E,
    """A catalog argument is not among the argument names the behavior's implementation
    declares it reads (`argument_names`; names match regardless of letter case) or,
    when it declares none, among the constant keys its hooks look up (`args["DEPTH"]`,
    found in the AST of its source; only when every look-up has a constant key). In
    flight: the specialist accepts the argument, the behavior never sees it, and the
    activation fails or does something else (the standard GO_TO_POINT reads
    `COORDINATES`; a catalog that calls it `POSITION` passes every check and fails at
    run time). Fix: rename the catalog argument to what the code reads, or make the code
    read it.""",
)
def argument_not_read(graphs: CatalogGraphs, behaviors: BehaviorSet) -> Iterator[Finding]:
    for behavior, implementation in _implemented(graphs, behaviors):
        read = read_names(implementation) if behavior.arguments else None
        if read is None or not read.complete:
            continue
        declared = read.names
        reads = {name.casefold() for name in declared}
        for spec in behavior.arguments:
            if spec.name.casefold() in reads:
                continue
            listed = ", ".join(declared) if declared else "no arguments"
            yield graphs.finding(
                "AX903",
                E,
                f"{behavior.name}: argument {spec.name} is not read by "
                f"{implementation.reference}, which {_how(implementation)} {listed}",
                spec.mark if spec.mark.line else behavior.mark,
                (behavior.name, spec.name),
            )


@code_rule(
    "AX904",
    "argument-not-in-catalog",
    I,
    """The behavior's implementation declares (or, declaring none, its code reads) an
    argument the catalog does not define.
    In flight: no mission can pass it (the specialist refuses unknown arguments), so the
    behavior always runs with its default. Often deliberate (an optional argument the
    catalog does not expose); a misspelling otherwise. Fix: add it to the catalog's
    arguments if missions should set it.""",
)
def argument_not_in_catalog(graphs: CatalogGraphs, behaviors: BehaviorSet) -> Iterator[Finding]:
    for behavior, implementation in _implemented(graphs, behaviors):
        read = read_names(implementation)
        for name in read.names if read is not None else ():
            if behavior.argument(name) is not None:
                continue
            yield graphs.finding(
                "AX904",
                I,
                f"{behavior.name}: {implementation.reference} {_how(implementation)} "
                f"argument {name}, which the catalog does not define: no mission can pass it",
                behavior.mark,
                (behavior.name, name),
            )


@code_rule(
    "AX905",
    "arguments-not-declared",
    I,
    """The catalog gives a behavior arguments, and its implementation does not declare
    which argument names it reads (`argument_names`), nor do its hooks read them by
    constant keys only (the AST shows `args[key]`, `**args`...), so the verifier cannot
    check them all.
    In flight: a catalog argument the code does not read goes unnoticed until the
    behavior misbehaves. Fix: set `argument_names = ("NAME", ...)` on the class.""",
)
def arguments_not_declared(graphs: CatalogGraphs, behaviors: BehaviorSet) -> Iterator[Finding]:
    for behavior, implementation in _implemented(graphs, behaviors):
        if not behavior.arguments or implementation.cls.argument_names is not None:
            continue
        read = read_names(implementation)
        if read is None or not read.complete:
            yield graphs.finding(
                "AX905",
                I,
                f"{behavior.name}: {implementation.reference} ({_where(implementation)}) "
                "does not declare argument_names: its arguments are not checked",
                behavior.mark,
                (behavior.name,),
            )
