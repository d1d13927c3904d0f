"""Benchmark: the live view (`fly --live`, issue 28) on a real-time flight against mavsim.

Three figures, medians of `--runs` flights of the thesis' Appendix C against `aeroexec
mavsim` at speed 1 (real time, every telemetry stream at its full rate):

* **latency**: from a message handed to the live view (the recorder's tap, timed with
  the system's monotonic clock) to the same message received by a foxglove.sdk.v1
  client in another process on loopback (the same clock); p99 of each flight.
  Baseline: foxglove-sdk alone, a bare server sending the same shape of traffic (bursts
  of 20 small messages, 10 a second) to the same client (the floor any server built on
  the SDK sits on). Target: p99 <= 20 ms.
* **cost**: CPU time of the flight (`fly()` in this process: every thread, the SDKs'
  servers too) with the live view and a client connected, against the same flight
  without it: with the Foxglove server (what `--live` serves), with the Rerun stream
  too (`--live --rerun-port`), and two floors: foxglove-sdk's own sending thread in
  `--live` (its Tokio worker, counted per thread in /proc: what any server built on the
  SDK pays to send these messages, before a line of aeroexec's), and a bare
  foxglove-sdk server fed each recorded message as it is written (no bursts). Target:
  <= 1.15x. Not in it: importing foxglove-sdk and, for the Rerun stream, rerun-sdk
  (~0.8 s of CPU once per start, almost all rerun's).
* **parity**: the share of the recording's messages the client received with the same
  topic, log time and bytes. Target: 100 %.

    .venv/bin/python benchmarks/live.py [--runs 3]
"""

from __future__ import annotations

import argparse
import collections
import contextlib
import io
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tests"))

from foxglove_client import FoxgloveClient  # noqa: E402


def client_main(url: str, out: str) -> None:
    """The client process: every message with its arrival time, written when the server
    closes the connection. (Before the imports below: the client imports none of them,
    and is connected sooner.)"""
    client = FoxgloveClient(url).start()
    client.wait_closed(600)
    rows = [[m.topic, m.log_time_ns, m.data.hex(), m.arrived_ns] for m in client.messages]
    Path(out).write_text(json.dumps(rows))


if __name__ == "__main__" and sys.argv[1:2] == ["--client"]:
    client_main(sys.argv[2], sys.argv[3])
    sys.exit(0)

from figures import Figure  # noqa: E402
from live_helpers import free_tcp_port, free_udp_port  # noqa: E402

from aeroexec.mission.live import FlightConfig, fly  # noqa: E402
from aeroexec.mission.paths import APPENDIX_C  # noqa: E402
from aeroexec.recording import open_recording  # noqa: E402
from aeroexec.viz.live import LiveOptions, LiveView, no_delay, sdk_runtime  # noqa: E402

LATENCY_TARGET_S = 0.020
COST_TARGET = 1.15


def start_client(url: str, out: Path) -> subprocess.Popen[bytes]:
    return subprocess.Popen([sys.executable, __file__, "--client", url, str(out)])


