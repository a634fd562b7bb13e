"""The motor commands as ROS 2 reads them: a bag of ``JointTrajectory`` messages, and a ``FollowJointTrajectory`` goal.

``write_bag(trajectory, folder)`` writes a ROS 2 bag (``rosbags``, pure Python; SQLite 3
storage, bag format 8) with two messages of type ``trajectory_msgs/msg/JointTrajectory``: the
arm's on ``ARM_TOPIC`` (joints ``panda_joint1..7``, every point's positions, velocities,
accelerations and ``time_from_start``) and the gripper's on ``GRIPPER_TOPIC`` (joints
``panda_finger_joint1`` and ``2``, each finger's opening in metres, half the width).
``follow_joint_trajectory_goal(trajectory)`` returns the arm's goal of the action
``control_msgs/action/FollowJointTrajectory`` as YAML, ready for ``ros2 action send_goal``.
Positions are joint angles (radians) in the robot's own joint frames, as its URDF names them.
"""

from __future__ import annotations

from pathlib import Path

from causalplan.errors import CausalPlanError
from causalplan.sim.robot.trajectory import Trajectory, TrajectoryInputError

ARM_TOPIC = "/panda_arm_controller/joint_trajectory"
GRIPPER_TOPIC = "/panda_hand_controller/joint_trajectory"
JOINT_TRAJECTORY = "trajectory_msgs/msg/JointTrajectory"
GOAL_TIME_TOLERANCE = 0.5
"""Seconds a controller may run over the trajectory's duration before it gives up on the goal."""


class BagError(CausalPlanError):
    """A ROS 2 bag cannot be written where asked."""

    code = "output_not_writable"


def _duration(seconds: float) -> tuple[int, int]:
    nanoseconds = round(seconds * 1e9)
    return nanoseconds // 1_000_000_000, nanoseconds % 1_000_000_000


def write_bag(trajectory: Trajectory, folder: Path) -> None:
    """Write the arm's and the gripper's ``JointTrajectory`` into a new ROS 2 bag at ``folder``."""
    import numpy as np
    from rosbags.rosbag2 import Writer
    from rosbags.typesys import Stores, get_typestore

    if folder.exists():
        raise BagError(f"{folder} exists: a ROS 2 bag is written into a new folder.")
    store = get_typestore(Stores.ROS2_HUMBLE)
    types = store.types
    header = types["std_msgs/msg/Header"](stamp=types["builtin_interfaces/msg/Time"](sec=0, nanosec=0), frame_id="")
    point_type, duration_type = (
        types["trajectory_msgs/msg/JointTrajectoryPoint"],
        types["builtin_interfaces/msg/Duration"],
    )

    def message(names: tuple[str, ...], rows: list[tuple[list[float], list[float], list[float], float]]) -> object:
        points = [
            point_type(
                positions=np.array(positions, dtype=np.float64),
                velocities=np.array(velocities, dtype=np.float64),
                accelerations=np.array(accelerations, dtype=np.float64),
                effort=np.array([], dtype=np.float64),
                time_from_start=duration_type(*_duration(time)),
            )
            for positions, velocities, accelerations, time in rows
        ]
        return types[JOINT_TRAJECTORY](header=header, joint_names=list(names), points=points)

    arm = message(
        trajectory.limits.joints,
        [(list(p.positions), list(p.velocities), list(p.accelerations), p.time) for p in trajectory.points],
    )
    fingers = len(trajectory.limits.gripper_joints)
    gripper = message(
        trajectory.limits.gripper_joints,
        [([p.gripper_width / 2] * fingers, [], [], p.time) for p in trajectory.points],
    )
    try:
        with Writer(folder, version=8) as writer:
            for topic, sent in ((ARM_TOPIC, arm), (GRIPPER_TOPIC, gripper)):
                connection = writer.add_connection(topic, JOINT_TRAJECTORY, typestore=store)
                writer.write(connection, 0, store.serialize_cdr(sent, JOINT_TRAJECTORY))
    except OSError as exc:
        raise BagError(f"Cannot write the ROS 2 bag {folder}: {exc.strerror}.") from None


def follow_joint_trajectory_goal(trajectory: Trajectory) -> str:
    """Return the arm's ``control_msgs/action/FollowJointTrajectory`` goal as YAML."""
    import yaml

    def duration(seconds: float) -> dict[str, int]:
        sec, nanosec = _duration(seconds)
        return {"sec": sec, "nanosec": nanosec}

    goal = {
        "trajectory": {
            "header": {"stamp": {"sec": 0, "nanosec": 0}, "frame_id": ""},
            "joint_names": list(trajectory.limits.joints),
            "points": [
                {
                    "positions": [round(value, 6) for value in point.positions],
                    "velocities": [round(value, 6) for value in point.velocities],
                    "accelerations": [round(value, 5) for value in point.accelerations],
                    "effort": [],
                    "time_from_start": duration(point.time),
                }
                for point in trajectory.points
            ],
        },
        "path_tolerance": [],
        "goal_tolerance": [],
        "goal_time_tolerance": duration(GOAL_TIME_TOLERANCE),
    }
    text: str = yaml.safe_dump(goal, sort_keys=False, default_flow_style=None, width=200)
    return text


