"""What a campaign's mutation context takes from its session: the type of every mutable leaf of
the message, and the values around the joint limits that the ``interesting`` mutators add to
their own (``fuzzer.campaign`` builds the ``MutationContext`` from these; the baselines too)."""

from __future__ import annotations

import math

from fuzzer.execution.session import Session
from fuzzer.generation.boundary import OFFSETS
from fuzzer.mutation import fields


def field_types(session: Session, msg_type: str) -> dict[str, str]:
    """Dotted path -> ROS builtin type of every mutable leaf (arrays of messages are left out;
    ``fuzzer.mutation.fields.field_types``)."""
    return fields.field_types(session.registry, msg_type)


def interesting_values(session: Session) -> list[float]:
    """Joint limits and the tolerance band around them: where divergences live."""
    eps = sorted(OFFSETS)
    values: list[float] = []
    for lim in session.reference.joint_limits:
        for bound in (lim.lower, lim.upper):
            if math.isfinite(bound):
                values.extend(bound + s * e for e in eps for s in (-1.0, 1.0))
    return values
