"""`run --live` and `fly --live` (issue 28): a Foxglove WebSocket client (foxglove.sdk.v1,
tests/foxglove_client.py) and Rerun's own `rerun download` connect to the session while
it runs, and what they receive is checked against the recording the same command wrote:

* every message of the MCAP, with the same bytes, log time and channel (topic, schema),
  and nothing else;
* the Rerun stream holds the rows `aeroexec view` writes for that recording;
* the abort service ends the mission and the vehicle lands; the parameters are the
  recording's and a client cannot change them;
* the servers listen on 127.0.0.1, close with the command, and one signal ends it all
  with the recording finished.
"""

from __future__ import annotations

import collections
import hashlib
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest
from foxglove_client import FoxgloveClient
from live_helpers import AeroexecProcess, free_tcp_port, free_udp_port, mavsim_thread, write_mission
from test_view import read_rrd
from thread_count import threads_with

from aeroexec.mission.paths import APPENDIX_C
from aeroexec.recording import open_recording
from aeroexec.recording.reader import RecordedTopic

RERUN = Path(sys.executable).with_name("rerun")
PATROL = """\
    api.executeBehavior("TAKE_OFF")
    for lap in range(20):
        api.executeBehavior("GO_TO_POINT", coordinates=[3, 0, 1.5])
        api.executeBehavior("GO_TO_POINT", coordinates=[0, 0, 1.5])
    api.executeBehavior("LAND")
"""


class Live(AeroexecProcess):
    wait_s = 60.0
    finish_s = 120.0

    _urls: tuple[str, str] | None = None

    def urls(self) -> tuple[str, str]:
        """The Foxglove and the Rerun server's addresses, as the command prints them."""
        if self._urls is None:
            foxglove = self.wait_for("live: Foxglove, Lichtblick: ").split(": ")[-1].strip()
            rerun = self.wait_for("live: Rerun: rerun ").split("rerun ")[-1].strip()
            self._urls = (foxglove, rerun)
        return self._urls

    def url(self) -> str:
        return self.urls()[0]

    def rerun_url(self) -> str:
        return self.urls()[1]


def recorded_messages(record: Path) -> list[tuple[str, int, bytes]]:
    recording = open_recording(record)
    assert recording.complete
    return [(m.channel.topic, m.log_time_ns, m.data) for m in recording.messages()]


def assert_parity(client: FoxgloveClient, record: Path) -> None:
    """Exactly the recording's messages: same topic, log time and bytes, each once, in
    the recording's order on each channel; and the recording's channels and schemas."""
    expected = recorded_messages(record)
    received = [(m.topic, m.log_time_ns, m.data) for m in client.messages]
    assert len(received) == len(expected)
    assert collections.Counter(received) == collections.Counter(expected)
    for topic in {t for t, _, _ in expected}:
        assert [m for m in received if m[0] == topic] == [m for m in expected if m[0] == topic]
    served = client.topics()
    for channel in open_recording(record).channels.values():
        advertised = served[channel.topic]
        assert advertised["encoding"] == channel.message_encoding == "json"
        assert advertised["schemaName"] == channel.schema_name
        assert advertised["schemaEncoding"] == channel.schema_encoding
        assert advertised["schema"].encode() == channel.schema_data
    assert set(served) == {c.topic for c in open_recording(record).channels.values()}


