"""Search processes started ahead: the same plans as fresh processes, limits kept, forks and exit safe."""

from __future__ import annotations

import json
import os
import signal
import stat
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from causalplan.inputs import load_mapping, load_model
from causalplan.objects.catalog import Catalog
from causalplan.pddl.canonical import canonical_pddl
from causalplan.pddl.task import PlanningTask, build_task
from causalplan.pddl.writer import compile_task
from causalplan.planners import fast_downward, search_processes
from causalplan.planners.fast_downward import CONFIGS, SearchConfig
from causalplan.planners.result import PlanStatus, SearchOutcome
from causalplan.planners.synthetic import synthetic_task
from tests.conftest import EXAMPLES, example_model
from tests.test_fast_downward import _children, star_task


@pytest.fixture(autouse=True)
def _no_idle_processes_left() -> Iterator[None]:
    """Start and end every test without idle search processes, so tests see only their own."""
    search_processes.stop_idle()
    yield
    search_processes.stop_idle()


def _is_gone(pid: int) -> bool:
    """Return whether ``pid`` has ended and been reaped (a zombie still has its /proc entry)."""
    return not Path(f"/proc/{pid}").exists()


def _wait_for_idle(count: int) -> list[int]:
    """Return the idle processes' pids once there are ``count`` (the pool starts them in the background)."""
    deadline = time.monotonic() + 30
    while len(pids := search_processes.idle_pids()) < count:
        assert time.monotonic() < deadline, "the idle processes were never started"
        time.sleep(0.005)
    return pids


def _ready_process() -> int:
    """Start the default search's idle process; return its pid once it is there."""
    fast_downward.prestart(CONFIGS["fd"])
    [ready] = _wait_for_idle(1)
    return ready


def _desk_lamp_task(catalog: Catalog) -> PlanningTask:
    return build_task(example_model("paper/desk_lamp.yaml", catalog), catalog.get("desk_lamp"))


def _solve(task: PlanningTask, config: SearchConfig, prestart: bool, monkeypatch: pytest.MonkeyPatch) -> SearchOutcome:
    """Solve ``task`` as the pipeline does (canonical PDDL), for real: the answer cache is emptied first."""
    monkeypatch.setenv("CAUSALPLAN_SEARCH_PRESTART", "1" if prestart else "0")
    fast_downward.clear_solve_cache()
    compiled = canonical_pddl(task) or compile_task(task)
    return fast_downward.solve(compiled.domain, compiled.problem, config)


def _example_tasks(catalog: Catalog) -> dict[str, PlanningTask]:
    """Every example model, on its own object and through every example mapping that builds a task."""
    files = sorted(EXAMPLES.rglob("*.yaml"))
    models = {path: loaded.model for path in files if (loaded := load_model(path, catalog)).model and loaded.is_valid}
    mappings = {path: read.mapping for path in files if (read := load_mapping(path, catalog)).mapping and read.is_valid}
    tasks: dict[str, PlanningTask] = {}
    for model_path, model in models.items():
        assert model is not None
        tasks[model_path.name] = build_task(model, catalog.get(model.object_id))
        for mapping_path, mapping in mappings.items():
            assert mapping is not None
            tasks[f"{model_path.name} on {mapping_path.name}"] = build_task(
                model, catalog.get(mapping.object_id), mapping
            )
    return tasks


def test_every_example_gets_the_plans_and_statuses_of_fresh_processes(
    user_catalog: Catalog, monkeypatch: pytest.MonkeyPatch
) -> None:
    tasks = _example_tasks(user_catalog)
    assert len(tasks) >= 30
    statuses = set()
    for name, task in tasks.items():
        for config in CONFIGS.values():  # alternating configurations: a mixed-up pool would show
            fast = _solve(task, config, True, monkeypatch)
            plain = _solve(task, config, False, monkeypatch)
            assert (fast.status, fast.actions) == (plain.status, plain.actions), (name, config.name)
            statuses.add(fast.status)
    assert statuses == {PlanStatus.SOLVED, PlanStatus.UNSOLVABLE}
    _wait_for_idle(2)  # the fast path did keep processes, for each configuration


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_synthetic_tasks_get_the_plans_of_fresh_processes(seed: int, monkeypatch: pytest.MonkeyPatch) -> None:
    differ = 0
    for size in (3, 8, 13, 21, 30):
        task = synthetic_task(size, seed=seed)
        fast = {name: _solve(task, config, True, monkeypatch) for name, config in CONFIGS.items()}
        plain = {name: _solve(task, config, False, monkeypatch) for name, config in CONFIGS.items()}
        for name in CONFIGS:
            assert fast[name].status is PlanStatus.SOLVED
            assert fast[name].actions == plain[name].actions, (size, name)
        differ += fast["fd"].actions != fast["fd-opt"].actions
    assert differ > 0  # so a process started for the other configuration would have been noticed


