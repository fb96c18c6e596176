"""Planners: pure functions (arrays in, arrays out) for coverage, occupancy, information maps, RRT,
next-best-view and visiting order (seed 002 §2–3). They import neither the simulator nor `perception_plugins`.
"""
