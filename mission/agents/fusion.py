"""Fusing several referenced views of one object (seed 000, approach 3): keep the largest group of views whose
own transforms agree, then one least-squares transform from all their points, each view's points placed in the
world with that view's (dead-reckoned) camera pose."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from mission.frames import transform_points

View = tuple[np.ndarray, np.ndarray]  # (identified model points (k, 3), the same points in the world (k, 3))
VIEW_AGREEMENT_M = 0.05  # views whose transforms place the points this close agree


def consistent_views(views: Sequence[View], agreement: float = VIEW_AGREEMENT_M) -> list[View]:
    """The largest group of views that agree with one another (a wrong identification that slipped through
    would otherwise pull the fused transform)."""
    from perception_plugins.referencing import rigid_transform

    if not views:
        return []
    probe = np.vstack([m for m, _ in views])
    placed = [transform_points(rigid_transform(m, w), probe) for m, w in views]
    agree = [[j for j in range(len(placed))
              if float(np.max(np.linalg.norm(placed[i] - placed[j], axis=1))) <= agreement]
             for i in range(len(placed))]
    return [views[j] for j in max(agree, key=len)]


def fuse_views(views: Sequence[View], minimum: int = 2, agreement: float = VIEW_AGREEMENT_M
               ) -> tuple[np.ndarray, int, float, int] | None:
    """T_world_object from the views that agree within `agreement` (m), with the number of views and points
    used and the residual RMS (m); None while fewer than `minimum` views agree."""
    from perception_plugins.referencing import rigid_transform

    agreeing = consistent_views(views, agreement)
    if len(agreeing) < minimum:
        return None
    model = np.vstack([m for m, _ in agreeing])
    world = np.vstack([w for _, w in agreeing])
    T = rigid_transform(model, world)
    residual = float(np.sqrt(np.mean(np.sum((transform_points(T, model) - world) ** 2, axis=1))))
    return T, len(agreeing), residual, len(model)
