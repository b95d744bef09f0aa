"""Angle conventions of the contract."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

TWO_PI = 2.0 * math.pi


def normalize_angle(v: float) -> float:
    """Continuous joints live in (-pi, pi]: ``r = fmod(v, 2pi)``, then one shift."""
    r = math.fmod(v, TWO_PI)
    if r <= -math.pi:
        r += TWO_PI
    elif r > math.pi:
        r -= TWO_PI
    return r


def normalize_angles(v: NDArray[np.float64]) -> NDArray[np.float64]:
    """Element-wise :func:`normalize_angle` of an array."""
    r = np.fmod(v, TWO_PI)
    r = np.where(r <= -math.pi, r + TWO_PI, r)
    return np.where(r > math.pi, r - TWO_PI, r)
