"""Seabed generation and the placed scene, against the numbers the world file gives."""

import math

import numpy as np
from conftest import WORLD

from mission.frames import heading_of
from mission.language.loader import load_world
from mission.language.world import Seabed
from mission.world.scene import build_scene
from mission.world.terrain import generate_seabed


def test_seabed_has_the_given_mean_slope_and_roughness():
    spec = Seabed.model_validate({"north": [0, 400], "east": [0, 400], "resolution": 1.0, "mean_depth": 50,
                                  "slope": {"north": 0.01, "east": -0.02},
                                  "roughness": {"amplitude": 0.5, "wavelength": 20, "seed": 4}})
    field = generate_seabed(spec)
    north, east = field.grid()
    assert field.depth.mean() == np.float64(field.depth.mean())
    assert abs(field.depth.mean() - 50.0) < 0.05
    # A least-squares plane recovers the slope; the residual is the roughness.
    nn, ee = np.meshgrid(north, east, indexing="ij")
    A = np.column_stack([np.ones(nn.size), nn.ravel(), ee.ravel()])
    coef, *_ = np.linalg.lstsq(A, field.depth.ravel(), rcond=None)
    assert abs(coef[1] - 0.01) < 1e-3 and abs(coef[2] + 0.02) < 1e-3
    residual = field.depth.ravel() - A @ coef
    assert abs(residual.std() - 0.5) < 0.05


def test_same_seed_same_seabed_and_other_seed_other_seabed():
    base = {"north": [0, 100], "east": [0, 100], "mean_depth": 30, "roughness": {"amplitude": 1, "seed": 1}}
    a = generate_seabed(Seabed.model_validate(base)).depth
    b = generate_seabed(Seabed.model_validate(base)).depth
    c = generate_seabed(Seabed.model_validate({**base, "roughness": {"amplitude": 1, "seed": 2}})).depth
    assert np.array_equal(a, b) and not np.array_equal(a, c)


def test_bilinear_depth_matches_grid_nodes_and_interpolates_planes():
    spec = Seabed.model_validate({"north": [0, 10], "east": [0, 10], "mean_depth": 20,
                                  "slope": {"north": 0.1, "east": 0.2}, "roughness": {"amplitude": 0}})
    field = generate_seabed(spec)
    assert math.isclose(field.depth_at(3.0, 4.0), field.depth[3, 4])
    assert math.isclose(field.depth_at(3.25, 4.5), 20 + 0.1 * (3.25 - 5) + 0.2 * (4.5 - 5), abs_tol=1e-9)
    assert np.allclose(field.depths_at(np.array([3.25]), np.array([4.5])), field.depth_at(3.25, 4.5))


def test_reference_world_puts_manifold_off_its_database_pose():
    scene = build_scene(load_world(WORLD))
    manifold = next(o for o in scene.objects if o.id == "manifold-1")
    charted = np.array([150.0, 200.0])
    shift = np.linalg.norm(manifold.T_world_object[:2, 3] - charted)
    assert 1.0 <= shift <= 3.0
    assert 1.0 <= abs(heading_of(manifold.T_world_object) - 30.0) <= 5.0
    unknown = [o for o in scene.objects if o.database is None]
    assert len(unknown) == 1
    n, e = unknown[0].T_world_object[:2, 3]
    assert 0 <= n <= 300 and 0 <= e <= 400  # inside the reference survey area


def test_altimeter_sees_object_tops_over_the_seabed():
    scene = build_scene(load_world(WORLD))
    manifold = next(o for o in scene.objects if o.id == "manifold-1")
    centre = manifold.footprint.centroid  # x = east, y = north
    over_object = scene.altitude(centre.y, centre.x, 50.0)
    assert math.isclose(over_object, manifold.top_depth - 50.0, abs_tol=0.6)
    beside = scene.altitude(centre.y + 30.0, centre.x, 50.0)
    assert math.isclose(beside, scene.seabed.depth_at(centre.y + 30.0, centre.x) - 50.0)
