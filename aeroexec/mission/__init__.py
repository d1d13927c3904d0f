"""The mission API (execute/activate/inhibit/consult_belief) and the script runner."""

from aeroexec.mission.activity import Activation, ActivityLog
from aeroexec.mission.api import MissionAPI
from aeroexec.mission.paths import APPENDIX_C
from aeroexec.mission.script import MissionOutcome, MissionScript, load_mission, run_script
from aeroexec.mission.session import SessionConfig, SessionResult, simulate

__all__ = [
    "APPENDIX_C",
    "Activation",
    "ActivityLog",
    "MissionAPI",
    "MissionOutcome",
    "MissionScript",
    "SessionConfig",
    "SessionResult",
    "load_mission",
    "run_script",
    "simulate",
]
