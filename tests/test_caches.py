"""The process's caches and their owner: bounded, counted, empty when fresh, hit on a repeat; none held elsewhere."""

from __future__ import annotations

import ast
from collections.abc import Callable
from dataclasses import fields
from pathlib import Path

import pytest

from causalplan import caches
from causalplan.caches import BoundedCache, Caches
from causalplan.objects.catalog import Catalog
from causalplan.pddl.task import build_task
from causalplan.pddl.writer import compile_task
from causalplan.planners import val
from causalplan.planners.fd import CONFIGS, solve
from causalplan.planners.result import PlanStatus
from causalplan.transfer.verdict import Verdict, evaluate_transfer
from tests.conftest import example_mapping, example_model
from tests.sim.fixtures import PEG_BOARD, parsed_object, steps

PACKAGE = Path(__file__).resolve().parent.parent / "causalplan"


def test_a_cache_keeps_the_most_recently_used_and_counts_hits_and_misses() -> None:
    cache: BoundedCache[str, int] = BoundedCache(2)
    cache.put("a", 1)
    cache.put("b", 2)
    assert cache.get("a") == 1  # now the most recently used
    cache.put("c", 3)
    assert cache.has("a") and not cache.has("b") and cache.has("c")  # 'has' neither counts nor reorders
    assert cache.get("b") is None
    assert cache.stats() == {"size": 2, "entries": 2, "hits": 1, "misses": 1}
    assert cache.get_or_make("d", lambda: 4, keep=lambda value: value > 10) == 4
    assert not cache.has("d")  # made, but not kept
    cache.clear()
    assert len(cache) == 0


def test_a_cache_of_size_zero_keeps_nothing() -> None:
    off: BoundedCache[str, int] = BoundedCache(0)
    off.put("a", 1)
    assert off.get("a") is None and len(off) == 0
    with pytest.raises(ValueError, match="0 or more"):
        BoundedCache(-1)


def test_a_fresh_owner_starts_empty_and_replaces_the_process_owner() -> None:
    used = caches.current()
    used.fd_answers.put(("search", "domain", "problem"), "answer")
    assert used.fd_answers.get(("search", "domain", "problem")) == "answer"
    new = caches.fresh({"fd_answers": 3})
    assert caches.current() is new and new is not used
    assert all(stats["entries"] == stats["hits"] == stats["misses"] == 0 for stats in new.stats().values())
    assert new.stats()["fd_answers"]["size"] == 3
    assert new.stats()["val_verdicts"]["size"] == caches.VAL_VERDICTS
    assert set(new.stats()) == {each.name for each in fields(Caches)}
    with pytest.raises(ValueError, match="no cache named fd_answer"):
        caches.fresh({"fd_answer": 3})


def test_clear_forgets_every_cache_of_an_owner() -> None:
    owner = caches.current()
    for _, cache in owner.named():
        cache.put(("key",), "value")
    owner.clear()
    assert all(stats["entries"] == 0 for stats in owner.stats().values())


def _plan_twice(catalog: Catalog) -> None:
    compiled = compile_task(build_task(example_model("paper/desk_lamp.yaml", catalog), catalog.get("desk_lamp")))
    for _ in range(2):
        assert solve(compiled.domain, compiled.problem, CONFIGS["fd"]).status is PlanStatus.SOLVED


def _validate_twice(catalog: Catalog) -> None:
    compiled = compile_task(build_task(example_model("paper/desk_lamp.yaml", catalog), catalog.get("desk_lamp")))
    plan = [("screw", ("light_bulb", "base_with_cables", "bulb_into_socket"))]
    for _ in range(2):
        assert val.validate(compiled.domain, compiled.problem, plan).verdict is val.ValVerdict.VALID


def _transfer_twice(catalog: Catalog) -> None:
    model = example_model("paper/desk_lamp.yaml", catalog)
    mapping = example_mapping("paper/flashlight_mapping.yaml", catalog)
    for _ in range(2):
        verdict = evaluate_transfer(model, mapping, catalog)
        assert verdict.verdict is Verdict.TRANSFERS and verdict.simulation is not None


def _robot_twice(catalog: Catalog) -> None:
    from causalplan.transfer.robot_verdict import robot_run

    board = parsed_object(PEG_BOARD)
    for _ in range(2):
        assert robot_run(board, steps("insert thin_peg board thin_peg_into_hole")).produces_goal


def _solids_twice(catalog: Catalog) -> None:
    from causalplan.sim.geometry import solids

    assert solids(catalog.get("flashlight")) is solids(catalog.get("flashlight"))


def _synthetic_twice(catalog: Catalog) -> None:
    from causalplan.comparison.synthetic import synthetic_object

    assert synthetic_object(12, 3) is synthetic_object(12, 3)


