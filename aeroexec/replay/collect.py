"""Build a `RunOutcome` from a message stream: a recording read back, or a live run.

`OutcomeBuilder` consumes service calls and topic messages in stream order and keeps
only per-command summaries. `OutcomeObserver` feeds it from the bus of a running
executive; `extract_outcome` feeds it from a recording with one selective streaming
pass. Both paths go through the same builder, so a replay and its original are
summarized by the same code.

Attribution: a command owns what happens from its `mission/command` message up to the
next command's (its activation answer, the capability and process changes, and, for an
activation, its end event whenever that comes). What happens before the first command
is the executive's initiation.
"""

from __future__ import annotations

import json
import os
from typing import Any

from aeroexec.errors import Mark, RecordingError
from aeroexec.executive.messages import ServiceCallRecord, TopicRecord
from aeroexec.progress import ProgressFactory
from aeroexec.recording.schemas import CODE_METADATA_NAME as CODE_RECORD
from aeroexec.recording.schemas import PROFILE
from aeroexec.replay.outcome import (
    ACTIVATIONS,
    CommandOutcome,
    FinalState,
    RunOutcome,
    Transition,
)
from aeroexec.replay.progress import ReadProgress
from aeroexec.replay.source import RecordingSource

COMMAND_TOPIC = "mission/command"
STATE_TOPIC = "vehicle/state"
#: The topics a summary is built from (names inside the drone's namespace)...
TOPICS = frozenset(
    {COMMAND_TOPIC, "behavior_event", "process_state", "list_of_active_capabilities"}
)
#: ... and the service channels (each behavior's check_situation too).
CALLS = frozenset({"activate_behavior", "inhibit_behavior"})
SITUATION_SUFFIX = "/check_situation"
#: Attachments replay needs from a recording.
ATTACHMENTS = frozenset({"catalog.yaml", "mission.py", "world.yaml"})


def wanted(name: str) -> bool:
    return name in TOPICS or name in CALLS or name.endswith(SITUATION_SUFFIX)


class _Command:
    """A command being summarized (mutable while the stream runs)."""

    __slots__ = (
        "accepted",
        "arguments",
        "behavior",
        "capabilities",
        "closed",
        "command",
        "end_code",
        "end_detail",
        "end_ns",
        "error",
        "index",
        "line",
        "preempted",
        "processes",
        "situation",
        "text",
        "time_ns",
        "uid",
    )

    def __init__(self, index: int, time_ns: int, data: dict[str, Any]) -> None:
        self.index = index
        self.time_ns = time_ns
        self.command = str(data.get("command", ""))
        behavior = data.get("behavior")
        self.behavior = behavior if isinstance(behavior, str) else ""
        arguments = data.get("arguments")
        self.arguments = dict(arguments) if isinstance(arguments, dict) else {}
        text = data.get("query", data.get("belief"))
        self.text = text if isinstance(text, str) else ""
        line = data.get("line")
        self.line = (
            line if isinstance(line, int) and not isinstance(line, bool) and line > 0 else None
        )
        self.accepted: bool | None = None
        self.error = ""
        self.uid: int | None = None
        self.preempted: tuple[str, ...] = ()
        self.situation: tuple[bool, str] | None = None
        self.capabilities: list[Transition] = []
        self.processes: list[Transition] = []
        self.end_code: str | None = None
        self.end_ns: int | None = None
        self.end_detail = ""
        #: True once the next command has started: no more transitions for this one.
        self.closed = False

    @property
    def final(self) -> bool:
        """Nothing can change any more: its window is closed and it is not an
        activation still waiting for its end event."""
        return self.closed and (self.uid is None or self.end_ns is not None)


