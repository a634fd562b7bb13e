"""The motor commands for ROS 2: a bag read back by rosbags' reader, and a FollowJointTrajectory goal."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from causalplan.sim.robot.limits import PANDA
from causalplan.sim.robot.ros import (
    ARM_TOPIC,
    GRIPPER_TOPIC,
    JOINT_TRAJECTORY,
    BagError,
    follow_joint_trajectory_goal,
    write_bag,
)
from causalplan.sim.robot.timing import time_parameterize
from causalplan.sim.robot.trajectory import Segment, Trajectory, Waypoints

HOME = (0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785)


def commands() -> Trajectory:
    turned = (*HOME[:6], 1.5)
    plan = Waypoints([Segment(1, "transit", "open", 0.08, [turned]), Segment(1, "grasp", "closed", 0.02, [turned])])
    return time_parameterize(plan, HOME, 0.08, PANDA, 0.5)


def test_a_bag_reads_back_with_the_message_type_the_joints_and_every_point(tmp_path: Path) -> None:
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore

    trajectory = commands()
    write_bag(trajectory, tmp_path / "bag")
    store = get_typestore(Stores.ROS2_HUMBLE)
    with Reader(tmp_path / "bag") as reader:
        assert {c.topic: c.msgtype for c in reader.connections} == {
            ARM_TOPIC: JOINT_TRAJECTORY,
            GRIPPER_TOPIC: JOINT_TRAJECTORY,
        }
        read = {c.topic: store.deserialize_cdr(raw, c.msgtype) for c, _, raw in reader.messages()}
    arm, gripper = read[ARM_TOPIC], read[GRIPPER_TOPIC]
    assert arm.joint_names == list(PANDA.joints) and gripper.joint_names == list(PANDA.gripper_joints)
    assert len(arm.points) == len(gripper.points) == len(trajectory.points)
    last = arm.points[-1]
    assert list(last.positions) == pytest.approx(trajectory.points[-1].positions)
    assert last.time_from_start.sec + last.time_from_start.nanosec / 1e9 == pytest.approx(trajectory.seconds)
    assert gripper.points[-1].positions[0] == pytest.approx(0.01)  # each finger: half the 2 cm width


def test_a_bag_is_written_only_into_a_new_folder(tmp_path: Path) -> None:
    with pytest.raises(BagError) as raised:
        write_bag(commands(), tmp_path)
    assert raised.value.code == "output_not_writable"


def test_the_goal_yaml_holds_every_point_with_its_time() -> None:
    trajectory = commands()
    goal = yaml.safe_load(follow_joint_trajectory_goal(trajectory))
    assert goal["trajectory"]["joint_names"] == list(PANDA.joints)
    points = goal["trajectory"]["points"]
    assert len(points) == len(trajectory.points)
    assert {"positions", "velocities", "accelerations", "time_from_start"} <= set(points[-1])
    end = points[-1]["time_from_start"]
    assert end["sec"] + end["nanosec"] / 1e9 == pytest.approx(trajectory.seconds, abs=1e-6)


def test_a_bag_and_a_goal_read_back_as_the_trajectory_written(tmp_path: Path) -> None:
    from causalplan.sim.robot.ros import bag_trajectory_data, goal_trajectory_data
    from causalplan.sim.robot.trajectory import read_trajectory

    trajectory = commands()
    write_bag(trajectory, tmp_path / "bag")
    from_bag = read_trajectory(bag_trajectory_data(tmp_path / "bag"))
    from_goal = read_trajectory(goal_trajectory_data(yaml.safe_load(follow_joint_trajectory_goal(trajectory))))
    for read in (from_bag, from_goal):
        assert len(read.points) == len(trajectory.points)
        assert read.seconds == pytest.approx(trajectory.seconds, abs=1e-6)
        assert read.points[-1].positions == pytest.approx(trajectory.points[-1].positions, abs=1e-6)
        assert read.points[3].velocities == pytest.approx(trajectory.points[3].velocities, abs=1e-6)
    assert [p.gripper_width for p in from_bag.points] == pytest.approx([p.gripper_width for p in trajectory.points])


def test_a_goal_without_a_trajectory_is_refused_saying_what_a_goal_holds() -> None:
    from causalplan.sim.robot.ros import goal_trajectory_data
    from causalplan.sim.robot.trajectory import TrajectoryInputError

    with pytest.raises(TrajectoryInputError, match="'trajectory': 'joint_names' and 'points'"):
        goal_trajectory_data({"object": "desk_lamp"})
    with pytest.raises(TrajectoryInputError, match="whole numbers 'sec' and 'nanosec'"):
        goal_trajectory_data({"trajectory": {"joint_names": [], "points": [{"time_from_start": 1.5}]}})
