"""A planner worker's start: what it warms before its first call."""

from __future__ import annotations

import subprocess
import sys

from tests.conftest import ROOT

WARMED = """
import sys
from causalplan.objects.catalog import load_catalog
from causalplan.service.pool.worker import warm_simulator

assert "pybullet" not in sys.modules and "PIL.Image" not in sys.modules
warm_simulator(load_catalog())
print(sorted(name for name in ("pybullet", "numpy", "PIL.Image", "causalplan.sim.render") if name in sys.modules))
"""


def test_a_worker_start_draws_once_so_its_first_picture_starts_nothing() -> None:
    """The first drawing made ahead (which a participant's plan may wait behind) pays no library's start."""
    done = subprocess.run([sys.executable, "-c", WARMED], capture_output=True, text=True, cwd=ROOT, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split("\n")[0] == "['PIL.Image', 'causalplan.sim.render', 'numpy', 'pybullet']"
