"""What the full engine's search is made of, beside libFuzzer (issue 11): the bandits over input
sources and mutators with their fresh-input makers (``fuzzer.selection.state.Sources``; for
``ik`` the joint-space walk of goals, ``fuzzer.generation.walk``), the
float-comparison tracer (``fuzzer.selection.floatcmp``) with the thresholds it learns for the
``compared`` mutator (``fuzzer.selection.compared``), the queue of new inputs for that mutator
(``fuzzer.selection.i2s``) and, for ``fk`` and ``move`` in process, the batched sweeps
(``fuzzer.generation.sweep``). ``fuzzer.campaign`` hands them to the Harness."""

from __future__ import annotations

from functools import partial
from typing import Any

from fuzzer.execution.session import Session, batches

SWEEP_SEED = 0x5EED
"""Added to ``-seed`` for the sweeps' Sobol stream (another sequence than ``spacefill``'s)."""

ALIGNED_SEED = 0xA1
"""Added to ``-seed`` for the aligned configurations' choices."""


def search_parts(session: Session, mutator: str, seed: int, features: Any, seeded: int = 0) -> dict[str, Any]:
    """The Harness's input sources, float-comparison tracer and (``fk`` in process) sweeps, as
    keyword arguments (issue 11; docs/engine.md, "Guidance"), for a campaign with ``--mutator
    mutator`` and ``-seed`` ``seed``. ``--mutator weights`` (the engine before them) and
    ``libfuzzer`` get none of them, only the tracer's guard against Atheris' leak of comparison
    results (budget 0). The fresh inputs carry the boundary probes the space-filling seeds did
    not (the first round went into the first ``seeded`` space-filling seeds, if this campaign
    wrote them)."""
    from fuzzer.selection.floatcmp import FloatCompareTracer

    if mutator != "rrosfuzz":  # no float features; still the guard of Atheris' leak
        return {"float_tracer": FloatCompareTracer(features, budget=0)}
    from fuzzer.generation.boundary import Boundary, probes
    from fuzzer.generation.spacefill import Aligned, SpaceFill, fresh_inputs
    from fuzzer.mutation import mutators
    from fuzzer.selection.bandit import Bandit
    from fuzzer.selection.compared import ComparedValues
    from fuzzer.selection.i2s import I2SQueue
    from fuzzer.selection.state import ALIGNED, MUTATE, SPACEFILL, WALK, Sources

    config = session.config
    weights: dict[str, float] = dict(mutators.WEIGHTS)
    if config.op == "scenario":
        from fuzzer.scenario.mutate import SEQ_WEIGHTS

        weights = dict(SEQ_WEIGHTS)
    limits = session.reference.joint_limits
    compared = ComparedValues()
    tracer = FloatCompareTracer(features, compared=compared)
    if not limits:  # a chain without joint variables (a tip on the root's rigid body): no joint space
        return {"float_tracer": tracer}
    facts = session.facts()
    stream = SpaceFill(facts.lower, facts.upper, seed=seed)
    first_round = len(probes(facts.lower, facts.upper, rounds=1))
    walk = _walk(session, facts) if config.op == "ik" else None
    maker = partial(
        fresh_inputs,
        config.op,
        config.message_type,
        joint_names=facts.joint_names,
        reachable=facts.reachable if walk is None else walk.recording(facts.reachable),
        max_steps=config.max_steps,
    )
    fresh = maker(stream, boundary=Boundary(facts.lower, facts.upper, start=min(seeded, first_round)))
    aligned = maker(Aligned(facts.lower, facts.upper, seed=seed + ALIGNED_SEED), name=ALIGNED)
    arms = (MUTATE, SPACEFILL, ALIGNED) if walk is None else (MUTATE, SPACEFILL, ALIGNED, WALK)
    sources = Sources(Bandit(arms), Bandit(tuple(weights), weights), fresh, aligned, walk)
    arm = "seq_compared" if config.op == "scenario" else "compared"
    search: dict[str, Any] = {
        "sources": sources,
        "float_tracer": tracer,
        "i2s": I2SQueue(arm, compared.is_unsolved),
    }
    from fuzzer.generation.sweep import EVERY_OP, SWEEP_OPS, Sweep

    if config.op in SWEEP_OPS and config.transport == "inprocess" and all(map(batches, config.targets)):
        search["sweep"] = Sweep(
            [lim.lower for lim in limits],
            [lim.upper for lim in limits],
            config.tolerance,
            seed=seed + SWEEP_SEED,
            every=EVERY_OP[config.op],
        )
        search["sweep"].prime()  # before libFuzzer runs, not in an input
    return search


def _walk(session: Session, facts: Any) -> Any:
    """The ``walk`` source of an ``ik`` campaign (``fuzzer.generation.walk``), on the first
    target's forward kinematics of any link."""
    from fuzzer.generation.walk import Walk

    model = session.reference

    def pose_of(values: tuple[float, ...], link: str | None) -> tuple[tuple[float, ...], tuple[float, ...]]:
        pose = model.forward_kinematics(list(values), link)
        return tuple(map(float, pose.position)), tuple(map(float, pose.orientation))

    return Walk(session.config.message_type, facts.lower, facts.upper, pose_of)
