"""The Franka Panda that builds the object: the arm, its motions, its motor commands.

``panda`` (the kinematic arm: IK, contacts), ``robot`` (a step's motions written as a
trajectory), ``steps`` (a plan step's share: bring, drive, let go), ``mover`` (the robot as the
simulator's ``Mover``), ``motion_planning`` (OMPL), ``grasps``, ``trajectory`` (the motor
commands and their file), ``replay`` (a trajectory played in a fresh scene) and ``arm`` (reach
only). Nothing here imports ``sim.executor``.
"""