def test_concurrent_solves_share_the_pool_safely(monkeypatch: pytest.MonkeyPatch) -> None:
    jobs = [(size, name) for size in (5, 8, 13, 21) for name in CONFIGS for _ in range(3)]
    tasks = {size: synthetic_task(size, seed=4) for size, _ in jobs}
    expected = {(size, name): _solve(tasks[size], CONFIGS[name], False, monkeypatch).actions for size, name in jobs}
    monkeypatch.setenv("CAUSALPLAN_SEARCH_PRESTART", "1")

    def run(job: tuple[int, str]) -> bool:
        size, name = job
        compiled = canonical_pddl(tasks[size]) or compile_task(tasks[size])
        # Directly, past the answer cache: every job runs a real search.
        outcome = fast_downward._solve_uncached(compiled.domain, compiled.problem, CONFIGS[name])
        return outcome.actions == expected[job]

    with ThreadPoolExecutor(max_workers=6) as pool:
        assert all(pool.map(run, jobs))
    search_processes.stop_idle()
    assert _children() == set()


def _record_starts(monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """Record the name of the thread of every process start from now on."""
    starts: list[str] = []
    real_start = search_processes.start

    def recording_start(command: search_processes.Command) -> search_processes.Started:
        starts.append(threading.current_thread().name)
        return real_start(command)

    monkeypatch.setattr(search_processes, "start", recording_start)
    return starts


def test_a_solve_uses_the_process_started_ahead_and_starts_its_replacement_in_the_background(
    catalog: Catalog, monkeypatch: pytest.MonkeyPatch
) -> None:
    ready = _ready_process()
    starts = _record_starts(monkeypatch)
    task = _desk_lamp_task(catalog)
    assert _solve(task, CONFIGS["fd"], True, monkeypatch).status is PlanStatus.SOLVED
    [replacement] = _wait_for_idle(1)
    assert _is_gone(ready) and replacement != ready
    assert starts == ["causalplan-retire"]  # none on the solving thread


def test_taking_a_process_starts_no_replacement_until_its_search_has_ended() -> None:
    """On two cores the replacement's start-up would compete with the search that took the process."""
    ready = _ready_process()
    command = fast_downward._search_command(fast_downward.search_binary(), CONFIGS["fd"].search)
    taken = search_processes.take(command)
    try:
        assert taken.process.pid == ready
        assert search_processes.idle_pids() == []
        assert not any(thread.name == "causalplan-prestart" for thread in threading.enumerate())
    finally:
        search_processes.discard(taken)


def test_a_used_process_is_reaped_and_its_folder_removed_off_the_solving_thread(
    catalog: Catalog, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Removing the folder alone takes ~0.6 ms, which the answer need not wait for."""
    ready = _ready_process()
    folder = Path(os.readlink(f"/proc/{ready}/cwd"))
    discarded: dict[int, str] = {}
    real_discard = search_processes.discard

    def recording_discard(started: search_processes.Started) -> None:
        discarded[started.process.pid] = threading.current_thread().name
        real_discard(started)

    monkeypatch.setattr(search_processes, "discard", recording_discard)
    task = _desk_lamp_task(catalog)
    assert _solve(task, CONFIGS["fd"], True, monkeypatch).status is PlanStatus.SOLVED
    search_processes.stop_idle()  # waits for the retirement, then ends the replacement
    assert discarded[ready] == "causalplan-retire"
    assert _is_gone(ready) and not folder.exists()
    assert _children() == set()


def test_held_retirements_wait_for_the_end_of_the_block(catalog: Catalog, monkeypatch: pytest.MonkeyPatch) -> None:
    """A worker holds them while it answers: the used process is neither killed nor replaced before."""
    ready = _ready_process()
    task = _desk_lamp_task(catalog)
    with search_processes.retirements_held():
        assert _solve(task, CONFIGS["fd"], True, monkeypatch).status is PlanStatus.SOLVED
        assert not any(thread.name == "causalplan-retire" for thread in threading.enumerate())
        assert search_processes.idle_pids() == [] and not _is_gone(ready)  # still there, maybe still printing
    [replacement] = _wait_for_idle(1)
    assert replacement != ready
    search_processes.stop_idle()
    assert _is_gone(ready) and _children() == set()


def test_a_second_solve_in_a_held_block_starts_its_replacement_first(
    catalog: Catalog, monkeypatch: pytest.MonkeyPatch
) -> None:
    """As without the block, it takes the replacement of the first solve's process, not one started for it."""
    ready = _ready_process()
    starts = _record_starts(monkeypatch)
    task = _desk_lamp_task(catalog)
    with search_processes.retirements_held():
        first = _solve(task, CONFIGS["fd"], True, monkeypatch)
        second = _solve(task, CONFIGS["fd"], True, monkeypatch)
    assert first.status is second.status is PlanStatus.SOLVED and first.actions == second.actions
    _wait_for_idle(1)
    assert starts == ["causalplan-retire", "causalplan-retire"]  # none on the solving thread
    search_processes.stop_idle()
    assert _is_gone(ready) and _children() == set()


def test_a_search_writes_its_output_to_a_file_and_its_plan_to_a_fifo_and_no_pipe_is_read(catalog: Catalog) -> None:
    """FD logs a line at a time: a reader of its stdout would wake up for each line (~1.3 ms per search)."""
    ready = _ready_process()
    command = fast_downward._search_command(fast_downward.search_binary(), CONFIGS["fd"].search)
    taken = search_processes.take(command)
    try:
        assert taken.process.pid == ready and taken.process.stdout is None
        task = _desk_lamp_task(catalog)
        compiled = canonical_pddl(task) or compile_task(task)
        translated = fast_downward._translate(compiled.domain, compiled.problem, time.monotonic() + 30, 2048)
        assert translated.product is not None
        deadline = time.monotonic() + 30
        handed = fast_downward._hand_over(taken, command, translated.product.encode(), deadline, 2048)
        assert handed.returncode == 0
        step = b"(assemble kind-screw light_bulb base_with_cables bulb_into_socket)\n"
        assert handed.plan == step + b"; cost = 1 (unit cost)\n"
        assert stat.S_ISFIFO((taken.folder / fast_downward.PLAN_FILE).stat().st_mode)
        taken.process.wait(30)  # it may still have been printing its statistics
        assert b"Solution found" in (taken.folder / search_processes.OUTPUT_FILE).read_bytes()
    finally:
        search_processes.discard(taken)


def _python_process(code: str) -> tuple[search_processes.Started, search_processes.Command]:
    command = (sys.executable, "-c", code)
    return search_processes.start(command), command


def test_a_task_larger_than_the_pipe_buffer_is_written_whole() -> None:
    """A big task (hundreds of parts) does not fit in the pipe: it is written as the process reads it."""
    started, command = _python_process("import sys; print(len(sys.stdin.buffer.read()))")
    task = b"x" * (4 * 1024 * 1024)  # 64 times a Linux pipe's buffer
    try:
        handed = fast_downward._hand_over(started, command, task, time.monotonic() + 60, 2048)
    finally:
        search_processes.discard(started)
    assert handed.returncode == 0 and handed.plan is None
    assert handed.output.strip() == str(len(task)).encode()


def test_a_process_that_ends_without_reading_its_task_gives_its_exit_code_and_output() -> None:
    started, command = _python_process("import sys; print('bad task'); sys.exit(3)")
    try:
        handed = fast_downward._hand_over(started, command, b"x" * (1024 * 1024), time.monotonic() + 60, 2048)
    finally:
        search_processes.discard(started)
    assert (handed.returncode, handed.plan) == (3, None)
    assert handed.output.strip() == b"bad task"


def test_a_process_that_stops_reading_is_killed_at_the_deadline() -> None:
    started, command = _python_process("import time; time.sleep(60)")
    began = time.monotonic()
    try:
        handed = fast_downward._hand_over(started, command, b"x" * (1024 * 1024), began + 1.0, 2048)
        assert handed.returncode is None
        assert time.monotonic() - began < 30  # it did not wait for the process's own minute
        assert started.process.wait(30) == -signal.SIGKILL
    finally:
        search_processes.discard(started)


def _planner(plan: str, then: str, tmp_path: Path) -> tuple[search_processes.Started, search_processes.Command]:
    """Start a process that reads its task, writes ``plan`` to the plan file as FD does, then runs ``then``."""
    source = tmp_path / "plan.txt"
    source.write_text(plan)
    return _python_process(
        "import sys, time\n"
        "sys.stdin.buffer.read()\n"
        f"with open({str(source)!r}) as source, open({fast_downward.PLAN_FILE!r}, 'w') as plan:\n"
        "    for line in source:\n"
        "        plan.write(line); plan.flush()\n"
        f"{then}\n"
    )


def test_a_complete_plan_is_taken_as_soon_as_it_is_closed_and_the_process_killed_afterwards(tmp_path: Path) -> None:
    """FD prints its statistics and exits ~1.3 ms after closing its plan; the answer need not wait for that."""
    plan = "(screw bulb base fit)\n(clip shade base ring)\n; cost = 2 (unit cost)\n"
    started, command = _planner(plan, "time.sleep(60)", tmp_path)
    try:
        handed = fast_downward._hand_over(started, command, b"task", time.monotonic() + 30, 2048)
        assert started.process.poll() is None  # still "printing": the plan did not wait for its exit
    finally:
        search_processes.discard(started)  # what retire does on its thread: kills it
    assert (handed.returncode, handed.plan) == (0, plan.encode())
    assert started.process.returncode == -signal.SIGKILL


def test_a_plan_larger_than_the_fifo_buffer_is_read_whole(tmp_path: Path) -> None:
    plan = "".join(f"(screw part{index} base fit{index})\n" for index in range(20000)) + "; cost = 20000 (unit cost)\n"
    assert len(plan) > 4 * 65536
    started, command = _planner(plan, "sys.exit(0)", tmp_path)
    try:
        handed = fast_downward._hand_over(started, command, b"task", time.monotonic() + 60, 2048)
    finally:
        search_processes.discard(started)
    assert handed.returncode == 0 and handed.plan == plan.encode()


def test_an_incomplete_plan_is_no_plan_and_the_exit_code_says_why(tmp_path: Path) -> None:
    """A plan file without FD's closing cost line (a crash while writing it) is not an answer."""
    started, command = _planner("(screw bulb base fit)\n", "sys.exit(5)", tmp_path)
    try:
        handed = fast_downward._hand_over(started, command, b"task", time.monotonic() + 60, 2048)
    finally:
        search_processes.discard(started)
    assert (handed.returncode, handed.plan) == (5, None)


def test_a_plan_written_without_end_is_stopped_at_the_deadline(tmp_path: Path) -> None:
    """Its lines keep the plan readable, so only the clock can end the reading."""
    source = tmp_path / "line.txt"
    source.write_text("(screw bulb base fit)\n")
    started, command = _python_process(
        "import sys\n"
        "sys.stdin.buffer.read()\n"
        f"line = open({str(source)!r}).read()\n"
        f"with open({fast_downward.PLAN_FILE!r}, 'w') as plan:\n"
        "    while True:\n"
        "        plan.write(line); plan.flush()\n"
    )
    began = time.monotonic()
    try:
        handed = fast_downward._hand_over(started, command, b"task", began + 1.0, 2048)
        assert time.monotonic() - began < 30
        assert (handed.returncode, handed.plan) == (None, None)
        assert started.process.wait(30) == -signal.SIGKILL
    finally:
        search_processes.discard(started)


def test_the_time_limit_kills_a_process_started_ahead(monkeypatch: pytest.MonkeyPatch) -> None:
    fast_downward.prestart(CONFIGS["fd-opt"])
    [ready] = _wait_for_idle(1)
    compiled = compile_task(star_task(24))  # far beyond a blind search's reach in a second
    monkeypatch.setenv("CAUSALPLAN_SEARCH_PRESTART", "1")
    outcome = fast_downward.solve(compiled.domain, compiled.problem, CONFIGS["fd-opt"], time_limit=1.0)
    assert outcome.status is PlanStatus.TIMEOUT
    assert "search" in outcome.timing
    assert _is_gone(ready)
    search_processes.stop_idle()
    assert _children() == set()


def test_the_memory_limit_applies_to_a_process_started_ahead(monkeypatch: pytest.MonkeyPatch) -> None:
    fast_downward.prestart(CONFIGS["fd-opt"])
    _wait_for_idle(1)
    compiled = compile_task(star_task(20))
    monkeypatch.setenv("CAUSALPLAN_SEARCH_PRESTART", "1")
    outcome = fast_downward.solve(compiled.domain, compiled.problem, CONFIGS["fd-opt"], memory_limit_mb=15)
    assert outcome.status is PlanStatus.OUT_OF_MEMORY


def test_an_idle_process_that_died_is_replaced(catalog: Catalog, monkeypatch: pytest.MonkeyPatch) -> None:
    ready = _ready_process()
    os.kill(ready, signal.SIGKILL)
    while Path(f"/proc/{ready}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z":  # dead, not yet reaped
        time.sleep(0.001)
    task = build_task(example_model("near/candle.yaml", catalog), catalog.get("candle"))
    outcome = _solve(task, CONFIGS["fd"], True, monkeypatch)
    assert outcome.status is PlanStatus.SOLVED and len(outcome.actions) == 2
    assert _is_gone(ready)


def test_stop_idle_kills_reaps_and_removes_every_idle_process() -> None:
    for config in CONFIGS.values():
        fast_downward.prestart(config)
    pids = _wait_for_idle(2)
    folders = [Path(os.readlink(f"/proc/{pid}/cwd")) for pid in pids]
    assert all(folder.is_dir() and folder.name.startswith("causalplan-fd-") for folder in folders)
    search_processes.stop_idle()
    assert search_processes.idle_pids() == []
    assert all(_is_gone(pid) for pid in pids)
    assert not any(folder.exists() for folder in folders)
    assert _children() == set()


def test_the_switch_turns_prestarting_off(catalog: Catalog, monkeypatch: pytest.MonkeyPatch) -> None:
    used: list[str] = []
    monkeypatch.setattr(search_processes, "take", lambda command: used.append("take"))
    monkeypatch.setattr(search_processes, "prestart", lambda command: used.append("prestart"))
    monkeypatch.setenv("CAUSALPLAN_SEARCH_PRESTART", "0")
    fast_downward.prestart(CONFIGS["fd"])
    task = _desk_lamp_task(catalog)
    assert _solve(task, CONFIGS["fd"], False, monkeypatch).status is PlanStatus.SOLVED
    assert used == []
    assert _children() == set()  # the fresh process is reaped, none is kept


def test_a_forked_child_neither_uses_nor_kills_the_parents_idle_processes(
    catalog: Catalog, monkeypatch: pytest.MonkeyPatch
) -> None:
    ready = _ready_process()
    task = _desk_lamp_task(catalog)
    monkeypatch.setenv("CAUSALPLAN_SEARCH_PRESTART", "1")
    go_read, go_write = os.pipe()
    report_read, report_write = os.pipe()
    child = os.fork()
    if child == 0:  # the child: wait (alive, pool untouched) for the parent's solve, then look around
        code = 1
        try:
            os.read(go_read, 1)
            seen: dict[str, object] = {"idle_at_fork": search_processes.idle_pids()}
            search_processes.stop_idle()  # must not touch the parent's
            seen["status"] = _solve(task, CONFIGS["fd"], True, monkeypatch).status.value
            seen["idle_after_solve"] = _wait_for_idle(1)
            search_processes.stop_idle()
            os.write(report_write, json.dumps(seen).encode())
            code = 0
        finally:
            os._exit(code)
    try:
        # Had the child kept its copy of the idle process's stdin, that process would never see
        # the end of its task while the child lives, and this solve would time out.
        fast_downward.clear_solve_cache()
        compiled = canonical_pddl(task) or compile_task(task)
        outcome = fast_downward.solve(compiled.domain, compiled.problem, CONFIGS["fd"], time_limit=20)
        assert outcome.status is PlanStatus.SOLVED
        [replacement] = _wait_for_idle(1)  # started once the used process was discarded
        assert _is_gone(ready)
    finally:
        os.write(go_write, b"x")
        _, status = os.waitpid(child, 0)
        for descriptor in (go_read, go_write, report_write):
            os.close(descriptor)
    report = json.loads(os.read(report_read, 10_000))
    os.close(report_read)
    assert os.waitstatus_to_exitcode(status) == 0
    assert report["idle_at_fork"] == []
    assert report["status"] == "solved"
    assert replacement not in report["idle_after_solve"]
    assert search_processes.idle_pids() == [replacement] and not _is_gone(replacement)


def test_idle_processes_and_their_folders_are_gone_when_the_owner_exits(tmp_path: Path) -> None:
    script = """
import json, os, time
from causalplan.planners import fast_downward, search_processes
for config in fast_downward.CONFIGS.values():
    fast_downward.prestart(config)
while len(search_processes.idle_pids()) < 2:
    time.sleep(0.005)
pids = search_processes.idle_pids()
print(json.dumps({"pids": pids, "folders": [os.readlink(f"/proc/{pid}/cwd") for pid in pids]}))
"""
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True, timeout=60)
    seen = json.loads(done.stdout)
    assert len(seen["pids"]) == 2
    assert not any(Path(folder).exists() for folder in seen["folders"])
