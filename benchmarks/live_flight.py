"""Benchmark: the thesis' Appendix C flown live, on ArduCopter SITL and on `aeroexec mavsim`.

Runs `aeroexec fly missions/appendix_c.py --output` against

* ArduCopter 4.5.6 SITL (`../shared/sitl/arducopter`, or `$AEROEXEC_SITL`), a fresh one
  per run, at `--speedup` (default 1: real time, as a real vehicle flies), over UDP;
* `aeroexec mavsim` at the same speed factor, for comparison,

and measures, with medians (the machine is shared: single runs are noisy):

* success: exit 0 and six GOAL_ACHIEVED, every run (target: all runs);
* flown time: the executive's seconds from the link up to the end of the mission;
* wall time: from starting the autopilot to fly's exit (SITL's EKF start-up included);
* command-ACK latency: each COMMAND_LONG sent to its COMMAND_ACK received, from the
  recording (baseline: the loopback floor of a datagram round trip; target: well under
  the 1 s ack timeout);
* link-loss detection: a `MavlinkVehicle` connected to SITL, the time from stopping
  SITL (SIGSTOP, UDP) or killing it (SIGKILL, TCP) to `link_lost` (baseline: the
  heartbeat timeout for UDP, 0 for a TCP connection that closes).

Prints each figure on one line with its baseline and target; exits 1 if a target is
missed. About 80 s per SITL run at speed-up 1.

    .venv/bin/python benchmarks/live_flight.py [--runs 10] [--speedup 1] [--mavsim-runs 3]
"""

from __future__ import annotations

import argparse
import json
import os
import re
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from aeroexec.mission.paths import APPENDIX_C
from aeroexec.recording import open_recording
from aeroexec.recording.reader import RecordedTopic
from aeroexec.vehicles.mavlink.vehicle import MavlinkConfig, MavlinkVehicle

REPO = Path(__file__).resolve().parents[1]
BINARY = Path(os.environ.get("AEROEXEC_SITL") or REPO.parent / "shared" / "sitl" / "arducopter")
PARM = BINARY.parent / "copter.parm"
#: SITL instances used here (ports 6260 and up), away from the tests' (30 and up).
FIRST_INSTANCE = 50
ACK_TARGET_MS = 1000.0


@dataclass
class Run:
    ok: bool
    flown_s: float
    wall_s: float
    acks_ms: list[float]
    detail: str


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def start_sitl(
    workdir: Path, instance: int, speedup: float, serial0: str | None
) -> subprocess.Popen[bytes]:
    args = [str(BINARY), "--model", "quad", "--speedup", f"{speedup:g}", "--defaults", str(PARM)]
    args += ["-I", str(instance)]
    if serial0 is not None:
        args += ["--serial0", serial0]
    log = (workdir / f"sitl{instance}.log").open("wb")
    return subprocess.Popen(args, cwd=workdir, stdout=log, stderr=subprocess.STDOUT)


def stop(proc: subprocess.Popen[bytes]) -> None:
    if proc.poll() is None:
        proc.send_signal(signal.SIGCONT)
        proc.terminate()
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(5)


def ack_latencies(record: Path) -> list[float]:
    """ms from each COMMAND_LONG sent to the first COMMAND_ACK for its command after it."""
    pending: dict[int, int] = {}
    latencies = []
    for item in open_recording(record).records():
        if not isinstance(item, RecordedTopic):
            continue
        data = item.data
        if item.name == "mavlink/tx" and data["type"] == "COMMAND_LONG":
            pending.setdefault(data["fields"]["command"], item.log_time_ns)
        elif item.name == "mavlink/rx" and data["type"] == "COMMAND_ACK":
            sent = pending.pop(data["fields"]["command"], None)
            if sent is not None:
                latencies.append((item.log_time_ns - sent) / 1e6)
    return latencies


def fly(workdir: Path, url: str, name: str) -> tuple[subprocess.CompletedProcess[str], Path]:
    record = workdir / f"{name}.mcap"
    args = [sys.executable, "-m", "aeroexec", "fly", str(APPENDIX_C), "--connect", url]
    args += ["--output", str(record), "--connect-timeout", "300", "-q"]
    return subprocess.run(args, capture_output=True, text=True, timeout=900), record


def judge(result: subprocess.CompletedProcess[str], record: Path, started: float) -> Run:
    wall = time.monotonic() - started
    flown = re.search(r"; ([0-9.]+) s flown;", result.stdout)
    ok = result.returncode == 0 and "7 activations: 6 GOAL_ACHIEVED, 0 rejected" in result.stdout
    detail = "" if ok else (result.stderr.strip().splitlines() or ["?"])[-1]
    if not ok:
        rows = [
            line for line in result.stdout.splitlines() if "GO_TO_POINT" in line or "end" in line
        ]
        detail += " | " + " | ".join(rows[-4:])
    acks = ack_latencies(record) if record.exists() else []
    return Run(ok, float(flown.group(1)) if flown else 0.0, wall, acks, detail)


def sitl_run(workdir: Path, instance: int, speedup: float) -> Run:
    port = free_udp_port()
    started = time.monotonic()
    sitl = start_sitl(workdir, instance, speedup, f"udpclient:127.0.0.1:{port}")
    try:
        result, record = fly(workdir, f"udpin:127.0.0.1:{port}", f"sitl{instance}")
    finally:
        stop(sitl)
    return judge(result, record, started)


