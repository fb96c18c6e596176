"""Onboard navigation: dead reckoning from DVL velocity and INS heading, corrected by acoustic (USBL) fixes
with a Kalman filter. Runs on the vehicle (simulated or real); it never sees the truth.

The horizontal position error is kept isotropic (variance `var` on both axes). Dead-reckoning error from a
DVL/INS is mostly systematic (scale factor and misalignment), so its standard deviation grows linearly with the
distance travelled at `drift_fraction`; white velocity noise adds a random walk. Fixes whose innovation fails a
chi-square gate are rejected as outliers; a run of rejections resets the filter to the fixes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

GATE_CHI2 = 13.8  # 2 degrees of freedom, 99.9 %
RESET_AFTER_REJECTS = 5


@dataclass
class FixResult:
    accepted: bool
    innovation: float


class NavigationFilter:
    """Horizontal position estimate (north, east) with an isotropic variance."""

    def __init__(self, north: float, east: float, sigma: float, drift_fraction: float, velocity_sigma: float):
        self.north, self.east = north, east
        self.var = sigma * sigma
        self.drift = drift_fraction
        self.velocity_var = velocity_sigma * velocity_sigma
        self.rejects = 0

    @property
    def sigma(self) -> float:
        return math.sqrt(self.var)

    def predict(self, v_north: float, v_east: float, dt: float) -> None:
        """Dead-reckon over dt with the measured velocity over ground (m/s, world frame)."""
        self.north += v_north * dt
        self.east += v_east * dt
        grown = math.sqrt(self.var) + self.drift * math.hypot(v_north, v_east) * dt
        self.var = grown * grown + self.velocity_var * dt * dt

    def update(self, fix_north: float, fix_east: float, fix_sigma: float) -> FixResult:
        """Fuse one position fix (Kalman update), unless the chi-square gate rejects it."""
        r = fix_sigma * fix_sigma
        dn, de = fix_north - self.north, fix_east - self.east
        s = self.var + r
        d2 = (dn * dn + de * de) / s
        innovation = math.sqrt(dn * dn + de * de)
        if d2 > GATE_CHI2 and self.rejects < RESET_AFTER_REJECTS:
            self.rejects += 1
            return FixResult(False, innovation)
        if d2 > GATE_CHI2:  # the estimate, not the fixes, has gone astray: restart from the fix
            self.north, self.east, self.var = fix_north, fix_east, r
            self.rejects = 0
            return FixResult(True, innovation)
        gain = self.var / s
        self.north += gain * dn
        self.east += gain * de
        self.var = (1.0 - gain) * self.var
        self.rejects = 0
        return FixResult(True, innovation)
