"""The headless PyBullet executor: run a plan's steps in physics, check each one, and draw it.

``simulate_plan(task_or_object, steps)`` builds the object's parts from the catalog's
geometry, moves each part along its connector's axis into place (screwing, inserting,
placing, igniting), checks every step (connectors fit, the path is clear, the weld is
aligned, nothing falls), lets the assembly settle, evaluates the object's true mechanism on
what was built, and can render a PNG, one frame per step, or a GIF. Who moves the parts is
a ``Mover`` (``sim.movers``): the parts themselves, or with ``robot=True`` the Franka Panda
(``sim.robot``: OMPL paths, IK lines, regrasps), whose motor commands come back as a
trajectory; pictures and the robot's film are observers (``sim.observers``, ``sim.video``). pybullet and numpy
are imported only when a simulation runs.
"""

from causalplan.sim.executor import simulate_plan
from causalplan.sim.plan_steps import PlanInputError, StepRequest, read_plan_steps
from causalplan.sim.report import RenderMode, SimulationReport
from causalplan.sim.scene import SimulatorUnavailableError

__all__ = [
    "PlanInputError",
    "RenderMode",
    "SimulationReport",
    "SimulatorUnavailableError",
    "StepRequest",
    "read_plan_steps",
    "simulate_plan",
]