def _embed_twice(catalog: Catalog) -> None:
    from causalplan.consensus.embedding import embeddings

    assert embeddings(["spread the light"])["spread the light"] is embeddings(["spread the light"])["spread the light"]


REPEATS: dict[str, Callable[[Catalog], None]] = {
    "fd_answers": _plan_twice,
    "val_verdicts": _validate_twice,
    "simulations": _transfer_twice,
    "robot_runs": _robot_twice,
    "solids": _solids_twice,
    "synthetic_objects": _synthetic_twice,
    "label_embeddings": _embed_twice,
}
SLOW = {"robot_runs"}  # the Panda moves


def test_every_cache_of_the_owner_has_a_repeat_here() -> None:
    assert set(REPEATS) == {each.name for each in fields(Caches)}


@pytest.mark.parametrize(
    "name", [pytest.param(name, marks=[pytest.mark.slow] if name in SLOW else []) for name in REPEATS]
)
def test_each_cache_is_hit_on_a_repeat(name: str, catalog: Catalog, process_caches: Caches) -> None:
    REPEATS[name](catalog)
    counted = process_caches.stats()[name]
    assert counted["hits"] >= 1 and counted["entries"] >= 1, counted
    assert counted["misses"] == counted["entries"], counted  # every miss made one entry; the repeats hit


CACHE_TYPES = {
    "LRUCache", "TTLCache", "LFUCache", "FIFOCache", "RRCache", "TLRUCache", "Cache",
    "BoundedCache", "PictureCache", "ResultCache", "Caches", "ServiceCaches",
}  # fmt: skip
MEMO_DECORATORS = {"cache", "lru_cache", "cached"}
HELD_BY_A_MODULE = {
    "causalplan.caches._owner": "the process's one owner",
    "causalplan.service.pool.catalog.worker_catalog": "a worker's catalog, read once per folder list it serves",
}


def _decorator_name(node: ast.expr) -> str:
    target = node.func if isinstance(node, ast.Call) else node
    if isinstance(target, ast.Attribute):
        return target.attr
    return target.id if isinstance(target, ast.Name) else ""


def _makes_a_cache(value: ast.expr | None) -> bool:
    """Return whether ``value`` makes a cache (not one a lambda makes: a dataclass's default is each instance's)."""
    if value is None or isinstance(value, ast.Lambda):
        return False
    if isinstance(value, ast.Call) and _decorator_name(value) in CACHE_TYPES:
        return True
    return any(_makes_a_cache(child) for child in ast.iter_child_nodes(value) if isinstance(child, ast.expr))


def module_caches(path: Path, module: str) -> set[str]:
    """Return the caches a module holds: globals made of cache objects, and memoized functions with arguments.

    A memoized function without parameters is a value made once per process (a binary's path,
    a loaded module), not a cache of answers.
    """
    found = set()
    tree = ast.parse(path.read_text(encoding="utf-8"))
    scopes = [(module, tree.body)]
    scopes += [(f"{module}.{node.name}", node.body) for node in tree.body if isinstance(node, ast.ClassDef)]
    for scope, body in scopes:
        for statement in body:
            if isinstance(statement, ast.FunctionDef | ast.AsyncFunctionDef):
                arguments = statement.args
                has_parameters = bool(
                    arguments.posonlyargs or arguments.args or arguments.kwonlyargs or arguments.vararg
                )
                if has_parameters and any(_decorator_name(d) in MEMO_DECORATORS for d in statement.decorator_list):
                    found.add(f"{scope}.{statement.name}")
            elif isinstance(statement, ast.Assign | ast.AnnAssign) and _makes_a_cache(statement.value):
                targets = statement.targets if isinstance(statement, ast.Assign) else [statement.target]
                found.update(f"{scope}.{ast.unparse(target)}" for target in targets)
    return found


def test_no_module_holds_a_cache_but_the_owner() -> None:
    held = set()
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        held |= module_caches(path, ".".join(parts[:-1] if parts[-1] == "__init__" else parts))
    assert held == set(HELD_BY_A_MODULE)


def test_the_check_finds_a_module_level_cache(tmp_path: Path) -> None:
    source = tmp_path / "held.py"
    source.write_text(
        "from functools import cache, lru_cache\nfrom cachetools import LRUCache\n"
        "_kept: LRUCache[str, int] = LRUCache(8)\n"
        "@lru_cache(maxsize=4)\ndef answer(x: int) -> int:\n    return x\n"
        "@cache\ndef binary() -> str:\n    return 'path'\n"
        "class Holder:\n    @staticmethod\n    @cache\n    def made(x: int) -> int:\n        return x\n"
        "    shared = [LRUCache(2)]\n"
        "    each: LRUCache[str, int] = field(default_factory=lambda: LRUCache(2))\n",
        encoding="utf-8",
    )
    assert module_caches(source, "held") == {"held._kept", "held.answer", "held.Holder.made", "held.Holder.shared"}
