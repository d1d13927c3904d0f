"""The pieces of `aeroexec view` on their own: interval matching, the call tree, batched
column writing, viewer discovery, progress, text rows."""

from __future__ import annotations

import io
from pathlib import Path
from typing import Any

import pytest
import rerun as rr
from rerun.chunk import RrdReader

from aeroexec.progress import progress_bar
from aeroexec.recording.reader import RecordedCall
from aeroexec.viz import texts
from aeroexec.viz.calltree import CallTree
from aeroexec.viz.columns import ColumnWriter
from aeroexec.viz.intervals import BehaviorIntervals, CapabilityCounts
from aeroexec.viz.layout import Layout, layouts_for
from aeroexec.viz.viewer import cannot_spawn, has_display, viewer_binary, viewer_command


# -- BehaviorIntervals -------------------------------------------------------------------
def _edges(transitions: list[Any]) -> list[tuple[str, int, bool]]:
    return [(t.name, t.t_ns, t.active) for t in transitions]


def test_activation_then_end() -> None:
    b = BehaviorIntervals()
    assert _edges(b.activated("TAKE_OFF", 1, 0, "#1")) == [("TAKE_OFF", 0, True)]
    assert b.active("TAKE_OFF") == 1
    assert _edges(b.ended("TAKE_OFF", 1, 5)) == [("TAKE_OFF", 5, False)]
    assert b.active("TAKE_OFF") is None


def test_end_event_read_before_its_activation() -> None:
    b = BehaviorIntervals()
    assert b.ended("LAND", 7, 13) == []  # not active yet: remembered
    assert _edges(b.activated("LAND", 7, 13)) == [("LAND", 13, True), ("LAND", 13, False)]
    assert b.active("LAND") is None
    assert _edges(b.finish(20)) == [("LAND", 20, False)]


def test_replaced_activation_ignores_its_late_end_event() -> None:
    b = BehaviorIntervals()
    b.activated("GO_TO_POINT", 3, 10)
    b.activated("GO_TO_POINT", 4, 20)  # replaces #3 before #3's end event was read
    assert b.ended("GO_TO_POINT", 3, 20) == []  # #3's late end does not end #4
    assert b.active("GO_TO_POINT") == 4
    assert _edges(b.ended("GO_TO_POINT", 4, 30)) == [("GO_TO_POINT", 30, False)]


def test_end_event_of_an_unknown_activation_changes_nothing() -> None:
    b = BehaviorIntervals()
    b.activated("ROTATE", 5, 0)
    assert b.ended("ROTATE", 99, 1) == []
    assert b.active("ROTATE") == 5


def test_finish_reports_each_behavior_state() -> None:
    b = BehaviorIntervals()
    b.activated("A", 1, 0)
    b.activated("B", 2, 0)
    b.ended("B", 2, 3)
    assert _edges(b.finish(9)) == [("A", 9, True), ("B", 9, False)]


# -- CapabilityCounts --------------------------------------------------------------------
def test_capability_counts_report_changes_and_drops() -> None:
    c = CapabilityCounts()
    assert c.update([{"name": "A", "references": 1}]) == [("A", 1)]
    assert c.update([{"name": "A", "references": 1}]) == []
    assert c.update([{"name": "A", "references": 2}, {"name": "B", "references": 1}]) == [
        ("A", 2),
        ("B", 1),
    ]
    assert c.update([{"name": "B", "references": 1}]) == [("A", 0)]
    assert c.update("garbage") == [("B", 0)]
    assert c.counts == {"A": 0, "B": 0}


# -- CallTree ----------------------------------------------------------------------------
def _call(seq: int, parent: int | None, ok: bool = True) -> RecordedCall:
    response = {"ok": ok, "error": "" if ok else "no"}
    return RecordedCall("/d/s", seq, seq, parent, "c", f"s{seq}", {}, response)


def test_call_tree_waits_for_the_root_and_returns_start_order() -> None:
    tree = CallTree()
    # written as they return: grandchild, children, then the root
    assert tree.add(_call(3, 2)) == []
    assert tree.add(_call(2, 1)) == []
    assert tree.add(_call(4, 1)) == []
    placed = tree.add(_call(1, None))
    assert [(c.seq, d) for c, d in placed] == [(1, 0), (2, 1), (3, 2), (4, 1)]
    assert tree.pending == 0


