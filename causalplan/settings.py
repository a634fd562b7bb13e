"""Every ``CAUSALPLAN_*`` setting: one ``Settings``, the only reader of the environment.

The service, its workers and ``causalplan serve`` all take their settings from here; a field
``name`` is the variable ``CAUSALPLAN_NAME``. Folders default to the user's data folder
(``platformdirs``: ``~/.local/share/causalplan`` on Linux).
"""

from __future__ import annotations

import ipaddress
from pathlib import Path

import platformdirs
from pydantic import Field, SecretStr, ValidationInfo, field_validator, model_validator
from pydantic_settings import BaseSettings, SettingsConfigDict

from causalplan.causal.model import MAX_LABEL_LENGTH

APP_NAME = "causalplan"
MIN_WORKER_MEMORY_MB = 2560
"""A worker's address space must hold its planner children's own limit (2048 MB) and itself."""

MIN_API_KEY_LENGTH = 16
"""Shortest API key ``api_keys`` takes: long enough that guessing, slowed to the research token's pace, is hopeless."""

MIN_REQUEST_THREADS = 40
"""anyio's own default number of worker threads, the least a server answers requests with."""
SPARE_REQUEST_THREADS = 20
"""Request threads beyond the solves that may run or wait, for the routes that do not solve."""
BACKGROUND_THREADS = 4
"""Threads of a server that use the database besides requests and job runners (the runner's poll, upkeep)."""

IpNetwork = ipaddress.IPv4Network | ipaddress.IPv6Network


def data_folder() -> Path:
    """Return the user's data folder for causalplan (created by whoever writes there first)."""
    return Path(platformdirs.user_data_dir(APP_NAME, appauthor=False))


