"""The targets' float comparison thresholds, learned while they run, for the ``compared`` mutator.

libFuzzer keeps a table of recent comparison operands (TORC) and its ``CMP`` mutators write
them into the input; AFL++'s CmpLog and Redqueen do the same with the operands of each
comparison site. Atheris feeds libFuzzer's table only for int, bytes and str comparisons, so a
branch on a float (``0.3 <= seed[0] < 0.31``, ``abs(q5) < 2e-3``, a calibration table's
edge) gives the search nothing to write. :class:`ComparedValues` is that table for floats.

It watches every comparison of two real numbers, at least one a float, that the instrumented
modules make (the float tracer's guard calls :meth:`ComparedValues.watch`; the modules are the
Python targets and the oracle, ``fuzzer.selection.instrument``). A site is a *threshold* once
one operand has kept one value while the other has taken two or more: the fixed one is the
threshold, whether it is a literal, a module constant or computed once (Atheris marks literal
operands, ``is_const``, but not in a chained comparison such as ``a <= x < b``). A site where
both operands vary, or that is solved, is settled and no longer watched, so the steady cost is
one set lookup per float comparison. A threshold site is *unsolved* until :data:`SOLVED_AFTER`
inputs have given the outcome its first comparison did not, each with a value more than
:data:`EDGE` past the threshold: the branch behind it has never been taken, or only by a few
inputs, or only at its very edge, which may not have shown what lies behind it.
:meth:`ComparedValues.pick` draws an unsolved site's threshold 3 times out of 4 (when there is
one), else any threshold; ``fuzzer.mutation.thresholds`` writes it, or a value just either side
of it, into a float field of the input.

Which field? Redqueen's input-to-state correspondence (Aschermann et al., NDSS 2019): an
operand a target compares is often a value of the input itself (a joint target the arm went
to, then the seed of the next IK). Each unsolved site keeps the last :data:`RECENT` distinct
values its varying operand took; :meth:`ComparedValues.crossing` names the thresholds whose
site compared a given value, and the mutator writes, into the leaf that holds it, the threshold
or a value past it on the side the site never compared a value on (the branch not yet taken;
:meth:`ComparedValues.crossings`).

Nothing here decides a verdict: the table only shapes mutations. The order of sites is the
order they were first seen, so a campaign with a given ``-seed`` draws the same values.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from random import Random
from typing import Final

UNSOLVED_PROBABILITY: Final = 0.75
""":meth:`ComparedValues.pick`: chance of an unsolved site's threshold (when there is one)."""
PATIENCE: Final = 1024
"""Observations after which a site whose operands never varied is no longer watched."""
MAX_SITES: Final = 4096
"""Sites watched at most (the rest are ignored): bounds the table's memory."""
RECENT: Final = 256
"""Distinct values of its varying operand an unsolved site remembers (the newest): enough to
still hold the values of most corpus inputs when one of them is mutated."""
SOLVED_AFTER: Final = 4
"""Inputs that must have given a site's other outcome (not the one its first comparison gave)
before the site is solved and no longer watched. The first input to take a branch often does
not show what lies behind it (a start state in a band reached by a ``/go``, whose trajectory
the oracle never sees, then no ``/plan``); the site's threshold keeps guiding the search a
little longer, as libFuzzer's hit-count buckets keep rewarding an edge taken more often."""
EDGE: Final = 1e-5
"""Relative distance (times ``max(1, |threshold|)``) within which an input that gave an ordering
comparison's site (``<``, ``<=``, ``>``, ``>=``) its other outcome does not count toward
:data:`SOLVED_AFTER`. The scenario oracle judges an IK step's divergence ill-conditioned when
moving the state by up to the campaign tolerance (1e-6) changes a target's answer
(``Evaluator._scenario_ik``), so an input that crossed a band's edge by a float or by 1e-6 (two
of the three crossings of ``fuzzer.mutation.thresholds._past``) shows nothing behind it:
``ik_seed_band``'s site ``seed[0] < 0.31`` was solved by four inputs at 0.30999999999999994,
each judged ill-conditioned, and its campaign (seed 28) never detected the bug, although the
same inputs with 0.305 do (docs/benchmarks-log.md, nineteenth session)."""
MEMORY: Final = 4096
"""Inputs whose operands at the unsolved sites are remembered (the most recently run or
mutated), for :meth:`ComparedValues.operands`."""

