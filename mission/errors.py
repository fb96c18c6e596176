"""The one exception root of auv-mission and a subclass per failure mode.

The library raises these; only the CLI turns them into one-line messages and exit codes.
"""

from __future__ import annotations

from dataclasses import dataclass


class AuvError(Exception):
    """Root of every error auv-mission raises on purpose."""


@dataclass(frozen=True)
class Diagnostic:
    """One located problem in a mission or world file (1-based line and column). A `warning` is legal but
    probably not what the designer meant (a leg that will trip a safety monitor): reported, not refused."""

    file: str
    line: int
    col: int
    message: str
    warning: bool = False

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.col}: {'warning: ' if self.warning else ''}{self.message}"


class MissionError(AuvError):
    """A mission (or the world it names) is invalid; carries every problem found."""

    def __init__(self, diagnostics: list[Diagnostic]):
        self.diagnostics = sorted(diagnostics, key=lambda d: (d.file, d.line, d.col))
        super().__init__("\n".join(str(d) for d in self.diagnostics))


class UnsupportedMissionError(AuvError):
    """The mission is valid but uses route-element kinds this build cannot run yet."""


class PluginError(AuvError):
    """A perception plug-in is missing, broken, or failed while running."""


class RunFolderError(AuvError):
    """A run folder is missing files or holds files of the wrong shape."""


class VehicleError(AuvError):
    """A vehicle adapter cannot be found, reached, or commanded (unknown URI scheme, no heartbeat, refused
    arming or mode change)."""


class LinkLostError(VehicleError):
    """The link to a real vehicle was silent for longer than `safety.link_timeout`."""
