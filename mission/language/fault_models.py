"""The `faults:` section of mission language v1 (simulation only): each entry one fault kind with its window of
mission time and parameters. The simulated vehicle applies them (`mission.sim.faults`); `auv run` refuses them
(`mission.faults`).
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

from mission.language.units import Duration

Positive = Annotated[float, Field(gt=0)]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)  # as `models.Strict`


class FaultWindow(_Strict):
    """When a fault acts, in seconds of mission time: from `start` to `end` (no `end`: to the end of the run)."""

    start: Duration = 0.0
    end: Duration | None = None

    @model_validator(mode="after")
    def _end_after_start(self) -> FaultWindow:
        if self.end is not None and self.end <= self.start:
            raise ValueError(f"a fault's end ({self.end:g} s) must come after its start ({self.start:g} s)")
        return self


class ThrusterDegraded(FaultWindow):
    fraction: Annotated[float, Field(gt=0, lt=1, description="share of thrust (speed) left")]


class BatteryStep(FaultWindow):
    """A step loss of stored energy at `start`: `wh`, or `percent` of the capacity (one of the two)."""

    wh: Positive | None = None
    percent: Annotated[float, Field(gt=0, le=100)] | None = None

    @model_validator(mode="after")
    def _one_amount(self) -> BatteryStep:
        if (self.wh is None) == (self.percent is None):
            raise ValueError("a battery_step needs exactly one of wh, percent")
        return self


class SensorFault(FaultWindow):
    sensor: Literal["multibeam", "scanner", "stereo"]


FAULT_KINDS = ("usbl_outage", "dvl_dropout", "thruster_degraded", "battery_step", "sensor_frozen", "sensor_lost")


class Fault(_Strict):
    """One injected fault (simulation only): exactly one kind, with its time window and parameters."""

    usbl_outage: FaultWindow | None = None
    dvl_dropout: FaultWindow | None = None
    thruster_degraded: ThrusterDegraded | None = None
    battery_step: BatteryStep | None = None
    sensor_frozen: SensorFault | None = None
    sensor_lost: SensorFault | None = None

    @model_validator(mode="after")
    def _exactly_one_kind(self) -> Fault:
        given = [k for k in FAULT_KINDS if getattr(self, k) is not None]
        if len(given) != 1:
            found = ", ".join(given) if given else "none"
            raise ValueError(f"a fault needs exactly one of {', '.join(FAULT_KINDS)} (found: {found})")
        return self

    @property
    def kind(self) -> str:
        return next(k for k in FAULT_KINDS if getattr(self, k) is not None)

    @property
    def window(self) -> FaultWindow:
        return getattr(self, self.kind)  # type: ignore[no-any-return]