def _field(value: object, name: str) -> object:
    """Return a field of a ROS message, read by rosbags (attributes) or from YAML (a mapping)."""
    return value.get(name) if isinstance(value, dict) else getattr(value, name, None)


def _seconds(duration: object, where: str) -> float:
    """Return a ROS ``builtin_interfaces/Duration`` (``sec``, ``nanosec``) in seconds."""
    sec, nanosec = _field(duration, "sec"), _field(duration, "nanosec")
    for value in (sec, nanosec):
        if isinstance(value, bool) or not isinstance(value, int):
            raise TrajectoryInputError(f"{where}: 'time_from_start' needs whole numbers 'sec' and 'nanosec'.")
    assert isinstance(sec, int) and isinstance(nanosec, int)
    return sec + nanosec / 1e9


def _listed(values: object) -> object:
    """Return a message's numbers as a list (rosbags reads them as numpy arrays); anything else as it is."""
    tolist = getattr(values, "tolist", None)
    return tolist() if callable(tolist) else values


def _arm_points(points: object, where: str) -> list[dict[str, object]]:
    """Return ``JointTrajectoryPoint`` s in the trajectory JSON's form, for ``read_trajectory`` to check."""
    if not isinstance(points, list):
        raise TrajectoryInputError(f"{where}: 'points' must be a list.")
    read: list[dict[str, object]] = []
    for number, point in enumerate(points):
        item: dict[str, object] = {
            "time_from_start": _seconds(_field(point, "time_from_start"), f"{where}, point {number}"),
            "positions": _listed(_field(point, "positions")),
        }
        for name in ("velocities", "accelerations"):
            values = _listed(_field(point, name))
            if values:  # ROS leaves them empty when the controller is to work them out
                item[name] = values
        read.append(item)
    return read


def goal_trajectory_data(data: object) -> dict[str, object]:
    """Return a ``FollowJointTrajectory`` goal (as ``follow_joint_trajectory_goal`` writes it) as trajectory data.

    The result is what ``read_trajectory`` reads from a trajectory JSON: 'joints' and 'points'.
    A goal has no gripper, so the gripper's width is left out (0).
    """
    if isinstance(data, dict) and "rosbag2_bagfile_information" in data:
        raise TrajectoryInputError("This is a ROS 2 bag's metadata.yaml: give the bag's folder instead.")
    trajectory = data.get("trajectory") if isinstance(data, dict) else None
    if not isinstance(trajectory, dict):
        raise TrajectoryInputError(
            "A FollowJointTrajectory goal is YAML with 'trajectory': 'joint_names' and 'points' "
            "(what `causalplan simulate --robot --joint-trajectory` writes)."
        )
    return {
        "joints": trajectory.get("joint_names"),
        "points": _arm_points(trajectory.get("points"), "trajectory"),
    }


def bag_trajectory_data(folder: Path) -> dict[str, object]:
    """Return the arm's (and the gripper's) ``JointTrajectory`` of a ROS 2 bag as trajectory data.

    Reads the bag ``write_bag`` writes: the first message on ``ARM_TOPIC`` gives the joints
    and points; the gripper's on ``GRIPPER_TOPIC``, when there, gives each point's width (two
    fingers, each half of it).
    """
    from rosbags.rosbag2 import Reader, ReaderError
    from rosbags.serde import SerdeError
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    messages: dict[str, object] = {}
    try:
        with Reader(folder) as reader:
            wanted = [c for c in reader.connections if c.topic in (ARM_TOPIC, GRIPPER_TOPIC)]
            for connection, _, raw in reader.messages(connections=wanted):
                if connection.msgtype != JOINT_TRAJECTORY:
                    raise TrajectoryInputError(
                        f"{folder}: {connection.topic} carries {connection.msgtype}, not {JOINT_TRAJECTORY}."
                    )
                messages.setdefault(connection.topic, store.deserialize_cdr(raw, connection.msgtype))
    except (ReaderError, SerdeError, OSError) as exc:
        raise TrajectoryInputError(f"{folder} is not a ROS 2 bag that can be read: {exc}") from None
    arm = messages.get(ARM_TOPIC)
    if arm is None:
        raise TrajectoryInputError(f"{folder}: the bag has no {JOINT_TRAJECTORY} message on {ARM_TOPIC}.")
    points = _arm_points(list(getattr(arm, "points", [])), ARM_TOPIC)
    gripper = messages.get(GRIPPER_TOPIC)
    if gripper is not None:
        fingers = list(getattr(gripper, "points", []))
        if len(fingers) != len(points):
            raise TrajectoryInputError(
                f"{folder}: {GRIPPER_TOPIC} has {len(fingers)} points, the arm {len(points)}: they must match."
            )
        for point, finger in zip(points, fingers, strict=True):
            opening = _listed(_field(finger, "positions"))
            point["gripper_width"] = sum(opening) if isinstance(opening, list) else opening  # each finger: half
    return {"joints": list(getattr(arm, "joint_names", [])), "points": points}
