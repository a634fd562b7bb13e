"""Writing the robot's film: MP4 or GIF from frames, and clear errors for anything else."""

from __future__ import annotations

import imageio.v3 as iio
import pytest

from causalplan.sim.outcomes import Picture
from causalplan.sim.video import FRAMES_PER_SECOND, VideoError, encode

RED = Picture(32, 24, bytes([200, 30, 30]) * 32 * 24)
BLUE = Picture(32, 24, bytes([30, 30, 200]) * 32 * 24)


def test_an_mp4_holds_every_frame_at_the_frame_rate() -> None:
    data = encode([RED, BLUE, RED], ".MP4")
    frames = iio.imread(data, index=None, extension=".mp4")
    assert frames.shape == (3, 24, 32, 3)
    assert frames[1][12, 16, 2] > 150 and frames[0][12, 16, 0] > 150  # blue, then red
    assert iio.immeta(data, extension=".mp4")["fps"] == FRAMES_PER_SECOND


def test_a_gif_loops_through_the_frames() -> None:
    data = encode([RED, BLUE], ".gif")
    assert data[:6] == b"GIF89a"
    assert iio.imread(data, index=None, extension=".gif").shape[0] == 2


@pytest.mark.parametrize(
    ("frames", "suffix", "says"),
    [([RED], ".avi", "not '.avi'"), ([], ".mp4", "no frames to write")],
)
def test_what_cannot_be_written_says_why(frames: list[Picture], suffix: str, says: str) -> None:
    with pytest.raises(VideoError) as raised:
        encode(frames, suffix)
    assert says in raised.value.message
