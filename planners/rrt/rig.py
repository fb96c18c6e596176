"""Rapidly-exploring information gathering (RIG-tree, Hollinger & Sukhatme 2014), run in receding horizon.

Pure tree logic, written here (no library provides it); the motions come from a `Steer` callable (the adapter
`planners.rrt.rig_survey` gives OMPL Dubins curves checked against the clearance grid) and the information from
`planners.rrt.photo_gain.PhotoModel`. Each node carries its pose (north, east, yaw), the path cost from the root
(metres), the photograph counts of every information cell along its branch and the information they revealed.

One round grows a tree from the vehicle's pose:

1. sample a point: with probability `informed` a cell drawn in proportion to the information still unrevealed
   there (Î·ρⁿ at the root; jittered inside the cell), otherwise uniformly over the sampling box;
2. take the open node nearest the sample (straight distance plus `turn_penalty` metres per radian the node must
   turn to face it) and steer from it towards the sample by at most `step` metres;
3. from each of the `k_near` open nodes within `near_radius` of that point (by the same measure), steer to it;
   a motion that is blocked or would exceed the round's horizon is dropped; the new node's photographs are
   triggered every `photo_spacing / (1 + gain·Î)` metres along the motion (skipped where the footprint holds no
   information or, given `allowed`, misses the area) and counted into a copy of its parent's counts;
4. prune by dominance: a new node is dropped when a node within `prune_radius` (heading within 45°) has no more
   cost and at least as much information; a node whose cost reaches the horizon is closed (never extended).

After `iterations` samples the round commits the branch to the node that revealed the most information per
metre (at least `step` long), and the next round starts at its end. When no node reveals anything, the round is
grown again with twice the horizon (up to the budget left); when even that finds nothing, the branch towards the
most informative unrevealed cell is committed (a tree whose root is nearest that cell is grown afresh, at most
`RETRIES` times). Rounds go on until the path budget is spent or the information
still unrevealed in the area (Σ Î·ρⁿ) is at most `enough` of the area's total (the budget is an upper bound: the
rest would only add photographs of ground already photographed). Everything random draws from one seeded
generator: a plan repeats exactly for its seed.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from planners.rrt.photo_gain import Counts, PhotoModel

Array = NDArray[np.float64]
Pose = tuple[float, float, float]
RETRIES = 3
Steer = Callable[[Pose, float, float, float], Array | None]
"""(pose, north, east, max_length) → samples (K, 3) of north, east, yaw from the pose (first row) to the end
of a feasible motion towards (north, east) no longer than max_length (≤ 0.5 m apart), or None when blocked."""


@dataclass(frozen=True)
class RigSettings:
    """Parameters of the RIG tree and of the receding horizon."""

    budget: float
    photo_spacing: float
    gain: float = 2.0
    horizon: float = 40.0
    iterations: int = 100
    step: float = 6.0
    near_radius: float = 8.0
    k_near: int = 2
    prune_radius: float = 1.5
    informed: float = 0.6
    enough: float = 0.2
    turn_penalty: float = 0.0
    seed: int = 0


@dataclass
class Node:
    pose: Pose
    cost: float
    info: float
    counts: Counts
    parent: int
    since_photo: float
    samples: Array
    photos: Array


@dataclass(frozen=True)
class RigPlan:
    """The committed path and its photographs."""

    samples: Array
    """(K, 3) north, east, yaw along the path."""
    photos: Array
    """(M, 3) north, east, yaw of the photographs."""
    length: float
    information: float
    counts: Counts
    rounds: int
    nodes: int


def plan_rig(start: Pose, model: PhotoModel, steer: Steer, box: tuple[float, float, float, float],
             settings: RigSettings, allowed: NDArray[np.bool_] | None = None) -> RigPlan:
    """Receding-horizon RIG from `start` within `box` (north_lo, north_hi, east_lo, east_hi) under the budget.

    `allowed` (flat, per information cell) marks the cells informed samples may be drawn in (the survey area).
    """
    rng = np.random.default_rng(settings.seed)
    root = Node(start, 0.0, 0.0, model.zero_counts(), -1, settings.photo_spacing, np.array([start]),
                np.zeros((0, 3)))
    root.photos = np.array([start])  # the first photograph at the start
    root.info = model.add(root.counts, model.cells(*start))
    samples, photos = [root.samples], [root.photos]
    spent, rounds, nodes = 0.0, 0, 0
    area = model.flat_info if allowed is None else model.flat_info * allowed
    total = float(area.sum())
    reach, misses = settings.horizon, 0
    while settings.budget - spent >= 1.0:
        if float(np.sum(area * model.repeat ** root.counts.astype(float))) <= settings.enough * total:
            break  # what is left unrevealed is not worth the rest of the budget
        horizon = min(reach, settings.budget - spent)
        tree = _grow(root, model, steer, box, settings, horizon, rng, allowed)
        rounds += 1
        nodes += len(tree)
        best, gained = _best(tree, root, model, settings.step, allowed)
        if not gained and horizon < settings.budget - spent:
            reach = 2.0 * horizon  # nothing to photograph within reach: look further before moving
            continue
        reach = settings.horizon
        branch = _branch(tree, best)
        if not branch:
            misses += 1
            if misses > RETRIES:
                break
            continue  # grow another tree from here: the samples differ
        misses = 0
        for node in branch:
            samples.append(node.samples[1:])
            photos.append(node.photos)
        end = branch[-1]
        spent += end.cost
        root = Node(end.pose, 0.0, end.info, end.counts, -1, end.since_photo, end.samples[-1:], np.zeros((0, 3)))
    path = np.concatenate(samples)
    return RigPlan(path, np.concatenate(photos), spent, root.info, root.counts, rounds, nodes)


def _grow(root: Node, model: PhotoModel, steer: Steer, box: tuple[float, float, float, float],
          s: RigSettings, horizon: float, rng: np.random.Generator, allowed: NDArray[np.bool_] | None) -> list[Node]:
    tree = [root]
    xy = np.full((1 + s.iterations * s.k_near, 2), np.inf)
    yaw = np.zeros(len(xy))
    cost = np.zeros(len(xy))
    info = np.zeros(len(xy))
    open_ = np.zeros(len(xy), dtype=bool)
    xy[0], yaw[0], open_[0] = root.pose[:2], root.pose[2], True
    weights = model.flat_info * model.repeat ** root.counts.astype(float)
    if allowed is not None:
        weights = weights * allowed
    total = float(weights.sum())
    cdf = np.cumsum(weights) / total if total > 0 else None
    for _ in range(s.iterations):
        target = _sample(rng, model, box, cdf, s.informed)
        d2 = np.where(open_, _reach(xy, yaw, target, s.turn_penalty), np.inf)
        nearest = int(np.argmin(d2))
        if not math.isfinite(d2[nearest]):
            break
        motion = steer(tree[nearest].pose, float(target[0]), float(target[1]), s.step)
        if motion is None or len(motion) < 2:
            continue
        feasible = motion[-1, :2]
        d2 = np.where(open_, _reach(xy, yaw, feasible, s.turn_penalty), np.inf)
        near = [int(k) for k in np.argsort(d2)[: s.k_near] if d2[k] <= s.near_radius]
        for k in near or [nearest]:
            parent = tree[k]
            if k == nearest:
                edge = motion
            else:
                found = steer(parent.pose, float(feasible[0]), float(feasible[1]), s.near_radius * 1.6)
                if found is None or len(found) < 2:
                    continue
                edge = found
            node = _extend(parent, k, edge, model, s, horizon, allowed)
            if node is None:
                continue
            dx, dy = xy[: len(tree), 0] - node.pose[0], xy[: len(tree), 1] - node.pose[1]
            dyaw = np.abs((yaw[: len(tree)] - node.pose[2] + math.pi) % (2 * math.pi) - math.pi)
            if np.any((dx * dx + dy * dy <= s.prune_radius ** 2) & (dyaw <= math.pi / 4)
                      & (cost[: len(tree)] <= node.cost) & (info[: len(tree)] >= node.info)):
                continue  # dominated: another node got at least as much for no more
            i = len(tree)
            tree.append(node)
            xy[i], yaw[i], cost[i], info[i] = node.pose[:2], node.pose[2], node.cost, node.info
            open_[i] = node.cost < horizon - 1e-6
    return tree


def _reach(xy: Array, yaw: Array, target: Array, turn_penalty: float) -> Array:
    """How far each node is from reaching `target`: the straight distance plus `turn_penalty` metres per radian
    the node must turn to face it (a cheap stand-in for the Dubins length, which puts the nodes behind the
    target's bearing farther away than those heading for it)."""
    d = target - xy
    dist = np.hypot(d[:, 0], d[:, 1])
    turn = np.abs((np.arctan2(d[:, 1], d[:, 0]) - yaw + math.pi) % (2.0 * math.pi) - math.pi)
    return np.asarray(dist + turn_penalty * np.where(dist > 1e-9, turn, 0.0))


def _sample(rng: np.random.Generator, model: PhotoModel, box: tuple[float, float, float, float],
            cdf: Array | None, informed: float) -> Array:
    if cdf is not None and rng.random() < informed:
        flat = min(int(np.searchsorted(cdf, rng.random())), len(cdf) - 1)
        i, j = divmod(flat, model.shape[1])
        c = model.field.cell
        return np.array([model.field.north0 + (i + rng.uniform(-0.5, 0.5)) * c,
                         model.field.east0 + (j + rng.uniform(-0.5, 0.5)) * c])
    return np.array([rng.uniform(box[0], box[1]), rng.uniform(box[2], box[3])])


def _extend(parent: Node, index: int, edge: Array, model: PhotoModel, s: RigSettings, horizon: float,
            allowed: NDArray[np.bool_] | None) -> Node | None:
    """The node at the end of `edge` from `parent`, its photographs counted (only those whose footprint holds
    information, or touches the `allowed` cells when given); None when past the horizon."""
    steps = np.hypot(np.diff(edge[:, 0]), np.diff(edge[:, 1])).tolist()
    length = float(sum(steps))
    if length < 1e-6 or parent.cost + length > horizon + 1e-6:
        return None
    counts = parent.counts.copy()
    gained, since, shots = parent.info, parent.since_photo, []
    rows = edge.tolist()
    for k in range(1, len(rows)):
        since += steps[k - 1]
        n, e, y = rows[k]
        if since >= s.photo_spacing / (1.0 + s.gain * model.info_at(n, e)):
            cells = model.cells(n, e, y)
            if (model.flat_info[cells] > 0).any() if allowed is None else allowed[cells].any():
                gained += model.add(counts, cells)
                shots.append(rows[k])
            since = 0.0
    end = edge[-1]
    return Node((float(end[0]), float(end[1]), float(end[2])), parent.cost + length, gained, counts, index, since,
                edge, np.asarray(shots, dtype=float).reshape(-1, 3))


def _best(tree: list[Node], root: Node, model: PhotoModel, step: float,
          allowed: NDArray[np.bool_] | None) -> tuple[int, bool]:
    """The node revealing the most information per metre (≥ `step` long, or the longest), and True; else the
    one nearest the most informative unrevealed cell, and False (−1 when that is the root or there is none)."""
    if len(tree) < 2:
        return -1, False
    cost = np.array([n.cost for n in tree])
    rate = np.array([(n.info - root.info) / n.cost if n.cost > 0 else -1.0 for n in tree])
    eligible = cost >= min(step, float(cost.max())) - 1e-9
    rate = np.where(eligible, rate, -1.0)
    if rate.max() > 1e-9:
        return int(np.argmax(rate)), True
    left = model.flat_info * model.repeat ** root.counts.astype(float)
    if allowed is not None:
        left = left * allowed
    if left.max() <= 0:
        return -1, False
    i, j = divmod(int(np.argmax(left)), model.shape[1])
    goal = np.array([model.field.north0 + i * model.field.cell, model.field.east0 + j * model.field.cell])
    d = np.array([math.hypot(n.pose[0] - goal[0], n.pose[1] - goal[1]) for n in tree])
    best = int(np.argmin(d))
    return (best if best != 0 else -1), False


def _branch(tree: list[Node], index: int) -> list[Node]:
    """The nodes from the root's child to `index`, in flying order."""
    out: list[Node] = []
    while index > 0:
        out.append(tree[index])
        index = tree[index].parent
    return out[::-1]
