"""A campaign's initial seeds (Algorithm 1's): Hypothesis seeds made and written to the first
corpus folder, with the full engine's space-filling points and MoveIt's tutorial scripts."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from fuzzer import reporting
from fuzzer.execution.session import Session
from fuzzer.generation.corpus import (
    make_seeds,
    orientation_cases,
    space_filling_count,
    space_filling_seeds,
    tutorial_seeds,
    write_seeds,
)
from fuzzer.input.testcase import TestCase

if TYPE_CHECKING:
    from fuzzer.dry_run import Stages

RESTART_SEEDS = 8
"""Seeds made in memory when the corpus has none that decode (to restart from damaged inputs)."""


def initial_seeds(
    session: Session,
    wanted: int,
    seed: int,
    mutator: str,
    folders: tuple[Path, ...],
    seeds: list[TestCase],
    dry: Stages | None = None,
) -> tuple[list[TestCase], list[TestCase]]:
    """The campaign's seeds and its space-filling ones.

    Parameters
    ----------
    session : Session
        The campaign's session (robot, op, message type).
    wanted : int
        Seeds to make and write to ``folders[0]`` (0: none).
    seed : int
        The campaign's ``--seed`` (Hypothesis' and the Sobol sequence's).
    mutator : str
        ``--mutator``: the full engine (``rrosfuzz``) also writes space-filling points and
        tutorial scripts.
    folders : tuple of Path
        The corpus folders (the first gets the new seeds).
    seeds : list of TestCase
        The test cases already in the corpus (``corpus.prescan``), after the new ones.
    dry : Stages or None
        The dry run, handed the Hypothesis seeds as soon as they exist (its second stage).

    Returns
    -------
    tuple of (list of TestCase, list of TestCase)
        The seeds (the new Hypothesis seeds, then ``seeds``; :data:`RESTART_SEEDS` in memory
        when both are empty) and the space-filling ones written beside them.

    Raises
    ------
    ConfigError
        Hypothesis draws no seed for this robot (a chain of 1,300 joints).
    """
    config = session.config
    filling: list[TestCase] = []
    if wanted and folders:
        generated = make_seeds(session, wanted, seed)
        orientation = orientation_cases(session, len(generated) + space_filling_count(config.op, wanted))
        if dry is not None:
            dry.second(generated)
        # the full engine's: as many space-filling points (IK: one, corpus.SLOW_OP_SPACEFILL_SEEDS)
        count = space_filling_count(config.op, wanted) if mutator == "rrosfuzz" else 0
        filling = space_filling_seeds(session, count, seed, len(generated)) if count else []
        filling += orientation if count else []  # a pose target's quaternion at lengths other than one
        tutorials = tutorial_seeds(session, seed, len(generated)) if mutator == "rrosfuzz" else []
        write_seeds(folders[0], generated + filling + tutorials)
        seeds = generated + seeds
        reporting.info(
            f"wrote {len(generated)} seeds from Hypothesis ({config.message_type})"
            + (f" and {len(filling)} space-filling configurations" if filling else "")
            + (f" and {len(tutorials)} script(s) of MoveIt's tutorials" if tutorials else "")
            + f" to {folders[0]}"
        )
    if not seeds:
        seeds = make_seeds(session, RESTART_SEEDS, seed)
    return seeds, filling
