"""The dry run's plan (``fuzzer.dry_run``): which ops have one, and how many inputs of each
source its stages evaluate, in which order. Each size says what it was measured to buy.

``fuzzer.dry_run`` runs the plan; ``benchmarks.dry_run_order`` counts, in inputs, where its first
stage meets a bug.
"""

from __future__ import annotations

DRY_RUN_OPS = frozenset({"fk", "move", "ik", "scenario"})
"""Ops with a dry run: ``fk`` and ``move`` seeds cost well under a millisecond each; an ``ik``
seed about 5 ms, but an IK campaign's start-up imports ``scipy.stats`` (0.55 s, for its
space-filling seed) after the fork, so its dry run reports what the seeds show that much sooner
(docs/benchmarks-log.md, "Orientation probes, and the baselines' scipy.stats import"). A ``scenario``
dry run has a first stage only (``SECOND_STAGE_OPS``): MoveIt's tutorial scripts and
``SCRIPTS`` uniform scripts."""

IN_PROCESS_FIRST = frozenset({"fk", "move"})
"""Ops whose dry run evaluates its first input (the first uniform configuration, one call) in
the campaign's process before it forks (``fuzzer.dry_run``, ``fuzzer.execution.guard``): the
child's fork, set-up and copy-on-write faults cost 5-7 ms before its first evaluation, which is
where a bug nearly every input shows is decided (BENCHMARKS.md, "Paired A/B"). Not ``ik`` (its
first inputs are probes of 5 ms each) nor ``scenario`` (a tutorial script, tens of ms): their
bugs are not decided in those milliseconds."""

SECOND_STAGE_OPS = DRY_RUN_OPS - {"scenario"}
"""Ops whose dry run evaluates the generated seeds once more (its second stage). Not
``scenario``: a scenario seed costs 10 to 100 times more than an ``fk`` one, and libFuzzer runs
every seed anyway."""

SCRIPTS = 32
"""Uniform random scripts (``corpus.uniform_scripts``, the uniform baseline's) a ``scenario``
dry run evaluates after MoveIt's tutorial scripts: about 5 ms each (median; 12 ms mean, a
Cartesian path costs more) on the default robot, so the first stage takes about 0.5 s of one
CPU, confirmations included. A scenario campaign's own first input otherwise waits for its
seeds, Atheris, the instrumentation and libFuzzer's start (about 0.8 s from the process start
against 0.35 s; docs/benchmarks-log.md, "A dry run for scenarios")."""

BOUNDARY_ROUNDS = 2
"""Rounds of boundary probes the dry run's first stage evaluates (``fuzzer.generation.boundary``:
each joint 5e-5 past a limit, inside MoveIt's goal tolerance, then 1.5e-4 past it, beyond; 24
inputs on a 6-joint arm): AFL's deterministic stage, run before the rest of the start-up. The
first round also rides on the space-filling seeds; the campaign's fresh inputs bring both again
later, on space-filling points."""

SWEEPS = 32
"""Sweeps of ``ROWS`` uniform configurations an ``fk`` dry run evaluates in all, ``EARLY`` and
``LATE`` of them in the first stage (32,768 rows, about 60 ms on one CPU for the default
robot): a band 1e-4 of one joint's range wide is met with probability 0.96, one 1e-5 wide with
0.28 (the campaign's Sobol sweeps go on from there)."""

TOTAL_SWEEPS = {"fk": SWEEPS, "move": 8}
"""Sweeps of ``ROWS`` a dry run evaluates in all, per op (``move``: ``LATE``'s in the first
stage, the rest after the seeds; the campaign's own sweeps come every 64 inputs,
``fuzzer.generation.sweep.EVERY_OP``)."""
LEADING_SWEEP_OPS = frozenset({"fk"})
"""Ops whose first stage starts with its sweeps (one of ``FIRST_ROWS`` rows, then ``EARLY``'s):
``fk``, which has no single-call configurations there. A ``move`` campaign's first inputs are
its uniform configurations, whose one-call bugs would wait for a sweep."""
FIRST_ROWS = 64
"""Rows of the first stage's first sweep (``fk``), before its ``EARLY`` sweeps of ``ROWS``: what
most configurations show is reported after 64 rows (about 0.8 ms on the first call) instead of
1,024 (3 ms)."""

SWEEP_SEED = 0xD5
"""Added to ``-seed`` for the dry run's uniform rows and configurations (not the campaign's
Sobol streams' seeds)."""

EARLY = {"fk": 4, "move": 128}
"""The first stage's uniform work, per op (``Stages``): sweeps (``fk``) or configurations
(``move``; ``LEAD`` of them before the aligned configurations and the boundary probes, the rest
after them)."""

