"""Which module defines each command, and the one sentence `aeroexec --help` shows for it.

`aeroexec` imports a command's module only when that command runs (or its own `--help`
is asked for): importing all of them would load the verifier, the bag reader, the
MAVLink dialect and the replay engine for every command, `--version` included. The
summaries are the first sentence of each command's docstring (tests/test_cli_startup.py
checks they still are), so the command list needs no import either.
"""

from __future__ import annotations

from typing import NamedTuple


class CommandEntry(NamedTuple):
    #: The module under aeroexec.cli that registers the command on `app`.
    module: str
    #: The first sentence of the command's help.
    summary: str


#: In the order `aeroexec --help` lists them.
COMMANDS: dict[str, CommandEntry] = {
    "run": CommandEntry(
        "run_cmd",
        "Run MISSION in simulation: print each behavior as it starts and ends, then a summary.",
    ),
    "fly": CommandEntry(
        "fly_cmd",
        "Fly MISSION on a live autopilot (ArduPilot Copter, GUIDED mode) over MAVLink.",
    ),
    "mavsim": CommandEntry(
        "mavsim_cmd",
        "Simulate an ArduCopter in GUIDED mode over MAVLink (UDP, TCP or serial), in real time.",
    ),
    "info": CommandEntry(
        "recording_cmd",
        "Summarize a recording: duration, channels and message counts, behaviors and "
        "their outcomes, metadata, attachments, and whether the file is complete.",
    ),
    "recover": CommandEntry(
        "recording_cmd",
        "Write a complete MCAP file with every message that can be read from REC.",
    ),
    "verify": CommandEntry(
        "verify_cmd", "Check behavior catalogs and mission scripts offline, before they fly."
    ),
    "view": CommandEntry(
        "view_cmd",
        "Show a session in Rerun: the flight in 3D (world markers, vehicle pose, trajectory), "
        "one lane per behavior with each activation, capability reference counts, and the "
        "events, rejected activations, errors and service call tree as logs, on a `sim_time` "
        "timeline (service calls also on `seq`).",
    ),
    "layout": CommandEntry(
        "layout_cmd",
        "Write a viewer layout for aeroexec recordings, to import once: the flight in 3D "
        "(the world's markers and object, the vehicle on its frame), the plot of position "
        "and battery, the behavior events, the call log and the session's log.",
    ),
    "replay": CommandEntry(
        "replay_cmd",
        "Replay recorded missions against a new catalog or code version and report, per "
        "mission command, what changed: accepted/rejected, preemptions, capabilities and "
        "processes, end events and their times, the final vehicle state.",
    ),
    "diff": CommandEntry(
        "diff_cmd",
        "Compare two recordings mission command by mission command: accepted/rejected and "
        "why, preemptions, capability and process transitions, end events and their times "
        "(within --tolerance), the final vehicle state; and the commands only one of them "
        "has (the mission took another path).",
    ),
    "explore": CommandEntry(
        "explore_cmd",
        "Strike every fault the simulator models at every transition of recorded missions "
        "(each activation, each end, each capability referenced or released, plus "
        "--offsets) and report, per transition and fault, whether the system held, the "
        "mission failed cleanly, or a property was violated (aeroexec:safety and --spec).",
    ),
    "fuzz": CommandEntry(
        "fuzz_cmd",
        "Generate missions for CATALOG, run them in simulation with properties on, and "
        "shrink each violation to a short mission that shows it.",
    ),
    "check": CommandEntry(
        "check_cmd",
        "Check recordings against properties in signal temporal logic (STL): what must "
        "always hold in a flight, such as `always(altitude <= 120)`.",
    ),
    "report": CommandEntry(
        "report_cmd",
        "Work with replay reports: merge the shards of a CI matrix into one.",
    ),
    "import": CommandEntry(
        "import_cmd",
        "Convert a ROS 1 or ROS 2 bag into an aeroexec recording (MCAP), losing nothing.",
    ),
    "behaviors": CommandEntry(
        "behaviors_cmd",
        "List every behavior implementation run, fly, replay and verify would use: the "
        "behavior, its class (module:Class), its file and the source that provided it; "
        "then the catalog's behaviors that have no implementation.",
    ),
    "catalog": CommandEntry(
        "catalog_cmd",
        "Inspect behavior catalogs (the YAML file of behavior_descriptors, behavior_lists "
        "and capability_descriptors that the behavior specialist reads).",
    ),
}