class _Interner:
    """Equal summary values share one object: a long mission repeats the same
    arguments and the same transition sequences hundreds of times."""

    def __init__(self) -> None:
        self._transitions: dict[tuple[str, bool], Transition] = {}
        self._sequences: dict[tuple[Transition, ...], tuple[Transition, ...]] = {}
        self._arguments: dict[str, dict[str, Any]] = {}
        self._texts: dict[str, str] = {}

    def transition(self, name: str, up: bool) -> Transition:
        key = (name, up)
        found = self._transitions.get(key)
        if found is None:
            found = self._transitions[key] = Transition(name, up)
        return found

    def sequence(self, items: list[Transition]) -> tuple[Transition, ...]:
        key = tuple(items)
        return self._sequences.setdefault(key, key)

    def text(self, value: str) -> str:
        return self._texts.setdefault(value, value)

    def arguments(self, value: dict[str, Any]) -> dict[str, Any]:
        if not value:
            return _NO_ARGUMENTS
        return self._arguments.setdefault(repr(value), value)

    def freeze(self, command: _Command) -> CommandOutcome:
        return CommandOutcome(
            index=command.index,
            time_ns=command.time_ns,
            command=command.command,
            behavior=command.behavior,
            arguments=self.arguments(command.arguments),
            text=command.text,
            accepted=command.accepted,
            error=self.text(command.error),
            uid=command.uid,
            preempted=command.preempted,
            situation=command.situation,
            capabilities=self.sequence(command.capabilities),
            processes=self.sequence(command.processes),
            end_code=command.end_code,
            end_ns=command.end_ns,
            end_detail=self.text(command.end_detail),
            line=command.line,
        )


_NO_ARGUMENTS: dict[str, Any] = {}