LATE = {"fk": 12, "move": 4}
"""Sweeps the first stage evaluates last, after its probes and literal configurations
(about 2 ms each); the second stage has the rest of ``TOTAL_SWEEPS``. ``move``'s (since the
sixty-sixth session) are its only ones in the first stage: a fault in the FK of a move's goal
that 1e-3 of uniform configurations show (``gated_band``) is met in 4,096 rows with
probability 0.98, and in the stage's 128 configurations with 0.12. With only ``EARLY``'s, a fault
that 2.7e-4 of uniform rows show (``joint_relation``: two joints in a relation) was missed by
the first stage in about a third of the trials and waited about 0.2 s more, for Hypothesis'
import, the seeds and their evaluation; after 16 sweeps it is missed with odds 0.013. On one
CPU the campaign waits for each stage, so libFuzzer starts no later: only the seeds' own
evaluation comes 20-25 ms later (docs/benchmarks-log.md, thirty-ninth session)."""

LEAD = 32
"""Uniform configurations (``move``) the first stage evaluates before its aligned
configurations and boundary probes (about 15 ms; the literal configurations go among them,
after ``HEAD``); the rest of ``EARLY`` comes after the probes (about 40 ms), still before the
seeds. With 32 in the first stage and 96 after the seeds,
``wrap_past_pi`` (a band 2.4% of uniform targets hit) waited for the second stage in about half
the trials."""

ALIGNED = {"fk": 32, "move": 32}
"""Aligned configurations (each joint at a multiple of pi/2 or a limit: where axes line up and
kinematics code branches; ``fuzzer.generation.spacefill.Aligned``) of the first stage, per op:
one input each (about 0.1 ms for ``fk``, 0.5 ms for ``move``). On the default robot 10% of them
show ``rpy_gimbal_band`` (a gimbal-lock branch of a roll-pitch-yaw conversion), which no
uniform configuration of 2,000 did."""

HEAD = 4
"""Uniform configurations (``move``) the first stage evaluates before its ``LITERALS``
configurations, the rest of ``LEAD`` after them. Until 2026-11-30 the literals came after the
boundary probes, 100 inputs in: in about half the seeds the first 32 uniform configurations
missed ``wrap_past_pi`` (a band 2.4% of them hit, starting at a number its module compares
against), which then waited for them, and the full engine was slower than uniform sampling on
it over seeds 30-69 (p = 0.0017). Counted in inputs over seeds 10-49
(``benchmarks.dry_run_order``), literals after the first configuration put ``wrap_past_pi`` at
13 (uniform sampling: median 31.5) and ``per_joint_band`` at 10 (97), and the boundary probes'
bugs 13-14 inputs later; after 4, a few seeds whose first configuration misses
``wrap_positive`` still meet it at once (docs/benchmarks-log.md, thirty-fifth session)."""

LITERALS = 16
"""Configurations with joints at the numbers the Python targets compare against
(``corpus.literal_cases``: AFL++'s autodictionary, for floats) the first stage evaluates, the
middles of the bands the targets test first: for ``move`` after ``HEAD`` uniform
configurations, for the other ops after the boundary probes; a scenario's first uniform
scripts each start at one (``corpus.literal_scripts``), right after the tutorial scripts
(since 2026-12-01: over seeds 20-49, ``ik_seed_band`` met at the 5th script instead of the
19th, ``execute_skips_start_check`` the 7th instead of the 13th; docs/benchmarks-log.md).
Middles first for the other ops too since 2026-12-02 (seeds 10-49: ``wrap_past_pi`` met at
input 6 instead of 16, ``per_joint_band`` 5 instead of 13, its search 9.4 against 17.5 ms;
docs/benchmarks-log.md, forty-first session).
Placed after the probes, with them `per_joint_band`
(a band 2e-5 wide starting at a module constant) was found 3.2 times sooner (1.76 against
0.54 s from process start, 10 trials, p = 0.00018), no zoo bug's search significantly longer
but `ik_status_misread`'s, by 12 ms (p = 0.045); placed first, before the probes, they cost
the boundary bugs 30-50 ms (docs/benchmarks-log.md, sixth session of 2026-11-26, item 6)."""

UNIFORM = {"move": 128}
"""Uniform random configurations the dry run evaluates in all, one input each, per op, ``EARLY``
of them in the first stage (``fuzzer.generation.corpus.uniform_cases``; about 60 ms for ``move``
on one CPU). ``fk`` sweeps
instead; ``ik`` has none (an FK and an IK solve per input). With 64, ``wrap_past_pi`` (a band
2.4% of uniform targets hit) was found in the dry run in 6 of 10 trials; 128 miss it with
odds 0.05."""
