"""Tactical agents by route-element kind, and the reports they hand to the metrics."""

from __future__ import annotations

from collections.abc import Callable

from mission.agents.base import Agent, AgentContext, Status
from mission.agents.explore import ExploreAgent
from mission.agents.inspect import InspectAgent
from mission.agents.reference import ReferenceAgent
from mission.agents.report import AgentReport
from mission.agents.survey import SurveyAgent
from mission.agents.transit import TransitAgent

AgentFactory = Callable[[], Agent]

REGISTRY: dict[str, AgentFactory] = {
    "transit": TransitAgent,
    "survey": SurveyAgent,
    "reference": ReferenceAgent,
    "explore": ExploreAgent,
    "inspect": InspectAgent,
}


def supported_kinds() -> list[str]:
    return sorted(REGISTRY)


def create_agent(kind: str) -> Agent:
    return REGISTRY[kind]()


__all__ = ["Agent", "AgentContext", "AgentReport", "ExploreAgent", "InspectAgent", "REGISTRY", "ReferenceAgent",
           "Status", "SurveyAgent", "TransitAgent", "create_agent", "supported_kinds"]
