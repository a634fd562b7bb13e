"""The app's caches, each named and bounded, held by its ``Services``: a new app starts with empty ones.

Like the process's (``causalplan.caches``), each key names everything its value depends on:
answers by the canonical form of the request and the catalog's fingerprint, pictures by the
catalog's fingerprint and what they show, a stored model's graph by its id (stored models
never change). So nothing kept goes stale, and sizes alone bound them.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from causalplan.caches import BoundedCache, NamedCaches
from causalplan.service.pages.pictures import PictureCache
from causalplan.service.work.calls import ResultCache
from causalplan.settings import Settings

MODEL_GRAPHS = 128
PAGE_GRAPHS = 256
PART_PICTURES = 512
PLAN_PICTURES = 256
ROBOT_RUNS = 64


@dataclass(frozen=True)
class ServiceCaches(NamedCaches):
    """Every cache of one app, by name."""

    answers: ResultCache
    """Planners' answers to valid requests, by canonical key (``work.calls.Workers.answer``); sized by the settings."""
    model_graphs: BoundedCache[str, bytes] = field(default_factory=lambda: BoundedCache(MODEL_GRAPHS))
    """``/v1/models/{id}/graph`` drawings (SVG), by model id."""
    page_graphs: PictureCache = field(default_factory=lambda: PictureCache(PAGE_GRAPHS))
    """The pages' causal graphs (SVG), by the model document's hash (``pages.drawings.graph_svg``)."""
    part_pictures: PictureCache = field(default_factory=lambda: PictureCache(PART_PICTURES))
    """The simulator's picture of each part (PNG), by catalog fingerprint, object and part."""
    plan_pictures: PictureCache = field(default_factory=lambda: PictureCache(PLAN_PICTURES))
    """The simulator's picture of an object after a plan (PNG), by catalog fingerprint, object and fits."""
    robot_runs: PictureCache = field(default_factory=lambda: PictureCache(ROBOT_RUNS))
    """The 3D player's document of the robot's run (JSON), by catalog fingerprint, object and fits
    (``pages.robot_films``): computed while a participant reads the plan, played at once on the click."""

    @classmethod
    def of(cls, settings: Settings) -> ServiceCaches:
        """Return empty caches sized by ``settings``."""
        return cls(ResultCache(settings.cache_size))
