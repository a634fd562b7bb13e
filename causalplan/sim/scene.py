"""The PyBullet world of one simulation: the table, one body per part, and the welds between them.

This is the one module that talks to PyBullet's physics server (headless, ``p.DIRECT``): one
server per thread, emptied after every scene, so runs cannot disturb each other and repeat
exactly. A body's frame is its part's frame moved to the part's centre of mass; ``pose`` and
``place`` speak in part frames. Parts waiting on the table are static (no mass); a part gets
its mass when it joins the assembly.
"""

from __future__ import annotations

import functools
import importlib
import os
import sys
import threading
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from types import ModuleType
from typing import Any

from causalplan.errors import CausalPlanError
from causalplan.objects.model import Shape, Vector
from causalplan.sim.geometry import Box, Solid, bounding_box
from causalplan.sim.poses import Pose, from_rpy, scale

TIME_STEP = 1.0 / 240.0
GRAVITY = -9.81
GROUND = "ground"
"""The name contacts with the table go by."""
SHAPES_PER_ARRAY = 16


class SimulatorUnavailableError(CausalPlanError):
    """PyBullet could not be imported or started."""

    code = "simulator_unavailable"


@functools.cache
def load_pybullet() -> ModuleType:
    """Return the pybullet module, imported without the build banner it prints on stderr."""
    sys.stderr.flush()
    saved = os.dup(2)
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 2)
    try:
        return importlib.import_module("pybullet")
    except ImportError as exc:
        raise SimulatorUnavailableError(
            f"The simulator needs pybullet and numpy ({exc}); install them with: pip install pybullet==3.2.7 numpy"
        ) from None
    finally:
        os.dup2(saved, 2)
        os.close(saved)
        os.close(devnull)


def _shape_arrays(pb: ModuleType, shapes: tuple[Shape, ...], center: Vector, role: str) -> dict[str, list[Any]]:
    """Return the arguments of PyBullet's ``role`` shape arrays ("collision" or "visual"), relative to ``center``."""
    kinds = {"box": pb.GEOM_BOX, "cylinder": pb.GEOM_CYLINDER, "sphere": pb.GEOM_SPHERE}
    return {
        "shapeTypes": [kinds[shape.kind] for shape in shapes],
        "halfExtents": [list(scale(shape.size, 0.5)) for shape in shapes],
        "radii": [shape.size[0] / 2 for shape in shapes],
        "lengths": [shape.size[2] for shape in shapes],
        f"{role}FramePositions": [[shape.position[i] - center[i] for i in range(3)] for shape in shapes],
        f"{role}FrameOrientations": [list(from_rpy(shape.rotation)) for shape in shapes],
    }


_servers = threading.local()


def _fresh_client(pb: ModuleType) -> int:
    """Return this thread's headless physics server, with an empty world.

    Starting a server costs far more than emptying one, so each thread (of each process:
    a forked child starts its own) keeps one; a scene empties it when it closes.
    """
    client: int | None = getattr(_servers, "client", None)
    if client is None or _servers.pid != os.getpid() or not pb.isConnected(physicsClientId=client):
        client = pb.connect(pb.DIRECT)
        if client < 0:
            raise SimulatorUnavailableError("PyBullet could not start a headless physics server.")
        _servers.client, _servers.pid = client, os.getpid()
    elif getattr(_servers, "in_use", False):
        pb.resetSimulation(physicsClientId=client)  # a scene that was never closed
    _servers.in_use = True
    return client


def _groups(shapes: tuple[Shape, ...]) -> list[tuple[Shape, ...]]:
    """Return ``shapes`` cut into groups that fit one PyBullet shape array."""
    return [shapes[start : start + SHAPES_PER_ARRAY] for start in range(0, len(shapes), SHAPES_PER_ARRAY)]


