"""The truth of a served simulation, written as it goes: `trajectory.csv` (true and estimated pose, the columns
of `mission.sim.vehicle.TRAJECTORY_COLUMNS`) and `usbl.csv`, appended from the vehicle's log and flushed at least
every `FLUSH_PERIOD` of wall time, so that a killed `auv sim serve` loses at most that much.
"""

from __future__ import annotations

import csv
import time
from pathlib import Path
from typing import IO

from mission.sim.vehicle import TRAJECTORY_COLUMNS, SimLog

FLUSH_PERIOD = 0.5  # s of wall time
USBL_COLUMNS = ("time", "north", "east", "used", "accepted")


class TruthLog:
    """Moves rows out of a `SimLog` into the run folder's CSV files (the log keeps nothing once written)."""

    def __init__(self, out: Path):
        self._traj: IO[str] = (out / "trajectory.csv").open("w", newline="", encoding="utf-8")
        self._usbl: IO[str] = (out / "usbl.csv").open("w", newline="", encoding="utf-8")
        self._w_traj = csv.writer(self._traj)
        self._w_usbl = csv.writer(self._usbl)
        self._w_traj.writerow(TRAJECTORY_COLUMNS)
        self._w_usbl.writerow(USBL_COLUMNS)
        self._flushed = time.monotonic()
        self.flush()

    def take(self, log: SimLog) -> None:
        """Write the rows and fixes logged since the last call, and flush when FLUSH_PERIOD has passed."""
        for row in log.rows:
            self._w_traj.writerow([f"{v:.4f}" if isinstance(v, float) else v for v in row])
        for fix in log.fixes:
            self._w_usbl.writerow((f"{fix.time:.2f}", f"{fix.north:.3f}", f"{fix.east:.3f}", int(fix.used),
                                   int(fix.accepted)))
        log.rows.clear()
        log.fixes.clear()
        if time.monotonic() - self._flushed >= FLUSH_PERIOD:
            self.flush()

    def flush(self) -> None:
        self._traj.flush()
        self._usbl.flush()
        self._flushed = time.monotonic()

    def close(self) -> None:
        self.flush()
        self._traj.close()
        self._usbl.close()
