"""Values out of decoded messages, by field names, across Aerostack's message versions."""

from __future__ import annotations

import math
from types import SimpleNamespace as M

import pytest

from aeroexec.bags import extract
from aeroexec.executive.messages import EventCode


@pytest.mark.parametrize(
    ("message", "code", "raw"),
    [
        (
            M(name="LAND", behavior_event_code="GOAL_ACHIEVED"),
            EventCode.GOAL_ACHIEVED,
            "GOAL_ACHIEVED",
        ),
        # June 2017: the constants were `= "TIME_OUT"` and ROS kept the quotes
        (M(name="LAND", behavior_event_code='"TIME_OUT"'), EventCode.TIME_OUT, "TIME_OUT"),
        (M(name="LAND", behavior_event_code="BLOCKED"), None, "BLOCKED"),
        # March 2017 integer codes: ACHIEVED=1 .. BLOCKED=4
        (M(name="LAND", mode="", event=1), EventCode.GOAL_ACHIEVED, "1"),
        (M(name="LAND", mode="", event=3), EventCode.WRONG_PROGRESS, "3"),
        (M(name="LAND", mode="", event=4), None, "4"),
        # 2019+ BehaviorActivationFinished: SITUATION_CHANGE=4 has no 2017 equivalent
        (
            M(name="LAND", termination_cause=5, error_message="motor"),
            EventCode.PROCESS_FAILURE,
            "5",
        ),
        (M(name="LAND", termination_cause=6, error_message=""), EventCode.INTERRUPTED, "6"),
        (M(name="LAND", termination_cause=4, error_message=""), None, "4"),
    ],
)
def test_event_codes_of_every_version(message: object, code: EventCode | None, raw: str) -> None:
    event = extract.event(message)
    assert event is not None
    assert (event.name, event.code, event.raw_code) == ("LAND", code, raw)


def test_event_detail_and_uid() -> None:
    event = extract.event(
        M(
            name="GO_TO_POINT",
            uid=7.0,
            behavior_event_code="ASSUMPTION_CONFLICT",
            failed_belief="flying(self)",
            belief_conflict="landed",
        )
    )
    assert event is not None
    assert event.detail == "flying(self); landed"
    assert event.bag_uid == 7.0
    assert extract.event(M(name="X")) is None
    assert extract.event(M(behavior_event_code="TIME_OUT")) is None


def test_active_lists_2017_and_2018() -> None:
    old = extract.active_list(M(active_behaviors=["TAKE_OFF", "WAIT", "TAKE_OFF"]))
    assert old == extract.ActiveList(("TAKE_OFF", "WAIT"), {})
    new = extract.active_list(
        M(
            behaviors=["GO_TO_POINT"],
            behavior_commands=[M(name="GO_TO_POINT", arguments="coordinates: [1, 2, 3]")],
        )
    )
    assert new == extract.ActiveList(("GO_TO_POINT",), {"GO_TO_POINT": "coordinates: [1, 2, 3]"})
    assert extract.active_list(M(capabilities=[])) is None


def test_capabilities_beliefs_processes() -> None:
    assert extract.capabilities(M(capabilities=["A", "B"])) == ("A", "B")
    assert extract.capabilities(M(active_capabilities=[M(name="A", basic=True, processes=[])])) == (
        "A",
    )
    assert extract.beliefs(M(beliefs="flying(self)\n\nbattery_level(self, HIGH)\n")) == (
        "flying(self)",
        "battery_level(self, HIGH)",
    )
    assert extract.beliefs(M(beliefs=["a", "b"])) == ("a", "b")
    alive = M(process_name="/drone1/droneCommand", current_state=M(state=7))
    assert extract.process(alive, "drone1") == ("droneCommand", True)
    assert extract.process(M(process_name="/other/x", current_state=M(state=2)), "drone1") == (
        "other/x",
        False,
    )
    assert extract.process(M(process_name="x", current_state=M(state=3)), "drone1") == ("x", True)


def _quaternion(yaw: float) -> M:
    return M(x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2))


@pytest.mark.parametrize(
    "message",
    [
        M(x=1.0, y=2.0, z=3.0, yaw=0.5, pitch=0.0, roll=0.0),  # droneMsgsROS/dronePose
        M(header=None, pose=M(position=M(x=1.0, y=2.0, z=3.0), orientation=_quaternion(0.5))),
        M(pose=M(pose=M(position=M(x=1, y=2, z=3), orientation=_quaternion(0.5)), covariance=[])),
    ],
    ids=["dronePose", "PoseStamped", "Odometry-like"],
)
def test_pose_shapes(message: object) -> None:
    pose = extract.pose(message)
    assert pose is not None
    assert pose.position == (1.0, 2.0, 3.0)
    assert pose.yaw == pytest.approx(0.5)


def test_turtlesim_pose_and_bad_poses() -> None:
    turtle = extract.pose(M(x=5.5, y=1.0, theta=-1.0, linear_velocity=0.0))
    assert turtle == extract.Pose((5.5, 1.0, 0.0), -1.0)
    assert extract.pose(M(x="1", y=2.0, yaw=0.0)) is None
    assert extract.pose(M(position=M(x=1.0, y=2.0, z=3.0))) is None  # no orientation
    assert extract.pose(M(data="hello")) is None


def test_velocity_battery_flying() -> None:
    assert extract.velocity(M(time=0.0, dx=1.0, dy=2.0, dz=3.0, dyaw=0.0)) == (1.0, 2.0, 3.0)
    twist = M(header=None, twist=M(linear=M(x=1, y=0, z=0), angular=M(x=0, y=0, z=0)))
    assert extract.velocity(twist) == (1.0, 0.0, 0.0)
    assert extract.battery(M(batteryPercent=42.0)) == pytest.approx(0.42)
    assert extract.battery(M(percentage=0.3)) == pytest.approx(0.3)
    assert extract.battery(M(batteryPercent=140.0)) == 1.0
    assert extract.battery(M(percentage=math.nan)) is None
    flying = {s: extract.flying(M(status=s)) for s in range(10)}
    assert [s for s, f in flying.items() if f] == [3, 4, 6, 8, 9]
    assert extract.flying(M(flying=True)) is True
    assert extract.flying(M(status="FLYING")) is None
