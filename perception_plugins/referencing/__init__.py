"""Referencing to a known object by its characteristic points (seed 002 §3.1–3.3): identification by structural
coherence (pairwise-distance consistency) in a 3D cloud, then the least-squares rigid transform.

Public API (fixed for users and benchmarks): `identify`, `reference` (with its `Referencing` result),
`rigid_transform`; the paper's exponential search is `exhaustive_identify`, kept as a test oracle. Pure numpy
and scipy: it imports neither `mission` nor `planners` nor the simulator.
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
