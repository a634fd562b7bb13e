"""Pictures of a simulation: PyBullet's software renderer, a glow where light is made, glass, captions.

PyBullet's ``ER_TINY_RENDERER`` draws without a display. It has no transparency and no
emissive colours, so two things are done on the picture afterwards, using the segmentation
mask it returns: glass parts (alpha below 1) are blended with a second picture taken without
them, and a soft glow is added around every light shape. numpy and Pillow are imported here,
when a picture is drawn.
"""

from __future__ import annotations

import io
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from causalplan.objects.model import Vector
from causalplan.sim.geometry import Solid
from causalplan.sim.outcomes import Picture
from causalplan.sim.poses import Pose
from causalplan.sim.scene import Scene

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

DEFAULT_SIZE = (640, 480)
FIELD_OF_VIEW = 40.0
"""Vertical field of view of the camera, in degrees."""
CAMERA_YAW, CAMERA_PITCH = 30.0, -24.0
"""Where the camera looks from: in front of the object, a little to the right, from above."""
LIGHT_DIRECTION = (-1.0, -2.0, 3.0)
GLOW_COLOR = (255.0, 230.0, 140.0)
GLOW_STRENGTH = 0.9
GLOW_SPREAD = 2.4
"""How far the glow reaches, in radii of the light shape as seen in the picture."""
CAPTION_HEIGHT = 26


@dataclass(frozen=True)
class Camera:
    """Where the pictures are taken from: a view and a projection matrix, and the picture size."""

    view: tuple[float, ...]
    projection: tuple[float, ...]
    width: int
    height: int

    @classmethod
    def around(cls, scene: Scene, lower: Vector, upper: Vector, size: tuple[int, int] = DEFAULT_SIZE) -> Camera:
        """Return a camera that shows the box ``lower``..``upper`` whole, from the front and above."""
        pb = scene.pb
        target = [(lower[i] + upper[i]) / 2 for i in range(3)]
        radius = max(0.05, math.dist(lower, upper) / 2)
        distance = 1.1 * radius / math.sin(math.radians(FIELD_OF_VIEW / 2))
        view = pb.computeViewMatrixFromYawPitchRoll(
            target, distance, CAMERA_YAW, CAMERA_PITCH, 0, 2, physicsClientId=scene.client
        )
        projection = pb.computeProjectionMatrixFOV(
            FIELD_OF_VIEW, size[0] / size[1], distance / 20, distance * 6, physicsClientId=scene.client
        )
        return cls(tuple(view), tuple(projection), size[0], size[1])


def _shot(scene: Scene, camera: Camera) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Return one rendered picture (height x width x 3, floats 0..255) and its segmentation mask.

    The mask holds, per pixel, body id + ((link index + 1) << 24), or -1 where nothing is.
    """
    import numpy as np

    pb = scene.pb
    _, _, rgba, _, mask = pb.getCameraImage(
        camera.width,
        camera.height,
        list(camera.view),
        list(camera.projection),
        renderer=pb.ER_TINY_RENDERER,
        flags=pb.ER_SEGMENTATION_MASK_OBJECT_AND_LINKINDEX,
        shadow=1,
        lightDirection=LIGHT_DIRECTION,
        lightAmbientCoeff=0.55,
        lightDiffuseCoeff=0.55,
        lightSpecularCoeff=0.15,
        physicsClientId=scene.client,
    )
    pixels = np.asarray(rgba, dtype=np.float64).reshape(camera.height, camera.width, 4)[:, :, :3]
    return pixels, np.asarray(mask, dtype=np.int64).reshape(camera.height, camera.width)


def _add_glow(pixels: NDArray[np.float64], mask: NDArray[np.int64], body: int) -> None:
    """Brighten a light body where it shows and add a soft halo around it, in place."""
    import numpy as np

    rows, columns = np.nonzero((mask >= 0) & ((mask & ((1 << 24) - 1)) == body))
    if rows.size == 0:
        return
    center_row, center_column = rows.mean(), columns.mean()
    spread = GLOW_SPREAD * max(3.0, math.sqrt(rows.size / math.pi))
    grid_rows, grid_columns = np.ogrid[: pixels.shape[0], : pixels.shape[1]]
    squared = (grid_rows - center_row) ** 2 + (grid_columns - center_column) ** 2
    glow = GLOW_STRENGTH * np.exp(-squared / (2 * spread * spread))
    pixels += (np.asarray(GLOW_COLOR) - pixels) * glow[:, :, None]
    pixels[rows, columns] = 0.7 * pixels[rows, columns] + 0.3 * np.asarray([255.0, 250.0, 225.0])


def _with_caption(pixels: NDArray[np.float64], caption: str) -> bytes:
    """Return the picture's RGB bytes with ``caption`` written on a dark band at the top."""
    import numpy as np
    from PIL import Image, ImageDraw, ImageFont

    image = Image.fromarray(np.clip(pixels, 0, 255).astype(np.uint8), "RGB")
    if caption:
        draw = ImageDraw.Draw(image, "RGBA")
        draw.rectangle((0, 0, image.width, CAPTION_HEIGHT), fill=(20, 20, 28, 190))
        draw.text((8, 5), caption, fill=(255, 255, 255, 255), font=ImageFont.load_default(size=15))
    return image.tobytes()


