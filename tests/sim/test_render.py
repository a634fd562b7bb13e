"""Pictures: the final assembly is a real picture, the light shows only when the goal is produced."""

from __future__ import annotations

import io

import numpy as np
import pytest
from PIL import Image

from causalplan.objects.catalog import Catalog
from causalplan.sim import RenderMode, SimulationReport, simulate_plan
from causalplan.sim.outcomes import Picture
from causalplan.sim.render import animation, strip
from tests.sim.fixtures import CORRECT_PLANS, steps

SIZE = (320, 240)


def picture(report: SimulationReport) -> Image.Image:
    assert report.picture is not None
    image = Image.open(io.BytesIO(report.picture.png()))
    assert image.format == "PNG"
    return image.convert("RGB")


def warm_glow(image: Image.Image) -> int:
    """Return how many pixels are bright and warm (the light and its glow)."""
    pixels = np.asarray(image, dtype=np.int64)
    red, green, blue = pixels[:, :, 0], pixels[:, :, 1], pixels[:, :, 2]
    return int(((red > 235) & (green > 205) & (blue < 190)).sum())


@pytest.fixture(scope="module")
def lit_flashlight(catalog: Catalog) -> SimulationReport:
    return simulate_plan(catalog.get("flashlight"), CORRECT_PLANS["flashlight"], render=RenderMode.FINAL, size=SIZE)


def test_the_final_picture_is_a_real_picture(lit_flashlight: SimulationReport) -> None:
    image = picture(lit_flashlight)
    assert image.size == SIZE
    colours = np.unique(np.asarray(image).reshape(-1, 3), axis=0)
    assert len(colours) > 200  # shading, several parts, the table, the sky: not one colour


def test_the_light_shows_only_when_the_object_produces_it(lit_flashlight: SimulationReport, catalog: Catalog) -> None:
    dark = simulate_plan(catalog.get("flashlight"), steps("screw head case"), render=RenderMode.FINAL, size=SIZE)
    assert not dark.produces_goal
    assert warm_glow(picture(lit_flashlight)) > 20 * max(1, warm_glow(picture(dark)))


def test_frames_show_the_start_each_step_and_the_end(catalog: Catalog) -> None:
    report = simulate_plan(catalog.get("candle"), CORRECT_PLANS["candle"], render=RenderMode.FRAMES, size=SIZE)
    assert len(report.frames) == 1 + len(CORRECT_PLANS["candle"]) + 1
    assert report.frames[-1] is report.picture
    gif = Image.open(io.BytesIO(animation(report.frames)))
    assert gif.format == "GIF" and gif.n_frames == len(report.frames)
    row = strip(report.frames, height=120)
    assert (row.width, row.height) == (4 * 160, 120)


def test_no_pictures_unless_asked(catalog: Catalog) -> None:
    report = simulate_plan(catalog.get("candle"), CORRECT_PLANS["candle"], render=RenderMode.NONE)
    assert report.picture is None and report.frames == ()


def test_a_picture_round_trips_through_png() -> None:
    rgb = bytes([10, 20, 30, 200, 100, 50]) * 2
    image = Image.open(io.BytesIO(Picture(2, 2, rgb).png()))
    assert image.size == (2, 2) and image.getpixel((1, 0)) == (200, 100, 50)