def without_row_ids(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Rerun stamps each row with an id made from its creation time: all else must match."""
    return [{k: v for k, v in row.items() if k != "rerun.controls.RowId"} for row in rows]


def live_args(record: Path, *extra: str) -> list[str]:
    return ["-o", str(record), "--live", "--port", "0", "--rerun-port", "0", *extra]


# -- run --live ---------------------------------------------------------------------------------


def test_run_live_serves_exactly_the_recording_and_the_rerun_stream_is_the_view(
    tmp_path: Path, procs: list[AeroexecProcess]
) -> None:
    record = tmp_path / "flight.mcap"
    proc = Live(["run", str(APPENDIX_C), *live_args(record, "--wait-viewer", "--speed", "4")])
    procs.append(proc)
    rerun_url = proc.rerun_url()
    # Rerun's own client saves what the gRPC server streams, until the server closes.
    download = subprocess.Popen(
        [str(RERUN), "download", rerun_url, "-o", str(tmp_path)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    client = FoxgloveClient(proc.url()).start()
    code, out, err = proc.finish()
    assert code == 0, err
    assert "7 activations: 6 GOAL_ACHIEVED" in out
    client.wait_closed()  # the server closed with the command
    assert client.server_info["capabilities"] == ["services", "parameters", "parametersSubscribe"]
    assert_parity(client, record)
    assert download.wait(30) == 0, download.stderr.read() if download.stderr else ""

    # The live Rerun stream against the file `aeroexec view` writes for the recording.
    view = subprocess.run(
        [sys.executable, "-m", "aeroexec", "view", str(record), "-o", str(tmp_path / "v.rrd")],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert view.returncode == 0, view.stderr
    live = read_rrd(tmp_path / "output.rrd")
    written = read_rrd(tmp_path / "v.rrd")
    assert live.rows.keys() == written.rows.keys()
    for entity, rows in written.rows.items():
        assert without_row_ids(live.rows[entity]) == without_row_ids(rows), entity
    assert live.static.keys() == written.static.keys()
    for entity, rows in written.static.items():
        assert without_row_ids(live.static[entity]) == without_row_ids(rows), entity
    assert len(live.rows["/vehicle"]) > 100  # the flight, not an empty stream


#: A node_modules folder with @foxglove/ws-protocol and ws (`npm install` them anywhere):
#: the test then connects with Foxglove's own protocol client, the one its apps use.
FOXGLOVE_NODE_MODULES = os.environ.get("AEROEXEC_FOXGLOVE_NODE_MODULES", "")
WS_CLIENT = Path(__file__).parent / "tools" / "foxglove_ws_client.js"


@pytest.mark.skipif(
    not (Path(FOXGLOVE_NODE_MODULES) / "@foxglove" / "ws-protocol").is_dir()
    or shutil.which("node") is None,
    reason="set AEROEXEC_FOXGLOVE_NODE_MODULES to a node_modules with @foxglove/ws-protocol "
    "and ws (and install node) to connect with Foxglove's own client",
)
def test_foxglove_s_own_client_receives_exactly_the_recording(
    tmp_path: Path, procs: list[AeroexecProcess]
) -> None:
    record = tmp_path / "flight.mcap"
    proc = Live(["run", str(APPENDIX_C), "-o", str(record), "--live", "--port", "0",
                 "--wait-viewer", "--speed", "10"])  # fmt: skip
    procs.append(proc)
    url = proc.wait_for("live: Foxglove, Lichtblick: ").split(": ")[-1].strip()
    # Into a file: a pipe nobody reads while the run goes on would stall the client.
    received_path = tmp_path / "received.jsonl"
    with received_path.open("w") as sink:
        client = subprocess.Popen(
            ["node", str(WS_CLIENT), url],
            stdout=sink,
            stderr=subprocess.PIPE,
            text=True,
            env={**os.environ, "NODE_PATH": FOXGLOVE_NODE_MODULES},
        )
        code, _, err = proc.finish()
        assert code == 0, err
        _, client_err = client.communicate(timeout=60)
    assert client.returncode == 0, client_err
    lines = [json.loads(line) for line in received_path.read_text().splitlines()]
    received = collections.Counter(
        (m["topic"], int(m["log_time"]), m["sha1"]) for m in lines if "topic" in m
    )
    expected = collections.Counter(
        (topic, log_time, hashlib.sha1(data).hexdigest())
        for topic, log_time, data in recorded_messages(record)
    )
    assert received == expected
    channels = open_recording(record).channels.values()
    advertised = {m["advertised"]: m["schemaName"] for m in lines if "advertised" in m}
    assert advertised == {c.topic: c.schema_name for c in channels}


def test_a_live_run_records_the_same_file_as_a_plain_run(tmp_path: Path) -> None:
    live, plain = tmp_path / "live.mcap", tmp_path / "plain.mcap"
    proc = Live(["run", str(APPENDIX_C), *live_args(live, "--speed", "50")])
    code, _, err = proc.finish()
    assert code == 0, err
    run = subprocess.run(
        [sys.executable, "-m", "aeroexec", "run", str(APPENDIX_C), "-o", str(plain), "-q"],
        capture_output=True,
        timeout=120,
    )
    assert run.returncode == 0
    assert live.read_bytes() == plain.read_bytes()


def test_speed_paces_the_simulated_clock_to_the_wall_clock() -> None:
    """Appendix C is 18.6 simulated seconds: at 4x real time it takes 4.65 s or more of
    wall time (unpaced it takes well under a second of simulation)."""
    started = time.monotonic()
    proc = subprocess.run(
        [sys.executable, "-m", "aeroexec", "run", str(APPENDIX_C), "--speed", "4", "-q"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    took = time.monotonic() - started
    assert proc.returncode == 0, proc.stderr
    assert "18.6 s simulated" in proc.stdout
    assert took >= 18.6 / 4


def test_the_abort_service_lands_the_vehicle_and_parameters_are_read_only(
    tmp_path: Path, procs: list[AeroexecProcess]
) -> None:
    record = tmp_path / "patrol.mcap"
    mission = write_mission(tmp_path, PATROL)
    proc = Live(["run", str(mission), *live_args(record, "--wait-viewer", "--speed", "5")])
    procs.append(proc)
    client = FoxgloveClient(proc.url()).start()
    proc.wait_for("end      TAKE_OFF GOAL_ACHIEVED")

    catalog = "aeroexec/catalog.yaml"
    values = client.parameters([catalog, "aeroexec/seed", "aeroexec/mission"])
    assert values["aeroexec/seed"] == "0" and values["aeroexec/mission"] == "mission.py"
    assert "TAKE_OFF" in values[catalog]
    after = client.parameters([], set_to={"aeroexec/seed": "7"})
    assert after == {"aeroexec/seed": "0"}  # what is recorded is not the client's to change

    answer = client.call("/abort_mission", {})
    assert answer == {"ok": True, "action": "land"}
    code, out, err = proc.finish()
    client.wait_closed()
    assert code == 1
    assert "mission stopped: aborted by a live viewer" in err and "landing" in err
    assert "vehicle landed" in out
    recording = open_recording(record)
    assert recording.complete
    # recorded as what it was: an operator's abort, not a violated property
    assert recording.metadata["aeroexec_end"]["reason"] == "abort"
    assert recording.metadata["aeroexec_end"]["detail"] == "aborted by a live viewer"
    assert_parity(client, record)
    # the ending is recorded: the behaviors inhibited, then a landing
    states = [
        r.data
        for r in recording.records()
        if isinstance(r, RecordedTopic) and r.name == "vehicle/state"
    ]
    assert states[-1]["position"][2] == pytest.approx(0.0, abs=0.05)
    laps = [r for r in proc.out if "end      GO_TO_POINT" in r]
    assert len(laps) < 40  # it did not fly the whole patrol
    # once the mission is over there is nothing to abort
    assert client.closed.is_set()


def test_one_signal_ends_a_live_run_with_the_recording_finished_and_the_servers_closed(
    tmp_path: Path, procs: list[AeroexecProcess]
) -> None:
    record = tmp_path / "patrol.mcap"
    mission = write_mission(tmp_path, PATROL)
    proc = Live(["run", str(mission), *live_args(record, "--speed", "1")])
    procs.append(proc)
    url = proc.url()
    port = int(url.rsplit(":", 1)[1])
    client = FoxgloveClient(url).start()
    proc.wait_for("start    TAKE_OFF")
    proc.popen.send_signal(signal.SIGINT)
    code, _, err = proc.finish(timeout=10)
    assert code == 130, err
    assert "interrupted by SIGINT" in err
    client.wait_closed(10)
    assert open_recording(record).complete
    with socket.socket() as s, pytest.raises(ConnectionRefusedError):
        s.connect(("127.0.0.1", port))


def test_a_signal_ends_the_wait_for_a_viewer(tmp_path: Path, procs: list[AeroexecProcess]) -> None:
    """--wait-viewer waits for nothing longer than one signal: the recording is finished
    (interrupted, with the session's first messages) and the servers closed."""
    record = tmp_path / "waited.mcap"
    proc = Live(["run", str(APPENDIX_C), *live_args(record, "--wait-viewer")])
    procs.append(proc)
    proc.wait_for("live: the mission starts when a viewer subscribes")
    time.sleep(1.0)
    proc.popen.send_signal(signal.SIGTERM)
    code, out, err = proc.finish(timeout=10)
    assert code == 143, err
    assert "start    TAKE_OFF" not in out  # the mission never started
    recording = open_recording(record)
    assert recording.complete
    assert recording.metadata["aeroexec_end"]["reason"] == "interrupted"


def listening(proc: AeroexecProcess) -> list[Any]:
    psutil = pytest.importorskip("psutil")
    return [
        c.laddr
        for c in psutil.Process(proc.popen.pid).net_connections(kind="tcp")
        if c.status == psutil.CONN_LISTEN
    ]


def test_the_servers_listen_on_loopback_only(tmp_path: Path, procs: list[AeroexecProcess]) -> None:
    mission = str(write_mission(tmp_path, PATROL))
    proc = Live(["run", mission, "--live", "--port", "0", "--rerun-port", "0"])
    procs.append(proc)
    proc.url()
    proc.rerun_url()
    addresses = listening(proc)
    assert len(addresses) == 2
    assert {address.ip for address in addresses} == {"127.0.0.1"}
    proc.stop()


def test_the_rerun_stream_runs_only_when_asked_for(
    tmp_path: Path, procs: list[AeroexecProcess]
) -> None:
    """Without --rerun-port, --live serves Foxglove alone: one server, no Rerun line, and
    rerun-sdk is not even imported (its import and its stream are most of --live's CPU)."""
    proc = Live(["run", str(write_mission(tmp_path, PATROL)), "--live", "--port", "0"])
    procs.append(proc)
    url = proc.wait_for("live: Foxglove, Lichtblick: ").split(": ")[-1].strip()
    port = int(url.rsplit(":", 1)[1])
    proc.wait_for("start    TAKE_OFF")
    assert [(a.ip, a.port) for a in listening(proc)] == [("127.0.0.1", port)]
    assert not any(line.startswith("live: Rerun") for line in proc.out)
    maps = Path(f"/proc/{proc.popen.pid}/maps")
    if maps.exists():  # Linux: rerun-sdk's native library is not loaded
        assert "rerun_bindings" not in maps.read_text()
    proc.stop()


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--port", "0"], "--port, --rerun-port and --wait-viewer are for --live: add --live"),
        (["--wait-viewer"], "--port, --rerun-port and --wait-viewer are for --live: add --live"),
        (["--allow-remote"], "--allow-remote is for --live: add --live"),
        (["--speed", "0"], "invalid value for --speed: 0: give a factor above 0"),
    ],
)
def test_live_options_without_live_are_one_line_and_exit_2(args: list[str], message: str) -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "aeroexec", "run", str(APPENDIX_C), *args],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert proc.returncode == 2
    assert proc.stderr.strip().splitlines() == [f"aeroexec run: error: {message}"]


