"""The truth of a served simulation, written as it goes: `trajectory.csv` (true and estimated pose, through
`mission.runfolder.TrajectoryWriter`) and `usbl.csv`, moved out of the vehicle's log and flushed at least every
`mission.runfolder.FLUSH_S` of wall time, so that a killed `auv sim serve` loses at most that much.
"""

from __future__ import annotations

import csv
import time
from pathlib import Path
from typing import IO

from mission.runfolder import FLUSH_S, TrajectoryWriter
from mission.sim.vehicle import SimLog

USBL_COLUMNS = ("time", "north", "east", "used", "accepted")


class TruthLog:
    """Moves rows out of a `SimLog` into the run folder's CSV files (the log keeps nothing once written)."""

    def __init__(self, out: Path):
        self._traj = TrajectoryWriter(out / "trajectory.csv")
        self._usbl: IO[str] = (out / "usbl.csv").open("w", newline="", encoding="utf-8")
        self._w_usbl = csv.writer(self._usbl)
        self._w_usbl.writerow(USBL_COLUMNS)
        self._usbl.flush()
        self._flushed = time.monotonic()

    def take(self, log: SimLog) -> None:
        """Write the rows and fixes logged since the last call."""
        for row in log.rows:
            self._traj.write(row)
        for fix in log.fixes:
            self._w_usbl.writerow((f"{fix.time:.2f}", f"{fix.north:.3f}", f"{fix.east:.3f}", int(fix.used),
                                   int(fix.accepted)))
        log.rows.clear()
        log.fixes.clear()
        if time.monotonic() - self._flushed >= FLUSH_S:
            self._usbl.flush()
            self._flushed = time.monotonic()

    def close(self) -> None:
        self._traj.close()
        self._usbl.close()
