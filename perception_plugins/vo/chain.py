"""Chains of local transforms (seed 003: the pose of a position is the product of the local matrices of the steps
that led to it). A chain is a persistent linked list: appending shares the prefix, so reference frames keep their
own chains cheaply and a position bound to a reference continues the reference's (shorter) chain.

>>> from perception_plugins.vo.se3 import from_rotvec_translation
>>> step = from_rotvec_translation([0, 0, 0], [1.0, 0, 0])
>>> c = Chain.origin().append(step).append(step)
>>> c.length, c.pose()[:3, 3].tolist()
(2, [2.0, 0.0, 0.0])
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from perception_plugins.vo.se3 import Matrix


@dataclass(frozen=True, eq=False)
class Chain:
    """The chain ending at one position: its parent chain and the local transform T_parent_this."""

    parent: Chain | None
    T_parent_this: Matrix
    length: int
    T_origin_this: Matrix
    """The product of the chain (kept with the node: poses are asked for often, chains only grow)."""

    @staticmethod
    def origin() -> Chain:
        return Chain(None, np.eye(4), 0, np.eye(4))

    def append(self, T_this_next: Matrix) -> Chain:
        return Chain(self, T_this_next.copy(), self.length + 1, self.T_origin_this @ T_this_next)

    def pose(self) -> Matrix:
        return self.T_origin_this.copy()

    def transforms(self) -> list[Matrix]:
        """The local transforms from the origin to this position, in order."""
        out: list[Matrix] = []
        node: Chain | None = self
        while node is not None and node.parent is not None:
            out.append(node.T_parent_this)
            node = node.parent
        return out[::-1]


__all__ = ["Chain"]
