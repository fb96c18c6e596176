"""Referencing to a known object by its characteristic points (seed 002 §3.1–3.3): identification by structural
coherence (pairwise-distance consistency) in a 3D cloud, then the least-squares rigid transform.

Public API (fixed for users and benchmarks): `identify`, `reference` (with its `Referencing` result),
`rigid_transform`; the paper's exponential search is `exhaustive_identify`, kept as a test oracle. Pure numpy
and scipy: the algorithm imports neither `mission` nor `planners` nor the simulator (only the plug-in adapter,
`plugin.py`, does, and this package does not import it).

Modules: `consistency` (distances, the consistency graph, signature pruning), `anchors` (the polynomial descent
over subset sizes by anchor triangles), `placements` (scoring and refining the placements they give), `clique`
(exact and polynomial maximum cliques), `transform` (Kabsch and its robust refinement), `identification` (the
pipeline and the API), `exhaustive` (the seed's search).
"""

from perception_plugins.referencing.exhaustive import exhaustive_identify
from perception_plugins.referencing.identification import Identification, Referencing, identify, reference
from perception_plugins.referencing.transform import rigid_transform, robust_rigid_transform

__all__ = [
    "Identification",
    "Referencing",
    "exhaustive_identify",
    "identify",
    "reference",
    "rigid_transform",
    "robust_rigid_transform",
]
