"""Diagnostic codes the catalog loader emits (the verifier adds its own rule codes).

Kept in one place so `aeroexec verify --explain CODE` and docs/rules.md can document them.
"""

from __future__ import annotations

MISSING_ERROR_TAG = "AX101"
MISSING_WARNING_TAG = "AX102"
MISSING_DEPENDENCY_TAG = "AX103"
UNKNOWN_TAG = "AX104"
WRONG_TYPE = "AX105"
DUPLICATE_DEFINITION = "AX106"
DUPLICATE_KEY = "AX107"
MALFORMED_ARGUMENT = "AX108"
DIALECT = "AX109"
IGNORED_SECTION = "AX110"
SCALAR_FOR_LIST = "AX111"

LOADER_DOCS: dict[str, tuple[str, str]] = {
    MISSING_ERROR_TAG: (
        "missing-error-tag",
        "A tag the thesis classes as an *error tag* is missing: `behavior_descriptors`, "
        "`capability_descriptors`, `behavior` in a descriptor, `list`/`behaviors` in a "
        "behavior list, `capability`/`processes` in a capability. In flight: the behavior "
        "specialist refuses to load, so every later activation silently fails. Fix: add the "
        "tag (for a capability, `processes: [node, ...]` or the 2.x `process_sequence`).",
    ),
    MISSING_WARNING_TAG: (
        "missing-warning-tag",
        "A *warning tag* (`timeout`, `recurrent`, `active_by_default`) is missing, so its "
        "default was applied (timeout 15 s, goal-based, not active by default). In flight: "
        "a localization behavior without `recurrent: yes` times out after 15 s. Fix: write "
        "the tag explicitly, or give a `default_behavior_values` block.",
    ),
    MISSING_DEPENDENCY_TAG: (
        "missing-dependency-tag",
        "A *dependency tag* (`incompatible_lists`, `capabilities`, `arguments`, "
        "`incompatible_capabilities`) is absent; the empty value is assumed. Informational.",
    ),
    UNKNOWN_TAG: (
        "unknown-tag",
        "A key the catalog format does not know (often a misspelling, e.g. "
        "`activate_by_default` for `active_by_default`, which the thesis itself writes). "
        "In flight: the setting you meant is silently not applied. Fix: use the suggested "
        "spelling.",
    ),
    WRONG_TYPE: (
        "wrong-type",
        "A tag has a value of the wrong type or outside its domain (`timeout: fast`, "
        "`recurrent: maybe`, a list where a name is expected). The loader cannot give it a "
        "meaning. Fix: write the value with the type the message names.",
    ),
    DUPLICATE_DEFINITION: (
        "duplicate-definition",
        "A behavior, list or capability is defined more than once. The real specialist kept "
        "them in a map, so the last definition silently won. Fix: keep one definition.",
    ),
    DUPLICATE_KEY: (
        "duplicate-key",
        "A mapping repeats a key; YAML keeps only the last value. Fix: remove one.",
    ),
    MALFORMED_ARGUMENT: (
        "malformed-argument-spec",
        "An argument's `allowed_values` is not one of the forms the format allows: a "
        "numeric range `[min, max]` with min <= max (optionally `dimensions: N`, N >= 1), a "
        "non-empty list of symbols, or `TEXT`. In flight: every value for it is rejected "
        "(or, in the 2017 code, silently accepted). Fix: write one of those forms.",
    ),
    DIALECT: (
        "catalog-dialect",
        "Which catalog dialect the loader read: the thesis' Appendix A (`recurrent`, "
        "`processes`, `active_by_default`) or the flown Aerostack 2.x format "
        "(`default_behavior_values`, `category`, `process_sequence`). Informational.",
    ),
    IGNORED_SECTION: (
        "ignored-section",
        "A section aeroexec reads but does not act on (e.g. the 2017 `reactive_activation` "
        "block). Informational: it has no effect on the executive.",
    ),
    SCALAR_FOR_LIST: (
        "scalar-for-list",
        "A reference list (`incompatible_lists`, `capabilities`, a list's `behaviors`, "
        "`processes`...) is written as a single name (`incompatible_lists: motion`, as "
        "the Aerostack 2.0 wiki shows it). aeroexec reads it as a one-name list, but "
        "Aerostack's C++ loaders (yaml-cpp) iterate a scalar as an empty list. In "
        "flight: on Aerostack the behavior preempted nothing through it; the catalog "
        "means different things to the two executives. Fix: write a list, `[motion]`.",
    ),
}
