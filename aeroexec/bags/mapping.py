"""Topic mapping: which bag topics are behavior events, active lists, commands, poses...

A mapping is a YAML file (the shipped default, `aeroexec/data/bag_mapping/aerostack.yaml`,
has Aerostack's 2017-2018 names)::

    version: 1
    drone: drone1          # what {drone} stands for (the import's --drone overrides it)
    grace_s: 0.5           # how far apart related messages may be (see reconstruct.py)
    state_period_s: 0.1    # vehicle/state at most this often (0: at every pose)
    topics:
      - {topic: "/{drone}/behavior_event", kind: behavior_event}
      - {topic: "/{drone}/EstimatedPose_droneGMR_wrt_GFF", kind: pose}
      - {type: geometry_msgs/PoseStamped, kind: pose}      # any topic of this type

A rule names a `topic` (exact, after `{drone}` is replaced), a `type` (`pkg/Name`), or
both. For each kind the **first rule that the bag has** is used and the later ones of
that kind are ignored, so a mapping can list fallbacks in order of preference. A topic
with `*` segments (`/{drone}/*/_behavior/behavior_status`) takes every topic it matches,
and the first `*` names the behavior or service (Aerostack2: one status topic per
behavior node). ROS 2 bags default to `aerostack2.yaml`. Every topic of the
bag is carried over unchanged whatever the mapping says; the mapping only adds the
aeroexec channels derived from it.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterable
from dataclasses import dataclass, replace
from enum import Enum
from importlib import resources
from pathlib import Path

from aeroexec.catalog.yamlnodes import YNode, load_yaml
from aeroexec.errors import CatalogError, Mark, RecordingError
from aeroexec.inputs import read_text

#: The mapping format's version (the `version:` key).
FORMAT_VERSION = 1
DEFAULT_GRACE_S = 0.5
#: vehicle/state at most every 0.1 s of bag time: the executive's own tick (10 Hz).
DEFAULT_STATE_PERIOD_S = 0.1
DEFAULT_MAPPING_NAME = "aerostack.yaml"
#: The default mapping of a ROS 2 bag: Aerostack2's names.
DEFAULT_ROS2_MAPPING_NAME = "aerostack2.yaml"


class Kind(str, Enum):
    """What a mapped topic is (and which aeroexec channel it feeds)."""

    BEHAVIOR_EVENT = "behavior_event"  # -> behavior_event
    ACTIVE_BEHAVIORS = "active_behaviors"  # -> list_of_active_behaviors (+ reconstruction)
    ACTIVE_CAPABILITIES = "active_capabilities"  # -> list_of_active_capabilities
    BELIEFS = "beliefs"  # -> beliefs (changes between snapshots)
    PROCESS_STATE = "process_state"  # -> process_state (started/stopped changes)
    ACTIVATE_COMMAND = "activate_command"  # -> mission/command activate_behavior
    INHIBIT_COMMAND = "inhibit_command"  # -> mission/command inhibit_behavior
    POSE = "pose"  # -> vehicle/state position, yaw
    VELOCITY = "velocity"  # -> vehicle/state velocity
    BATTERY = "battery"  # -> vehicle/state battery
    FLIGHT_STATUS = "flight_status"  # -> vehicle/state flying
    # ROS 2 (Aerostack2): one topic per behavior or service, named by the `*` of the rule
    BEHAVIOR_STATUS = "behavior_status"  # IDLE/RUNNING/PAUSED -> active list (+ reconstruction)
    ACTION_STATUS = "action_status"  # GoalStatusArray -> end events (outcome)
    ACTION_GOAL = "action_goal"  # send_goal service events -> activation arguments
    ACTION_RESULT = "action_result"  # get_result service events -> end events (outcome)
    SERVICE_EVENTS = "service_events"  # any `_service_event` topic -> service calls


_RULE_KEYS = ("topic", "type", "kind")
_TOP_KEYS = ("version", "drone", "grace_s", "state_period_s", "topics")


@dataclass(frozen=True, slots=True)
class Rule:
    kind: Kind
    topic: str | None  # may contain {drone}
    type: str | None  # ROS 1 spelling, `pkg/Name`
    mark: Mark

    def topic_for(self, drone: str) -> str | None:
        return None if self.topic is None else self.topic.replace("{drone}", drone)

    @property
    def is_pattern(self) -> bool:
        """A topic with `*` segments: it takes every topic it matches."""
        return self.topic is not None and "*" in self.topic

    def label(self, topic: str, drone: str) -> str | None:
        """What the first `*` of a pattern matched in `topic` (the behavior's node name,
        the service's name); None when `topic` does not match."""
        wanted = self.topic_for(drone)
        if wanted is None:
            return ""
        if not self.is_pattern:
            return "" if wanted == topic else None
        return _match_segments(wanted, topic)

    def matches(self, topic: str, ros1_type: str, drone: str) -> bool:
        if self.label(topic, drone) is None:
            return False
        return self.type is None or self.type == ros1_type

    def describe(self) -> str:
        parts = [p for p in (self.topic, self.type) if p]
        return " ".join(parts)


@dataclass(frozen=True, slots=True)
class Mapping:
    rules: tuple[Rule, ...]
    drone: str
    grace_ns: int
    #: Minimum bag time between two vehicle/state messages (0: one per pose).
    state_period_ns: int
    #: Where it came from (file name), and its text (kept as an attachment of the import).
    source: str
    text: str

    def select(self, topics: Iterable[tuple[str, str]], drone: str) -> dict[Kind, Rule]:
        """For each kind, the first rule that one of `topics` ((topic, ROS 1 type) pairs)
        matches."""
        present = list(topics)
        chosen: dict[Kind, Rule] = {}
        for rule in self.rules:
            if rule.kind in chosen:
                continue
            if any(rule.matches(topic, typ, drone) for topic, typ in present):
                chosen[rule.kind] = rule
        return chosen


def _match_segments(pattern: str, topic: str) -> str | None:
    """`/d/*/_behavior/behavior_status` against a topic: the first `*`'s segment. A `*`
    matches one whole segment; a `**` segment any number of them (a service name
    with a namespace: `/**/_service_event`)."""
    want = pattern.split("/")
    have = topic.split("/")
    if "**" in want:
        at = want.index("**")
        head, tail = want[:at], want[at + 1 :]
        if len(have) < len(head) + len(tail) + 1:
            return None
        if _match_segments("/".join(head), "/".join(have[: len(head)])) is None:
            return None
        if (
            tail
            and _match_segments("/".join(tail), "/".join(have[len(have) - len(tail) :])) is None
        ):
            return None
        return "/".join(have[len(head) : len(have) - len(tail)])
    if len(want) != len(have):
        return None
    label: str | None = None
    for w, h in zip(want, have, strict=True):
        if w == "*":
            if not h:
                return None
            label = h if label is None else label
        elif w != h:
            return None
    return label or ""


def default_mapping_path(ros_version: int = 1) -> Path:
    name = DEFAULT_MAPPING_NAME if ros_version == 1 else DEFAULT_ROS2_MAPPING_NAME
    return Path(str(resources.files("aeroexec").joinpath("data", "bag_mapping", name)))


def load_mapping(path: str | os.PathLike[str] | None = None, ros_version: int = 1) -> Mapping:
    """The mapping in `path` (when None, the shipped default: Aerostack's for a ROS 1
    bag, Aerostack2's for a ROS 2 one). `RecordingError` with file:line:col for anything
    wrong in it."""
    file = Path(path) if path is not None else default_mapping_path(ros_version)
    name = str(path) if path is not None else file.name
    try:
        text = read_text(file, "a mapping file", RecordingError)
    except RecordingError as exc:  # named as the user named it (or as the default)
        raise RecordingError(exc.message, replace(exc.mark or Mark(name), file=name)) from None
    return parse_mapping(text, name)


def parse_mapping(text: str, name: str) -> Mapping:
    try:
        root = load_yaml(text, name)
    except CatalogError as exc:  # the YAML layer speaks of catalogs; this is a mapping
        raise RecordingError(exc.message, exc.mark) from None
    if root is None or not root.is_map:
        raise RecordingError(
            "a mapping file is a YAML mapping with a `topics:` list",
            root.mark if root is not None else Mark(name, 1, 1),
        )
    _no_unknown_keys(root, _TOP_KEYS, "top level")
    version = root.get("version")
    if version is not None and version.value != FORMAT_VERSION:
        raise RecordingError(
            f"unsupported mapping version {version.value!r} (this aeroexec reads {FORMAT_VERSION})",
            version.mark,
        )
    drone = _drone(root.get("drone"))
    grace_ns = _seconds(root.get("grace_s"), "grace_s", DEFAULT_GRACE_S)
    period_ns = _seconds(root.get("state_period_s"), "state_period_s", DEFAULT_STATE_PERIOD_S)
    topics = root.get("topics")
    if topics is None:
        raise RecordingError("missing `topics:` (the list of mapped topics)", root.mark)
    if not topics.is_list:
        raise RecordingError("`topics:` must be a list of {topic, type, kind}", topics.mark)
    rules = tuple(_rule(item) for item in topics.value)
    return Mapping(rules, drone, grace_ns, period_ns, name, text)


def check_drone(value: object, mark: Mark) -> str:
    """A drone namespace: one topic segment, letters, digits and _."""
    if not isinstance(value, str) or not value or not value.replace("_", "").isalnum():
        raise RecordingError(
            f"drone must be one topic name segment (letters, digits, _), not {value!r}", mark
        )
    return value


def _drone(node: YNode | None) -> str:
    if node is None:
        return "drone1"
    return check_drone(node.value, node.mark)


def _seconds(node: YNode | None, key: str, default: float) -> int:
    if node is None:
        return round(default * 1e9)
    value = node.value
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise RecordingError(f"{key} must be a number of seconds, not {value!r}", node.mark)
    if not math.isfinite(value) or not 0 <= value <= 60:
        raise RecordingError(f"{key} must be between 0 and 60 seconds, not {value!r}", node.mark)
    return round(value * 1e9)


def _rule(item: YNode) -> Rule:
    if not item.is_map:
        raise RecordingError("each topics entry is a mapping {topic, type, kind}", item.mark)
    _no_unknown_keys(item, _RULE_KEYS, "topics entry")
    kind_node = item.get("kind")
    if kind_node is None:
        raise RecordingError("missing `kind:`", item.mark)
    try:
        kind = Kind(kind_node.value)
    except ValueError:
        known = ", ".join(k.value for k in Kind)
        raise RecordingError(
            f"unknown kind {kind_node.value!r} (known: {known})", kind_node.mark
        ) from None
    topic = _text(item.get("topic"), "topic")
    typ = _text(item.get("type"), "type")
    if topic is None and typ is None:
        raise RecordingError("a topics entry needs a `topic:`, a `type:` or both", item.mark)
    if topic is not None and not topic.startswith("/"):
        mark = item.get("topic").mark  # type: ignore[union-attr]
        raise RecordingError(f"topic {topic!r} must be absolute (start with /)", mark)
    if typ is not None:
        typ = typ.replace("/msg/", "/")
        if typ.count("/") != 1 or typ.startswith("/") or typ.endswith("/"):
            mark = item.get("type").mark  # type: ignore[union-attr]
            raise RecordingError(f"type {typ!r} must be package/Name", mark)
    return Rule(kind, topic, typ, item.mark)


def _text(node: YNode | None, key: str) -> str | None:
    if node is None:
        return None
    if not isinstance(node.value, str) or not node.value.strip():
        raise RecordingError(f"{key} must be a non-empty string, not {node.value!r}", node.mark)
    return node.value.strip()


def _no_unknown_keys(node: YNode, allowed: tuple[str, ...], where: str) -> None:
    for key, _ in node.items():
        if key not in allowed:
            mark = node.key_marks.get(key, node.mark)
            raise RecordingError(
                f"unknown key {key!r} in {where} (allowed: {', '.join(allowed)})", mark
            )
