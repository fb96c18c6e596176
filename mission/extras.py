"""Optional parts of the install: `pip install auv-mission` is the onboard install; the simulator (`[sim]`:
MuJoCo) and figures (`[plots]`: matplotlib) are extras. `require` turns a missing extra into one clear error.

>>> has("json")
True
"""

from __future__ import annotations

import importlib.util

from mission.errors import AuvError

EXTRAS = {"mujoco": "sim", "matplotlib": "plots"}


class MissingExtraError(AuvError):
    """An optional dependency a command needs is not installed."""


def has(module: str) -> bool:
    """Whether a top-level module can be imported (without importing it)."""
    try:
        return importlib.util.find_spec(module) is not None
    except (ImportError, ValueError):  # a broken install counts as missing
        return False


def require(module: str, purpose: str) -> None:
    """Raise `MissingExtraError` naming the extra that provides `module` when it is not installed."""
    if not has(module):
        extra = EXTRAS.get(module, module)
        raise MissingExtraError(f"{purpose} needs {module}, which is not installed: "
                                f"pip install 'auv-mission[{extra}]'")
