"""An exact solver that splits the problem again after every attempt: attached parts couple nothing.

The base couples nothing because it is always there (``components.py``); the same holds for
every part once attached. So after an attempt the rest of the problem often falls apart:
once a holder is on, the subtrees on its sockets are independent. This solver memoises
*residual sub-problems* (the open fits of a group, the goal nodes it must make, and the
attached parts they depend on), not whole states: a tree of holders is solved as a product
of small pieces, where the state graph has exponentially many states.

At each residual it tries the applicable fits of its group (one clean fit only, where forcing
applies: ``Splitter.forced``; fits that can no longer help are dropped: ``Splitter.useful``),
splits each outcome's residual
into independent groups, and combines them: the success probability is the product (proved
as for the components), and the groups run one after another, whole, in decreasing
``(1 - success) / attempts`` (Smith's ratio rule), which gives the fewest expected attempts
among such orders. The attempt kept is the most reliable, then the one with the fewest
expected attempts. The policy is the *agenda* of groups: ``decide`` replays the outcomes of a
state from the start, so it follows exactly the policy whose figures were computed.

It is exhaustive inside a group that does not split, so it stops (``SplitStopped``) beyond its
residual budget or at the time limit. ``split_solve.py`` runs its passes and turns the memo into a policy.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

from causalplan.planners.mdp.components import goal_conjuncts
from causalplan.planners.mdp.model import CompiledMdp

MAX_RESIDUALS = 400_000
"""The residuals one pass may memoise before it stops (``SplitStopped``): it bounds the memory."""
FINER_RESIDUALS = MAX_RESIDUALS // 4
"""A finer pass's budget (``split_solve.FINER_PASSES``): it only looks for fewer attempts, so it gives up sooner."""
TIE = 1e-12

Key = tuple[int, tuple[str, ...], int]
"""A residual: its open fits (a mask), the goal nodes it must make, the attached parts it depends on."""


@dataclass(frozen=True)
class Entry:
    success: float
    attempts: float
    action: int  # -1: done (its goal holds) or dead
    on_success: tuple[Key, ...] = ()
    on_failure: tuple[Key, ...] = ()


def _ratio(entry: Entry) -> float:
    """Smith's ratio: the chance of failing per expected attempt (a dead residual first, a sure one last)."""
    if entry.attempts == 0.0:
        return math.inf if entry.success < 1.0 else 0.0
    return (1.0 - entry.success) / entry.attempts


class SplitStopped(Exception):
    """Raised when the residual budget or the time is exhausted."""


