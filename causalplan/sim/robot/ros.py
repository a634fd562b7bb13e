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
from causalplan.sim.robot.trajectory import Trajectory

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
