"""Visiting order of characteristic-point sets and targets (seed 002 §3.4, Figs 11–13): a travelling-salesman path
with precedence (a set before the targets referenced to it), each target bound to its nearest set, re-planned when
a set is not recognised.

Exact (Held–Karp dynamic programming) up to 12 stops besides the start; beyond, iterated local search with
Lin–Kernighan-style 2-/3-opt chains (plain tours) or precedence-keeping Or-opt and 2-opt moves (paths with
precedence), deterministic under a seed. Pure Python and numpy; imports nothing from `mission`.
"""

from .costs import Tour, distance_matrix, tour_cost
from .exact import EXACT_MAX_STOPS, held_karp
from .plan import InspectionPlan, Stop, inspection_order, nearest_set, replan
from .precedence import violations
from .tsp import solve_precedence, solve_tsp

__all__ = [
    "EXACT_MAX_STOPS",
    "InspectionPlan",
    "Stop",
    "Tour",
    "distance_matrix",
    "held_karp",
    "inspection_order",
    "nearest_set",
    "replan",
    "solve_precedence",
    "solve_tsp",
    "tour_cost",
    "violations",
]
