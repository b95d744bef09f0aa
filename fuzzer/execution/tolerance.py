"""The reasonable-difference indicator (paper III.E): tolerances per quantity."""

from __future__ import annotations

import math
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


def _positive(raw: str) -> float:
    try:
        value = float(raw)
    except ValueError:
        raise ValueError(f"tolerance {raw!r} is not a number") from None
    if not (math.isfinite(value) and value > 0.0):
        raise ValueError(f"tolerance {raw!r} must be a positive finite number")
    return value


def default_tolerance(op: str) -> Tolerance:
    """1e-6 (m and rad), inside the paper's 1e-4..1e-6; 1e-5 for IK, whose converged
    answers may each sit up to sqrt(3) * IK_EPS (1.7e-6) from the target, so two
    correct answers can differ by 3.5e-6."""
    return Tolerance(1e-5, 1e-5) if op == "ik" else Tolerance()
