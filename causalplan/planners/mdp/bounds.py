"""An admissible bound for the heuristic search: no policy does better than this from a state.

Think of each fit's outcome as drawn in advance (it is attempted at most once: afterwards it
is made or unusable). A part is *necessary* when the goal cannot hold without it even if every
other usable fit succeeded (the dead-end test with that part kept out). Every successful run
attaches every necessary part. A failed attempt makes its connectors unusable, so a part is
tried at most once per connector of its own, and at best with that connector's most reliable
usable fit: success needs, for each necessary part, one of these at most one-per-connector
draws to succeed. Giving each (part, connector) one draw makes these events independent across
parts, with probability ``q = 1 - prod(1 - max p)`` over the part's connectors. Hence:

* ``P(success) <= prod q`` over the necessary parts not yet attached;
* every run that touches a necessary part spends an attempt on it, and a run that gives up
  early still ends at -1, so the value ``2 P - 1 - cost E[attempts]`` is at most that of the
  best *sequential test* of those parts: test them one at a time, stop at the first failure,
  or do not start (value -1). A part whose usable fits all go onto one part not yet attached
  is tested after that part (an out-forest of precedences). Two carriers of which one is
  needed (an OR of the rules: the goal fails without both) are one test, passed if either
  is. A route onto a holder that must join first also needs that holder (and its own single
  holder, and so on) to join: their chances multiply the route's. A holder that several
  tests' routes go through is counted in the first of them only (the others' walks stop
  before it), so the tests draw on disjoint parts and their chances still multiply. The
  cheapest order of tests with forest precedences is found by merging the best ratio
  ``(1 - q) / expected cost`` into its parent (Horn's rule, as in Garey 1973).

The bound is exact at the goal (1) and at dead ends (-1), and exact whenever the remaining
parts have one fit each and can be attached in the cheapest order, which is what lets the
search skip the orders that do not matter.
"""

from __future__ import annotations

import heapq
from dataclasses import dataclass

from causalplan.planners.mdp.model import CompiledMdp, single_bits


@dataclass(frozen=True)
class Bound:
    """Upper bounds at a state: on the value, and on the success probability of any policy."""

    value: float
    success: float
    necessary: int  # part bits of the necessary parts not yet attached (passed on to the children)
    dead_end: bool
    goal: bool


GOAL = Bound(1.0, 1.0, 0, False, True)
DEAD_END = Bound(-1.0, 0.0, 0, True, False)


def cheapest_test_cost(chances: dict[int, float], parent: dict[int, int]) -> float:
    """Return the least expected number of tests that find a failure or pass them all.

    ``chances`` maps each test to its pass probability; ``parent`` maps a test to the test
    that must come before it (a forest). Tests run until one fails.
    """
    head = {node: node for node in chances}  # union-find: node -> head of its group

    def find(node: int) -> int:
        while head[node] != node:
            head[node] = head[head[node]]
            node = head[node]
        return node

    passing = dict(chances)
    cost = {node: 1.0 for node in chances}
    version = {node: 0 for node in chances}
    scheduled: set[int] = set()
    root_passing, root_cost = 1.0, 0.0
    heap = [(-(1.0 - q), node, 0) for node, q in chances.items()]
    heapq.heapify(heap)
    while heap:
        _, node, seen = heapq.heappop(heap)
        if head[node] != node or version[node] != seen or node in scheduled:
            continue
        up = parent.get(node)
        group = None if up is None else find(up)
        if group is None or group in scheduled:  # nothing left before it: it goes next
            root_cost += root_passing * cost[node]
            root_passing *= passing[node]
            scheduled.add(node)
            continue
        cost[group] += passing[group] * cost[node]
        passing[group] *= passing[node]
        head[node] = group
        version[group] += 1
        heapq.heappush(heap, (-(1.0 - passing[group]) / cost[group], group, version[group]))
    return root_cost


def _usable_fits(compiled: CompiledMdp, bit: int, unusable: int, reach: int) -> list[int]:
    return [
        index
        for index in compiled.fits_of_part.get(bit, ())
        if not unusable >> index & 1 and compiled.fixed[index] & reach
    ]


def _chance(compiled: CompiledMdp, bit: int, unusable: int, reach: int) -> float:
    """Return the bound on the chance that the part ever joins: one draw per connector of its own."""
    best_by_connector: dict[str, float] = {}
    for index in _usable_fits(compiled, bit, unusable, reach):
        connector = compiled.moving_connector[index]
        best_by_connector[connector] = max(best_by_connector.get(connector, 0.0), compiled.probability[index])
    failing = 1.0
    for chance in best_by_connector.values():
        failing *= 1.0 - chance
    return 1.0 - failing


def _chained_chance(compiled: CompiledMdp, bit: int, settled: int, unusable: int, reach: int) -> tuple[float, int]:
    """Return a part's chance bound with each route's holder chain counted, and the chain's parts.

    A route onto a holder that is not ``settled`` (attached, or counted as necessary) needs
    that holder to join first: its chance, and its own holder's while it has only one.
    Per connector of the part one draw serves every route; the holders' chances are of
    increasing events, so a union of them is bounded by one minus the product of the misses
    (Harris-FKG).
    """
    routes: dict[str, list[tuple[float, float]]] = {}
    chain = 0
    for index in _usable_fits(compiled, bit, unusable, reach):
        factor, holder, walked = 1.0, compiled.fixed[index], 0
        while not holder & (settled | walked):
            walked |= holder
            factor *= _chance(compiled, holder, unusable, reach)
            holders = {compiled.fixed[above] for above in _usable_fits(compiled, holder, unusable, reach)}
            if len(holders) != 1:
                break
            holder = holders.pop()
        chain |= walked
        routes.setdefault(compiled.moving_connector[index], []).append((compiled.probability[index], factor))
    failing = 1.0
    for options in routes.values():
        # One draw W serves the connector: it succeeds when W < the best p among the routes
        # whose holders joined, so P <= sum over p's layers of P(some route that good is open).
        options.sort(reverse=True)
        chance, closed = 0.0, 1.0
        for position, (probability, open_chance) in enumerate(options):
            closed *= 1.0 - open_chance
            below = options[position + 1][0] if position + 1 < len(options) else 0.0
            chance += (probability - below) * (1.0 - closed)
        failing *= 1.0 - chance
    return 1.0 - failing, chain


