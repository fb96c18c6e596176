"""Faults injected into a simulated run (the mission's `faults:`): which act at a moment of mission time, and the
events that say when each starts and ends.

What each fault does to the simulated vehicle (`mission.sim.vehicle`):
- `usbl_outage`: no acoustic fix arrives; the navigation dead-reckons and its estimate drifts;
- `dvl_dropout`: no DVL velocity or altitude; the navigation dead-reckons on the propeller's speed through the
  water along the measured heading (the current is unknown), its uncertainty growing at `DVL_LOST_DRIFT_M_S`;
- `thruster_degraded`: top speed, acceleration and station-keeping effort scaled by `fraction`;
- `battery_step`: `wh` (or `percent` of the capacity) lost at `start`;
- `sensor_lost`: the sensor delivers nothing; `sensor_frozen`: it keeps delivering its last data, re-stamped.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import Any, TypeVar

from mission.language.fault_models import BatteryStep, Fault, SensorFault, ThrusterDegraded
from mission.language.models import VehicleSettings

SENSOR_KEYS = {"multibeam": "mbes", "scanner": "scanner", "stereo": "stereo"}  # fault name → payload name
DVL_LOST_DRIFT_M_S = 0.1  # growth of the position sigma while the DVL is lost: unknown current and speed error

EmitFn = Callable[..., None]
T = TypeVar("T")


def fault_fields(fault: Fault) -> dict[str, Any]:
    """A fault as event fields: its kind, window and parameters."""
    return {"fault": fault.kind, **fault.window.model_dump(exclude_none=True)}


class ActiveFaults:
    """The faults of a run, stepped with mission time (`update`); its attributes say what acts now."""

    def __init__(self, faults: Sequence[Fault], capacity_wh: float):
        self.faults = list(faults)
        self.capacity_wh = capacity_wh
        self._state = ["pending"] * len(self.faults)  # pending → active → ended
        self.usbl_out = False
        self.dvl_out = False
        self.thrust_fraction = 1.0
        self.lost: set[str] = set()  # payload names (mbes, scanner, stereo)
        self.frozen: set[str] = set()

    def update(self, time: float, emit: EmitFn | None) -> float:
        """Start and end the faults due at `time` (emitting `fault_started`/`fault_ended`); returns the energy lost
        by battery steps that start now (Wh)."""
        lost_wh = 0.0
        changed = False
        for k, fault in enumerate(self.faults):
            window = fault.window
            if self._state[k] == "pending" and time >= window.start - 1e-9:
                self._state[k] = "active"
                changed = True
                params = fault.window
                if isinstance(params, BatteryStep):
                    lost_wh += params.wh if params.wh is not None else (params.percent or 0.0) / 100.0 * \
                        self.capacity_wh
                if emit is not None:
                    emit("fault_started", time, **fault_fields(fault))
            if self._state[k] == "active" and window.end is not None and time >= window.end - 1e-9:
                self._state[k] = "ended"
                changed = True
                if emit is not None:
                    emit("fault_ended", time, fault=fault.kind)
        if changed:  # (every control step comes here: a mission without faults costs a loop over nothing)
            self._refresh()
        return lost_wh

    def _refresh(self) -> None:
        active = [f for f, s in zip(self.faults, self._state, strict=True) if s == "active"]
        self.usbl_out = any(f.kind == "usbl_outage" for f in active)
        self.dvl_out = any(f.kind == "dvl_dropout" for f in active)
        self.thrust_fraction = min((f.window.fraction for f in active if isinstance(f.window, ThrusterDegraded)),
                                   default=1.0)
        self.lost = {SENSOR_KEYS[f.window.sensor] for f in active
                     if f.kind == "sensor_lost" and isinstance(f.window, SensorFault)}
        self.frozen = {SENSOR_KEYS[f.window.sensor] for f in active
                       if f.kind == "sensor_frozen" and isinstance(f.window, SensorFault)} - self.lost

    def active(self) -> list[str]:
        """The kinds of the faults acting now."""
        return [f.kind for f, s in zip(self.faults, self._state, strict=True) if s == "active"]


@functools.lru_cache(maxsize=8)
def degraded(limits: VehicleSettings, fraction: float) -> VehicleSettings:
    """The vehicle's limits with `fraction` of its thrust: top speed and acceleration scaled (unchanged at 1)."""
    if fraction >= 1.0:
        return limits
    return limits.model_copy(update={"max_speed": limits.max_speed * fraction,
                                     "max_acceleration": limits.max_acceleration * fraction})


def restamp(item: T, time: float, **tags: Any) -> T:
    """A frozen sensor's last output delivered again: the same data with a new time (and pose tags)."""
    return replace(item, time=time, **tags)  # type: ignore[type-var]