def start_mavsim(port: int) -> subprocess.Popen[bytes]:
    return subprocess.Popen(
        [sys.executable, "-m", "aeroexec", "mavsim", "--connect", f"udpout:127.0.0.1:{port}"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )


def stop(proc: subprocess.Popen[bytes]) -> None:
    proc.terminate()
    try:
        proc.wait(10)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()


def p99(values: list[float]) -> float:
    return statistics.quantiles(values, n=100)[98]


class Timed(LiveView):
    """The live view, noting when each message is handed to it."""

    def __init__(self, options: LiveOptions) -> None:
        super().__init__(options)
        self.logged: dict[tuple[int, int, bytes], int] = {}
        self.topics: dict[int, str] = {}
        self.viewer_ns = 0

    def channel_added(self, channel):  # type: ignore[no-untyped-def]
        self.topics[channel.id] = channel.topic
        super().channel_added(channel)

    def session_started(self, executive):  # type: ignore[no-untyped-def]
        super().session_started(executive)  # returns once the client has subscribed
        self.viewer_ns = time.monotonic_ns()

    def message_written(self, channel_id: int, log_time_ns: int, data: bytes) -> None:
        self.logged.setdefault((channel_id, log_time_ns, data), time.monotonic_ns())
        super().message_written(channel_id, log_time_ns, data)


def latency_run(workdir: Path, index: int) -> tuple[float, float, int]:
    """One flight in this process, served live to a client process: (p99 latency s,
    parity, messages)."""
    port = free_udp_port()
    record = workdir / f"latency{index}.mcap"
    out = workdir / f"latency{index}.json"
    view = Timed(LiveOptions(port=0, rerun_port=free_tcp_port(), wait_viewer=True))
    client = start_client(view.urls[0], out)
    sim = start_mavsim(port)
    try:
        config = FlightConfig(
            mission=APPENDIX_C, connect=f"udpin:127.0.0.1:{port}", record=record, tap=view
        )
        with contextlib.redirect_stdout(io.StringIO()):
            result = fly(config, observers=[view])
        assert result.outcome.returned, result.outcome.error
    finally:
        view.close()
        stop(sim)
    client.wait(60)
    received = json.loads(out.read_text())
    topics = view.topics
    logged = {(topics[c], t, d): ns for (c, t, d), ns in view.logged.items()}
    # What was logged before the viewer was there (held for it by --wait-viewer) is not
    # live: from the viewer's subscription on, each message's way to the client.
    latencies = [
        (arrived - logged[(topic, t, bytes.fromhex(data))]) / 1e9
        for topic, t, data, arrived in received
        if logged[(topic, t, bytes.fromhex(data))] >= view.viewer_ns
    ]
    expected = collections.Counter(
        (m.channel.topic, m.log_time_ns, m.data) for m in open_recording(record).messages()
    )
    got = collections.Counter((topic, t, bytes.fromhex(data)) for topic, t, data, _ in received)
    same = sum((expected & got).values())  # received as recorded; an extra one counts too
    parity = same / max(sum(expected.values()), sum(got.values()))
    return p99(latencies), parity, sum(expected.values())


def sdk_floor(workdir: Path) -> float:
    """p99 latency of foxglove-sdk alone: a bare server sending the flight's shape of
    traffic, bursts of 20 small messages 10 times a second, with TCP_NODELAY set on its
    connection as the live view sets it (`no_delay`)."""
    import foxglove

    context = foxglove.Context()
    with sdk_runtime():  # the live view's runtime (the SDK builds one per process)
        server = foxglove.start_server(host="127.0.0.1", port=0, context=context)
    channel = foxglove.Channel("/floor", message_encoding="json", context=context)
    out = workdir / "floor.json"
    client = start_client(f"ws://127.0.0.1:{server.port}", out)
    deadline = time.monotonic() + 30
    while not no_delay(server.port):  # the client is connected (and subscribes at once)
        assert time.monotonic() < deadline, "the client did not connect"
        time.sleep(0.05)
    time.sleep(0.5)
    sent: dict[int, int] = {}
    for i in range(2000):
        data = json.dumps({"i": i, "pad": "x" * 200}).encode()
        sent[i] = time.monotonic_ns()
        channel.log(data, log_time=i)
        if i % 20 == 19:
            time.sleep(0.1)
    time.sleep(0.3)
    server.stop()
    client.wait(60)
    received = json.loads(out.read_text())
    return p99([(arrived - sent[t]) / 1e9 for _, t, _, arrived in received])


class BareSdk:
    """The floor: a foxglove-sdk server fed by the recorder's tap with nothing of the live
    view's own (no held channels, no services, no parameters): a channel per recorded
    channel, each message logged as written."""

    def __init__(self) -> None:
        import foxglove

        self._foxglove = foxglove
        self._context = foxglove.Context()
        with sdk_runtime():
            self.server = foxglove.start_server(host="127.0.0.1", port=0, context=self._context)
        self._channels: dict[int, Any] = {}

    def recording_started(self, metadata: Any, attachments: Any) -> None:
        return None

    def channel_added(self, channel: Any) -> None:
        self._channels[channel.id] = self._foxglove.Channel(
            channel.topic, message_encoding="json", context=self._context
        )

    def message_written(self, channel_id: int, log_time_ns: int, data: bytes) -> None:
        self._channels[channel_id].log(data, log_time=log_time_ns)

    def recording_closed(self) -> None:
        return None


def sdk_thread_cpu() -> float:
    """CPU seconds so far of this process's Tokio worker threads (foxglove-sdk's server
    sends from them; Linux, /proc; 0 elsewhere). Counted in clock ticks (10 ms)."""
    total = 0.0
    tick = os.sysconf("SC_CLK_TCK")
    with contextlib.suppress(OSError):
        for task in os.listdir("/proc/self/task"):
            with contextlib.suppress(OSError):
                if not Path(f"/proc/self/task/{task}/comm").read_text().startswith("tokio"):
                    continue
                fields = Path(f"/proc/self/task/{task}/stat").read_text().rsplit(")", 1)[1]
                utime, stime = fields.split()[11:13]
                total += (int(utime) + int(stime)) / tick
    return total


def cpu_run(workdir: Path, index: int, variant: str) -> tuple[float, float, float]:
    """CPU seconds of this process (all its threads: the SDKs' servers too) while it
    flies Appendix C on mavsim in real time: `plain` without a live view, `sdk` with a
    bare foxglove-sdk server, `foxglove` with the live view's Foxglove server, `both`
    with the Rerun stream too; a client process connected to the Foxglove server."""
    port = free_udp_port()
    record = workdir / f"cpu{index}{variant}.mcap"
    view: Any = None
    client = None
    bare = None
    if variant == "sdk":
        bare = BareSdk()
        client = start_client(f"ws://127.0.0.1:{bare.server.port}", workdir / f"cpu{index}.json")
        deadline = time.monotonic() + 30
        while not no_delay(bare.server.port):  # connected, as --wait-viewer would wait
            assert time.monotonic() < deadline, "the client did not connect"
            time.sleep(0.05)
    elif variant != "plain":
        rerun = free_tcp_port() if variant == "both" else None
        view = LiveView(LiveOptions(port=0, rerun_port=rerun, wait_viewer=True))
        client = start_client(view.urls[0], workdir / f"cpu{index}.json")
    sim = start_mavsim(port)
    config = FlightConfig(
        mission=APPENDIX_C,
        connect=f"udpin:127.0.0.1:{port}",
        record=record,
        tap=view if bare is None else bare,
    )
    try:
        with contextlib.redirect_stdout(io.StringIO()):
            started, wall = time.process_time(), time.monotonic()
            sdk = sdk_thread_cpu()
            result = fly(config, observers=[view] if view is not None else [])
            sdk = sdk_thread_cpu() - sdk
            took, wall = time.process_time() - started, time.monotonic() - wall
        assert result.outcome.returned, result.outcome.error
    finally:
        if view is not None:
            view.close()
        if bare is not None:
            time.sleep(0.3)
            bare.server.stop()
        stop(sim)
    if client is not None:
        client.wait(60)
    return took, wall, sdk


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=3)
    options = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        workdir = Path(tmp)
        floor = statistics.median(sdk_floor(workdir) for _ in range(options.runs))
        runs = [latency_run(workdir, i) for i in range(options.runs)]
        cpu: dict[str, list[tuple[float, float, float]]] = {
            "plain": [],
            "sdk": [],
            "foxglove": [],
            "both": [],
        }
        for i in range(options.runs):  # interleaved: drift hits all alike
            for variant, samples in cpu.items():
                samples.append(cpu_run(workdir, i, variant))
    latency = statistics.median(r[0] for r in runs)
    parity = statistics.median(r[1] for r in runs)
    messages = statistics.median(r[2] for r in runs)

    def cpu_of(variant: str) -> float:
        return statistics.median(c for c, _, _ in cpu[variant])

    plain = cpu_of("plain")

    def cpu_figure(label: str, value: float) -> Figure:
        return Figure(label, value, plain, "without --live", COST_TARGET)

    figures = [
        Figure(
            f"latency p99, logged to received ({messages:.0f} messages a flight)",
            latency,
            floor,
            "foxglove-sdk alone",
            LATENCY_TARGET_S,
            kind="max",
        ),
        cpu_figure(
            "CPU of a real-time flight, --live (the Foxglove server) and a client",
            cpu_of("foxglove"),
        ),
        cpu_figure(
            "CPU of a real-time flight, --live --rerun-port (Foxglove and Rerun)",
            cpu_of("both"),
        ),
        cpu_figure(
            "  the floor: the flight plus foxglove-sdk's sending thread alone, in --live",
            plain + statistics.median(t for _, _, t in cpu["foxglove"]),
        ),
        cpu_figure(
            "  the same flight with a bare foxglove-sdk server, fed message by message",
            cpu_of("sdk"),
        ),
        Figure(
            "CPU --live adds, in % of one core over the flight",
            100
            * statistics.median(
                (live - plain) / wall
                for (live, wall, _), (plain, _, _) in zip(
                    cpu["foxglove"], cpu["plain"], strict=True
                )
            ),
            100 * statistics.median(c / w for c, w, _ in cpu["plain"]),
            "the flight's own",
            15.0,
            unit=" %",
            kind="max",
        ),
        Figure("parity", parity * 100, 100.0, "the recording", 100.0, unit=" %", kind="min"),
    ]
    for figure in figures:
        print(figure.line())
    print(f"runs: latency p99 {[round(r[0] * 1000, 2) for r in runs]} ms; CPU {cpu}")
    return 0 if all(f.ok for f in figures) else 1


if __name__ == "__main__":
    sys.exit(main())
