"""The information map and anomaly detection on planted boxes with known geometry."""

import math

import numpy as np
import pytest

from planners.detection import detect_anomalies
from planners.infomap import information_map, sobel_gradient


def seabed(rows=120, cols=160, cell=0.5, seed=0):
    """A sloping seabed at ~50 m with 0.1 m roughness (depth grid) and its coordinates."""
    rng = np.random.default_rng(seed)
    ii, jj = np.mgrid[0:rows, 0:cols]
    from scipy.ndimage import gaussian_filter

    rough = gaussian_filter(rng.standard_normal((rows, cols)), 6)
    rough *= 0.1 / rough.std()
    return 50.0 + 0.01 * ii * cell - 0.02 * jj * cell + rough


def plant_box(depth, cell, north, east, length, width, height, heading_deg=0.0):
    ii, jj = np.mgrid[0:depth.shape[0], 0:depth.shape[1]]
    n, e = ii * cell - north, jj * cell - east
    h = math.radians(heading_deg)
    along, across = n * math.cos(h) + e * math.sin(h), -n * math.sin(h) + e * math.cos(h)
    inside = (np.abs(along) <= length / 2) & (np.abs(across) <= width / 2)
    out = depth.copy()
    out[inside] -= height
    return out


def test_sobel_gradient_of_a_plane_is_its_slope():
    ii, jj = np.mgrid[0:30, 0:30].astype(float)
    plane = 0.1 * ii * 2.0 + 0.2 * jj * 2.0  # cell 2 m: slopes 0.1 and 0.2 m/m
    g = sobel_gradient(plane, cell=2.0)
    assert g[10:20, 10:20] == pytest.approx(math.hypot(0.1, 0.2))


def test_information_map_lights_the_edges_of_a_planted_box_and_blur_follows_nav_sigma():
    cell = 0.5
    depth = plant_box(seabed(cell=cell), cell, north=30, east=40, length=6, width=4, height=2)
    sharp = information_map(depth, cell, nav_sigma_m=0.25)
    wide = information_map(depth, cell, nav_sigma_m=2.0)
    edge = (int(30 / cell), int((40 + 2) / cell))  # on the east edge
    far = (10, 10)
    assert sharp[edge] > 20 * sharp[far]
    # A larger navigation sigma spreads the same edge: lower peak, wider support.
    assert wide.max() < sharp.max()
    assert (wide > 0.2 * wide.max()).sum() > (sharp > 0.2 * sharp.max()).sum()


def test_information_map_is_zero_where_nothing_was_observed():
    depth = seabed()
    depth[:, :20] = np.nan
    info = information_map(depth, 0.5, 1.0)
    assert np.all(info[:, :20] == 0.0) and np.isfinite(info).all()


def test_planted_objects_are_detected_with_their_position_size_and_height():
    cell = 0.5
    depth = seabed(rows=200, cols=240, cell=cell, seed=3)
    truth = [(30.0, 40.0, 8.0, 5.0, 2.5, 30.0), (70.0, 90.0, 3.0, 3.0, 1.0, 0.0)]
    for north, east, length, width, height, heading in truth:
        depth = plant_box(depth, cell, north, east, length, width, height, heading)
    info = information_map(depth, cell, nav_sigma_m=0.5)
    found = detect_anomalies(depth, 0.0, 0.0, cell, info)
    assert len(found) == len(truth)  # no false alarm on the rough, sloping seabed
    for north, east, length, width, height, _heading in truth:
        d = min(found, key=lambda f: math.hypot(f.north - north, f.east - east))
        assert math.hypot(d.north - north, d.east - east) < 0.5
        assert d.length == pytest.approx(length, abs=1.0) and d.width == pytest.approx(width, abs=1.0)
        assert d.height == pytest.approx(height, abs=0.3)
    big = max(found, key=lambda f: f.length)
    assert abs((big.heading_deg - 30.0 + 90) % 180 - 90) < 5.0


def test_a_bare_seabed_has_no_detections():
    depth = seabed(seed=5)
    assert detect_anomalies(depth, 0.0, 0.0, 0.5, information_map(depth, 0.5, 1.0)) == []
