"""Fast Downward run directly: statuses, limits that really stop it, isolation of concurrent solves."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from causalplan.causal.documents import SourceMap
from causalplan.causal.model import read_model
from causalplan.objects.catalog import Catalog, build_object
from causalplan.objects.schema import ObjectSchema
from causalplan.pddl.task import PlanningTask, build_task
from causalplan.pddl.writer import compile_task
from causalplan.planners import fast_downward, search_processes
from causalplan.planners.fast_downward import CONFIGS, parse_plan, solve, status_of_exit_code
from causalplan.planners.result import PlanStatus
from tests.conftest import example_mapping, example_model


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


def test_parse_plan_reads_actions_and_skips_the_cost_comment() -> None:
    text = "(screw light_bulb base_with_cables bulb_into_socket)\n; cost = 1 (unit cost)\n"
    assert parse_plan(text) == (("screw", ("light_bulb", "base_with_cables", "bulb_into_socket")),)
    with pytest.raises(ValueError, match="unexpected line"):
        parse_plan("screw light_bulb\n")


def test_search_binary_is_found_in_the_wheel() -> None:
    assert fast_downward.search_binary().name == "downward"
    assert fast_downward.translator_available()


def test_a_paper_task_solves_with_both_configurations(catalog: Catalog) -> None:
    compiled = compile_task(build_task(example_model("paper/desk_lamp.yaml", catalog), catalog.get("desk_lamp")))
    for config in CONFIGS.values():
        outcome = solve(compiled.domain, compiled.problem, config)
        assert outcome.status is PlanStatus.SOLVED
        assert outcome.actions == (("screw", ("light_bulb", "base_with_cables", "bulb_into_socket")),)
        assert set(outcome.timing) == {"translate", "search"}


def test_the_time_limit_stops_the_search_and_leaves_no_process() -> None:
    compiled = compile_task(star_task(24))
    started = time.monotonic()
    outcome = solve(compiled.domain, compiled.problem, CONFIGS["fd-opt"], time_limit=1.0)
    assert outcome.status is PlanStatus.TIMEOUT
    assert time.monotonic() - started < 10
    search_processes.stop_idle()  # the killed search's replacement, waiting for the next task
    assert _children() == set()


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


def test_a_missing_binary_is_an_error_not_a_crash(monkeypatch: pytest.MonkeyPatch, catalog: Catalog) -> None:
    monkeypatch.setenv("CAUSALPLAN_FD_BINARY", "/nonexistent/downward")
    fast_downward.search_binary.cache_clear()
    try:
        compiled = compile_task(build_task(example_model("paper/desk_lamp.yaml", catalog), catalog.get("desk_lamp")))
        outcome = solve(compiled.domain, compiled.problem, CONFIGS["fd"])
    finally:
        monkeypatch.delenv("CAUSALPLAN_FD_BINARY")
        fast_downward.search_binary.cache_clear()
    assert outcome.status is PlanStatus.ERROR
    assert "/nonexistent/downward" in outcome.message


def _sas(task: PlanningTask, mode: str, monkeypatch: pytest.MonkeyPatch) -> str:
    """Return the SAS task the translator writes for ``task`` in ``mode`` (in-process or fork)."""
    monkeypatch.setenv("CAUSALPLAN_TRANSLATOR", mode)
    compiled = compile_task(task)
    run = fast_downward._translate(compiled.domain, compiled.problem, time.monotonic() + 60, 2048)
    assert run.returncode == 0, run.output
    assert run.product is not None
    return run.product


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
    size: int, seed: int, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    from causalplan.planners.synthetic import synthetic_task

    task = synthetic_task(size, seed=seed)
    first = _sas(task, "in-process", monkeypatch)
    again = _sas(task, "in-process", monkeypatch)  # translator state left from the first
    forked = _sas(task, "fork", monkeypatch)
    assert first == again == forked == _sas_of_the_translators_own_process(task, tmp_path)


def test_translation_of_every_golden_case_matches_the_translators_own_process(
    catalog: Catalog, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    from tests.test_golden import CASES

    for case, (model_file, mapping_file) in sorted(CASES.items()):
        model = example_model(model_file, catalog)
        mapping = example_mapping(mapping_file, catalog) if mapping_file else None
        task = build_task(model, catalog.get(mapping.object_id if mapping else model.object_id), mapping)
        (tmp_path / case).mkdir()
        assert _sas(task, "in-process", monkeypatch) == _sas_of_the_translators_own_process(task, tmp_path / case), case


def test_an_in_process_translation_stops_at_its_deadline_and_the_next_solve_works(catalog: Catalog) -> None:
    from causalplan.planners.synthetic import synthetic_task

    big = compile_task(synthetic_task(320, seed=0))
    outcome = solve(big.domain, big.problem, CONFIGS["fd"], time_limit=0.05)
    assert outcome.status is PlanStatus.TIMEOUT
    small = compile_task(build_task(example_model("paper/desk_lamp.yaml", catalog), catalog.get("desk_lamp")))
    assert solve(small.domain, small.problem, CONFIGS["fd"]).status is PlanStatus.SOLVED


def test_the_forked_translator_is_still_available(monkeypatch: pytest.MonkeyPatch, catalog: Catalog) -> None:
    monkeypatch.setenv("CAUSALPLAN_TRANSLATOR", "fork")
    compiled = compile_task(build_task(example_model("near/candle.yaml", catalog), catalog.get("candle")))
    outcome = solve(compiled.domain, compiled.problem, CONFIGS["fd"])
    assert outcome.status is PlanStatus.SOLVED and len(outcome.actions) == 2


def test_solves_work_when_the_process_has_more_than_1024_open_files(
    monkeypatch: pytest.MonkeyPatch, catalog: Catalog
) -> None:
    """A busy server holds many sockets: waiting for a translator or a search must not use select()."""
    monkeypatch.setenv("CAUSALPLAN_TRANSLATOR", "fork")
    monkeypatch.setenv("CAUSALPLAN_SEARCH_PRESTART", "0")
    fast_downward.clear_solve_cache()
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


def test_a_lost_translator_timeout_is_raised_again(monkeypatch: pytest.MonkeyPatch) -> None:
    """The deadline's exception can be lost (raised in a GC callback, or under a broad except):
    the alarm fires again until the translation stops, instead of letting it run on."""
    lost: list[bool] = []

    def translator_that_loses_the_first_timeout(domain: str, problem: str) -> tuple[int, str | None]:
        finish = time.monotonic() + 5.0
        while time.monotonic() < finish:
            try:
                while time.monotonic() < finish:
                    pass
            except fast_downward._TranslatorTimeout:
                if lost:
                    raise
                lost.append(True)  # swallowed, as the interpreter does inside a GC callback
        return 0, "begin_version"  # ran to its end: the deadline did not hold

    monkeypatch.setattr(fast_downward, "_run_translator", translator_that_loses_the_first_timeout)
    run = fast_downward._translate_here("", "", time.monotonic() + 0.05, 2048)
    assert lost == [True]
    assert run.returncode is None


def test_without_invariant_synthesis_every_example_and_synthetic_task_translates_the_same(
    user_catalog: Catalog, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Skipping invariant synthesis (TRANSLATOR_ARGUMENTS) changes nothing in causalplan's tasks: all binary."""
    from fast_downward.translate import options

    from causalplan.pddl.canonical import canonical_pddl
    from causalplan.planners.synthetic import synthetic_task
    from tests.test_search_processes import _example_tasks

    assert "--invariant-generation-max-candidates" in fast_downward.TRANSLATOR_ARGUMENTS
    tasks = _example_tasks(user_catalog)
    for seed in range(3):
        tasks |= {f"synthetic {size}, seed {seed}": synthetic_task(size, seed=seed) for size in (5, 21, 60)}
    compared = 0
    for name, task in tasks.items():
        for compiled in (canonical_pddl(task), compile_task(task)):
            if compiled is None:
                continue
            ours = fast_downward._run_translator(compiled.domain, compiled.problem)
            with monkeypatch.context() as patch:
                patch.setattr(fast_downward, "translator_options", lambda: options.parse_args(["d.pddl", "p.pddl"]))
                defaults = fast_downward._run_translator(compiled.domain, compiled.problem)
            assert ours == defaults and ours[0] == 0, name
            compared += 1
    assert compared >= 90
    capsys.readouterr()  # the translator's log


