"""Render replay and diff results for people (text) and for CI (JSON, JUnit XML).

Text is for a reviewer's ten seconds: one header line per recording, then one line per
difference saying which command, what changed and why. JSON is one object with `equal`
and `differences` (flattened, each naming its recording); nothing in it depends on
timing, so the same results always render the same bytes.

JUnit XML is a `<testsuites>` root (what Jenkins, GitLab and GitHub's test-report actions
all read) holding one testsuite, with one testcase per recording (replay) or one for the
pair (diff); differences are a `<failure>`, an unreadable recording an `<error>`. Each
testcase is named by its recording, and its `file` is the mission script whose commands
were compared (the recording when no script is known) with, on a failure, the `line` of
the command of the first difference: test-report actions annotate that line of the
mission (a binary .mcap cannot be annotated). Each has its duration in `time`; the suite
has the `timestamp` of the run (UTC) and its `time`, the root the suite's totals. Those
make two runs' reports differ, as JUnit reports do — unless `SOURCE_DATE_EPOCH` is set
(the reproducible-builds convention): then the timestamp is that instant and every
duration 0, so the same results render the same bytes again.
"""

from __future__ import annotations

import json
import os
import time
import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from datetime import UTC, datetime

from aeroexec.errors import AeroexecError
from aeroexec.replay.diff import DiffResult
from aeroexec.replay.engine import ReplayResult

MODE_NAMES = {"closed": "closed-loop replay", "open": "open-loop replay"}
SOURCE_DATE_EPOCH = "SOURCE_DATE_EPOCH"


@dataclass(frozen=True, slots=True)
class Timing:
    """When a run started (the JUnit suite's `timestamp`) and whether durations are
    reported (not when SOURCE_DATE_EPOCH asks for reproducible output)."""

    timestamp: str
    reproducible: bool = False

    def duration(self, seconds: float | None) -> str:
        if self.reproducible or seconds is None:
            return "0.000"
        return f"{max(seconds, 0.0):.3f}"


def start_timing(environ: Mapping[str, str] | None = None, now: float | None = None) -> Timing:
    """The timing of a run starting now: the wall clock in UTC, or SOURCE_DATE_EPOCH
    (seconds since 1970) when set. A malformed value is an error, as the convention asks."""
    env = os.environ if environ is None else environ
    epoch = env.get(SOURCE_DATE_EPOCH)
    if epoch is not None:
        try:
            instant = int(epoch)
        except ValueError:
            raise AeroexecError(
                f"{SOURCE_DATE_EPOCH} must be whole seconds since 1970, got '{epoch}'"
            ) from None
        return Timing(_iso(instant), reproducible=True)
    return Timing(_iso(time.time() if now is None else now))


def _iso(seconds: float) -> str:
    # JUnit's schema wants a local date-time without zone; aeroexec writes UTC.
    instant = datetime.fromtimestamp(int(seconds), tz=UTC)
    return instant.strftime("%Y-%m-%dT%H:%M:%S")


def _count(n: int, word: str) -> str:
    return f"{n} {word}{'' if n == 1 else 's'}"


def _verdict(diff: DiffResult) -> str:
    compared = _count(diff.compared, "command")
    if diff.equal:
        return f"no differences ({compared} compared)"
    return f"{_count(len(diff.differences), 'difference')} ({compared} compared)"


def _diff_lines(diff: DiffResult, notes: Sequence[str]) -> list[str]:
    lines = [f"  {d.message}" for d in diff.differences]
    lines.extend(f"  note: {note}" for note in notes)
    return lines


# -- replay ------------------------------------------------------------------------------
def replay_header(result: ReplayResult) -> str:
    mode = MODE_NAMES.get(result.mode or "", "replay")
    if result.diff is None:
        return f"{result.recording}: {mode}: error: {result.error}"
    catalog = f"its recorded {result.catalog}" if result.catalog_recorded else result.catalog
    changed = "; code changed" if result.code_changes else ""
    return f"{result.recording}: {mode} with {catalog}: {_verdict(result.diff)}{changed}"


def replay_summary(results: Sequence[ReplayResult]) -> str:
    errors = sum(r.error is not None for r in results)
    differing = sum(r.error is None and not r.equal for r in results)
    same = len(results) - errors - differing
    return (
        f"{_count(len(results), 'recording')}: {differing} with differences, "
        f"{same} without, {errors} unreadable"
    )


