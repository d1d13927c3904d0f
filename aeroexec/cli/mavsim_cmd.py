"""`aeroexec mavsim`: the simulated vehicle behind ArduCopter's MAVLink protocol."""

from __future__ import annotations

import signal
import sys
from pathlib import Path
from types import FrameType

import typer

from aeroexec.cli.app import app, guarded
from aeroexec.mavlink.codec import signing_key as make_key
from aeroexec.mavlink.endpoint import DEFAULT_BAUD, DEFAULT_VEHICLE_URL, MavlinkError
from aeroexec.mavlink.sim_peer import MavSim, MavSimConfig, refuse_numbers


@app.command("mavsim")
@guarded
def mavsim_command(
    connect: str = typer.Option(
        DEFAULT_VEHICLE_URL,
        "--connect",
        metavar="URL",
        help="Where to talk: udpout:HOST:PORT (send to a ground station), udpin:HOST:PORT, "
        "tcpin:HOST:PORT (listen, as SITL does), tcp:HOST:PORT, or a serial device.",
    ),
    baud: int = typer.Option(
        DEFAULT_BAUD, "--baud", metavar="N", help="Baud rate of a serial device given without one."
    ),
    speed_factor: float = typer.Option(
        1.0, "--speed-factor", help="Vehicle seconds per wall-clock second (tests use 3-5)."
    ),
    heartbeat_hz: float = typer.Option(
        1.0, "--heartbeat-hz", help="HEARTBEAT rate (ArduPilot sends 1 Hz)."
    ),
    duration: float | None = typer.Option(
        None, "--duration", help="Stop after this many seconds (default: until Ctrl-C)."
    ),
    drop_heartbeats_at: float | None = typer.Option(
        None, "--drop-heartbeats-at", help="Stop sending heartbeats T s after the first take-off..."
    ),
    drop_for: float = typer.Option(5.0, "--drop-for", help="...for N seconds."),
    refuse: list[str] = typer.Option(
        [],
        "--refuse",
        help="Answer this command TEMPORARILY_REJECTED (e.g. MAV_CMD_CONDITION_YAW); repeatable.",
    ),
    corrupt_every: int = typer.Option(
        0, "--corrupt-every", help="Corrupt the CRC of every Nth packet sent (0: never)."
    ),
    signing_key: str | None = typer.Option(
        None, "--signing-key", help="MAVLink 2 signing: 64 hex digits or a passphrase."
    ),
    world: Path | None = typer.Option(
        None, "--world", help="Simulator world file (limits, start)."
    ),
    system_id: int = typer.Option(1, "--system-id", help="MAVLink system id of the vehicle."),
    ekf_delay: float = typer.Option(
        2.0,
        "--ekf-delay",
        metavar="SECONDS",
        help="Vehicle seconds before the EKF has a position (no LOCAL_POSITION_NED, arming "
        "refused); ArduCopter SITL takes ~40.",
    ),
    overshoot: float = typer.Option(
        0.15,
        "--overshoot",
        metavar="METERS",
        help="How far a position setpoint is overshot before the vehicle creeps back (0: none).",
    ),
    rtl_altitude: float = typer.Option(
        15.0, "--rtl-altitude", metavar="METERS", help="RTL's return altitude (RTL_ALT)."
    ),
    stats: Path | None = typer.Option(
        None, "--stats", help="At exit, write the message counts (JSON) here ('-': stdout)."
    ),
    allow_remote: bool = typer.Option(
        False, "--allow-remote", help="Allow a non-loopback endpoint."
    ),
) -> None:
    """Simulate an ArduCopter in GUIDED mode over MAVLink (UDP, TCP or serial), in real time.

    Fly a mission against it from another terminal:

    \b
        aeroexec mavsim --speed-factor 3
        aeroexec fly missions/appendix_c.py

    Exit code 0 when it stopped (Ctrl-C, SIGTERM or --duration), 2 on bad options.
    """
    try:
        key = make_key(signing_key) if signing_key is not None else None
        refused = refuse_numbers(refuse)
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
                sim.write_stats(stats)
            except OSError as exc:
                raise MavlinkError(f"cannot write --stats {stats}: {exc.strerror or exc}") from None
    counts = sim.link.stats
    typer.echo(f"mavsim: stopped after {sim.elapsed:.1f} s; {counts.summary()}")
