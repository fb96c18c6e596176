"""Vehicle adapters for `auv run`: entry points in the group `auv.vehicles`, picked by the scheme of a vehicle URI.

A URI is `SCHEME:ADDRESS` (`mavlink:udpin:0.0.0.0:14550`): the entry point named SCHEME is a factory
`open_vehicle(address, mission, options) -> OnboardVehicle`. The factory connects (waiting at most
`options.connect_timeout` seconds), checks what the vehicle offers against the mission, and returns an adapter
that the executive drives like any `VehicleInterface`; it raises `VehicleError` with one clear line otherwise.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from importlib.metadata import entry_points
from typing import Any, Protocol

from mission.errors import VehicleError
from mission.language.models import Mission
from mission.vehicle import VehicleInterface

GROUP = "auv.vehicles"


@dataclass(frozen=True)
class VehicleOptions:
    """How `auv run` opens a vehicle. `emit(event, time, **fields)` logs what the adapter sees (mode changes,
    refused commands) into the run's event log."""

    connect_timeout: float = 10.0
    emit: Callable[..., None] = field(default=lambda *a, **k: None)


class OnboardVehicle(VehicleInterface, Protocol):
    """A real vehicle's adapter: the executive's interface, plus `close()` to release the link (after the executive
    has commanded its last hold)."""

    def close(self) -> None: ...


VehicleFactory = Callable[[str, Mission, VehicleOptions], OnboardVehicle]


def installed_vehicles() -> dict[str, str]:
    """Installed adapters: scheme → entry-point value."""
    return {ep.name: ep.value for ep in entry_points(group=GROUP)}


def split_uri(uri: str) -> tuple[str, str]:
    """`mavlink:udpin:0.0.0.0:14550` → (`mavlink`, `udpin:0.0.0.0:14550`).

    >>> split_uri("mavlink:tcp:127.0.0.1:5760")
    ('mavlink', 'tcp:127.0.0.1:5760')
    """
    scheme, sep, address = uri.partition(":")
    if not sep or not scheme or not address:
        raise VehicleError(f"vehicle URI '{uri}' is not SCHEME:ADDRESS (e.g. mavlink:udpin:0.0.0.0:14550)")
    return scheme, address


def open_vehicle(uri: str, mission: Mission, options: VehicleOptions | None = None) -> OnboardVehicle:
    """Find the adapter for the URI's scheme and open the vehicle (see the module docstring)."""
    scheme, address = split_uri(uri)
    eps = {ep.name: ep for ep in entry_points(group=GROUP)}
    if scheme not in eps:
        known = ", ".join(sorted(eps)) or "none"
        raise VehicleError(f"no vehicle adapter for scheme '{scheme}' (installed: {known}; `auv vehicles` lists them)")
    try:
        factory: Any = eps[scheme].load()
    except Exception as exc:  # a broken adapter package is the user's environment, not our crash
        raise VehicleError(f"vehicle adapter '{scheme}' failed to load: {exc!r}") from exc
    vehicle: OnboardVehicle = factory(address, mission, options or VehicleOptions())
    return vehicle