def replay_text(results: Sequence[ReplayResult]) -> str:
    """Readable results; unreadable recordings are left to stderr (one line each) and
    only counted in the summary line (printed for more than one recording)."""
    lines: list[str] = []
    for result in results:
        if result.diff is None:
            continue
        lines.append(replay_header(result))
        lines.extend(f"  injected: {item}" for item in result.injected)
        lines.extend(f"  failed: {item}" for item in result.failures)
        lines.extend(_diff_lines(result.diff, result.notes))
        lines.extend(f"  code changed: {change}" for change in result.code_changes)
        if result.output:
            lines.append(f"  replay written to {result.output}")
    if len(results) > 1:
        lines.append(replay_summary(results))
    return "\n".join(lines)


def replay_json(results: Sequence[ReplayResult]) -> str:
    differences = []
    for result in results:
        if result.diff is not None:
            for d in result.diff.differences:
                differences.append({"recording": result.recording, **d.as_dict()})
    document = {
        "equal": all(r.equal for r in results),
        "recordings": [r.as_dict() for r in results],
        "differences": differences,
        "errors": [{"recording": r.recording, "error": r.error} for r in results if r.error],
        "summary": replay_summary(results),
    }
    return json.dumps(document, indent=2)


def replay_junit(
    results: Sequence[ReplayResult],
    suite: str = "aeroexec replay",
    *,
    timing: Timing | None = None,
    seconds: float | None = None,
) -> str:
    """`timing`: when the run started (default: now); `seconds`: how long it took."""
    timing = timing or start_timing()
    root = _suite(suite, len(results), timing, seconds)
    failures = errors = 0
    for result in results:
        case = _case(root, "aeroexec.replay", result.recording, result.recording, result.diff)
        case.set("time", timing.duration(result.seconds))
        if result.diff is None:
            errors += 1
            error = ET.SubElement(case, "error", {"message": result.error or "", "type": "input"})
            error.text = replay_header(result)
            continue
        notes = (*result.notes, *(f"code changed: {c}" for c in result.code_changes))
        if not result.diff.equal:
            failures += 1
            _failure(case, result.diff, notes, replay_header(result))
        elif notes:
            ET.SubElement(case, "system-out").text = "\n".join(notes)
    return _finish(root, failures, errors)


# -- diff --------------------------------------------------------------------------------
def diff_text(diff: DiffResult) -> str:
    header = f"{diff.base} -> {diff.new}: {_verdict(diff)}"
    return "\n".join([header, *_diff_lines(diff, diff.notes)])


def diff_json(diff: DiffResult) -> str:
    return json.dumps(diff.as_dict(), indent=2)


def diff_junit(
    diff: DiffResult, *, timing: Timing | None = None, seconds: float | None = None
) -> str:
    """The pair as one testcase, attached to the NEW recording (the one judged)."""
    timing = timing or start_timing()
    root = _suite("aeroexec diff", 1, timing, seconds)
    case = _case(root, "aeroexec.diff", f"{diff.base} -> {diff.new}", diff.new, diff)
    case.set("time", timing.duration(seconds))
    failures = 0
    if not diff.equal:
        failures = 1
        _failure(case, diff, diff.notes, f"{diff.base} -> {diff.new}: {_verdict(diff)}")
    return _finish(root, failures, 0)


# -- JUnit plumbing ------------------------------------------------------------------------
def _suite(name: str, tests: int, timing: Timing, seconds: float | None) -> ET.Element:
    return ET.Element(
        "testsuite",
        {
            "name": name,
            "tests": str(tests),
            "timestamp": timing.timestamp,
            "time": timing.duration(seconds),
        },
    )


def _case(
    root: ET.Element, classname: str, name: str, recording: str, diff: DiffResult | None
) -> ET.Element:
    """A testcase in `file` (the mission script when known, else the recording) at the
    `line` of its first difference (when it has one)."""
    attributes = {"classname": classname, "name": name}
    attributes["file"] = diff.mission if diff is not None and diff.mission else recording
    line = diff.first_line if diff is not None and diff.mission else None
    if line is not None:
        attributes["line"] = str(line)
    return ET.SubElement(root, "testcase", attributes)


def _failure(case: ET.Element, diff: DiffResult, notes: Sequence[str], header: str) -> None:
    failure = ET.SubElement(
        case,
        "failure",
        {"message": _count(len(diff.differences), "difference"), "type": "replay-difference"},
    )
    failure.text = "\n".join([header, *_diff_lines(diff, notes)])


def _finish(suite: ET.Element, failures: int, errors: int) -> str:
    suite.set("failures", str(failures))
    suite.set("errors", str(errors))
    suite.set("skipped", "0")
    root = ET.Element(
        "testsuites",
        {
            key: suite.get(key, "")
            for key in ("name", "tests", "failures", "errors", "skipped", "time", "timestamp")
        },
    )
    root.append(suite)
    ET.indent(root)
    body = ET.tostring(root, encoding="unicode")
    return f'<?xml version="1.0" encoding="UTF-8"?>\n{body}'
