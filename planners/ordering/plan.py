"""The visiting order of characteristic-point sets and targets on an object (seed 002 §3.4, Figs 11–13).

Each target is referenced from a set of characteristic points: by default the nearest of its candidate sets
("the set nearest to the point of interest is chosen for referencing"), unless the caller fixes the binding. A set
is visited (recognised, the vehicle referenced to the object) before the targets bound to it, and the order of
all stops minimises the distance travelled from the start, plus an optional cost per set visited (the search and
referencing there, so fewer transitions are preferred when `set_cost` > 0). When a set is not recognised,
`replan` binds its targets to their next-nearest candidate set and orders the remaining stops from where the
vehicle is.

Positions are [north, east] or [north, east, down] in metres, in any one frame (the object's, usually).
"""

from __future__ import annotations

from collections.abc import Hashable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from .costs import distance_matrix
from .tsp import Method, solve_precedence

SetId = Hashable
TargetId = Hashable
Stop = tuple[Literal["set", "target"], Hashable]
TargetSpec = tuple[ArrayLike, Sequence[SetId] | None]


@dataclass(frozen=True)
class InspectionPlan:
    """An order of stops from `start`. `cost` is `length_m` plus `set_cost` per set in `order`; `binding` maps
    each target still to photograph to the set it is referenced from; `unreachable` lists targets none of whose
    candidate sets is left; `failed` are the sets found unrecognisable so far."""

    start: tuple[float, ...]
    order: tuple[Stop, ...]
    cost: float
    length_m: float
    binding: Mapping[TargetId, SetId]
    unreachable: tuple[TargetId, ...] = ()
    failed: frozenset[SetId] = frozenset()
    exact: bool = False
    sets: Mapping[SetId, tuple[float, ...]] = field(default_factory=dict, repr=False)
    targets: Mapping[TargetId, tuple[tuple[float, ...], tuple[SetId, ...]]] = field(default_factory=dict, repr=False)
    set_cost: float = 0.0


def _point(p: ArrayLike, dim: int | None, what: str) -> tuple[float, ...]:
    a = np.asarray(p, dtype=np.float64).reshape(-1)
    if a.size not in (2, 3) or (dim is not None and a.size != dim) or not np.all(np.isfinite(a)):
        want = f"{dim}" if dim is not None else "2 or 3"
        raise ValueError(f"{what} must be a finite position of {want} coordinates, got {p!r}")
    return tuple(float(x) for x in a)


def nearest_set(target: Sequence[float], candidates: Iterable[SetId], sets: Mapping[SetId, Sequence[float]],
                exclude: Iterable[SetId] = ()) -> SetId | None:
    """The candidate set nearest to `target`, skipping `exclude`; None when none is left (ties: first listed).

    >>> nearest_set((0, 0), ["a", "b"], {"a": (5, 0), "b": (1, 1)})
    'b'
    """
    skip = set(exclude)
    best: SetId | None = None
    best_d = np.inf
    for s in candidates:
        if s in skip:
            continue
        d = float(np.linalg.norm(np.subtract(sets[s], target)))
        if d < best_d:
            best, best_d = s, d
    return best


def _order(start: tuple[float, ...], sets: Mapping[SetId, tuple[float, ...]],
           targets: Mapping[TargetId, tuple[tuple[float, ...], tuple[SetId, ...]]], binding: Mapping[TargetId, SetId],
           satisfied: frozenset[SetId], set_cost: float, seed: int, method: Method,
           time_limit_s: float | None) -> tuple[tuple[Stop, ...], float, float, bool]:
    """Order the targets in `binding` and the sets they need (sets in `satisfied` are referenced already)."""
    need_sets = sorted({s for s in binding.values() if s not in satisfied}, key=repr)
    tids = list(binding)
    stops: list[Stop] = [("set", s) for s in need_sets] + [("target", t) for t in tids]
    if not stops:
        return (), 0.0, 0.0, True
    pts = np.array([start] + [sets[s] for s in need_sets] + [targets[t][0] for t in tids])
    length = distance_matrix(pts)
    cost = length.copy()
    if set_cost:
        half = 0.5 * set_cost                 # half on each of a set's two edges: a set is never last
        k = 1 + len(need_sets)
        cost[1:k, :] += half
        cost[:, 1:k] += half
        np.fill_diagonal(cost, 0.0)
    index = {s: 1 + i for i, s in enumerate(need_sets)}
    prec = [(index[binding[t]], 1 + len(need_sets) + j) for j, t in enumerate(tids) if binding[t] in index]
    tour = solve_precedence(cost, 0, prec, seed=seed, method=method, time_limit_s=time_limit_s)
    seq = tour.order[1:]
    metres = float(sum(length[a, b] for a, b in zip(tour.order[:-1], tour.order[1:], strict=True)))
    return tuple(stops[v - 1] for v in seq), metres + set_cost * len(need_sets), metres, tour.exact


