"""Log-odds parameters of the voxel occupancy map of seed 002 §2.1, and the 16-bit code its voxels are stored in.

The seed updates each voxel's occupancy with Bayes' theorem as sonar returns arrive. In log-odds form
L = log(p / (1 − p)) that update is an addition: a beam ending in a voxel adds logit(p_hit), a beam passing through
it adds logit(p_miss), and the sum is clamped to [logit(clamp_min), logit(clamp_max)] so that the map stays able
to change its mind (OctoMap's scheme; its defaults are ours).

Voxels are stored as 16-bit codes, not floats, to halve the memory of a survey-sized map: code 0 means unknown
(never observed) and a known log-odds L is kept as round(L / quantum) + 32768 with a power-of-two quantum (2⁻¹³
for the defaults, so one update is exact to 6·10⁻⁵ in log-odds). An update is then one lookup in a 65,536-entry
transition table, which also turns unknown into the prior (L = 0) plus the update and applies the clamping.

>>> p = LogOddsParams()
>>> round(p.hit, 4), round(p.miss, 4), round(p.clamp_max_log, 4), round(p.clamp_min_log, 4)
(0.8473, -0.4055, 3.4761, -1.9924)
>>> float(probability(logit(0.7)))
0.7
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

UNKNOWN = 0
"""The code of a voxel that no beam has touched."""
BIAS = 32768
"""Code of log-odds 0: known codes are round(L / quantum) + BIAS."""
MAX_STEPS = 32000
"""Largest |round(L / quantum)| a code may hold (keeps every known code in 768..64768, away from UNKNOWN)."""


def logit(p: ArrayLike) -> NDArray[np.float64]:
    """Log-odds log(p / (1 − p)) of a probability."""
    q = np.asarray(p, dtype=float)
    return np.asarray(np.log(q / (1.0 - q)))


def probability(log_odds: ArrayLike) -> NDArray[np.float64]:
    """Probability 1 / (1 + exp(−L)) of a log-odds value."""
    return np.asarray(1.0 / (1.0 + np.exp(-np.asarray(log_odds, dtype=float))))


@dataclass(frozen=True)
class LogOddsParams:
    """Sensor model and clamping of the Bayes update (probabilities; OctoMap's defaults)."""

    p_hit: float = 0.7
    """P(occupied | a beam ended in the voxel)."""
    p_miss: float = 0.4
    """P(occupied | a beam passed through the voxel)."""
    clamp_min: float = 0.12
    clamp_max: float = 0.97
    occupied: float = 0.5
    """A voxel is occupied when its probability is at least this (OctoMap: log-odds ≥ logit(occupied))."""

    def __post_init__(self) -> None:
        for name in ("p_hit", "p_miss", "clamp_min", "clamp_max", "occupied"):
            value = getattr(self, name)
            if not 0.0 < value < 1.0:
                raise ValueError(f"LogOddsParams.{name} must lie strictly between 0 and 1, got {value}")
        if not self.p_miss < 0.5 < self.p_hit:
            raise ValueError(f"need p_miss < 0.5 < p_hit, got p_miss={self.p_miss}, p_hit={self.p_hit}")
        if not self.clamp_min <= self.occupied <= self.clamp_max:
            raise ValueError(f"need clamp_min <= occupied <= clamp_max, got {self.clamp_min}, {self.occupied}, "
                             f"{self.clamp_max}")

    @property
    def hit(self) -> float:
        """Log-odds added by a beam ending in a voxel: logit(p_hit)."""
        return float(logit(self.p_hit))

    @property
    def miss(self) -> float:
        """Log-odds added by a beam passing through a voxel: logit(p_miss) (negative)."""
        return float(logit(self.p_miss))

    @property
    def clamp_min_log(self) -> float:
        return float(logit(self.clamp_min))

    @property
    def clamp_max_log(self) -> float:
        return float(logit(self.clamp_max))

    @property
    def occupied_log(self) -> float:
        return float(logit(self.occupied))

    @property
    def quantum(self) -> float:
        """Log-odds step of the stored code: the smallest power of two that fits the clamping range in 16 bits."""
        span = max(abs(self.clamp_min_log), abs(self.clamp_max_log), abs(self.hit), abs(self.miss))
        return float(2.0 ** math.ceil(math.log2(span / MAX_STEPS)))


class Codec:
    """Tables between 16-bit voxel codes and log-odds for one parameter set (built once, 65,536 entries each)."""

    def __init__(self, params: LogOddsParams) -> None:
        q = params.quantum
        self.quantum = q
        lo = round(params.clamp_min_log / q)
        hi = round(params.clamp_max_log / q)
        codes = np.arange(65536, dtype=np.int64)
        steps = np.where(codes == UNKNOWN, 0, codes - BIAS)  # unknown voxels start from the prior, L = 0
        self.log_odds: NDArray[np.float32] = np.where(codes == UNKNOWN, 0.0, (codes - BIAS) * q).astype(np.float32)
        """code → log-odds (0 for unknown)."""
        self.after_hit: NDArray[np.uint16] = (np.clip(steps + round(params.hit / q), lo, hi) + BIAS).astype(np.uint16)
        """code → code after one hit."""
        self.after_miss: NDArray[np.uint16] = (np.clip(steps + round(params.miss / q), lo, hi) + BIAS).astype(
            np.uint16)
        """code → code after one miss."""
        self.occupied_code = BIAS + math.ceil(params.occupied_log / q - 1e-9)
        """Smallest code that counts as occupied (log-odds ≥ logit(occupied), as OctoMap's isNodeOccupied)."""

    def encode(self, log_odds: ArrayLike) -> NDArray[np.uint16]:
        """Known codes of log-odds values (rounded to the quantum)."""
        steps = np.clip(np.round(np.asarray(log_odds, dtype=float) / self.quantum), -MAX_STEPS, MAX_STEPS)
        return (steps + BIAS).astype(np.uint16)
