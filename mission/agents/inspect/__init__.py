"""The `inspect` agent, made of parts (seed 002 §3.4): `agent` sequences the stops that `itinerary` orders;
`visit` references at a set (searching with `search`, viewing with `viewing`, judging and fusing with
`referencer`), `odometry` carries the fix between sets, `targets` photographs; `placement` is where the object is
believed to be, `motion` how the vehicle moves over it, `settings` its numbers and `states` its states."""

from mission.agents.inspect.agent import InspectAgent
from mission.agents.inspect.search import expanding_square, meander_offsets
from mission.agents.inspect.settings import InspectSettings
from mission.agents.inspect.viewing import fit_altitude

__all__ = ["InspectAgent", "InspectSettings", "expanding_square", "fit_altitude", "meander_offsets"]