def inspection_order(start: ArrayLike, sets: Mapping[SetId, ArrayLike], targets: Mapping[TargetId, TargetSpec],
                     seed: int = 0, binding: Mapping[TargetId, SetId] | None = None, set_cost: float = 0.0,
                     method: Method = "auto", time_limit_s: float | None = None) -> InspectionPlan:
    """Order the visits of point sets and targets from `start`.

    `targets[t] = (position, candidate_set_ids)`; an empty or None candidate list means any set. Each target is
    bound to its nearest candidate set unless `binding` fixes it; only sets some target is bound to are visited,
    each before its targets.

    >>> plan = inspection_order((0, 0), {"A": (10, 0), "B": (0, 10)},
    ...                         {"t1": ((12, 0), ["A", "B"]), "t2": ((0, 12), None), "t3": ((11, 1), ["A"])})
    >>> plan.order
    (('set', 'A'), ('target', 't1'), ('target', 't3'), ('set', 'B'), ('target', 't2'))
    >>> dict(plan.binding)
    {'t1': 'A', 't2': 'B', 't3': 'A'}
    """
    origin = _point(start, None, "start")
    dim = len(origin)
    set_pos = {s: _point(p, dim, f"set {s!r}") for s, p in sets.items()}
    target_spec: dict[TargetId, tuple[tuple[float, ...], tuple[SetId, ...]]] = {}
    for t, spec in targets.items():
        if not isinstance(spec, tuple | list) or len(spec) != 2:
            raise ValueError(f"target {t!r} must be (position, candidate set ids)")
        pos, cands = spec
        cand = tuple(cands) if cands else tuple(set_pos)
        unknown = [s for s in cand if s not in set_pos]
        if unknown:
            raise ValueError(f"target {t!r} names unknown sets {unknown} (known: {sorted(map(repr, set_pos))})")
        target_spec[t] = (_point(pos, dim, f"target {t!r}"), cand)
    fixed = dict(binding or {})
    for t, s in fixed.items():
        if t not in target_spec:
            raise ValueError(f"binding names unknown target {t!r}")
        if s not in set_pos:
            raise ValueError(f"binding ties target {t!r} to unknown set {s!r}")
    bound: dict[TargetId, SetId] = {}
    unreachable: list[TargetId] = []
    for t, (pos, cand) in target_spec.items():
        s = fixed.get(t, nearest_set(pos, cand, set_pos))
        if s is None:
            unreachable.append(t)
        else:
            bound[t] = s
    order, cost, metres, exact = _order(origin, set_pos, target_spec, bound, frozenset(), set_cost, seed, method,
                                        time_limit_s)
    return InspectionPlan(origin, order, cost, metres, bound, tuple(unreachable), frozenset(), exact, set_pos,
                          target_spec, set_cost)


def replan(plan: InspectionPlan, done: Iterable[Stop], failed_set: SetId | None, position: ArrayLike,
           seed: int = 0, method: Method = "auto", time_limit_s: float | None = None) -> InspectionPlan:
    """The remaining order from `position` after the stops in `done`, when `failed_set` (if not None) was not
    recognised: its targets (and those of sets that failed before) are bound to their nearest candidate set that
    has not failed; targets with none left become unreachable. Sets in `done` were recognised and count as
    visited, so targets bound to them need no new visit there.

    >>> plan = inspection_order((0, 0), {"A": (10, 0), "B": (0, 10)},
    ...                         {"t1": ((12, 0), ["A", "B"]), "t2": ((0, 12), ["B"])})
    >>> new = replan(plan, done=[], failed_set="A", position=(9, 0))
    >>> new.order, dict(new.binding)
    ((('set', 'B'), ('target', 't2'), ('target', 't1')), {'t1': 'B', 't2': 'B'})
    """
    here = _point(position, len(plan.start), "position")
    finished = set(done)
    for kind, ident in finished:
        if kind not in ("set", "target"):
            raise ValueError(f"a done stop must be ('set', id) or ('target', id), got {(kind, ident)!r}")
    failed = set(plan.failed)
    if failed_set is not None:
        if failed_set not in plan.sets:
            raise ValueError(f"unknown failed set {failed_set!r}")
        failed.add(failed_set)
    visited = frozenset(s for kind, s in finished if kind == "set") - failed
    bound: dict[TargetId, SetId] = {}
    unreachable: list[TargetId] = []
    for t, (pos, cand) in plan.targets.items():
        if ("target", t) in finished:
            continue
        s = plan.binding.get(t)
        if s is None or s in failed:
            s = nearest_set(pos, cand, plan.sets, exclude=failed)
        if s is None:
            unreachable.append(t)
        else:
            bound[t] = s
    order, cost, metres, exact = _order(here, plan.sets, plan.targets, bound, visited, plan.set_cost, seed, method,
                                        time_limit_s)
    return InspectionPlan(here, order, cost, metres, bound, tuple(unreachable), frozenset(failed), exact, plan.sets,
                          plan.targets, plan.set_cost)
