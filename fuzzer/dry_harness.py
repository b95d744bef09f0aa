"""The dry run's Harness (``fuzzer.dry_run``): one that evaluates and records without libFuzzer,
coverage or mutation, its uniform sweeps for ``fk``, and the loop that hands it inputs as
libFuzzer would."""

from __future__ import annotations

import random
from collections.abc import Callable, Sequence
from typing import Any

from fuzzer.artifacts.divlog import CampaignLog
from fuzzer.artifacts.store import ArtifactStore
from fuzzer.execution.evaluate import Evaluator
from fuzzer.execution.session import Session
from fuzzer.generation.sweep import SWEEP_OPS, Sweep
from fuzzer.harness import Harness
from fuzzer.input.testcase import TestCase
from fuzzer.mutation import mutators
from fuzzer.selection.guidance import Features


def harness(
    evaluator: Evaluator,
    store: ArtifactStore,
    log: CampaignLog,
    sidecar: Callable[[TestCase, bytes, Any], dict[str, Any]],
    seeds: Sequence[TestCase],
    joint_names: tuple[str, ...],
    sweep: Sweep | None = None,
    campaign_seeds: tuple[int | None, int] | None = None,
) -> Harness:
    """A Harness that evaluates and records, without libFuzzer, coverage or mutation; with
    ``sweep`` (see ``sweep``), ``evaluate`` runs its sweeps; its snapshots record the campaign's
    ``campaign_seeds`` (``Harness.campaign_seeds``)."""
    return Harness(
        evaluator=evaluator,
        store=store,
        features=Features(enabled=False),
        context=mutators.MutationContext(rng=random.Random(0), field_types={}),  # never mutates
        sidecar=sidecar,
        seeds=list(seeds),
        log=log,
        joint_names=joint_names,
        sweep=sweep,
        campaign_seeds=campaign_seeds,
    )


def sweep(session: Session, mutator: str, seed: int, first_rows: int = 0) -> Sweep | None:
    """A dry run's sweeps for a campaign with ``--mutator mutator``, uniform rows seeded with
    ``seed``, the first of ``first_rows`` rows (0: ``ROWS``), never due on their own
    (``evaluate`` runs them); None but for the full engine's ``fk`` in process on a chain with
    joints (as the campaign's sweeps), and ``move``'s (the FK of its goals)."""
    config = session.config
    limits = session.reference.joint_limits
    if mutator != "rrosfuzz" or config.op not in SWEEP_OPS or config.transport != "inprocess" or not limits:
        return None
    lower, upper = [lim.lower for lim in limits], [lim.upper for lim in limits]
    tolerance = config.tolerance
    return Sweep(lower, upper, tolerance, seed=seed, source="uniform", every=0, first_rows=first_rows)


def evaluate(
    h: Harness, cases: Sequence[TestCase], before: int = 0, after: int = 0, snapshot: bool = True
) -> None:
    """Evaluate ``cases`` in order, as libFuzzer hands inputs over (their encoding), then log
    a stats snapshot (unless not ``snapshot``); with the Harness's sweep, ``before`` sweeps
    first and ``after`` sweeps last."""
    for _ in range(before if h.sweep is not None else 0):
        h.run_sweep()
    for case in cases:
        h.test_one_input(case.encode())
    for _ in range(after if h.sweep is not None else 0):
        h.run_sweep()
    if snapshot:
        h.maybe_snapshot(force=True)


MakeHarness = Callable[[Sequence[TestCase], Sweep | None], Harness]
"""``(seeds, sweep) -> Harness``: ``harness`` with the campaign's evaluator, store, log and
sidecar bound."""