_FIRST_A, _FIRST_B, _A_VARIES, _B_VARIES, _FIRST_OUTCOME, _COUNT, _FLIPS = range(7)


class ComparedValues:
    """Float comparison sites of the instrumented modules and their thresholds.

    Attributes
    ----------
    done : set of int
        Sites no longer watched (settled, or watched :data:`PATIENCE` times without a varying
        operand); the guard skips them before calling :meth:`watch`.
    thresholds : dict of int to float
        Site -> its fixed operand (finite), in the order first seen.
    """

    def __init__(self) -> None:
        self.done: set[int] = set()
        self.thresholds: dict[int, float] = {}
        self._state: dict[int, list[float | bool | int]] = {}
        self._recent: dict[int, dict[float, None]] = {}
        self._running: dict[int, tuple[float, float]] = {}
        self._memory: OrderedDict[bytes, dict[int, tuple[float, float]]] = OrderedDict()
        self._parent: dict[int, tuple[float, float]] = {}
        self._focus: int | None = None
        """The one site the input being mutated aims at (the input-to-state stage's), or None."""
        self._flipped: set[int] = set()
        """Sites where the running input gave the other outcome (counted once per input)."""

    def watch(self, site: int, a: float, b: float, result: object, ordered: bool = True) -> None:
        """Record one comparison ``a <op> b`` at ``site`` that gave ``result``; ``ordered``:
        ``<op>`` is ``<``, ``<=``, ``>`` or ``>=`` (else ``==`` or ``!=``, whose other outcome
        lies only on the threshold: :data:`EDGE` does not apply)."""
        state = self._state.get(site)
        outcome = 2 if result else 1
        if site not in self._running:  # this input's first comparison there, whichever operand varies
            self._running[site] = (a, b)
        if state is None:
            if len(self._state) < MAX_SITES:
                self._state[site] = [a, b, False, False, outcome, 1, 0]
            else:
                self.done.add(site)
            return
        if not state[_A_VARIES] and a != state[_FIRST_A]:
            state[_A_VARIES] = True
        if not state[_B_VARIES] and b != state[_FIRST_B]:
            state[_B_VARIES] = True
        a_varies, b_varies = state[_A_VARIES], state[_B_VARIES]
        flipped = outcome != state[_FIRST_OUTCOME] and site not in self._flipped
        if flipped and (not ordered or _clear(state, a, b)):  # a flip at an ordering's edge: no count
            self._flipped.add(site)
            state[_FLIPS] = int(state[_FLIPS]) + 1
        state[_COUNT] = int(state[_COUNT]) + 1
        if a_varies and b_varies:  # both operands move with the input: no threshold here
            self.thresholds.pop(site, None)
            self._settle(site)
        elif a_varies or b_varies:
            fixed = float(state[_FIRST_B] if a_varies else state[_FIRST_A])
            if math.isfinite(fixed):
                self.thresholds[site] = fixed
            if int(state[_FLIPS]) >= SOLVED_AFTER:  # both branches taken, often enough: solved
                self._settle(site)
                return
            recent = self._recent.get(site)
            if recent is None:  # the first value it took counts too
                recent = self._recent[site] = {}
                _remember(recent, float(state[_FIRST_A] if a_varies else state[_FIRST_B]))
            _remember(recent, float(a if a_varies else b))
        elif int(state[_COUNT]) >= PATIENCE:
            self._settle(site)

    def _settle(self, site: int) -> None:
        self.done.add(site)
        self._recent.pop(site, None)

    def unsolved(self) -> list[float]:
        """Thresholds of the sites not yet solved (:data:`SOLVED_AFTER`)."""
        return [value for site, value in self.thresholds.items() if not self._solved(site)]

    def _solved(self, site: int) -> bool:
        return int(self._state[site][_FLIPS]) >= SOLVED_AFTER

    def is_unsolved(self, site: int) -> bool:
        """Whether ``site`` is a threshold site not yet solved (:data:`SOLVED_AFTER`)."""
        return site in self.thresholds and not self._solved(site)

    def crossing(self, value: float) -> list[float]:
        """Thresholds of the unsolved sites that recently compared ``value`` (one of the last
        :data:`RECENT` values of their varying operand), in the order the sites were first seen.
        None for 0.0, the default of every field, which matches by coincidence."""
        return [threshold for threshold, _ in self.crossings(value)]

    def begin(self) -> None:
        """An input starts running: what the unsolved sites compare from now on is its own."""
        self._running = {}
        self._flipped = set()

    def end(self, key: bytes) -> None:
        """The input ``key`` (a digest of its bytes) has run: remember the operands of the
        first comparison it made at each site still watched (the newest :data:`MEMORY` inputs),
        the first input to reach a site included, although the site's threshold is known
        only once another input compares a different value there."""
        done = self.done
        running = {site: pair for site, pair in self._running.items() if site not in done}
        if running:
            self._memory[key] = running
            self._memory.move_to_end(key)
            if len(self._memory) > MEMORY:
                self._memory.popitem(last=False)
        else:
            self._memory.pop(key, None)
        self._running = {}
        self._flipped = set()

    def select(self, key: bytes, focus: int | None = None) -> None:
        """The input ``key`` is about to be mutated: :meth:`operands` are now its. With
        ``focus`` (a site, from the input-to-state stage, ``fuzzer.selection.i2s``) the mutation
        aims at that site alone: :meth:`operands`, :meth:`crossings` and :meth:`pick` give only
        its threshold, until the next :meth:`select`."""
        self._focus = focus
        self._parent = self._memory.get(key, {})
        if self._parent:
            self._memory.move_to_end(key)

    def operands(self) -> list[tuple[float, float, float]]:
        """For the input being mutated (:meth:`select`), each still unsolved threshold site it
        reached off its threshold: (threshold, the value it compared there, the way from that
        value to the branch never taken: +1.0 up, -1.0 down; from a value within :data:`EDGE`
        of the threshold, the way to the side no value clear of it was compared on, when there is
        one: past a band's edge by a float, deeper into the band), in the order that input reached
        them (a value on the threshold is left to :meth:`crossings`, which knows the way; a
        value of 0 is left out: no scaling moves it, and it would queue an input for the
        input-to-state stage, ``fuzzer.selection.i2s``, that the stage cannot change).
        A value computed from the input (a ratio of two scaling factors, a distance) rather than
        held by a leaf: ``fuzzer.mutation.leaves.apply_compared`` scales a leaf by threshold /
        value, which puts a value proportional to that leaf right past the threshold."""
        return [(t, v, w) for site, t, v, w in self._operands(self._parent) if self._focus in (None, site)]

    def operands_of(self, key: bytes) -> list[tuple[float, float, float]]:
        """:meth:`operands` of the remembered input ``key``, without selecting it (whatever the
        focus)."""
        return [(t, v, w) for _, t, v, w in self._operands(self._memory.get(key, {}))]

    def sites_of(self, key: bytes) -> list[int]:
        """The sites of :meth:`operands_of`, in the order the input reached them."""
        return [site for site, *_ in self._operands(self._memory.get(key, {}))]

    def _operands(self, entry: dict[int, tuple[float, float]]) -> list[tuple[int, float, float, float]]:
        out = []
        for site, (a, b) in entry.items():
            threshold = self.thresholds.get(site)
            if threshold is None or self._solved(site):
                continue
            value = float(a if self._state[site][_A_VARIES] else b)
            if value != threshold and value != 0.0:  # 0 is every field's default; no factor moves it
                way = 1.0 if value < threshold else -1.0
                if abs(value - threshold) <= edge(threshold):
                    way = self._new_side(site, threshold) or way  # at the edge: deeper past it
                out.append((site, threshold, value, way))
        return out

    def crossings(self, value: float) -> list[tuple[float, float]]:
        """``crossing``'s thresholds, each with the way (+1.0 up, -1.0 down) from it to the side
        its site never compared a value on: an unsolved ``<``, ``<=``, ``>`` or ``>=`` that no
        input has crossed yet gave one outcome, so the values it saw lie on one side of the
        threshold, or on it. From a value *on* the threshold that side is the one away from the
        site's other values (``x < t`` seen false with x = t and x = 1.5: down), which the value
        alone cannot tell. Values within :data:`EDGE` of the threshold count on neither side (a
        site crossed only at its edge is not solved either): ``x < 0.31`` seen false with 0.9 and
        true with 0.30999999999999994 still gives down, from either value. 0.0 when the site saw
        no value clear of its threshold, or such values on both sides (``==``, ``!=``, a site
        fewer than :data:`SOLVED_AFTER` inputs crossed): ``_past`` then goes away from the leaf's
        value."""
        if value == 0.0:
            return []
        out = []
        for site, threshold in self.thresholds.items():
            if self._focus is not None and site != self._focus:
                continue
            if value in self._recent.get(site, ()) and not self._solved(site):
                out.append((threshold, self._new_side(site, threshold)))
        return out

    def _new_side(self, site: int, threshold: float) -> float:
        """The way (+1.0 up, -1.0 down) from ``threshold`` to the side on which ``site`` compared
        no recent value clear of it (farther than :data:`EDGE`), or 0.0 (values clear of it on
        both sides, or on neither). A value at the edge counts on neither side, as it does not
        count toward :data:`SOLVED_AFTER`: past a band's edge by a float, the side is still new."""
        recent = self._recent.get(site, ())
        near = edge(threshold)
        below = any(v < threshold - near for v in recent)
        above = any(v > threshold + near for v in recent)
        return 0.0 if below == above else (1.0 if below else -1.0)

    def __len__(self) -> int:
        return len(self.thresholds)

    def pick(self, rng: Random) -> float | None:
        """A threshold (an unsolved one with probability :data:`UNSOLVED_PROBABILITY`; the
        focus site's, :meth:`select`, while it is unsolved), or None before any site has one."""
        if not self.thresholds:
            return None
        if self._focus is not None and self.is_unsolved(self._focus):
            return self.thresholds[self._focus]
        unsolved = self.unsolved()
        if unsolved and rng.random() < UNSOLVED_PROBABILITY:
            return rng.choice(unsolved)
        return rng.choice(list(self.thresholds.values()))


def edge(threshold: float) -> float:
    """How close to ``threshold`` a value is at its edge: :data:`EDGE` times
    ``max(1, |threshold|)``."""
    return EDGE * max(1.0, abs(threshold))


def _clear(state: list[float | bool | int], a: float, b: float) -> bool:
    """Whether the varying operand of a comparison ``a <op> b`` lies farther than :func:`edge`
    from the site's fixed one; True while neither or both have varied (no one threshold to
    measure from)."""
    if state[_A_VARIES] == state[_B_VARIES]:
        return True
    fixed, value = (float(state[_FIRST_B]), a) if state[_A_VARIES] else (float(state[_FIRST_A]), b)
    return not abs(value - fixed) <= edge(fixed)


def _remember(recent: dict[float, None], value: float) -> None:
    """Add ``value`` (finite) to a site's recent operand values, forgetting the oldest past
    :data:`RECENT`."""
    if value not in recent and math.isfinite(value):
        recent[value] = None
        if len(recent) > RECENT:
            del recent[next(iter(recent))]
