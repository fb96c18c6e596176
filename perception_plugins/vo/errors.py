"""The visual-odometry package's one exception (perception plug-ins may not import `mission.errors`; the CLI maps
`VoError` onto its own error root)."""

from __future__ import annotations


class VoError(Exception):
    """A stereo sequence is missing, unreadable or laid out wrongly, or an option is invalid."""


__all__ = ["VoError"]