class Scene:
    """One headless PyBullet world holding an object's parts."""

    def __init__(self, solids: dict[str, Solid], drawn: bool = True) -> None:
        self.pb = load_pybullet()
        self.client = _fresh_client(self.pb)
        self.solids = solids
        self.drawn = drawn
        """Whether bodies get visual shapes (pictures); without them a scene builds faster."""
        self.bodies: dict[str, int] = {}
        self.names: dict[int, str] = {}
        self.glass: list[tuple[int, int, tuple[float, float, float, float]]] = []
        """(body, link, colour) of every group of see-through shapes."""
        pb, client = self.pb, self.client
        pb.setPhysicsEngineParameter(fixedTimeStep=TIME_STEP, deterministicOverlappingPairs=1, physicsClientId=client)
        pb.setGravity(0, 0, GRAVITY, physicsClientId=client)
        plane = pb.createCollisionShape(pb.GEOM_PLANE, physicsClientId=client)
        table = -1
        if drawn:
            table = pb.createVisualShape(
                pb.GEOM_BOX,
                halfExtents=[4, 4, 0.005],
                visualFramePosition=[0, 0, -0.005],
                rgbaColor=[0.86, 0.82, 0.74, 1],
                physicsClientId=client,
            )
        self.ground: int = pb.createMultiBody(0, plane, table, physicsClientId=client)
        self.names[self.ground] = GROUND

    def __enter__(self) -> Scene:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Empty the physics server's world (safe to call twice); the server stays for the next scene."""
        if self.client >= 0 and self.pb.isConnected(physicsClientId=self.client):
            self.pb.resetSimulation(physicsClientId=self.client)
            _servers.in_use = False
        self.client = -1

    # --- building --------------------------------------------------------------------------------

    def add_part(self, part_id: str, pose: Pose, dynamic: bool) -> None:
        """Create the body of a part at ``pose`` (part frame), static unless ``dynamic``."""
        solid = self.solids[part_id]
        body = self._body(solid.shapes, solid.center, pose * Pose(solid.center), solid.mass if dynamic else 0.0, True)
        self.bodies[part_id] = body
        self.names[body] = part_id

    def add_light(self, part_id: str) -> int:
        """Create the light of a part (drawn, never touched) at the part's pose; return its body."""
        solid = self.solids[part_id]
        return self._body(solid.light, solid.center, self.pose(part_id) * Pose(solid.center), 0.0, False)

    def _body(self, shapes: tuple[Shape, ...], center: Vector, pose: Pose, mass: float, solid: bool) -> int:
        """Create a body of ``shapes`` (positions relative to ``center``) at ``pose``.

        PyBullet's shape arrays hold at most 16 shapes (it drops the rest of a collision array
        without a word, and crashes on a visual one), so shapes come in groups of 16: the first
        group on the body's base, each further group on a massless link welded to it.
        """
        opaque: list[Shape] = []
        glass: dict[tuple[float, float, float, float], list[Shape]] = {}
        for shape in shapes:
            if solid and shape.color[3] < 1.0:
                glass.setdefault(shape.color, []).append(shape)
            else:
                opaque.append(shape)
        groups = _groups(tuple(opaque)) + [group for same in glass.values() for group in _groups(tuple(same))]
        collisions = [self._collision(group, center) if solid else -1 for group in groups]
        visuals = [self._visual(group, center) if self.drawn else -1 for group in groups]
        links = len(groups) - 1
        body: int = self.pb.createMultiBody(
            mass,
            collisions[0],
            visuals[0],
            basePosition=pose.position,
            baseOrientation=pose.orientation,
            linkMasses=[0.0] * links,
            linkCollisionShapeIndices=collisions[1:],
            linkVisualShapeIndices=visuals[1:],
            linkPositions=[[0, 0, 0]] * links,
            linkOrientations=[[0, 0, 0, 1]] * links,
            linkInertialFramePositions=[[0, 0, 0]] * links,
            linkInertialFrameOrientations=[[0, 0, 0, 1]] * links,
            linkParentIndices=[0] * links,
            linkJointTypes=[self.pb.JOINT_FIXED] * links,
            linkJointAxis=[[0, 0, 1]] * links,
            physicsClientId=self.client,
        )
        for link, group in enumerate(groups, start=-1):
            if group[0].color[3] < 1.0 and solid:
                self.glass.append((body, link, group[0].color))
        return body

    @contextmanager
    def glass_hidden(self) -> Iterator[None]:
        """Hide every see-through shape for a moment (to draw what is behind glass)."""
        for body, link, color in self.glass:
            self.pb.changeVisualShape(body, link, rgbaColor=[*color[:3], 0.0], physicsClientId=self.client)
        try:
            yield
        finally:
            for body, link, color in self.glass:
                self.pb.changeVisualShape(body, link, rgbaColor=[*color[:3], 1.0], physicsClientId=self.client)

    def _collision(self, shapes: tuple[Shape, ...], center: Vector) -> int:
        collision: int = self.pb.createCollisionShapeArray(
            **_shape_arrays(self.pb, shapes, center, "collision"), physicsClientId=self.client
        )
        return collision

    def _visual(self, shapes: tuple[Shape, ...], center: Vector) -> int:
        visual: int = self.pb.createVisualShapeArray(
            **_shape_arrays(self.pb, shapes, center, "visual"),
            # pybullet 3.2.7 crashes on visual shape arrays with lengths or orientations
            # unless the mesh and plane arrays are given too.
            fileNames=["" for _ in shapes],
            meshScales=[[1, 1, 1] for _ in shapes],
            planeNormals=[[0, 0, 1] for _ in shapes],
            rgbaColors=[[*shape.color[:3], 1.0] for shape in shapes],
            physicsClientId=self.client,
        )
        return visual

    def remove(self, body: int) -> None:
        self.pb.removeBody(body, physicsClientId=self.client)

    # --- poses -----------------------------------------------------------------------------------

    def body_pose(self, body: int) -> Pose:
        """Return a body's frame in the world: its centre of mass, which PyBullet's constraints are in."""
        position, orientation = self.pb.getBasePositionAndOrientation(body, physicsClientId=self.client)
        return Pose(tuple(position), tuple(orientation))

    def pose(self, part_id: str) -> Pose:
        """Return the pose of a part's frame in the world."""
        return self.body_pose(self.bodies[part_id]) * Pose(scale(self.solids[part_id].center, -1.0))

    def place(self, part_id: str, pose: Pose) -> None:
        """Put a part's frame at ``pose``, at rest."""
        body_pose = pose * Pose(self.solids[part_id].center)
        body = self.bodies[part_id]
        self.pb.resetBasePositionAndOrientation(
            body, body_pose.position, body_pose.orientation, physicsClientId=self.client
        )
        self.pb.resetBaseVelocity(body, [0, 0, 0], [0, 0, 0], physicsClientId=self.client)

    def set_dynamic(self, part_id: str, dynamic: bool) -> None:
        """Give a part its mass (it falls, rests and is pushed), or none (it stays where it is put)."""
        mass = self.solids[part_id].mass if dynamic else 0.0
        self.pb.changeDynamics(self.bodies[part_id], -1, mass=mass, physicsClientId=self.client)

    # --- joining ---------------------------------------------------------------------------------

    def weld(self, fixed: str, moving: str) -> None:
        """Join two parts rigidly where they are now, and stop them colliding with each other."""
        fixed_body, moving_body = self.bodies[fixed], self.bodies[moving]
        # Body frames (centres of mass), since that is what PyBullet's constraint frames are in.
        relative = self.body_pose(fixed_body).inverse() * self.body_pose(moving_body)
        self.fix(fixed_body, -1, moving_body, relative)
        self.ignore_contacts(fixed, moving)

    def fix(self, parent: int, parent_link: int, child: int, relative: Pose) -> int:
        """Hold ``child``'s body frame at ``relative`` in ``parent``'s link (-1: its base); return the constraint."""
        return int(
            self.pb.createConstraint(
                parent,
                parent_link,
                child,
                -1,
                self.pb.JOINT_FIXED,
                [0, 0, 0],
                relative.position,
                [0, 0, 0],
                relative.orientation,
                [0, 0, 0, 1],
                physicsClientId=self.client,
            )
        )

    def ignore_contacts(self, a: str, b: str) -> None:
        """Stop two parts colliding (joined parts touch along their connectors)."""
        pb, client = self.pb, self.client
        body_a, body_b = self.bodies[a], self.bodies[b]
        for link_a in range(-1, pb.getNumJoints(body_a, physicsClientId=client)):
            for link_b in range(-1, pb.getNumJoints(body_b, physicsClientId=client)):
                pb.setCollisionFilterPair(body_a, body_b, link_a, link_b, 0, physicsClientId=client)

    def settle(self, seconds: float) -> None:
        """Run the physics for ``seconds``."""
        for _ in range(round(seconds / TIME_STEP)):
            self.pb.stepSimulation(physicsClientId=self.client)

    # --- measuring -------------------------------------------------------------------------------

    def bounds(self, part_ids: Iterable[str]) -> Box:
        """Return the world axis-aligned bounds around the given parts."""
        pb, client = self.pb, self.client
        return bounding_box(
            corner
            for part in part_ids
            for link in range(-1, pb.getNumJoints(self.bodies[part], physicsClientId=client))
            for corner in pb.getAABB(self.bodies[part], link, physicsClientId=client)
        )

    def bodies_near(self, lower: Vector, upper: Vector) -> set[int]:
        """Return the bodies whose bounds overlap the box ``lower``..``upper``."""
        found = self.pb.getOverlappingObjects(lower, upper, physicsClientId=self.client) or ()
        return {body for body, _link in found}

    def deepest_overlap(self, part_id: str, bodies: Iterable[int]) -> tuple[float, str | None]:
        """Return how deep (metres, 0 when none) a part overlaps the given bodies, and which one most."""
        deepest, hit = 0.0, None
        body = self.bodies[part_id]
        for other in bodies:
            for point in self.pb.getClosestPoints(body, other, 0.0, physicsClientId=self.client):
                if -point[8] > deepest:
                    deepest, hit = -point[8], self.names[other]
        return deepest, hit

    def gap(self, a: str, b: str, within: float = 0.5) -> float:
        """Return the distance between two parts' surfaces (negative when they overlap), up to ``within``."""
        points = self.pb.getClosestPoints(self.bodies[a], self.bodies[b], within, physicsClientId=self.client)
        return min((point[8] for point in points), default=within)
