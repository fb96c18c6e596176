"""The settings a mission hands its perception plug-ins' `configure` (see `mission.plugin_api`): the sensors'
settings, and the multi-view model file of each database object that names one. Any runner (the simulator, a
vehicle's executive) builds them here, so that plug-ins see the same settings wherever the mission runs.
"""

from __future__ import annotations

from typing import Any

from mission.language.models import Mission


def plugin_settings(mission: Mission) -> dict[str, Any]:
    """`{"sensors": …, "models": {object id: model file}}`; the loader has made model paths absolute."""
    return {"sensors": mission.sensors.model_dump(),
            "models": {o.id: o.model for o in mission.objects if o.model is not None}}


__all__ = ["plugin_settings"]