def mavsim_run(workdir: Path, index: int, speed: float) -> Run:
    port = free_udp_port()
    started = time.monotonic()
    sim = subprocess.Popen(
        [
            *(sys.executable, "-m", "aeroexec", "mavsim", "--connect", f"udpout:127.0.0.1:{port}"),
            *("--speed-factor", f"{speed:g}", "--duration", "600"),
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        result, record = fly(workdir, f"udpin:127.0.0.1:{port}", f"mavsim{index}")
    finally:
        sim.terminate()
        sim.wait(10)
    return judge(result, record, started)


def detection(workdir: Path, instance: int, speedup: float, kind: str) -> float:
    """Seconds from stopping (UDP) or killing (TCP) SITL to the vehicle's `link_lost`."""
    port = free_udp_port()
    serial0 = f"udpclient:127.0.0.1:{port}" if kind == "udp" else None
    sitl = start_sitl(workdir, instance, speedup, serial0)
    url = f"udpin:127.0.0.1:{port}" if kind == "udp" else f"tcp:127.0.0.1:{5760 + 10 * instance}"
    vehicle = MavlinkVehicle(MavlinkConfig(url=url, connect_timeout=300.0, heartbeat_timeout=3.0))
    try:
        vehicle.connect()
        for _ in range(20):
            vehicle.step(0.1)
            time.sleep(0.1)
        sitl.send_signal(signal.SIGSTOP if kind == "udp" else signal.SIGKILL)
        failed = time.monotonic()
        while not vehicle.link_lost and time.monotonic() - failed < 30:
            vehicle.step(0.01)
            time.sleep(0.01)
        return time.monotonic() - failed
    finally:
        vehicle.close()
        stop(sitl)


def median(values: list[float]) -> float:
    return statistics.median(values) if values else float("nan")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=10, help="SITL flights (default 10)")
    parser.add_argument("--speedup", type=float, default=1.0, help="SITL and mavsim speed")
    parser.add_argument("--mavsim-runs", type=int, default=3, help="mavsim flights (default 3)")
    parser.add_argument("--json", type=Path, help="also write every run's figures here")
    options = parser.parse_args()
    if not (BINARY.is_file() and PARM.is_file()):
        print(f"ArduCopter SITL not found at {BINARY}: set AEROEXEC_SITL", file=sys.stderr)
        return 2
    failures = 0
    with tempfile.TemporaryDirectory(prefix="aeroexec-live-bench-") as tmp:
        workdir = Path(tmp)
        sitl_runs = []
        for i in range(options.runs):
            run = sitl_run(workdir, FIRST_INSTANCE + i % 5, options.speedup)
            sitl_runs.append(run)
            state = "ok" if run.ok else f"FAILED: {run.detail}"
            print(
                f"  SITL run {i + 1}: {run.flown_s:.1f} s flown, {run.wall_s:.1f} s wall, {state}"
            )
            sys.stdout.flush()
        sim_runs = [mavsim_run(workdir, i, options.speedup) for i in range(options.mavsim_runs)]
        udp = detection(workdir, FIRST_INSTANCE + 5, options.speedup, "udp")
        tcp = detection(workdir, FIRST_INSTANCE + 6, options.speedup, "tcp")
    succeeded = sum(r.ok for r in sitl_runs)
    sim_ok = sum(r.ok for r in sim_runs)
    flown = median([r.flown_s for r in sitl_runs if r.ok])
    sim_flown = median([r.flown_s for r in sim_runs if r.ok])
    wall = median([r.wall_s for r in sitl_runs if r.ok])
    sim_wall = median([r.wall_s for r in sim_runs if r.ok])
    acks = [a for r in sitl_runs for a in r.acks_ms]
    sim_acks = [a for r in sim_runs for a in r.acks_ms]
    print(
        f"Appendix C on SITL x{options.speedup:g}: {succeeded}/{len(sitl_runs)} succeeded "
        f"(mavsim {sim_ok}/{len(sim_runs)}); target: all"
    )
    print(
        f"flown time: SITL {flown:.1f} s median; baseline mavsim {sim_flown:.1f} s; "
        f"ratio {flown / sim_flown:.2f}; no target (the real autopilot is slower to settle)"
    )
    print(
        f"wall time: SITL {wall:.1f} s median (EKF start-up included); baseline mavsim "
        f"{sim_wall:.1f} s; ratio {wall / sim_wall:.2f}; no target"
    )
    print(
        f"command-ACK latency: SITL {median(acks):.1f} ms median, {max(acks, default=0):.1f} ms "
        f"max ({len(acks)} commands); baseline mavsim {median(sim_acks):.1f} ms; "
        f"target < {ACK_TARGET_MS:.0f} ms (the ack timeout)"
    )
    print(
        f"link-loss detection: UDP {udp:.2f} s after SITL stopped (baseline: heartbeat "
        f"timeout 3 s, ratio {udp / 3.0:.2f}); TCP {tcp:.3f} s after SITL died (baseline 0); "
        "target: UDP < 3 s + one heartbeat period, TCP < 0.5 s"
    )
    failures += succeeded < len(sitl_runs)
    failures += max(acks, default=0.0) >= ACK_TARGET_MS
    failures += not (udp < 3.0 + 1.0 / options.speedup + 0.2) + (not tcp < 0.5)
    if options.json is not None:
        runs = {"sitl": [r.__dict__ for r in sitl_runs], "mavsim": [r.__dict__ for r in sim_runs]}
        options.json.write_text(json.dumps({**runs, "udp_s": udp, "tcp_s": tcp}, indent=1))
    return 1 if failures else 0


if __name__ == "__main__":
    raise SystemExit(main())