def draw(scene: Scene, camera: Camera, lit_parts: Iterable[str], caption: str) -> Picture:
    """Return a picture of the scene now, with the light of ``lit_parts`` on and a caption."""
    import numpy as np

    lights = [scene.add_light(part) for part in lit_parts if scene.solids[part].light]
    try:
        pixels, mask = _shot(scene, camera)
        if scene.glass:
            with scene.glass_hidden():
                behind, behind_mask = _shot(scene, camera)
            for body, link, color in scene.glass:
                covered = (mask == body + ((link + 1) << 24))[:, :, None]
                pixels = np.where(covered, color[3] * pixels + (1 - color[3]) * behind, pixels)
            mask = behind_mask  # a light behind glass still glows
        for body in lights:
            _add_glow(pixels, mask, body)
    finally:
        for body in lights:
            scene.remove(body)
    return Picture(camera.width, camera.height, _with_caption(pixels, caption))


def part_alone(part_id: str, solid: Solid, size: tuple[int, int]) -> Picture:
    """Return a picture of one part alone, centred on the table and standing on it."""
    with Scene({part_id: solid}) as scene:
        pose = Pose((-(solid.lower[0] + solid.upper[0]) / 2, -(solid.lower[1] + solid.upper[1]) / 2, -solid.lower[2]))
        scene.add_part(part_id, pose, dynamic=False)
        camera = Camera.around(scene, pose.apply(solid.lower), pose.apply(solid.upper), size=size)
        return draw(scene, camera, (), "")


def animation(pictures: Sequence[Picture], seconds_per_frame: float = 1.0) -> bytes:
    """Return the pictures as an animated GIF that loops."""
    frames = [picture.image() for picture in pictures]
    buffer = io.BytesIO()
    frames[0].save(
        buffer,
        format="GIF",
        save_all=True,
        append_images=frames[1:],
        duration=round(seconds_per_frame * 1000),
        loop=0,
    )
    return buffer.getvalue()


def strip(pictures: Sequence[Picture], height: int = 240) -> Picture:
    """Return the pictures side by side, scaled to ``height``."""
    from PIL import Image

    scaled = [
        picture.image().resize((round(picture.width * height / picture.height), height), Image.Resampling.LANCZOS)
        for picture in pictures
    ]
    canvas = Image.new("RGB", (sum(image.width for image in scaled), height), (255, 255, 255))
    left = 0
    for image in scaled:
        canvas.paste(image, (left, 0))
        left += image.width
    return Picture(canvas.width, canvas.height, canvas.tobytes())
