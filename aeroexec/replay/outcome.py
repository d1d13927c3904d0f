"""What a run did, per mission command: the values `diff` compares.

A `RunOutcome` is a small summary of one session (recorded or replayed): for every
command on `mission/command`, what the executive decided (accepted or rejected, which
behaviors it preempted), what changed in the resource manager while that command was the
latest one (capabilities referenced/released, processes started/stopped), and how the
activation ended (event code and time). Nothing else of the message stream is kept, so
its size grows with the number of commands, not with the length of the recording.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from aeroexec.display import shown_arguments

NS_PER_S = 1_000_000_000

#: Mission commands that activate a behavior.
ACTIVATIONS = ("execute_behavior", "activate_behavior")
#: Mission commands that answer accepted/rejected (a service call of the coordinator).
BEHAVIOR_COMMANDS = (*ACTIVATIONS, "inhibit_behavior")


@dataclass(frozen=True, slots=True)
class Transition:
    """A capability referenced (`up`) or released, or a process started (`up`) or
    stopped."""

    name: str
    up: bool

    def __str__(self) -> str:
        return ("+" if self.up else "-") + self.name


@dataclass(frozen=True, slots=True)
class CommandOutcome:
    """One mission command and what came of it.

    `accepted` is None for commands that are not behavior services (beliefs) and when no
    answer was recorded (the mission API refused before asking the executive).
    `end_ns` is None while the activation is still running at the end of the run.
    """

    index: int
    time_ns: int
    command: str
    behavior: str = ""
    arguments: dict[str, Any] = field(default_factory=dict)
    #: The belief query or belief of a belief command.
    text: str = ""
    accepted: bool | None = None
    error: str = ""
    uid: int | None = None
    preempted: tuple[str, ...] = ()
    #: The recorded answer of the behavior's check_situation (open-loop replay feeds it).
    situation: tuple[bool, str] | None = None
    capabilities: tuple[Transition, ...] = ()
    processes: tuple[Transition, ...] = ()
    end_code: str | None = None
    end_ns: int | None = None
    end_detail: str = ""
    #: The mission script's line that made the command (None: not recorded). Where it
    #: came from, not what happened: never compared.
    line: int | None = field(default=None, compare=False)

    @property
    def key(self) -> tuple[str, str]:
        """What identifies the command when two runs are aligned (not its arguments,
        which a mission may compute from beliefs)."""
        return (self.command, self.behavior or self.text)

    @property
    def activates(self) -> bool:
        return self.command in ACTIVATIONS

    @property
    def duration_ns(self) -> int | None:
        """From the command to its activation's end event."""
        return None if self.end_ns is None else self.end_ns - self.time_ns

    @property
    def label(self) -> str:
        """`#4 GO_TO_POINT coordinates=[3, 5.5, 1.3]`: what a reviewer recognizes in the
        mission, its arguments spelled as `aeroexec run` prints them."""
        return f"#{self.index} {describe_command(self)}"


@dataclass(frozen=True, slots=True)
class FinalState:
    """The last `vehicle/state` of a run."""

    position: tuple[float, float, float]
    flying: bool
    battery: float
    time_ns: int

    @classmethod
    def from_message(cls, data: Any, time_ns: int) -> FinalState | None:
        try:
            x, y, z = (float(v) for v in data["position"])
            battery = float(data.get("battery", 0.0))
            return cls((x, y, z), bool(data.get("flying")), battery, time_ns)
        except (KeyError, TypeError, ValueError, AttributeError):
            return None

    def describe(self) -> str:
        x, y, z = self.position
        return f"({x:.2f}, {y:.2f}, {z:.2f}) {'flying' if self.flying else 'landed'}"


@dataclass(frozen=True, slots=True)
class RunOutcome:
    """One run, summarized. `source` names the recording (or the replay)."""

    source: str
    commands: tuple[CommandOutcome, ...]
    initial_capabilities: tuple[Transition, ...] = ()
    initial_processes: tuple[Transition, ...] = ()
    final_state: FinalState | None = None
    start_ns: int | None = None
    end_ns: int | None = None
    complete: bool = True
    problem: str | None = None
    metadata: dict[str, str] = field(default_factory=dict)
    notes: tuple[str, ...] = ()
    #: Which transitions the run recorded at all ("capabilities", "processes"): a ROS bag
    #: may carry neither, and what was not recorded cannot be compared.
    observed: frozenset[str] = frozenset({"capabilities", "processes"})
    #: A damaged recording is intact only before this log time (None: not damaged):
    #: comparisons stop there, so that a lost message is not taken for a change.
    intact_until_ns: int | None = None

    @property
    def duration_s(self) -> float:
        if self.start_ns is None or self.end_ns is None:
            return 0.0
        return (self.end_ns - self.start_ns) / NS_PER_S


#: `count=2 coordinates=[3, 5.5, 1.3]`: as `aeroexec run` prints them.
describe_arguments = shown_arguments


def describe_command(command: CommandOutcome) -> str:
    if command.command == "execute_behavior":
        return f"{command.behavior} {describe_arguments(command.arguments)}".rstrip()
    if command.command == "activate_behavior":
        return f"activate {command.behavior} {describe_arguments(command.arguments)}".rstrip()
    if command.command == "inhibit_behavior":
        return f"inhibit {command.behavior}"
    return f"{command.command} {command.text}".rstrip()
