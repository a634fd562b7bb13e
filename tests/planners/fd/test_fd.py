"""Fast Downward run directly: exit codes, the translator, limits that really stop it, isolated solves."""

from __future__ import annotations

import os
import resource
import signal
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from causalplan import caches
from causalplan.causal.documents import SourceMap
from causalplan.causal.model import read_model
from causalplan.inputs import load_mapping, load_model
from causalplan.objects.catalog import Catalog, build_object
from causalplan.objects.schema import ObjectSchema
from causalplan.pddl.canonical import canonical_pddl
from causalplan.pddl.task import PlanningTask, build_task
from causalplan.pddl.writer import compile_task
from causalplan.planners import fd
from causalplan.planners.fd import CONFIGS, ExitCode, parse_plan, solve, status_of_exit_code
from causalplan.planners.fd import translate as fd_translate
from causalplan.planners.result import PlanStatus
from tests.conftest import EXAMPLES, example_mapping, example_model


def star_task(n_parts: int) -> PlanningTask:
    """A hub with ``n_parts`` satellites, every one needed: 2^n states for a blind search."""
    parts = [
        {
            "id": "hub",
            "name": "hub",
            "connectors": [{"id": f"s{i}", "kind": "slot", "spec": f"k{i}"} for i in range(n_parts)],
        }
    ]
    parts += [
        {"id": f"p{i}", "name": f"part {i}", "connectors": [{"id": "c", "kind": "tab", "spec": f"k{i}"}]}
        for i in range(n_parts)
    ]
    fits = [{"id": f"f{i}", "primitive": "insert", "moving": f"p{i}.c", "fixed": f"hub.s{i}"} for i in range(n_parts)]
    obj = build_object(
        ObjectSchema.model_validate(
            {
                "id": "star",
                "name": "star",
                "category": "synthetic",
                "goal": "light",
                "base": "hub",
                "parts": parts,
                "fits": fits,
                "mechanism": {"explanation": "all parts", "requires": [{"any": ["f0"], "says": "part 0 in"}]},
            }
        )
    )
    rule = " AND ".join(f"g{i}" for i in range(n_parts)) + " CAUSES light"
    model, _ = read_model(
        {"object": "star", "functions": {f"p{i}": [f"g{i}"] for i in range(n_parts)}, "rules": [rule]}, SourceMap()
    )
    assert model is not None
    return build_task(model, obj)


@pytest.mark.parametrize(
    ("code", "status"),
    [
        (0, PlanStatus.SOLVED),
        (2, PlanStatus.SOLVED),
        (10, PlanStatus.UNSOLVABLE),
        (11, PlanStatus.UNSOLVABLE),
        (20, PlanStatus.OUT_OF_MEMORY),
        (22, PlanStatus.OUT_OF_MEMORY),
        (21, PlanStatus.TIMEOUT),
        (23, PlanStatus.TIMEOUT),
        (30, PlanStatus.ERROR),
        (31, PlanStatus.ERROR),
        (35, PlanStatus.ERROR),
        (99, PlanStatus.ERROR),
        (-9, PlanStatus.ERROR),
    ],
)
def test_exit_codes_map_to_one_closed_status(code: int, status: PlanStatus) -> None:
    assert status_of_exit_code(code) is status


def test_exit_codes_are_named_as_fast_downward_names_them() -> None:
    assert ExitCode(12) is ExitCode.SEARCH_UNSOLVED_INCOMPLETE
    assert ExitCode.SEARCH_PLAN_FOUND_AND_OUT_OF_TIME.found_plan()
    assert not ExitCode.SEARCH_UNSOLVABLE.found_plan()
    assert [code.name for code in ExitCode if code.is_unrecoverable()][:2] == [
        "TRANSLATE_CRITICAL_ERROR",
        "TRANSLATE_INPUT_ERROR",
    ]
    assert not ExitCode.SEARCH_OUT_OF_MEMORY.is_unrecoverable()


def test_parse_plan_reads_actions_and_skips_the_cost_comment() -> None:
    text = "(screw light_bulb base_with_cables bulb_into_socket)\n; cost = 1 (unit cost)\n"
    assert parse_plan(text) == (("screw", ("light_bulb", "base_with_cables", "bulb_into_socket")),)
    with pytest.raises(ValueError, match="unexpected line"):
        parse_plan("screw light_bulb\n")


