"""The multi-view package's own exception (the CLI maps it to a one-line message; it imports nothing of `mission`)."""

from __future__ import annotations


class MultiviewError(Exception):
    """A model that cannot be built, read or used: too few views, no base segment, a malformed model file."""


__all__ = ["MultiviewError"]
