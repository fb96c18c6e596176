"""The order of an inspection's stops (seed 002 §3.4: the visiting order optimised with a set before the targets
referenced to it, re-planned when a set is not recognised): the queue of stops, what is done, and the plan of
`planners.ordering` behind them."""

from __future__ import annotations

from collections.abc import Collection, Hashable, Mapping
from typing import Any

import numpy as np

from mission.language.models import Target
from planners.ordering import Stop


class Itinerary:
    """The stops still to visit (`queue`, a set as `("set", id)`, a target as `("target", id)`), those done,
    and the current plan; `order` is "auto" (optimised) or "as-listed" (the targets in the mission's order, each
    after its set)."""

    def __init__(self, sets: Mapping[str, np.ndarray], targets: Mapping[str, Target], order: str,
                 start_object: np.ndarray, seed: int, set_cost_m: float,
                 ratings: Mapping[str, float] | None = None):
        from planners.ordering import inspection_order

        self.sets = sets
        self.ratings = ratings or {}
        self.targets = targets
        self.seed = seed
        set_pos: dict[Hashable, Any] = {s: pts.mean(axis=0) for s, pts in sets.items()}
        spec: dict[Hashable, Any] = {tid: (np.asarray(t.at, dtype=float), self._candidates(t.reference, t.at))
                                     for tid, t in targets.items()}
        binding: dict[Hashable, Hashable] = {tid: t.reference for tid, t in targets.items()}
        self.plan = inspection_order(start_object, set_pos, spec, seed=seed, binding=binding, set_cost=set_cost_m)
        self.queue: list[Stop] = self._as_listed(binding) if order == "as-listed" else list(self.plan.order)
        self.done: list[Stop] = []

    def _reach(self, set_id: str, point: Any) -> float:
        """Distance from a set to a point, divided by the set's detectability (`mission.language.detectability`):
        a set half as detectable counts as twice as far, so a target is re-bound to, and re-referenced at, the
        set most likely to be recognised unless it is much farther."""
        distance = float(np.linalg.norm(self.sets[set_id].mean(axis=0) - np.asarray(point, dtype=float)))
        return distance / max(self.ratings.get(set_id, 1.0), 1e-3)

    def _candidates(self, reference: str, at: Any) -> list[str]:
        """The target's own set first, then the others by detectability-weighted distance (`_reach`), for
        re-binding when a set fails."""
        others = sorted((s for s in self.sets if s != reference), key=lambda s: self._reach(s, at))
        return [reference, *others]

    def _as_listed(self, binding: Mapping[Hashable, Hashable]) -> list[Stop]:
        order: list[Stop] = []
        for tid in self.targets:
            if ("set", binding[tid]) not in order:
                order.append(("set", binding[tid]))
            order.append(("target", tid))
        return order

    @property
    def failed(self) -> Collection[Hashable]:
        """The sets found unrecognisable so far."""
        return self.plan.failed

    def position(self, stop: Stop) -> np.ndarray:
        """A stop's point in the object frame: a set's centroid or a target."""
        kind, raw = stop
        ident = str(raw)
        return self.sets[ident].mean(axis=0) if kind == "set" else np.array(self.targets[ident].at, dtype=float)

    def nearest_usable_set(self, point: np.ndarray) -> str | None:
        usable = [s for s in self.sets if s not in self.plan.failed]
        if not usable:
            return None
        return min(usable, key=lambda s: self._reach(s, point))

    def replan(self, failed: str, here_object: np.ndarray, pending: Collection[str]) -> dict[str, Any]:
        """Bind the targets of a set that failed to other sets and order what is left (`pending` targets) from
        `here_object`; returns the record of the re-plan."""
        from planners.ordering import replan

        done: list[Stop] = [s for s in self.done if s[0] == "set"]
        done += [("target", t) for t in self.targets if t not in pending]
        self.plan = replan(self.plan, done, failed, here_object, seed=self.seed)
        self.queue = list(self.plan.order)
        return {"failed_set": failed, "order": [list(s) for s in self.queue], "binding": dict(self.plan.binding),
                "unreachable": list(self.plan.unreachable)}