def test_a_port_in_use_is_one_line_and_exit_2(tmp_path: Path) -> None:
    port = free_tcp_port()
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", port))
        taken.listen()
        proc = subprocess.run(
            [
                sys.executable,
                "-m",
                "aeroexec",
                "run",
                str(APPENDIX_C),
                "--live",
                "--port",
                str(port),
            ],
            capture_output=True,
            text=True,
            timeout=60,
        )
    assert proc.returncode == 2
    assert proc.stderr.strip().splitlines() == [
        f"aeroexec run: error: the Foxglove WebSocket server cannot listen on 127.0.0.1:{port}: "
        "Address already in use"
    ]


# -- fly --live against mavsim ------------------------------------------------------------------


def test_fly_live_on_mavsim_serves_exactly_the_recording(
    tmp_path: Path, procs: list[AeroexecProcess]
) -> None:
    port = free_udp_port()
    record = tmp_path / "flight.mcap"
    proc = Live(
        [
            "fly",
            str(APPENDIX_C),
            "--connect",
            f"udpin:127.0.0.1:{port}",
            *live_args(record, "--wait-viewer"),
        ]
    )
    procs.append(proc)
    url = proc.url()
    with mavsim_thread(f"udpout:127.0.0.1:{port}"):
        client = FoxgloveClient(url).start()
        code, out, err = proc.finish()
    assert code == 0, err
    assert "7 activations: 6 GOAL_ACHIEVED" in out
    client.wait_closed()
    assert_parity(client, record)
    topics = {m.topic for m in client.messages}
    assert {"/drone1/mavlink/rx", "/drone1/mavlink/tx", "/drone1/scene"} <= topics