def test_call_returning_after_its_parent_is_placed_at_once() -> None:
    tree = CallTree()
    tree.add(_call(1, None))
    assert [(c.seq, d) for c, d in tree.add(_call(2, 1))] == [(2, 1)]


def test_calls_without_their_root_come_out_of_drain() -> None:
    tree = CallTree()
    tree.add(_call(6, 5))
    tree.add(_call(5, 4))  # root 4 never written (file cut)
    tree.add(_call(9, 8))
    assert [(c.seq, d) for c, d in tree.drain()] == [(5, 1), (6, 2), (9, 1)]
    assert tree.pending == 0


def test_call_tree_memory_is_bounded() -> None:
    tree = CallTree(recent=8)
    for root in range(0, 3000, 3):
        tree.add(_call(root + 2, root + 1))
        tree.add(_call(root + 1, root))
        assert len(tree.add(_call(root, None))) == 3
    assert tree.pending == 0
    assert len(tree._depths) == 8


# -- ColumnWriter ------------------------------------------------------------------------
def _stream(path: Path) -> rr.RecordingStream:
    stream = rr.RecordingStream("aeroexec-test", recording_id="units", send_properties=False)
    stream.set_log_time_enabled(False)
    stream.save(str(path))
    return stream


def _close(stream: rr.RecordingStream) -> None:
    stream.flush()
    stream.disconnect()


def test_column_writer_sends_full_batches_and_the_rest_at_flush(tmp_path: Path) -> None:
    path = tmp_path / "w.rrd"
    stream = _stream(path)
    writer = ColumnWriter(stream, batch=3)
    for i in range(7):
        writer.row("/x", rr.Scalars, i * 10, scalars=float(i))
    assert writer.rows_sent == 6  # two full batches already sent
    writer.flush()
    assert writer.rows_sent == 7
    _close(stream)
    values: list[float] = []
    times: list[int] = []
    for chunk in RrdReader(path).stream():
        if chunk.entity_path == "/x":
            batch = chunk.to_record_batch()
            values += [v[0] for v in batch.column("Scalars:scalars").to_pylist()]
            times += batch.column("sim_time").cast("int64").to_pylist()
    assert sorted(zip(times, values, strict=True)) == [(i * 10, float(i)) for i in range(7)]


def test_column_writer_seq_timeline_and_row_shape_changes(tmp_path: Path) -> None:
    path = tmp_path / "s.rrd"
    stream = _stream(path)
    writer = ColumnWriter(stream, batch=100)
    writer.row("/log", rr.TextLog, 5, seq=1, text="a", level="INFO")
    writer.row("/log", rr.TextLog, 5, text="b", level="WARN")  # no seq: a new chunk
    writer.row("/log", rr.TextLog, 6, seq=2, text="c", level="INFO")
    writer.flush()
    _close(stream)
    rows: list[tuple[str, Any]] = []
    for chunk in RrdReader(path).stream():
        if chunk.entity_path == "/log":
            batch = chunk.to_record_batch()
            seqs = (
                batch.column("seq").to_pylist()
                if "seq" in batch.schema.names
                else [None] * chunk.num_rows
            )
            rows += [
                (t[0], s)
                for t, s in zip(batch.column("TextLog:text").to_pylist(), seqs, strict=True)
            ]
    assert sorted(rows) == [("a", 1), ("b", None), ("c", 2)]


def test_column_writer_rejects_empty_batches(tmp_path: Path) -> None:
    with pytest.raises(ValueError):
        ColumnWriter(_stream(tmp_path / "e.rrd"), batch=0)


# -- layout ------------------------------------------------------------------------------
def test_layout_roots_and_escaping() -> None:
    assert Layout().events == "/events" and Layout().origin == "/"
    assert Layout("base").behavior_active("GO_TO_POINT") == "/base/behaviors/active/GO_TO_POINT"
    # a name with a slash or space stays one path part
    assert Layout().process("a/b c") == "/processes/a\\/b\\ c"
    assert [layout.root for layout in layouts_for(["x", "y"])] == ["base", "new"]
    with pytest.raises(ValueError):
        layouts_for(["a", "b", "c"])