def _lost_without(compiled: CompiledMdp, parts: int, unusable: int, reach: int) -> dict[int, int]:
    """Return, for each reachable part not attached, the parts that cannot join without it (itself included).

    These are the parts it dominates in the graph of usable fits from the attached parts
    (iterative dominator sets as bit masks, visited in breadth-first order), the same answer
    as ``reachable_parts(..., without=part)`` for all parts at once.
    """
    order: list[int] = []
    seen, frontier = parts, parts
    while frontier:
        new = 0
        for holder in single_bits(frontier):
            for index in compiled.fits_onto_part.get(holder, ()):
                moving = compiled.moving[index]
                if not unusable >> index & 1 and not (seen | new) & moving:
                    new |= moving
                    order.append(moving)
        seen |= new
        frontier = new
    dominators = {bit: reach for bit in order}
    changed = True
    while changed:
        changed = False
        for bit in order:
            common = reach
            for index in compiled.fits_of_part.get(bit, ()):
                holder = compiled.fixed[index]
                if not unusable >> index & 1 and holder & reach:
                    common &= 0 if holder & parts else dominators[holder]
            common |= bit
            if common != dominators[bit]:
                dominators[bit] = common
                changed = True
    lost = {bit: 0 for bit in order}
    for bit, above in dominators.items():
        for dominator in single_bits(above):
            lost[dominator] |= bit
    return lost


def _cutting_pairs(compiled: CompiledMdp) -> list[tuple[int, int]]:
    """Return pairs of carriers, neither necessary at the start, without both of which the goal cannot hold."""
    if compiled.cutting_pairs is None:
        parts = compiled.base
        reach = compiled.reachable_parts(parts, 0)
        carriers = [
            bit
            for bit in single_bits(reach & ~parts)
            if bit in compiled.functions_of_part
            and compiled.goal_holds(compiled.reachable_parts(parts, 0, without=bit))
        ]
        compiled.cutting_pairs = [
            (first, second)
            for position, first in enumerate(carriers)
            for second in carriers[position + 1 :]
            if not compiled.goal_holds(compiled.reachable_parts(parts, 0, without=first | second))
        ]
    return compiled.cutting_pairs


def bound(compiled: CompiledMdp, parts: int, unusable: int, known_necessary: int, step_cost: float) -> Bound:
    """Return the bounds at the state with ``parts`` assembled and ``unusable`` fits.

    ``known_necessary`` are parts known to be necessary at a predecessor (still necessary
    here, as fewer fits remain); only the others are tested.
    """
    if compiled.goal_holds(parts):
        return GOAL
    reach = compiled.reachable_parts(parts, unusable)
    if not compiled.goal_holds(reach):
        return DEAD_END
    necessary = known_necessary & reach & ~parts
    candidates = reach & ~parts & ~necessary
    if candidates:
        lost = _lost_without(compiled, parts, unusable, reach)
        for bit in single_bits(candidates):
            if not compiled.goal_holds(reach & ~lost[bit]):
                necessary |= bit
    parent: dict[int, int] = {}
    for bit in single_bits(necessary):
        holders = {compiled.fixed[index] for index in _usable_fits(compiled, bit, unusable, reach)}
        if len(holders) == 1 and (holder := holders.pop()) & necessary:
            parent[bit] = holder
    # Pairs of carriers of which one is needed (an OR in the rules): one test that passes if
    # either does. Found once at the start; a pair that cuts the goal there cuts it everywhere.
    chances: dict[int, float] = {}
    paired = 0
    for first, second in _cutting_pairs(compiled):
        if (first | second) & (parts | necessary | paired) or not (first | second) & reach:
            continue
        miss = (1.0 - _chance(compiled, first, unusable, reach)) * (1.0 - _chance(compiled, second, unusable, reach))
        chances[first] = 1.0 - miss
        paired |= first | second
    # A necessary part's routes through holders that must join first count those holders'
    # chances. Each holder is counted once: the first test (in bit order) whose walk reaches
    # it keeps it, later walks stop before it, so the tests draw on disjoint parts and stay
    # independent (a shared holder counted in no test was the loose spot before).
    claimed = paired
    if compiled.holders_counted_once:
        for bit in single_bits(necessary):
            chances[bit], chain = _chained_chance(compiled, bit, parts | necessary | claimed, unusable, reach)
            claimed |= chain
    else:  # the earlier bound, kept to measure the difference (benchmarks/mdp.py)
        chained = {
            bit: _chained_chance(compiled, bit, parts | necessary, unusable, reach) for bit in single_bits(necessary)
        }
        shared, seen = paired, 0
        for _, chain in chained.values():
            shared |= seen & chain
            seen |= chain
        for bit, (chance, chain) in chained.items():
            if chain & shared:  # walk again, stopping before the holders others draw on too
                chance = _chained_chance(compiled, bit, parts | necessary | shared, unusable, reach)[0]
            chances[bit] = chance
    success = 1.0
    for chance in chances.values():
        success *= chance
    value = max(-1.0, 2.0 * success - 1.0 - step_cost * cheapest_test_cost(chances, parent))
    return Bound(value, success, necessary, False, False)
