"""The reasonable-difference indicator (paper III.E): tolerances per quantity."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass


@dataclass(frozen=True)
class Tolerance:
    """Reasonable difference (paper III.E): per quantity, metres and radians."""

    metres: float = 1e-6
    radians: float = 1e-6

    @classmethod
    def parse(cls, text: str) -> Tolerance:
        """``1e-5`` (both) or ``m=1e-5,rad=1e-6``.

        Raises
        ------
        ValueError
            With a message naming the bad part.
        """
        parts = [p.strip() for p in text.split(",")]
        if not all(parts):  # '', ',', '1e-6,': a part left out (the defaults silently, before)
            raise ValueError(f"tolerance {text!r}: an empty part; expected 1e-6 or m=<value>,rad=<value>")
        if len(parts) == 1 and "=" not in parts[0]:
            value = _positive(parts[0])
            return cls(value, value)
        values = {"m": cls.metres, "rad": cls.radians}
        given: set[str] = set()
        for part in parts:
            key, sep, raw = part.partition("=")
            key = key.strip()
            if not sep or key not in values:
                raise ValueError(f"tolerance {part!r}: expected m=<value> or rad=<value>")
            if key in given:  # m=1e-5,m=1e-6: the last one won silently
                raise ValueError(f"tolerance {text!r}: {key} given twice")
            given.add(key)
            values[key] = _positive(raw)
        return cls(values["m"], values["rad"])


DECIMAL = re.compile(r"\s*[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?\s*", re.ASCII)
"""A number as written on a command line: ASCII digits, no ``_`` (``float()`` also takes
``1_0`` for 10 and other scripts' digits, which libFuzzer's flags are refused for)."""


def _positive(raw: str) -> float:
    if not DECIMAL.fullmatch(raw):
        raise ValueError(f"tolerance {raw!r} is not a number")
    value = float(raw)
    if not (math.isfinite(value) and value > 0.0):
        raise ValueError(f"tolerance {raw!r} must be a positive finite number")
    return value


def default_tolerance(op: str) -> Tolerance:
    """1e-6 (m and rad), inside the paper's 1e-4..1e-6; 1e-5 for IK, whose converged
    answers may each sit up to sqrt(3) * IK_EPS (1.7e-6) from the target, so two
    correct answers can differ by 3.5e-6."""
    return Tolerance(1e-5, 1e-5) if op == "ik" else Tolerance()


def below_ik_precision(op: str, tolerance: Tolerance) -> str | None:
    """A warning for an ``ik`` campaign whose tolerance is below what two correct IK answers
    can differ by (2 sqrt(3) IK_EPS, 3.5e-6): its divergences are the solver's noise (a helper's
    probe at ``--tolerance 1e-10`` found two, both answers within sqrt(3) IK_EPS of the target);
    None otherwise."""
    from robot_api.constants import IK_EPS

    floor = 2 * math.sqrt(3) * IK_EPS
    if op != "ik" or min(tolerance.metres, tolerance.radians) >= floor:
        return None
    return (
        f"--tolerance {tolerance.metres:g} m / {tolerance.radians:g} rad is below what two correct IK "
        f"answers can differ by ({floor:.2g}: each may end sqrt(3) * IK_EPS from the target); "
        "divergences that small are the solver's tolerance, not a bug (default for ik: 1e-05)"
    )