class OutcomeBuilder:
    """Summarizes a stream per mission command. `horizon_ns`: ignore everything logged
    at or after this time (to compare a run with a recording that was cut short)."""

    def __init__(self, horizon_ns: int | None = None) -> None:
        self.horizon_ns = horizon_ns
        self._observed: set[str] = set()
        #: Each command's summary: frozen as soon as it is final, so it exists once.
        self.commands: list[_Command | CommandOutcome] = []
        self._current: _Command | None = None
        self._running: dict[int, _Command] = {}
        self._early: dict[int, tuple[str, int, str]] = {}
        self._capabilities: tuple[str, ...] = ()
        self._initial_capabilities: list[Transition] = []
        self._initial_processes: list[Transition] = []
        self._state: tuple[Any, int] | None = None
        self._intern = _Interner()
        self.start_ns: int | None = None
        self.end_ns: int | None = None

    # -- input -------------------------------------------------------------------------
    def call(
        self,
        service: str,
        parent_seq: int | None,
        request: dict[str, Any],
        response: dict[str, Any],
        time_ns: int,
    ) -> None:
        if not self._keep(time_ns):
            return
        current = self._current
        if current is None:
            return
        if service.endswith(SITUATION_SUFFIX):
            current.situation = (bool(response.get("ok")), str(response.get("error", "")))
            return
        if parent_seq is not None or current.accepted is not None:
            return
        if service == "activate_behavior" and current.command in ACTIVATIONS:
            self._answer(current, response)
            preempted = response.get("preempted")
            if isinstance(preempted, list):
                current.preempted = tuple(str(p) for p in preempted)
            uid = response.get("uid")
            if current.accepted and isinstance(uid, int):
                current.uid = uid
                early = self._early.pop(uid, None)
                if early is None:
                    self._running[uid] = current
                else:
                    current.end_code, current.end_ns, current.end_detail = early
        elif service == "inhibit_behavior" and current.command == "inhibit_behavior":
            self._answer(current, response)

    def topic(self, name: str, data: Any, time_ns: int) -> None:
        if not self._keep(time_ns) or not isinstance(data, dict):
            return
        if name == COMMAND_TOPIC:
            previous = self._current
            self._current = _Command(len(self.commands), time_ns, data)
            self.commands.append(self._current)
            self._early.clear()
            if previous is not None:
                previous.closed = True
                self._settle(previous)
        elif name == "behavior_event":
            self._event(data, time_ns)
        elif name == "process_state":
            self._observed.add("processes")
            up = data.get("state") == "started"
            transition = self._transition(str(data.get("process", "")), up)
            self._window(self._initial_processes, "processes").append(transition)
        elif name == "list_of_active_capabilities":
            self._observed.add("capabilities")
            self._capability_snapshot(data)

    def vehicle_state(self, data: Any, time_ns: int) -> None:
        """Only the last state is kept (the run's final state)."""
        if self._keep(time_ns):
            self._state = (data, time_ns)

    # -- output ------------------------------------------------------------------------
    def outcome(
        self,
        source: str,
        *,
        complete: bool = True,
        problem: str | None = None,
        metadata: dict[str, str] | None = None,
        notes: tuple[str, ...] = (),
        intact_until_ns: int | None = None,
    ) -> RunOutcome:
        final = None
        if self._state is not None:
            final = FinalState.from_message(self._state[0], self._state[1])
        return RunOutcome(
            source=source,
            commands=tuple(
                c if isinstance(c, CommandOutcome) else self._intern.freeze(c)
                for c in self.commands
            ),
            initial_capabilities=tuple(self._initial_capabilities),
            initial_processes=tuple(self._initial_processes),
            final_state=final,
            start_ns=self.start_ns,
            end_ns=self.end_ns,
            complete=complete,
            problem=problem,
            metadata=dict(metadata or {}),
            notes=notes,
            observed=frozenset(self._observed),
            intact_until_ns=intact_until_ns,
        )

    # -- internals ---------------------------------------------------------------------
    def _keep(self, time_ns: int) -> bool:
        if self.horizon_ns is not None and time_ns >= self.horizon_ns:
            return False
        if self.start_ns is None:
            self.start_ns = time_ns
        self.end_ns = time_ns
        return True

    @staticmethod
    def _answer(command: _Command, response: dict[str, Any]) -> None:
        command.accepted = bool(response.get("ok"))
        command.error = str(response.get("error", ""))

    def _transition(self, name: str, up: bool) -> Transition:
        return self._intern.transition(name, up)

    def _settle(self, command: _Command) -> None:
        if command.final:
            self.commands[command.index] = self._intern.freeze(command)

    def _window(self, initial: list[Transition], field: str) -> list[Transition]:
        current = self._current
        return initial if current is None else getattr(current, field)

    def _event(self, data: dict[str, Any], time_ns: int) -> None:
        uid = data.get("uid")
        if not isinstance(uid, int):
            return
        end = (str(data.get("code", "")), time_ns, str(data.get("detail", "")))
        command = self._running.pop(uid, None)
        if command is None:
            # A behavior that fails in on_start ends inside its own activation call,
            # before the call's answer (with its uid) is in the stream.
            self._early[uid] = end
            return
        command.end_code, command.end_ns, command.end_detail = end
        self._settle(command)

    def _capability_snapshot(self, data: dict[str, Any]) -> None:
        items = data.get("capabilities")
        if not isinstance(items, list):
            return
        names = tuple(str(c.get("name", "")) for c in items if isinstance(c, dict))
        before = set(self._capabilities)
        after = set(names)
        window = self._window(self._initial_capabilities, "capabilities")
        window.extend(self._transition(n, False) for n in self._capabilities if n not in after)
        window.extend(self._transition(n, True) for n in names if n not in before)
        self._capabilities = names


class OutcomeObserver:
    """A bus observer feeding an `OutcomeBuilder` from a running executive."""

    def __init__(self, builder: OutcomeBuilder, offset_ns: int = 0) -> None:
        self.builder = builder
        self.offset_ns = offset_ns

    def on_service_call(self, record: ServiceCallRecord) -> None:
        self.builder.call(
            record.service,
            record.parent_seq,
            record.request,
            record.response,
            record.log_time_ns + self.offset_ns,
        )

    def on_topic(self, record: TopicRecord) -> None:
        if record.topic == STATE_TOPIC:
            self.builder.vehicle_state(record.data, record.log_time_ns + self.offset_ns)
        elif record.topic in TOPICS:
            self.builder.topic(record.topic, record.data, record.log_time_ns + self.offset_ns)