def test_search_binary_is_found_in_the_wheel() -> None:
    assert fd.search_binary().name == "downward"
    assert fd.translator_available()


def test_a_paper_task_solves_with_both_configurations(catalog: Catalog) -> None:
    compiled = compile_task(build_task(example_model("paper/desk_lamp.yaml", catalog), catalog.get("desk_lamp")))
    for config in CONFIGS.values():
        outcome = solve(compiled.domain, compiled.problem, config)
        assert outcome.status is PlanStatus.SOLVED
        assert outcome.actions == (("screw", ("light_bulb", "base_with_cables", "bulb_into_socket")),)
        assert set(outcome.timing) == {"translate", "search"}


def test_the_time_limit_stops_the_search_and_leaves_no_process() -> None:
    compiled = compile_task(star_task(24))
    before = _children()  # e.g. multiprocessing's resource tracker, left by earlier tests
    started = time.monotonic()
    outcome = solve(compiled.domain, compiled.problem, CONFIGS["fd-opt"], time_limit=1.0)
    assert outcome.status is PlanStatus.TIMEOUT
    assert time.monotonic() - started < 10
    assert _children() - before == set()


def _children() -> set[int]:
    """Return the pids of this process's children (its main thread's), but multiprocessing's resource tracker.

    The tracker is started once by whatever first spawns a process (a Dask LocalCluster in the
    cluster tests) and lives as long as the test process, by design: it is no planner's leftover.
    """
    pids = {int(pid) for pid in Path(f"/proc/{os.getpid()}/task/{os.getpid()}/children").read_text().split()}
    return {pid for pid in pids if not _is_resource_tracker(pid)}


def _is_resource_tracker(pid: int) -> bool:
    try:
        return b"multiprocessing.resource_tracker" in Path(f"/proc/{pid}/cmdline").read_bytes()
    except OSError:  # it has just ended
        return False


def test_the_memory_limit_is_reported_as_out_of_memory() -> None:
    compiled = compile_task(star_task(20))  # A* needs far more than 15 MB here
    outcome = solve(compiled.domain, compiled.problem, CONFIGS["fd-opt"], time_limit=60, memory_limit_mb=15)
    assert outcome.status is PlanStatus.OUT_OF_MEMORY


def test_malformed_pddl_is_an_error_with_the_translators_words() -> None:
    outcome = solve("(define (domain broken)", "(define (problem p))", CONFIGS["fd"])
    assert outcome.status is PlanStatus.ERROR
    assert "exit code" in outcome.message


def test_concurrent_solves_do_not_interfere(catalog: Catalog) -> None:
    tasks = {
        "desk_lamp": (example_model("paper/desk_lamp.yaml", catalog), "desk_lamp"),
        "candle": (example_model("near/candle.yaml", catalog), "candle"),
        "abstract": (example_model("far/abstract_desk_lamp.yaml", catalog), "desk_lamp"),
    }
    expected_first_fit = {"desk_lamp": "bulb_into_socket", "candle": "wick_into_wax", "abstract": "bulb_into_socket"}
    jobs = [name for name in tasks for _ in range(4)]

    def run(name: str) -> tuple[str, PlanStatus, str]:
        model, object_id = tasks[name]
        compiled = compile_task(build_task(model, catalog.get(object_id)))
        outcome = solve(compiled.domain, compiled.problem, CONFIGS["fd"])
        return name, outcome.status, outcome.actions[0][1][2]

    with ThreadPoolExecutor(max_workers=6) as pool:
        results = list(pool.map(run, jobs))
    assert all(status is PlanStatus.SOLVED for _, status, _ in results)
    assert all(fit == expected_first_fit[name] for name, _, fit in results)


