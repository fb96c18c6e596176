"""The bounded frame queue drops the oldest frames and counts them; the navigation track places a frame at its
own stamp, not at the latest estimate."""

from __future__ import annotations

import threading

import pytest

from mission.sensors.navtrack import NavTrack
from mission.sensors.queue import DropOldestQueue
from mission.vehicle import NavState


def nav(t: float, north: float, east: float, heading: float = 90.0) -> NavState:
    return NavState(time=t, north=north, east=east, depth=10.0 + t, heading=heading, speed=1.0, altitude=5.0,
                    position_sigma=0.5, energy_wh=100.0)


def test_a_full_queue_drops_the_oldest_frames_and_counts_them() -> None:
    q: DropOldestQueue[int] = DropOldestQueue(4)
    for i in range(10):
        q.put(i)
    assert q.drain() == [6, 7, 8, 9]
    assert (q.received, q.dropped, len(q)) == (10, 6, 0)


def test_a_queue_fed_by_a_thread_faster_than_its_consumer_never_holds_more_than_its_capacity() -> None:
    q: DropOldestQueue[bytes] = DropOldestQueue(3)
    seen: list[int] = []

    def produce() -> None:
        for _ in range(20_000):
            q.put(b"x" * 100)

    worker = threading.Thread(target=produce)
    worker.start()
    while worker.is_alive():
        seen.append(len(q.drain()))
    worker.join()
    seen.append(len(q.drain()))
    assert max(seen) <= 3
    assert q.received == 20_000
    assert q.dropped + sum(seen) == 20_000


def test_the_track_interpolates_the_estimate_to_a_frame_stamp() -> None:
    track = NavTrack()
    track.add(nav(10.0, 0.0, 0.0))
    track.add(nav(10.2, 0.3, 0.1))
    at = track.at(10.05)
    assert at is not None
    assert at.time == pytest.approx(10.05)
    assert (at.north, at.east, at.depth) == pytest.approx((0.075, 0.025, 20.05))


def test_a_frame_ahead_of_the_estimate_waits_and_one_before_the_history_takes_its_oldest_pose() -> None:
    track = NavTrack()
    track.add(nav(10.0, 1.0, 2.0))
    track.add(nav(10.2, 1.2, 2.0))
    assert track.at(10.3) is None
    old = track.at(5.0)
    assert old is not None and (old.north, old.east) == (1.0, 2.0)


def test_headings_interpolate_the_short_way_across_north() -> None:
    track = NavTrack()
    track.add(nav(0.0, 0.0, 0.0, heading=350.0))
    track.add(nav(1.0, 0.0, 0.0, heading=20.0))
    at = track.at(0.5)
    assert at is not None and at.heading == pytest.approx(5.0)


def test_the_track_keeps_only_its_history_window() -> None:
    track = NavTrack(history_s=1.0)
    for i in range(100):
        track.add(nav(i * 0.2, float(i), 0.0))
    assert len(track._states) <= 6