class Settings(BaseSettings):
    """Everything the service can be told; each field is ``CAUSALPLAN_<FIELD>`` in the environment."""

    model_config = SettingsConfigDict(env_prefix="CAUSALPLAN_", extra="ignore", frozen=True)

    data_folder: Path = Field(
        default_factory=data_folder, description="Where the default SQLite file lives; /health checks its free space."
    )
    database_url: str = Field(
        default="",
        validate_default=True,
        description="SQLAlchemy URL: sqlite:///PATH (created on first start) or postgresql://USER:PASSWORD@HOST/DB; "
        "empty: causalplan.sqlite3 in data_folder.",
    )
    database_wait_seconds: float = Field(
        default=30.0,
        ge=0,
        le=3600,
        description="How long a starting server waits for a PostgreSQL server that does not take connections "
        "yet (a replica that starts before its database); 0: fail at once.",
    )
    research_token: SecretStr | None = Field(
        default=None, description="Bearer token for GET /v1/trials and /v1/export; unset, they are disabled."
    )
    research_max_failures: int = Field(
        default=10,
        ge=1,
        le=1000,
        description="Wrong research tokens one client may send within research_failure_window_seconds; "
        "its further attempts get 429 until the oldest failure leaves the window.",
    )
    research_max_failures_total: int = Field(
        default=100,
        ge=1,
        le=100_000,
        description="Wrong research tokens all clients together may send within the window; then every "
        "attempt gets 429 (guessing from many addresses is slowed too).",
    )
    research_failure_window_seconds: float = Field(
        default=60.0, gt=0, le=86_400, description="The window, in seconds, in which failures are counted."
    )
    trusted_proxies: list[IpNetwork] = Field(
        default_factory=list,
        description="Addresses or networks of reverse proxies whose X-Forwarded-For names the client "
        '(e.g. ["127.0.0.1"]); from any other peer the header is ignored.',
    )
    catalog_folders: list[Path] = Field(default_factory=list, description="Folders of extra object files.")
    fd_binary: Path | None = Field(
        default=None, description="A Fast Downward search binary to use instead of the one up-fast-downward ships."
    )
    solve_cache_size: int = Field(
        default=512, ge=0, le=1_000_000, description="Fast Downward answers each planner worker keeps (0: none)."
    )

    planning_workers: int = Field(default=2, ge=1, le=64, description="Planner worker processes.")
    queue_size: int = Field(default=16, ge=0, le=1000, description="Solves that may wait for a free worker.")
    queue_wait_seconds: float = Field(default=120.0, gt=0, description="Longest wait for a free worker.")
    client_requests_in_flight: int = Field(
        default=4,
        ge=1,
        le=1000,
        description="Interactive planner requests (plans, transfers, repairs, explanations, pictures, a participant's "
        "robot runs) one client may have running or waiting at once; one more gets 429 (service.fair_share).",
    )
    address_requests_in_flight: int = Field(
        default=16,
        ge=1,
        le=1000,
        description="Interactive planner requests of the participants of one address (their pages' robot runs, "
        "plans and verdicts) running or waiting at once; they share one client's share of the workers.",
    )
    client_workers: int = Field(
        default=0,
        ge=0,
        le=64,
        description="Planner workers one client may hold at once; 0: all but one (at least one), so one client "
        "alone never takes every worker.",
    )
    search_seconds: float = Field(
        default=10.0,
        gt=0,
        le=3600,
        description="Seconds a repair search may take, whatever the time_limit: it stops there with what it found.",
    )
    default_time_limit: float = Field(default=30.0, gt=0, description="Seconds per solve when none is asked for.")
    max_time_limit: float = Field(default=60.0, gt=0, description="The largest time_limit a request may ask for.")
    solve_grace_seconds: float = Field(
        default=10.0, gt=0, description="A worker still busy this long after its time limit is killed."
    )
    worker_memory_mb: int = Field(
        default=4096,
        ge=MIN_WORKER_MEMORY_MB,
        description="Address-space limit of each worker process (its planner children get less).",
    )
    cache_size: int = Field(default=512, ge=0, description="Answers kept for identical requests (0: no cache).")
    access_log: bool = Field(default=True, description="Log one line per request (method, path, status).")
    min_free_disk_mb: int = Field(
        default=100, ge=0, description="Below this much free space where data is stored, /health says 'degraded'."
    )

    max_body_bytes: int = Field(default=262_144, ge=1024, description="Largest request body.")
    max_label_length: int = Field(default=MAX_LABEL_LENGTH, ge=1, le=MAX_LABEL_LENGTH)
    max_parts: int = Field(default=64, ge=1, description="Most parts a model or mapping may label.")
    max_labels_per_part: int = Field(default=16, ge=1, description="Most function labels one part may carry.")
    max_rules: int = Field(default=200, ge=1, description="Most rules a model may have.")

    models_per_minute: int = Field(
        default=60, ge=0, description="Models one client may store with POST /v1/models a minute (0: no limit)."
    )
    invalid_model_hours: float = Field(
        default=168.0,
        gt=0,
        description="Hours an invalid model stored by POST /v1/models is kept (unless a trial uses it); then purged.",
    )

    # The participant pages (causalplan.service.pages).
    demo_starts_per_minute: int = Field(
        default=10,
        ge=0,
        description="Demo participants ('Try it yourself') one client may start a minute (0: no limit).",
    )
    demo_retention_hours: float = Field(
        default=24.0, gt=0, description="Hours a demo participant's work is kept after their last change; then purged."
    )
    arrivals_per_minute: int = Field(
        default=30,
        ge=0,
        description="New arrivals one client may make on public study links a minute (0: no limit).",
    )
    undecided_arrival_hours: float = Field(
        default=24.0,
        gt=0,
        description="Hours an arrival on a public study link is kept without a consent decision; then purged.",
    )
    place_start_minutes: float = Field(
        default=15.0,
        gt=0,
        description="Minutes a participant admitted on a public link holds a place before saving anything.",
    )
    place_hold_hours: float = Field(
        default=3.0, gt=0, description="Hours a participant who started holds a place after their last change."
    )
    over_admission: float = Field(
        default=0.1,
        ge=0,
        le=1,
        description="Fraction of a quota admitted beyond it while completions are under it (rounded down).",
    )
    robot_seconds: float = Field(
        default=240.0,
        gt=0,
        description="Seconds a worker may take to have the robot carry out a plan and film it, "
        "beyond the planner's limit (a robot simulation job, a video job, 'Watch the robot').",
    )
    robot_video_width: int = Field(default=480, ge=64, le=1920, description="Width of the robot's films, in pixels.")
    robot_video_height: int = Field(default=360, ge=48, le=1080, description="Height of the robot's films, in pixels.")
    draw_plans_ahead: bool = Field(
        default=True, description="Draw the pictures of the catalog objects' likely plans in the background at start."
    )

    # Long work as jobs (causalplan.service.jobs), and where it runs.
    dask_scheduler: str | None = Field(
        default=None,
        description="A Dask scheduler's address (tcp://HOST:8786): batch jobs run their trials there; "
        "unset, they run in this replica's planner workers.",
    )
    job_runners: int = Field(
        default=1, ge=0, le=16, description="Jobs this replica runs at once (0: it only answers for jobs)."
    )
    job_lease_seconds: float = Field(
        default=30.0,
        ge=1,
        le=3600,
        description="A running job's lease, renewed every third of it; a job whose replica stopped renewing "
        "is taken up by another replica once its lease has lapsed.",
    )
    job_poll_seconds: float = Field(default=1.0, gt=0, le=60, description="How often an idle runner looks for jobs.")
    job_result_seconds: float = Field(
        default=86_400.0, gt=0, description="Seconds a finished job's result is kept; then the job is deleted."
    )
    max_queued_jobs: int = Field(default=100, ge=1, description="Unfinished jobs at once; more get 429.")
    max_job_trials: int = Field(default=10_000, ge=1, description="Most trials one batch or consensus job may have.")
    max_upload_bytes: int = Field(
        default=16 * 1024 * 1024, ge=1024, description="Largest request body of POST /v1/jobs (it carries uploads)."
    )

    # Who a job belongs to, and how much one client may hold (``service.owners``).
    api_keys: list[SecretStr] = Field(
        default_factory=list,
        description="JSON list of API keys (at least 16 characters each) a client may send as "
        "'Authorization: Bearer <key>': its jobs are its own, under the key's limits (job_*).",
    )
    jobs_in_flight: int = Field(
        default=10,
        ge=1,
        description="Queued or running jobs one client (an API key, a participant) may have; the research token: no "
        "limit.",
    )
    job_megabytes: float = Field(
        default=512.0,
        gt=0,
        description="Megabytes one client's jobs may keep stored (requests and results, until they expire).",
    )
    jobs_per_minute: int = Field(default=60, ge=0, description="Jobs one client may post a minute (0: no limit).")
    anonymous_jobs_in_flight: int = Field(
        default=3, ge=1, description="Queued or running jobs a client without a key (one address) may have."
    )
    anonymous_job_megabytes: float = Field(
        default=40.0, gt=0, description="Megabytes the jobs of a client without a key may keep stored."
    )
    anonymous_jobs_per_minute: int = Field(
        default=10, ge=0, description="Jobs a client without a key may post a minute (0: no limit)."
    )

    anonymous_record_hours: float = Field(
        default=24.0,
        gt=0,
        description="Hours the models and trials a client without a key stores through plans, transfers, "
        "explanations and POST /v1/models are kept (they belong to no experiment); then purged.",
    )
    participant_jobs_in_flight: int = Field(
        default=2, ge=1, description="Films a participant's pages may have queued or running at once."
    )
    address_jobs_in_flight: int = Field(
        default=10,
        ge=1,
        description="Unfinished jobs of clients without a key from one address (its own jobs and its participants' "
        "films) at once.",
    )
    anonymous_job_share: float = Field(
        default=0.5,
        gt=0,
        le=1,
        description="Share of max_queued_jobs the clients without a key (addresses, participants) may take together, "
        "so API keys and the research token always find room.",
    )

    @field_validator("dask_scheduler")
    @classmethod
    def _empty_scheduler_is_none(cls, value: str | None) -> str | None:
        return value.strip() or None if value is not None else None

    @field_validator("trusted_proxies", mode="before")
    @classmethod
    def _networks(cls, value: object) -> object:
        # "10.0.0.1" is the network of that one address; a host part in "10.0.0.1/8" is an error.
        if isinstance(value, list):
            return [ipaddress.ip_network(str(item), strict=True) for item in value]
        return value

    @field_validator("database_url")
    @classmethod
    def _database_url(cls, value: str, info: ValidationInfo) -> str:
        if not value:
            return f"sqlite:///{info.data['data_folder'] / 'causalplan.sqlite3'}"
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

    @field_validator("api_keys")
    @classmethod
    def _long_keys(cls, value: list[SecretStr]) -> list[SecretStr]:
        # A short key is guessed; an empty one (an unset variable in a list) would match nothing useful.
        if any(len(key.get_secret_value().strip()) < MIN_API_KEY_LENGTH for key in value):
            raise ValueError(f"every API key must have at least {MIN_API_KEY_LENGTH} characters")
        return value

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

    @property
    def request_threads(self) -> int:
        """Return how many requests the server answers at once in threads (each waiting solve holds one)."""
        return max(MIN_REQUEST_THREADS, self.max_in_flight + SPARE_REQUEST_THREADS)

    @property
    def database_connections(self) -> int:
        """Return how many threads may use the database at once: request threads, job runners, background threads."""
        return self.request_threads + self.job_runners + BACKGROUND_THREADS

    def is_trusted_proxy(self, address: str) -> bool:
        """Return whether ``address`` (a peer's IP) is one of the operator's reverse proxies."""
        try:
            ip = ipaddress.ip_address(address)
        except ValueError:  # e.g. a Unix socket, or the test client's "testclient"
            return False
        return any(ip in network for network in self.trusted_proxies)