def test_fly_wait_viewer_keeps_the_link_while_it_waits(
    tmp_path: Path, procs: list[AeroexecProcess]
) -> None:
    """A viewer that comes after the heartbeat timeout (3 s): the link was served while
    fly waited, so the flight is as it would have been, with no link lost."""
    port = free_udp_port()
    record = tmp_path / "flight.mcap"
    proc = Live(
        [
            "fly",
            str(APPENDIX_C),
            "--connect",
            f"udpin:127.0.0.1:{port}",
            *live_args(record, "--wait-viewer"),
        ]
    )
    procs.append(proc)
    url = proc.url()
    with mavsim_thread(f"udpout:127.0.0.1:{port}"):
        proc.wait_for("mavlink: autopilot system 1")
        time.sleep(4.5)
        assert not any("start    TAKE_OFF" in line for line in proc.out)  # still waiting
        client = FoxgloveClient(url).start()
        code, out, err = proc.finish()
    assert code == 0, err
    assert "link lost" not in out + err
    client.wait_closed()
    assert_parity(client, record)


# -- foxglove-sdk's runtime -------------------------------------------------------------------
THREADS_OF_A_LIVE_VIEW = """\
import os, sys
from aeroexec.viz.live import LiveOptions, LiveView
view = LiveView(LiveOptions(port=0))
print(len(os.listdir("/proc/self/task")), os.environ.get("TOKIO_WORKER_THREADS"))
view.close()
"""