def test_no_output_sas_is_left_in_the_working_directory(
    catalog: Catalog, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    compiled = compile_task(build_task(example_model("paper/desk_lamp.yaml", catalog), catalog.get("desk_lamp")))
    assert solve(compiled.domain, compiled.problem, CONFIGS["fd"]).status is PlanStatus.SOLVED
    assert list(tmp_path.iterdir()) == []


def test_a_missing_binary_is_an_error_not_a_crash(catalog: Catalog) -> None:
    fd.use_search_binary(Path("/nonexistent/downward"))
    try:
        compiled = compile_task(build_task(example_model("paper/desk_lamp.yaml", catalog), catalog.get("desk_lamp")))
        outcome = solve(compiled.domain, compiled.problem, CONFIGS["fd"])
    finally:
        fd.use_search_binary(None)
    assert outcome.status is PlanStatus.ERROR
    assert "/nonexistent/downward" in outcome.message


def _sas(task: PlanningTask, where: str, tmp_path: Path) -> str:
    """Return the SAS task the translator writes for ``task``, on the main thread or off it."""
    compiled = compile_task(task)
    folder = tmp_path / f"{where}-{len(list(tmp_path.iterdir()))}"
    folder.mkdir()

    def run() -> fd_translate.Finished:
        return fd_translate.translate(compiled.domain, compiled.problem, folder, 60, 2048)

    if where == "main":
        finished = run()
    else:
        with ThreadPoolExecutor(max_workers=1) as pool:
            finished = pool.submit(run).result()
    assert finished.returncode == 0, finished.output
    return (folder / fd_translate.SAS_FILE).read_text(encoding="utf-8")


def _sas_of_the_translators_own_process(task: PlanningTask, tmp_path: Path) -> str:
    """Return the SAS task of ``python -m fast_downward.translate`` on ``task``'s PDDL files."""
    compiled = compile_task(task)
    (tmp_path / "domain.pddl").write_text(compiled.domain, encoding="utf-8")
    (tmp_path / "problem.pddl").write_text(compiled.problem, encoding="utf-8")
    command = [sys.executable, "-m", "fast_downward.translate", "domain.pddl", "problem.pddl", "--sas-file", "out.sas"]
    subprocess.run(command, cwd=tmp_path, check=True, capture_output=True)
    return (tmp_path / "out.sas").read_text(encoding="utf-8")


@pytest.mark.parametrize(("size", "seed"), [(3, 2), (12, 5), (40, 2)])
def test_translation_writes_exactly_what_the_translators_own_process_writes(
    size: int, seed: int, tmp_path: Path
) -> None:
    from causalplan.comparison.synthetic import synthetic_task

    task = synthetic_task(size, seed=seed)
    first = _sas(task, "main", tmp_path)
    again = _sas(task, "main", tmp_path)  # translator state left from the first
    off_main = _sas(task, "thread", tmp_path)  # its own process
    assert first == again == off_main == _sas_of_the_translators_own_process(task, tmp_path)


def test_translation_of_every_golden_case_matches_the_translators_own_process(catalog: Catalog, tmp_path: Path) -> None:
    from tests.pddl.test_golden import CASES

    for case, (model_file, mapping_file) in sorted(CASES.items()):
        model = example_model(model_file, catalog)
        mapping = example_mapping(mapping_file, catalog) if mapping_file else None
        task = build_task(model, catalog.get(mapping.object_id if mapping else model.object_id), mapping)
        (tmp_path / case).mkdir()
        assert _sas(task, "main", tmp_path) == _sas_of_the_translators_own_process(task, tmp_path / case), case


def test_an_in_process_translation_stops_at_its_deadline_and_the_next_solve_works(catalog: Catalog) -> None:
    from causalplan.comparison.synthetic import synthetic_task

    big = compile_task(synthetic_task(320, seed=0))
    outcome = solve(big.domain, big.problem, CONFIGS["fd"], time_limit=0.05)
    assert outcome.status is PlanStatus.TIMEOUT
    small = compile_task(build_task(example_model("paper/desk_lamp.yaml", catalog), catalog.get("desk_lamp")))
    assert solve(small.domain, small.problem, CONFIGS["fd"]).status is PlanStatus.SOLVED


def test_a_solve_off_the_main_thread_translates_in_its_own_process_under_the_deadline() -> None:
    from causalplan.comparison.synthetic import synthetic_task

    big = compile_task(synthetic_task(320, seed=0))
    before = _children()
    with ThreadPoolExecutor(max_workers=1) as pool:
        outcome = pool.submit(solve, big.domain, big.problem, CONFIGS["fd"], 0.2).result()
    assert outcome.status is PlanStatus.TIMEOUT
    assert "translator" in outcome.message
    assert _children() - before == set()


def test_solves_work_when_the_process_has_more_than_1024_open_files(catalog: Catalog) -> None:
    """A busy server holds many sockets: waiting for a translator or a search must not use select()."""
    compiled = compile_task(build_task(example_model("near/candle.yaml", catalog), catalog.get("candle")))
    held: list[int] = []
    try:
        while not held or held[-1] <= 1100:
            held.append(os.open(os.devnull, os.O_RDONLY))
        outcome = solve(compiled.domain, compiled.problem, CONFIGS["fd"])
    finally:
        for descriptor in held:
            os.close(descriptor)
    assert outcome.status is PlanStatus.SOLVED, outcome.message


def test_a_lost_translator_timeout_is_raised_again(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    """The deadline's exception can be lost (raised in a GC callback, or under a broad except):
    the alarm fires again until the translation stops, instead of letting it run on."""
    lost: list[bool] = []

    def translator_that_loses_the_first_timeout(folder: Path) -> int:
        finish = time.monotonic() + 5.0
        while time.monotonic() < finish:
            try:
                while time.monotonic() < finish:
                    pass
            except fd_translate._TranslatorTimeout:
                if lost:
                    raise
                lost.append(True)  # swallowed, as the interpreter does inside a GC callback
        return 0  # ran to its end: the deadline did not hold

    monkeypatch.setattr(fd_translate, "_run_main", translator_that_loses_the_first_timeout)
    finished = fd_translate.translate("", "", tmp_path, 0.05, 2048)
    assert lost == [True]
    assert finished.returncode is None


def test_an_alarm_due_during_the_clean_up_leaves_the_process_as_it_was(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    """On a busy machine the repeated alarm can come due as the translation ends: it must not
    escape, nor leave the process with the translator's memory limit, alarm or stderr; and a
    timer the process had (pytest-timeout's) goes on."""

    def translator_past_its_deadline(folder: Path) -> int:
        while True:
            pass

    monkeypatch.setattr(fd_translate, "_run_main", translator_past_its_deadline)
    monkeypatch.setattr(fd_translate, "ALARM_REPEAT_SECONDS", 0.00001)  # due again at once, as under load
    earlier_handler = signal.signal(signal.SIGALRM, lambda signum, frame: None)
    earlier_delay, earlier_interval = signal.setitimer(signal.ITIMER_REAL, 600.0)
    try:
        before = (resource.getrlimit(resource.RLIMIT_AS), signal.getsignal(signal.SIGALRM), sys.stdout, sys.stderr)
        for _ in range(100):
            assert fd_translate.translate("", "", tmp_path, 0.001, 2048).returncode is None
            now = (resource.getrlimit(resource.RLIMIT_AS), signal.getsignal(signal.SIGALRM), sys.stdout, sys.stderr)
            assert now == before
        assert 500.0 < signal.getitimer(signal.ITIMER_REAL)[0] < 600.0
    finally:
        signal.setitimer(signal.ITIMER_REAL, earlier_delay, earlier_interval)
        signal.signal(signal.SIGALRM, earlier_handler)


def example_tasks(catalog: Catalog) -> dict[str, PlanningTask]:
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


def test_every_example_solves_the_same_in_canonical_and_readable_form(user_catalog: Catalog) -> None:
    """The canonical form FD solves gives the plan the person's own PDDL gives, on every example."""
    from causalplan.pddl.canonical import plan_actions

    compared = 0
    for name, task in example_tasks(user_catalog).items():
        canonical = canonical_pddl(task)
        if canonical is None:
            continue
        readable = compile_task(task)
        ours = solve(canonical.domain, canonical.problem, CONFIGS["fd-opt"])
        theirs = solve(readable.domain, readable.problem, CONFIGS["fd-opt"])
        assert ours.status is theirs.status, name
        assert len(plan_actions(ours.actions)) == len(theirs.actions), name
        compared += 1
    assert compared >= 10


def test_answers_are_kept_and_none_when_told_to_keep_none(catalog: Catalog) -> None:
    compiled = compile_task(build_task(example_model("paper/desk_lamp.yaml", catalog), catalog.get("desk_lamp")))
    solve(compiled.domain, compiled.problem, CONFIGS["fd"])
    assert set(solve(compiled.domain, compiled.problem, CONFIGS["fd"]).timing) == {"cached"}
    caches.fresh({"fd_answers": 0})
    solve(compiled.domain, compiled.problem, CONFIGS["fd"])
    assert set(solve(compiled.domain, compiled.problem, CONFIGS["fd"]).timing) == {"translate", "search"}