_ROOMS_DOMAIN = """(define (domain rooms) (:requirements :strips :typing) (:types room)
  (:predicates (at ?r - room))
  (:action move :parameters (?from ?to - room) :precondition (at ?from)
   :effect (and (not (at ?from)) (at ?to))))"""
_ROOMS_PROBLEM = """(define (problem two) (:domain rooms) (:objects a b - room) (:init (at a)) (:goal (at b)))"""


def test_the_invariant_shortcut_finds_nothing_only_when_no_candidate_is_allowed(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A domain with a real invariant (one room at a time): FD's own search finds it under any other limit."""
    from fast_downward.translate import invariant_finder, normalize, options
    from fast_downward.translate.pddl_parser import parsing_functions

    fast_downward.install_invariant_shortcut()
    fast_downward.install_invariant_shortcut()  # once is enough; again changes nothing
    assert invariant_finder.find_invariants.is_causalplan_shortcut  # type: ignore[attr-defined]
    saved = options.options
    try:
        groups = {}
        for name, arguments in (("none allowed", fast_downward.TRANSLATOR_ARGUMENTS), ("defaults", ())):
            options.options = options.parse_args(["d.pddl", "p.pddl", *arguments])
            task = parsing_functions.parse_task(
                fast_downward.parse_pddl("domain", _ROOMS_DOMAIN), fast_downward.parse_pddl("problem", _ROOMS_PROBLEM)
            )
            normalize.normalize(task)
            groups[name] = [[str(atom) for atom in group] for group in invariant_finder.get_groups(task)]
    finally:
        options.options = saved
    assert groups == {"none allowed": [], "defaults": [["Atom at(?X)"]]}  # at most one room
    assert "0 initial candidates" in capsys.readouterr().out  # what FD itself prints with the limit