# -- viewer discovery --------------------------------------------------------------------
def test_display_detection() -> None:
    assert not has_display({}, "linux")
    assert has_display({"DISPLAY": ":0"}, "linux")
    assert has_display({"WAYLAND_DISPLAY": "wayland-0"}, "linux")
    assert has_display({}, "darwin") and has_display({}, "win32")


def test_cannot_spawn_reasons(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    binary = tmp_path / "rerun"
    assert "no display" in (cannot_spawn(environ={}, binary=binary) or "")
    assert cannot_spawn(web=True, environ={}, binary=binary) is None
    assert cannot_spawn(environ={"DISPLAY": ":1"}, binary=binary) is None
    monkeypatch.setattr("aeroexec.viz.viewer.viewer_binary", lambda: None)
    assert "no Rerun viewer" in (cannot_spawn(environ={"DISPLAY": ":1"}) or "")


def test_viewer_command(tmp_path: Path) -> None:
    exe = tmp_path / "rerun"
    assert viewer_command(tmp_path / "a.rrd", binary=exe) == [str(exe), str(tmp_path / "a.rrd")]
    web = viewer_command(tmp_path / "a.rrd", web=True, binary=exe)
    assert web[1] == "--web-viewer" and web[-1] == str(tmp_path / "a.rrd")
    # this machine only, the page on rerun's usual port, the data server on a free one
    assert web[web.index("--bind") + 1] == "127.0.0.1"
    assert web[web.index("--web-viewer-port") + 1] == "9090"
    assert web[web.index("--port") + 1] == "0"
    remote = viewer_command(tmp_path / "a.rrd", web=True, binary=exe, bind="0.0.0.0", port=1)
    assert remote[remote.index("--bind") + 1] == "0.0.0.0"
    assert remote[remote.index("--web-viewer-port") + 1] == "1"


def test_the_bundled_viewer_is_found() -> None:
    found = viewer_binary()
    assert found is not None and found.is_file()


# -- progress ----------------------------------------------------------------------------
class _Tty(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_progress_only_on_a_terminal_and_for_long_conversions() -> None:
    quiet = io.StringIO()
    with progress_bar("x", 10**6, stream=quiet) as advance:
        advance(10)
    assert quiet.getvalue() == ""  # not a terminal
    short = _Tty()
    with progress_bar("x", 10, stream=short) as advance:
        advance(10)
    assert short.getvalue() == ""  # too short to be worth a bar
    shown = _Tty()
    with progress_bar("converting", 10**6, stream=shown, enabled=True) as advance:
        advance(500)
    assert "converting" in shown.getvalue()


# -- text rows ---------------------------------------------------------------------------
def test_text_rows() -> None:
    assert texts.event_row({"name": "LAND", "uid": 7, "code": "PROCESS_FAILURE"}) == (
        "LAND #7 PROCESS_FAILURE",
        "ERROR",
    )
    assert texts.event_row({"name": "X", "uid": 1, "code": "SOMETHING_NEW"})[1] == "WARN"
    refused = RecordedCall(
        "/d/activate_behavior",
        0,
        2,
        None,
        "mission",
        "activate_behavior",
        {"behavior": "GO_TO_POINT", "arguments": {"coordinates": [1, 1, 1]}},
        {"ok": False, "error": "not flying"},
    )
    assert texts.rejection_row(refused) == (
        "REJECTED GO_TO_POINT coordinates=[1, 1, 1]: not flying",
        "WARN",
    )
    text, level = texts.call_row(refused, 2)
    assert text.startswith("    [2] mission -> activate_behavior ") and level == "WARN"
    answer = RecordedCall("/d/c", 0, 9, 8, "bc", "check_consistency", {}, {"ok": False})
    assert texts.call_row(answer, 1)[0].endswith(": no")
    assert texts.log_row({"level": 4, "message": "boom"}) == ("boom", "ERROR")
    assert texts.belief_row({"op": "remove", "belief": "flying(self)"}) == (
        "- flying(self)",
        "DEBUG",
    )
    replaced = {"op": "replace", "belief": "yaw(self, 90)", "replaced": "yaw(self, 0)"}
    assert texts.belief_row(replaced) == ("+ yaw(self, 90) (- yaw(self, 0))", "DEBUG")
    assert texts.compact("x" * 500, 20).endswith("…") and len(texts.compact("x" * 500, 20)) == 20
