"""Fusing several referenced views of one object (seed 000, approach 3): keep the largest group of views whose
own transforms agree, then one least-squares transform from all their points, each view's points placed in the
common frame (the world, or the object's tracked frame) with that view's camera pose."""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from mission.geometry import rigid_transform, transform_points

View = tuple[np.ndarray, np.ndarray]  # (identified model points (k, 3), the same points in the common frame (k, 3))
# How closely the transforms of two views must place the points for the views to agree, in one place for both
# agents. Views taken from one range (the reference agent's, at the seed's 3.6 m) agree within 4 cm; the inspect
# agent's fine views are taken across 3.6–4.4 m above a set, where the stereo depth error grows like the range
# squared, and its base at 3.6 m is 5 cm, scaled with the range (`inspect.viewing.SetViewer.agreement`). Measured:
# the reference agent at 5 cm fuses a 4 cm-off view into the multiview mission's fix (3.4 cm off, 3.0 cm before);
# the inspect campaigns (README, "Reliability over seeds") were measured at 5 cm.
VIEW_AGREEMENT_M = 0.04  # views from one range
SPREAD_VIEW_AGREEMENT_M = 0.05  # views across the fine heights, at the lowest (scaled with the range)


class Fused(NamedTuple):
    """One transform from agreeing views: T_frame_object, how many views and points it used, its residual RMS."""

    T: np.ndarray
    views: int
    residual_m: float
    points: int


def consistent_views(views: Sequence[View], agreement: float) -> list[View]:
    """The largest group of views that agree with one another (a wrong identification that slipped through
    would otherwise pull the fused transform).

    >>> model = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    >>> wrong = (model, model + [0.3, 0.0, 0.0])
    >>> len(consistent_views([(model, model), (model, model + 0.01), wrong], VIEW_AGREEMENT_M))
    2
    """
    if not views:
        return []
    probe = np.vstack([m for m, _ in views])
    placed = [transform_points(rigid_transform(m, w), probe) for m, w in views]
    agree = [[j for j in range(len(placed))
              if float(np.max(np.linalg.norm(placed[i] - placed[j], axis=1))) <= agreement]
             for i in range(len(placed))]
    return [views[j] for j in max(agree, key=len)]


def fuse_views(views: Sequence[View], agreement: float, minimum: int = 2) -> Fused | None:
    """T_frame_object from the views that agree within `agreement` (m), with the number of views and points
    used and the residual RMS (m); None while fewer than `minimum` views agree."""
    agreeing = consistent_views(views, agreement)
    if len(agreeing) < minimum:
        return None
    model = np.vstack([m for m, _ in agreeing])
    common = np.vstack([w for _, w in agreeing])
    T = rigid_transform(model, common)
    residual = float(np.sqrt(np.mean(np.sum((transform_points(T, model) - common) ** 2, axis=1))))
    return Fused(T, len(agreeing), residual, len(model))