class RecordedRun:
    """A recording read for replay: its outcome plus what the replay engines need
    (metadata, attachments) — all from one streaming pass."""

    def __init__(
        self,
        outcome: RunOutcome,
        metadata: dict[str, str],
        attachments: dict[str, bytes],
        profile: str,
        code: dict[str, str] | None = None,
    ) -> None:
        self.outcome = outcome
        self.metadata = metadata
        self.attachments = attachments
        self.profile = profile
        #: The `behaviors` record: which code implemented each behavior ({} if unsaid).
        self.code = dict(code or {})

    def text(self, name: str) -> str | None:
        data = self.attachments.get(name)
        return None if data is None else data.decode("utf-8", errors="replace")


def read_run(
    path: str | os.PathLike[str],
    horizon_ns: int | None = None,
    *,
    require_commands: bool = True,
    progress: ProgressFactory | None = None,
) -> RecordedRun:
    """One selective pass over `path`. `RecordingError` if it cannot be read, or (with
    `require_commands`) if it holds no mission command to replay or compare. `progress`
    is told how many bytes of the file the pass has read."""
    source = RecordingSource(path)
    if progress is None:
        return _read_run(source, horizon_ns, require_commands, None)
    size = source.path.stat().st_size
    with progress(f"reading {source.path.name}", size) as advance:
        read = ReadProgress(advance)
        run = _read_run(source, horizon_ns, require_commands, read)
        read(size)
    return run


def _read_run(
    source: RecordingSource,
    horizon_ns: int | None,
    require_commands: bool,
    on_read: ReadProgress | None,
) -> RecordedRun:
    builder = OutcomeBuilder(horizon_ns)
    undecodable = 0
    scan = source.scan(wanted, frozenset({STATE_TOPIC}), ATTACHMENTS, horizon_ns, on_read)
    for message in scan:
        try:
            data = json.loads(message.data)
        except ValueError:
            undecodable += 1
            continue
        if not isinstance(data, dict):
            undecodable += 1
        elif message.name in TOPICS:
            builder.topic(message.name, data, message.log_time_ns)
        else:
            _feed_call(builder, data, message.log_time_ns)
    summary = source.summary
    assert summary is not None
    state = summary.tail.get(STATE_TOPIC)
    if state is not None:
        try:
            builder.vehicle_state(json.loads(state.data), state.log_time_ns)
        except ValueError:
            undecodable += 1
    notes = list(summary.notes)
    if undecodable:
        notes.append(f"{undecodable} message(s) were not valid JSON objects, skipped")
    metadata = dict(summary.metadata.get(PROFILE, {}))
    if require_commands and not builder.commands:
        raise RecordingError(_no_commands(source.profile, summary.problem), Mark(source.name))
    outcome = builder.outcome(
        source.name,
        complete=summary.complete,
        problem=summary.problem,
        metadata=metadata,
        notes=tuple(notes),
        # Damaged before its first message: nothing of it can be compared.
        intact_until_ns=(summary.intact_until_ns or 0) if summary.damages else None,
    )
    code = summary.metadata.get(CODE_RECORD, {})
    return RecordedRun(outcome, metadata, dict(summary.attachments), source.profile, code)


def extract_outcome(path: str | os.PathLike[str], horizon_ns: int | None = None) -> RunOutcome:
    """The per-command summary of a recording (one selective streaming pass)."""
    return read_run(path, horizon_ns).outcome


def _feed_call(builder: OutcomeBuilder, data: dict[str, Any], time_ns: int) -> None:
    request, response = data.get("request"), data.get("response")
    parent = data.get("parent_seq")
    if not isinstance(request, dict) or not isinstance(response, dict):
        return
    builder.call(
        str(data.get("service", "")),
        parent if isinstance(parent, int) else None,
        request,
        response,
        time_ns,
    )


def _no_commands(profile: str, problem: str | None) -> str:
    if profile != PROFILE:
        return (
            f"not an aeroexec recording (profile {profile or '(none)'!r}): "
            "no mission commands to replay"
        )
    if problem is not None:
        return f"no mission commands before the file stops ({problem})"
    return "no mission commands in this recording (mission/command is empty): nothing to replay"