def _live_view_threads(tokio_workers: str | None) -> tuple[int, str]:
    return threads_with(THREADS_OF_A_LIVE_VIEW, "TOKIO_WORKER_THREADS", tokio_workers)


@pytest.mark.skipif(not os.path.isdir("/proc/self/task"), reason="threads counted in /proc")
def test_the_server_runs_on_one_worker_thread_unless_the_user_says_otherwise() -> None:
    # One worker: a second is woken to steal each burst's sends (benchmarks/live.py).
    ours, left = _live_view_threads(None)
    theirs, kept = _live_view_threads("3")
    assert theirs - ours == 2  # the user's three workers, against our one
    assert left == "None"  # not left for the mission's child processes to inherit
    assert kept == "3"


def test_a_worker_count_the_runtime_cannot_read_is_one_line_and_exit_2() -> None:
    # Tokio would panic inside the SDK, with a Rust backtrace.
    proc = subprocess.run(
        [sys.executable, "-m", "aeroexec", "run", str(APPENDIX_C), "--live", "--port", "0"],
        capture_output=True,
        text=True,
        timeout=60,
        env={**os.environ, "TOKIO_WORKER_THREADS": "two"},
    )
    assert proc.returncode == 2
    assert proc.stderr.strip().splitlines() == [
        "aeroexec run: error: TOKIO_WORKER_THREADS='two' (the live servers' worker threads) "
        "is not a whole number above 0"
    ]
