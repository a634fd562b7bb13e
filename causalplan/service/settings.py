"""The service's settings: one ``Settings``, read from ``CAUSALPLAN_*`` environment variables."""

from __future__ import annotations

import os
from pathlib import Path

from pydantic import Field, SecretStr, field_validator, model_validator
from pydantic_settings import BaseSettings, SettingsConfigDict

from causalplan.causal.model import MAX_LABEL_LENGTH
from causalplan.planners.fd import DEFAULT_MEMORY_LIMIT_MB


def default_database_url() -> str:
    """Return the SQLite file in the user's data folder (``$XDG_DATA_HOME/causalplan``)."""
    data_home = Path(os.environ.get("XDG_DATA_HOME") or Path.home() / ".local" / "share")
    return f"sqlite:///{data_home / 'causalplan' / 'causalplan.sqlite3'}"


class Settings(BaseSettings):
    """Everything the service can be told; each field is ``CAUSALPLAN_<FIELD>`` in the environment."""

    model_config = SettingsConfigDict(env_prefix="CAUSALPLAN_", extra="ignore", frozen=True)

    database_url: str = Field(
        default_factory=default_database_url,
        description="SQLAlchemy URL: sqlite:///PATH (created on first start) or postgresql://USER:PASSWORD@HOST/DB.",
    )
    research_token: SecretStr | None = Field(
        default=None, description="Bearer token for GET /v1/trials and /v1/export; unset, they are disabled."
    )
    research_max_failures: int = Field(
        default=10,
        ge=1,
        le=1000,
        description="Wrong research tokens one client address may send within research_failure_window_seconds; "
        "its further attempts get 429 until the oldest failure leaves the window.",
    )
    research_failure_window_seconds: float = Field(
        default=60.0, gt=0, le=86_400, description="The window, in seconds, in which research_max_failures counts."
    )
    catalog_folders: list[Path] = Field(default_factory=list, description="Folders of extra object files.")

    planning_workers: int = Field(default=2, ge=1, le=64, description="Planner worker processes.")
    queue_size: int = Field(default=16, ge=0, le=1000, description="Solves that may wait for a free worker.")
    queue_wait_seconds: float = Field(default=120.0, gt=0, description="Longest wait for a free worker.")
    default_time_limit: float = Field(default=30.0, gt=0, description="Seconds per solve when none is asked for.")
    max_time_limit: float = Field(default=60.0, gt=0, description="The largest time_limit a request may ask for.")
    solve_grace_seconds: float = Field(
        default=10.0, gt=0, description="A worker still busy this long after its time limit is killed."
    )
    worker_memory_mb: int = Field(
        default=4096,
        ge=DEFAULT_MEMORY_LIMIT_MB + 512,
        description="Address-space limit of each worker process (its planner children get less).",
    )
    cache_size: int = Field(default=512, ge=0, description="Answers kept for identical requests (0: no cache).")
    access_log: bool = Field(
        default=True, description="Log one line per request (method, path, status); ~0.07 ms per request here."
    )

    max_body_bytes: int = Field(default=262_144, ge=1024, description="Largest request body.")
    max_label_length: int = Field(default=MAX_LABEL_LENGTH, ge=1, le=MAX_LABEL_LENGTH)
    max_parts: int = Field(default=64, ge=1, description="Most parts a model or mapping may label.")
    max_labels_per_part: int = Field(default=16, ge=1, description="Most function labels one part may carry.")
    max_rules: int = Field(default=200, ge=1, description="Most rules a model may have.")

    @field_validator("database_url")
    @classmethod
    def _use_psycopg(cls, value: str) -> str:
        # SQLAlchemy's default PostgreSQL driver is psycopg2; the package ships psycopg 3.
        for prefix in ("postgres://", "postgresql://"):
            if value.startswith(prefix):
                return "postgresql+psycopg://" + value.removeprefix(prefix)
        return value

    @field_validator("research_token")
    @classmethod
    def _empty_token_is_none(cls, value: SecretStr | None) -> SecretStr | None:
        # An empty variable (e.g. compose's ${CAUSALPLAN_RESEARCH_TOKEN:-}) must not be a valid token.
        return value if value is not None and value.get_secret_value().strip() else None

    @model_validator(mode="after")
    def _time_limits_agree(self) -> Settings:
        if self.default_time_limit > self.max_time_limit:
            raise ValueError(
                f"default_time_limit ({self.default_time_limit:g}) exceeds max_time_limit ({self.max_time_limit:g})"
            )
        return self

    @property
    def max_in_flight(self) -> int:
        """Return how many solves may be running or waiting at once before requests get 429."""
        return self.planning_workers + self.queue_size