class Splitter:
    def __init__(self, compiled: CompiledMdp, deadline: float, force: int = 2, oracle: Splitter | None = None) -> None:
        self.c = compiled
        self.deadline = deadline
        self.memo: dict[Key, Entry] = {}
        self.force = force  # which clean attempts are forced: 2 all, 1 the necessary parts', 0 none
        self.oracle = oracle  # gives each residual's exact success, the bound (a pass forcing every clean attempt)
        self.max_residuals = MAX_RESIDUALS if oracle is None else FINER_RESIDUALS
        conjuncts = goal_conjuncts(compiled) or {}
        part_bit = {part_id: 1 << index for index, part_id in enumerate(compiled.task.obj.part_ids)}
        keys = compiled.goal_keys or tuple(conjuncts) or (compiled.task.goal_key,)
        self.support = {key: sum(part_bit[part] for part in conjuncts.get(key, frozenset(part_bit))) for key in keys}
        self.all_fits = (1 << len(compiled.fits)) - 1
        self.holds_cache: dict[tuple[int, str], bool] = {}
        self.chance_cache: dict[int, float] = {}
        count = len(compiled.fits)
        self.fits_of_bit: dict[int, int] = {}
        for index in range(count):
            self.fits_of_bit[compiled.moving[index]] = self.fits_of_bit.get(compiled.moving[index], 0) | 1 << index
        self.neighbours = [
            self.fits_of_bit[compiled.moving[index]]
            | compiled.taken_on_success[index]
            | compiled.taken_on_failure[index]
            | self.fits_of_bit.get(compiled.fixed[index], 0)  # the fits attaching its holder
            | sum(1 << other for other in range(count) if compiled.fixed[other] == compiled.moving[index])
            for index in range(count)
        ]
        for index in range(count):  # a fit that blocks another is joined to it from either side
            others = self.neighbours[index]
            while others:
                low = others & -others
                others ^= low
                self.neighbours[low.bit_length() - 1] |= 1 << index
        self.key_fits = {
            key: sum(1 << index for index in range(count) if compiled.moving[index] & support)
            for key, support in self.support.items()
        }

    def holds(self, parts: int, key: str) -> bool:
        relevant = parts & self.support[key]
        known = self.holds_cache.get((relevant, key))
        if known is None:
            known = key in self.c.active(relevant)
            self.holds_cache[(relevant, key)] = known
        return known

    def groups(self, parts: int, unusable: int, keys: tuple[str, ...], within: int) -> tuple[Key, ...] | None:
        """Return the independent residuals of ``within``'s fits after an outcome; None when one cannot succeed.

        A flood fill over bit masks: fits are joined when they attach one part, when one attaches
        the other's holder (an attached holder has no open fits left to join), when they exclude
        each other, or when one goal node still waiting depends on both.
        """
        c = self.c
        waiting = tuple(key for key in keys if not self.holds(parts, key))
        if not waiting:
            return ()
        useful = self.useful(parts, within & ~unusable & ~self.fits_moving_into(parts), waiting)
        if useful is None or any(not self.key_fits[key] & useful for key in waiting):
            return None  # nothing open can make this goal node
        open_mask = useful
        found: list[Key] = []
        remaining = open_mask
        while remaining:
            group = frontier = remaining & -remaining
            while frontier:
                reached = 0
                while frontier:
                    low = frontier & -frontier
                    frontier ^= low
                    reached |= self.neighbours[low.bit_length() - 1]
                for key in waiting:
                    if reached & self.key_fits[key] or group & self.key_fits[key]:
                        reached |= self.key_fits[key]
                frontier = reached & open_mask & ~group
                group |= frontier
            remaining &= ~group
            own = tuple(key for key in waiting if group & self.key_fits[key])
            if own:
                depends = 0
                bits = group
                while bits:
                    low = bits & -bits
                    bits ^= low
                    depends |= c.fixed[low.bit_length() - 1]
                for key in own:
                    depends |= self.support[key]
                found.append((group, own, parts & depends))
        return tuple(sorted(found))

    def useful(self, parts: int, open_mask: int, waiting: tuple[str, ...]) -> int | None:
        """Return the open fits that can still help a waiting goal node; None when one can no longer hold.

        A fit whose holder can never join is dropped, and so is one whose part neither carries
        a waiting goal node's function nor holds (by open fits) a part that leads to one:
        attaching such a part only takes connectors, so no policy loses by never trying it.
        Dropping them lets the rest fall apart into smaller groups, and makes residuals that
        differ only in dead fits one.
        """
        c = self.c
        reach = c.reachable_parts(parts, self.all_fits & ~open_mask)
        if not all(self.holds(reach, key) for key in waiting):
            return None
        kept, bits = 0, open_mask
        while bits:
            low = bits & -bits
            bits ^= low
            if c.fixed[low.bit_length() - 1] & reach:
                kept |= low
        needed = 0
        for key in waiting:
            needed |= self.support[key]
        needed &= reach & ~parts
        frontier = needed
        while frontier:
            low = frontier & -frontier
            frontier ^= low
            holders = self.fits_of_bit.get(low, 0) & kept
            while holders:
                fit = holders & -holders
                holders ^= fit
                holder = c.fixed[fit.bit_length() - 1]
                if not (holder & (needed | parts)):
                    needed |= holder
                    frontier |= holder
        return kept & self.fits_moving_into(needed)

    def fits_moving_into(self, parts: int) -> int:
        """Return the fits whose moving part is among ``parts`` (attached: nothing left to attach)."""
        mask = 0
        bits = parts
        while bits:
            low = bits & -bits
            bits ^= low
            mask |= self.fits_of_bit.get(low, 0)
        return mask

    def combined(self, residuals: tuple[Key, ...] | None) -> tuple[float, float, tuple[Key, ...]]:
        """Return the success, expected attempts and order (by ratio) of running ``residuals`` one after another."""
        if residuals is None:
            return 0.0, 0.0, ()
        solved = [(self.solve(residual), residual) for residual in residuals]
        solved.sort(key=lambda item: -_ratio(item[0]))
        success, attempts = 1.0, 0.0
        for entry, _ in solved:
            attempts += success * entry.attempts
            success *= entry.success
        return success, attempts, tuple(residual for _, residual in solved)

    def upper(self, residuals: tuple[Key, ...] | None) -> float:
        """Return an upper bound on the success of running ``residuals`` (independent, so a product)."""
        if residuals is None:
            return 0.0
        bound = 1.0
        for residual in residuals:
            if self.oracle is not None:
                bound *= self.oracle.solve(residual).success  # exact: only equally reliable options are solved
                continue
            known = self.memo.get(residual)
            bound *= known.success if known is not None else self.residual_upper(residual)
        return bound

    def residual_upper(self, residual: Key) -> float:
        """Return an upper bound on one residual's success.

        A goal node still waiting needs one more of the parts under it to join, and a part joins
        only by one of its own draws (one per connector of its own, at best its most reliable
        open fit's). Draws of different parts are independent, so over goal nodes with disjoint
        parts the chances multiply. (Counting the necessary parts on the way too made the bound
        tighter but pruned no more residuals once clean attempts are forced, at six times the cost.)
        """
        within, keys, parts = residual
        bound, counted = 1.0, 0
        for key in keys:
            carriers = self.support[key] & ~parts
            if carriers & counted:
                continue
            counted |= carriers
            missing, bits = 1.0, carriers
            while bits:
                low = bits & -bits
                bits ^= low
                missing *= 1.0 - self.chance(low, within)
            bound *= 1.0 - missing
        return bound

    def chance(self, part: int, within: int) -> float:
        """Return the best chance that ``part`` joins by ``within``'s fits: one draw per connector of its own."""
        fits = within & self.fits_of_bit.get(part, 0)
        known = self.chance_cache.get(fits)
        if known is None:
            best: dict[str, float] = {}
            bits = fits
            while bits:
                low = bits & -bits
                bits ^= low
                index = low.bit_length() - 1
                connector = self.c.moving_connector[index]
                best[connector] = max(best.get(connector, 0.0), self.c.probability[index])
            known = 1.0 - math.prod(1.0 - chance for chance in best.values())
            self.chance_cache[fits] = known
        return known

    def forced(self, applicable: list[int], parts: int, unusable: int, keys: tuple[str, ...], within: int) -> int:
        """Return an attempt that loses no success probability when taken first (-1: none).

        A fit is *clean* when no usable fit of its part is more reliable and neither its success
        nor its failure takes any open fit but its part's own. Attempting a clean fit now is as
        reliable as any policy (docs/planners.md, "Forced attempts"): its outcome changes nothing
        for the other fits, so any policy can be replayed after it, and having its part earlier
        only adds options. ``force`` says which are forced: 2 every clean fit, 1 the necessary
        parts' only, 0 none. Necessary parts (a waiting goal node cannot hold without them even if every
        other open fit succeeded) go first, the least likely first (the most likely to end the
        run, Smith's rule for single tests); then the other clean fits, the most likely first.
        """
        c = self.c
        open_fits = within & ~unusable
        best, best_rank = -1, (2, 0.0)
        if not self.force:
            return best
        for index in applicable:
            own = self.fits_of_bit[c.moving[index]]
            taken = (c.taken_on_success[index] | c.taken_on_failure[index]) & open_fits & ~own
            p = c.probability[index]
            if taken or p < self.best_chance(open_fits & own):
                continue
            rank = (1, -p)
            if p < best_rank[1] or best_rank[0] > 0:
                reach = c.reachable_parts(parts, unusable, without=c.moving[index])
                if not all(self.holds(reach, key) for key in keys):
                    rank = (0, p)
            if rank < best_rank and rank[0] < self.force:
                best, best_rank = index, rank
        return best

    def best_chance(self, fits: int) -> float:
        """Return the highest probability among ``fits``."""
        best, bits = 0.0, fits
        while bits:
            low = bits & -bits
            bits ^= low
            best = max(best, self.c.probability[low.bit_length() - 1])
        return best

    def solve(self, residual: Key) -> Entry:
        known = self.memo.get(residual)
        if known is not None:
            return known
        if len(self.memo) >= self.max_residuals or time.monotonic() > self.deadline:
            raise SplitStopped
        within, keys, parts = residual
        c = self.c
        unusable = self.all_fits & ~within
        reach = c.reachable_parts(parts, unusable)
        best = Entry(0.0, 0.0, -1)
        if all(self.holds(reach, key) for key in keys):
            options = []
            applicable = c.applicable(parts, unusable)
            forced = self.forced(applicable, parts, unusable, keys, within)
            for index in applicable if forced < 0 else (forced,):
                p = c.probability[index]
                won = self.groups(parts | c.moving[index], unusable | c.taken_on_success[index], keys, within)
                lost = self.groups(parts, unusable | c.taken_on_failure[index], keys, within) if p < 1.0 else None
                options.append((p * self.upper(won) + (1 - p) * self.upper(lost), index, won, lost))
            options.sort(key=lambda option: (-option[0], option[1]))
            for upper, index, won, lost in options:
                if best.action >= 0 and upper < best.success - TIE:
                    break  # no later option can be as reliable (branch and bound)
                p = c.probability[index]
                s_success, a_success, after_success = self.combined(won)
                after_failure: tuple[Key, ...] = ()
                s_failure, a_failure = 0.0, 0.0
                if p < 1.0:
                    s_failure, a_failure, after_failure = self.combined(lost)
                success = p * s_success + (1 - p) * s_failure
                attempts = 1 + p * a_success + (1 - p) * a_failure
                if (
                    best.action < 0
                    or success > best.success + TIE
                    or (success > best.success - TIE and attempts < best.attempts - TIE)
                    or (success > best.success - TIE and attempts < best.attempts + TIE and index < best.action)
                ):
                    best = Entry(success, attempts, index, after_success, after_failure)
        if best.success == 0.0:
            best = Entry(0.0, 0.0, -1)  # nothing left to gain: the run ends here
        self.memo[residual] = best
        return best
