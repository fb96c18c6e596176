"""The inspect agent's explicit states.

A stop is a point set or a target. At a set the agent is in one of two stages, and in both it moves through the
same phases; at a target, through the photo phases:

| stop   | stage  | phases                                     | a result leads to                               |
|--------|--------|--------------------------------------------|-------------------------------------------------|
| set    | SEARCH | GO → SETTLE → CAPTURE → AWAIT → GO (next)  | a hit (also from a frame on the way): FINE      |
| set    | FINE   | GO → SETTLE → CAPTURE → AWAIT → GO (view)  | enough agreeing views: referenced, next stop;   |
|        |        |                                            | too many failures: re-plan, or back to SEARCH   |
| target | —      | GO ⇄ SETTLE → PHOTO                        | photos taken: next stop; odometry lost: a set   |

AWAIT holds the station until the referencing plug-in answers (its result may come ticks later).
"""

from __future__ import annotations

import enum


class Stage(enum.Enum):
    SEARCH = "search"  # the object not yet placed: any set will do, over the search pattern
    FINE = "fine"  # over one set, fused views to fix the object


class Phase(enum.Enum):
    GO = "go"  # on the way to the goal
    SETTLE = "settle"  # there, letting the vehicle settle
    CAPTURE = "capture"  # the next stereo frame is referenced
    AWAIT = "await"  # the referencing plug-in has the frame
    PHOTO = "photo"  # at a target's viewpoint, taking photos


class StopKind(enum.Enum):
    SET = "set"
    TARGET = "target"
