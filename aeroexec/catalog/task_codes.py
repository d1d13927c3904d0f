"""Diagnostic codes the task catalog loader emits (AX80x; the task rules are AX81x-AX82x).

Kept with their documentation so `aeroexec verify --explain CODE` and docs/rules.md can
show them. "The coordinator" is the 2021 constraint-based coordinator
(cvar-upm/coordinator_cbc, `catalog.cpp`), whose behavior the messages describe.
"""

from __future__ import annotations

from aeroexec.catalog.model import Severity

TASK_MISSING_TAG = "AX801"
TASK_UNKNOWN_TAG = "AX802"
MISINDENTED_PARAMETER = "AX803"
TASK_WRONG_TYPE = "AX804"
DUPLICATE_TASK = "AX805"
DUPLICATE_TASK_BEHAVIOR = "AX806"
TASK_VOCABULARY = "AX807"
BOOLEAN_SPELLING = "AX808"
MIXED_VOCABULARY = "AX809"
MALFORMED_PARAMETER = "AX810"

TASK_LOADER_DOCS: dict[str, tuple[str, Severity, str]] = {
    TASK_MISSING_TAG: (
        "task-missing-tag",
        Severity.ERROR,
        "An entry lacks the tag that names it: a behavior without `behavior` or without "
        "`task`, a task without `task`, a requirement without `task`, an exclusivity "
        "constraint without `mutually_exclusive`. In flight: for a behavior without a "
        "task the coordinator reports 'The behavior: X has no task defined' and stops "
        "reading the catalog at that entry (yaml-cpp throws on the missing key), so the "
        "behaviors after it, the tasks and the requirements are never loaded — the "
        "CBC's own bad_behavior_catalog.yaml shows this. Fix: name the task the "
        "behavior performs.",
    ),
    TASK_UNKNOWN_TAG: (
        "task-unknown-tag",
        Severity.WARNING,
        "A key the task catalog format does not know (often a misspelling). In flight: "
        "the coordinator ignores it, so the setting meant is not applied. Fix: use the "
        "suggested spelling.",
    ),
    MISINDENTED_PARAMETER: (
        "misindented-parameter",
        Severity.WARNING,
        "`allowed_values` (or `dimensions`) sits on the task instead of on a parameter: "
        "it is indented as a key of the task, next to `parameters`, not under the last "
        "`- parameter:` entry (every 2020-2021 catalog has this under "
        "REQUEST_OPERATOR_ASSISTANCE's `options`). In flight: the parameter has no "
        "allowed values and the task key is ignored. Fix: indent it under its "
        "`- parameter:` line.",
    ),
    TASK_WRONG_TYPE: (
        "task-wrong-type",
        Severity.ERROR,
        "A value has the wrong type or is outside its domain: a timeout that is not a "
        "whole positive number of seconds (the coordinator reads it with yaml-cpp's "
        "`as<int>()`, which throws on `1.5`, and stops loading), a suitability or "
        "minimum performance outside 0-100, an execution goal other than achieve_goal "
        "or keep_running, a list where a name is expected. Fix: write the value the "
        "message names.",
    ),
    DUPLICATE_TASK: (
        "duplicate-task",
        Severity.WARNING,
        "A task is declared twice in `tasks`. In flight: the coordinator applies the "
        "later declaration's attributes (and its defaults for what it leaves out) to the "
        "same task, so what the first one says is silently replaced. Fix: keep one "
        "declaration.",
    ),
    DUPLICATE_TASK_BEHAVIOR: (
        "duplicate-task-behavior",
        Severity.WARNING,
        "Two behavior entries have the same name. In flight: the coordinator keeps both "
        "as candidates, but behaviors are started, stopped and reported by name, so the "
        "two cannot be told apart. Fix: keep one entry, or rename one.",
    ),
    TASK_VOCABULARY: (
        "task-vocabulary",
        Severity.INFO,
        "Which vocabulary the task catalog is written in: 2020 (Aerostack 4.0's behavior "
        "manager: `category`, `default`, `automatic_activation`, `efficacy`) or 2021 "
        "(the CBC coordinator: `execution_goal`, `reactive_start`, `start_on_request`, "
        "`suitability`). aeroexec reads both with the meaning the catalogs' own header "
        "comments give. The 2021 coordinator reads only the 2021 keys, so a 2020 "
        "catalog loaded by it keeps its defaults (the CBC's own test catalogs are "
        "written in the 2020 vocabulary). Informational.",
    ),
    BOOLEAN_SPELLING: (
        "boolean-spelling",
        Severity.WARNING,
        "A boolean attribute (`start_on_request`, `reactive_start`, `default`, "
        "`automatic_activation`) is spelled otherwise than TRUE or FALSE (`true`, `yes`, "
        '`True`). In flight: the coordinator compares the text with "TRUE", so every '
        "other spelling means FALSE. Fix: write TRUE or FALSE.",
    ),
    MIXED_VOCABULARY: (
        "mixed-task-vocabulary",
        Severity.WARNING,
        "The catalog mixes the 2020 and 2021 vocabularies (e.g. `automatic_activation` "
        "in `default_values` with `start_on_request` on the tasks). In flight: the 2021 "
        "coordinator ignores the 2020 keys; a `default_values` block without "
        "`start_on_request` leaves that default unset (an uninitialized C++ bool), so "
        "whether undeclared attributes mean TRUE or FALSE is not defined. Fix: use one "
        "vocabulary, the 2021 one for the CBC coordinator.",
    ),
    MALFORMED_PARAMETER: (
        "malformed-parameter",
        Severity.ERROR,
        "A parameter's `allowed_values` is not a form the format allows: a numeric range "
        "`[min, max]` with min <= max, a non-empty list of distinct words, or a type word "
        "(`string`, `point`, `point_list`...). Fix: write one of those forms.",
    ),
}
