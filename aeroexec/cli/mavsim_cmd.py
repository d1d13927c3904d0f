"""`aeroexec mavsim`: the simulated vehicle behind ArduCopter's MAVLink protocol."""

from __future__ import annotations

import signal
import sys
from pathlib import Path
from types import FrameType

import typer

from aeroexec.cli.app import app, guarded
from aeroexec.cli.options import allow_remote_option, connect_option, world_option
from aeroexec.mavlink.sim_peer import MavSim, MavSimConfig, parse_params, refuse_numbers
from aeroexec.vehicles.mavlink.codec import signing_key as make_key
from aeroexec.vehicles.mavlink.endpoint import DEFAULT_BAUD, DEFAULT_VEHICLE_URL, MavlinkError


@app.command("mavsim")
@guarded
def mavsim_command(
    connect: str = connect_option(
        DEFAULT_VEHICLE_URL,
        "Where to talk: udpout:HOST:PORT (send to a ground station), udpin:HOST:PORT, "
        "tcpin:HOST:PORT (listen, as SITL does), tcp:HOST:PORT, or a serial device.",
    ),
    baud: int = typer.Option(
        DEFAULT_BAUD,
        "--baud",
        metavar="N",
        help="Baud rate of a serial device given without one.",
        show_default=True,
    ),
    speed_factor: float = typer.Option(
        1.0,
        "--speed-factor",
        metavar="FACTOR",
        help="Vehicle seconds per wall-clock second (tests use 3-5).",
        show_default=True,
    ),
    heartbeat_hz: float = typer.Option(
        1.0,
        "--heartbeat-hz",
        metavar="HZ",
        help="HEARTBEAT rate (ArduPilot sends 1 Hz).",
        show_default=True,
    ),
    duration: float | None = typer.Option(
        None,
        "--duration",
        metavar="SECONDS",
        help="Stop after this many seconds (default: until Ctrl-C).",
        show_default=False,
    ),
    drop_heartbeats_at: float | None = typer.Option(
        None,
        "--drop-heartbeats-at",
        metavar="SECONDS",
        help="Stop sending heartbeats this long after the first take-off (for --drop-for).",
        show_default=False,
    ),
    drop_for: float = typer.Option(
        5.0,
        "--drop-for",
        metavar="SECONDS",
        help="How long heartbeats stay dropped (with --drop-heartbeats-at).",
        show_default=True,
    ),
    refuse: list[str] = typer.Option(
        [],
        "--refuse",
        metavar="COMMAND",
        help="Answer this command TEMPORARILY_REJECTED (e.g. MAV_CMD_CONDITION_YAW); repeatable.",
        show_default=False,
    ),
    param: list[str] = typer.Option(
        [],
        "--param",
        metavar="NAME=VALUE",
        help="Set one of mavsim's autopilot parameters (FS_GCS_ENABLE=0, BATT_ARM_VOLT=20, "
        "...); repeatable.",
        show_default=False,
    ),
    corrupt_every: int = typer.Option(
        0,
        "--corrupt-every",
        metavar="N",
        help="Corrupt the CRC of every Nth packet sent (0: never).",
        show_default=True,
    ),
    signing_key: str | None = typer.Option(
        None,
        "--signing-key",
        metavar="KEY",
        help="MAVLink 2 signing: 64 hex digits or a passphrase.",
        show_default=False,
    ),
    world: Path | None = world_option("Simulator world file (limits, start)."),
    system_id: int = typer.Option(
        1, "--system-id", metavar="N", help="MAVLink system id of the vehicle.", show_default=True
    ),
    ekf_delay: float = typer.Option(
        2.0,
        "--ekf-delay",
        metavar="SECONDS",
        help="Vehicle seconds before the EKF has a position (no LOCAL_POSITION_NED, arming "
        "refused); ArduCopter SITL takes ~40.",
        show_default=True,
    ),
    overshoot: float = typer.Option(
        0.15,
        "--overshoot",
        metavar="METERS",
        help="How far a position setpoint is overshot before the vehicle creeps back (0: none).",
        show_default=True,
    ),
    rtl_altitude: float = typer.Option(
        15.0,
        "--rtl-altitude",
        metavar="METERS",
        help="RTL's return altitude (RTL_ALT).",
        show_default=True,
    ),
    stats: Path | None = typer.Option(
        None,
        "--stats",
        metavar="FILE",
        help="At exit, write the message counts (JSON) here ('-': standard output).",
        show_default=False,
    ),
    stats_tail: bool = typer.Option(
        False,
        "--stats-tail",
        help="With --stats, also list the last 1024 packets sent (seq, type, corrupted): "
        "what was still in flight when a peer's recording stopped.",
    ),
    allow_remote: bool = allow_remote_option("Allow a non-loopback endpoint."),
) -> None:
    """Simulate an ArduCopter in GUIDED mode over MAVLink (UDP, TCP or serial), in real time.

    \b
    Examples (fly a mission against it from another terminal):
      aeroexec mavsim --speed-factor 3
      aeroexec fly missions/appendix_c.py
      aeroexec mavsim --duration 60 --stats counts.json

    Exit code 0 when it stopped (Ctrl-C, SIGTERM or --duration), 2 on bad options.
    """
    try:
        key = make_key(signing_key) if signing_key is not None else None
        refused = refuse_numbers(refuse)
        params = parse_params(param)
        config = MavSimConfig(
            url=connect,
            allow_remote=allow_remote,
            signing_key=key,
            system=system_id,
            speed_factor=speed_factor,
            heartbeat_hz=heartbeat_hz,
            duration=duration,
            drop_heartbeats_at=drop_heartbeats_at,
            drop_for=drop_for,
            refuse=refused,
            corrupt_every=corrupt_every,
            world=world,
            ekf_delay=ekf_delay,
            overshoot=overshoot,
            rtl_altitude=rtl_altitude,
            baud=baud,
            params=params,
        )
    except ValueError as exc:
        raise MavlinkError(str(exc)) from None
    if stats is not None and str(stats) != "-" and not stats.resolve().parent.is_dir():
        raise MavlinkError(f"cannot write --stats {stats}: no such directory")
    sim = MavSim(config)
    stop = False

    def _stop(signum: int, frame: FrameType | None) -> None:
        nonlocal stop
        stop = True

    signal.signal(signal.SIGTERM, _stop)
    signal.signal(signal.SIGINT, _stop)
    typer.echo(
        f"mavsim: ArduCopter (GUIDED protocol) system {system_id} on {sim.endpoint.url} "
        f"(local {sim.link.local_text}), speed x{speed_factor:g}"
        + (", signed" if key is not None else "")
    )
    sys.stdout.flush()
    try:
        sim.run(lambda: stop)
    finally:
        sim.close()
        if stats is not None:
            try:
                sim.write_stats(stats, tail=stats_tail)
            except OSError as exc:
                raise MavlinkError(f"cannot write --stats {stats}: {exc.strerror or exc}") from None
    counts = sim.link.stats
    typer.echo(f"mavsim: stopped after {sim.elapsed:.1f} s; {counts.summary()}")
