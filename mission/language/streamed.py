"""What every payload sensor entry of a mission (`sensors.mbes`, `sensors.stereo`, `sensors.scanner`) says about
its stream onboard (`mission.sensors`): the driver that delivers it and how long it may be silent."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict

from mission.language.units import Duration


class Streamed(BaseModel):
    """`driver`: an `auv.sensors` URI (`zenoh:auv/sim`, `replay:DIR`, `camera:0,1?calibration=FILE`; `auv run`
    only, the simulator ignores it); a stream silent for `timeout` while the sensor is on is lost."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)  # as `models.Strict`

    driver: str | None = None
    timeout: Duration = 2.0
