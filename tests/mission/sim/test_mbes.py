"""The MuJoCo world model and the simulated multibeam (seed 002 §2.1), against geometry worked out by hand."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from mission.language.loader import load_world
from mission.language.world import World
from mission.sim.mbes import Multibeam
from mission.sim.mjworld import R_MJ_NED, MjWorld, mj_dir_to_ned, mj_to_ned, mjworld_for, ned_dir_to_mj, ned_to_mj
from mission.world.scene import Scene, build_scene

REFERENCE_WORLD = Path(__file__).resolve().parents[3] / "worlds" / "sps_field.yaml"
SEABED_DEPTH = 40.0
BOX_TOP = 38.0  # a 4 × 4 × 2 m box resting on the flat seabed at the origin
PIPE_TOP = 39.0  # a pipe along object y (east), radius 0.5 m, axis 0.5 m above the seabed, 6 m long
PIPE_NORTH = 20.0


def flat_world(objects: list[dict[str, object]] | None = None) -> Scene:
    world = World.model_validate({
        "name": "flat",
        "seabed": {"north": [-60, 60], "east": [-60, 60], "resolution": 1.0, "mean_depth": SEABED_DEPTH,
                   "roughness": {"amplitude": 0.0}},
        "objects": objects or [],
    })
    return build_scene(world)


@pytest.fixture(scope="module")
def flat() -> MjWorld:
    return MjWorld(flat_world())


@pytest.fixture(scope="module")
def with_objects() -> MjWorld:
    return MjWorld(flat_world([
        {"id": "block", "pose": {"north": 0, "east": 0, "depth": SEABED_DEPTH},
         "parts": [{"shape": "box", "size": [4, 4, 2], "at": [0, 0, -1]}]},
        {"id": "pipe", "pose": {"north": PIPE_NORTH, "east": 0, "depth": SEABED_DEPTH},
         "parts": [{"shape": "cylinder", "radius": 0.5, "height": 6, "axis": "y", "at": [0, 0, -0.5]}]},
    ]))


def fan(world: MjWorld, **kwargs: float) -> Multibeam:
    settings = {"beams": 121, "swath_deg": 120.0, "max_range": 200.0, "range_sigma": 0.0, "rate_hz": 5.0,
                "seed": 0, **kwargs}
    return Multibeam(world, int(settings.pop("beams")), **settings)  # type: ignore[arg-type]


@pytest.mark.parametrize("pose", [(3.3, -2.1, 20.0, 30.0), (0.0, 0.0, 20.0, 0.0), (5.0, 7.0, 25.0, 135.0)])
def test_ranges_over_a_flat_seabed_are_altitude_over_cos_beam_angle(flat: MjWorld, pose: tuple[float, ...]) -> None:
    north, east, depth, heading = pose
    ping = fan(flat).ping(north, east, depth, heading)
    altitude = SEABED_DEPTH - depth
    theta = np.radians(ping.angles_deg)
    assert ping.hit.all()
    np.testing.assert_allclose(ping.ranges, altitude / np.cos(theta), atol=0.02)
    np.testing.assert_allclose(ping.endpoints_ned[:, 2], SEABED_DEPTH, atol=0.01)
    starboard = np.array([-math.sin(math.radians(heading)), math.cos(math.radians(heading))])
    offsets = (ping.endpoints_ned[:, :2] - [north, east]) @ starboard
    np.testing.assert_allclose(offsets, altitude * np.tan(theta), atol=0.02)
    assert (ping.object_ids == "").all()


@pytest.mark.parametrize("heading", [0.0, 90.0, 135.0, 180.0, 315.0])
def test_fans_from_whole_metre_positions_land_on_a_sloping_seabed(heading: float) -> None:
    # Fans lying exactly in the plane of a grid row or cell diagonal once went through MuJoCo's hfield.
    scene = build_scene(World.model_validate({
        "name": "slope",
        "seabed": {"north": [-60, 60], "east": [-60, 60], "resolution": 1.0, "mean_depth": SEABED_DEPTH,
                   "slope": {"north": 0.05, "east": -0.03}, "roughness": {"amplitude": 0.0}},
    }))
    sonar = fan(mjworld_for(scene))
    for north, east in [(float(n), e) for n in range(-20, 21, 3) for e in (0.0, 7.0, -3.0)]:
        ping = sonar.ping(north, east, SEABED_DEPTH - 20.0, heading)
        assert ping.hit.all()
        plane = SEABED_DEPTH + 0.05 * ping.endpoints_ned[:, 0] - 0.03 * ping.endpoints_ned[:, 1]
        np.testing.assert_allclose(ping.endpoints_ned[:, 2], plane, atol=0.01)


def test_nadir_beams_over_a_box_return_its_top_and_its_id(with_objects: MjWorld) -> None:
    ping = fan(with_objects).ping(0.3, -0.2, 20.0, 10.0)
    theta = np.radians(ping.angles_deg)
    on_top = np.abs(ping.angles_deg) <= 5.0  # 18 m · tan 5° = 1.6 m < the box's 2 m half-width (minus the offset)
    np.testing.assert_allclose(ping.ranges[on_top], (BOX_TOP - 20.0) / np.cos(theta[on_top]), atol=0.02)
    np.testing.assert_allclose(ping.endpoints_ned[on_top, 2], BOX_TOP, atol=0.01)
    assert (ping.object_ids[on_top] == "block").all()
    outer = np.abs(ping.angles_deg) >= 20.0
    np.testing.assert_allclose(ping.endpoints_ned[outer, 2], SEABED_DEPTH, atol=0.01)
    assert (ping.object_ids[outer] == "").all()


def test_beams_along_a_horizontal_pipe_return_its_top_line(with_objects: MjWorld) -> None:
    ping = fan(with_objects).ping(PIPE_NORTH, 0.0, 20.0, 0.0)  # the fan runs east, along the pipe's axis
    along = np.abs((PIPE_TOP - 20.0) * np.tan(np.radians(ping.angles_deg))) < 2.9
    assert (ping.object_ids[along] == "pipe").all()
    np.testing.assert_allclose(ping.endpoints_ned[along, 2], PIPE_TOP, atol=0.01)
    np.testing.assert_allclose(ping.endpoints_ned[along, 0], PIPE_NORTH, atol=0.01)
    beyond = np.abs(ping.angles_deg) > 15.0  # lands more than 4.8 m east or west: past the pipe's ends
    assert (ping.object_ids[beyond] == "").all()


@pytest.mark.parametrize("roll", [10.0, -25.0])
def test_rolling_the_vehicle_turns_each_beam_by_minus_the_roll(flat: MjWorld, roll: float) -> None:
    altitude = 15.0
    ping = fan(flat).ping(1.7, 2.2, SEABED_DEPTH - altitude, 0.0, roll_deg=roll)
    world_angle = np.radians(ping.angles_deg - roll)  # starboard down swings the fan to port
    seen = np.abs(world_angle) < np.radians(60.0)
    np.testing.assert_allclose(ping.ranges[seen], altitude / np.cos(world_angle[seen]), atol=0.02)
    np.testing.assert_allclose(ping.endpoints_ned[seen, 1] - 2.2, altitude * np.tan(world_angle[seen]), atol=0.02)
    nadir = int(np.argmin(np.abs(ping.angles_deg - roll)))
    assert math.isclose(ping.ranges[nadir], altitude, abs_tol=0.02)


def test_beams_beyond_max_range_report_no_return(flat: MjWorld) -> None:
    sonar = fan(flat, max_range=25.0, range_sigma=0.05)
    ping = sonar.ping(0.0, 0.0, SEABED_DEPTH - 20.0, 0.0)
    slant = 20.0 / np.cos(np.radians(ping.angles_deg))
    far, near = slant > 25.05, slant < 24.9
    assert far.any() and near.any()
    assert not ping.hit[far].any() and ping.hit[near].all()
    assert np.isnan(ping.ranges[far]).all() and not np.isnan(ping.ranges[near]).any()
    np.testing.assert_allclose(np.linalg.norm(ping.endpoints_ned[far] - ping.origin_ned, axis=1), 25.0)
    assert (ping.object_ids[far] == "").all()


def test_looking_up_sees_nothing(flat: MjWorld) -> None:
    ping = fan(flat).ping(0.0, 0.0, 20.0, 0.0, roll_deg=180.0)
    assert not ping.hit.any()


@pytest.mark.parametrize("max_range", [10.0, 75.0, 80.0, 300.0])
@pytest.mark.parametrize("rate_hz", [0.5, 9.0, 10.0, 40.0])
def test_effective_ping_rate_never_exceeds_the_two_way_travel_limit(flat: MjWorld, max_range: float,
                                                                    rate_hz: float) -> None:
    sonar = fan(flat, max_range=max_range, rate_hz=rate_hz)
    limit = 1500.0 / (2.0 * max_range)
    assert math.isclose(sonar.max_ping_rate, limit)
    assert sonar.effective_rate_hz <= limit + 1e-12
    assert math.isclose(sonar.effective_rate_hz, min(rate_hz, limit))
    assert math.isclose(sonar.period_s, 1.0 / sonar.effective_rate_hz)


def test_range_noise_has_the_configured_sigma_and_the_same_seed_repeats(flat: MjWorld) -> None:
    a, b = fan(flat, range_sigma=0.1, seed=7), fan(flat, range_sigma=0.1, seed=7)
    pings = [a.ping(0.0, 0.0, 20.0, 0.0) for _ in range(40)]
    residual = np.concatenate([p.ranges - 20.0 / np.cos(np.radians(p.angles_deg)) for p in pings])
    assert abs(residual.mean()) < 0.01 and abs(residual.std() - 0.1) < 0.01
    assert np.array_equal(pings[0].ranges, b.ping(0.0, 0.0, 20.0, 0.0).ranges)


def test_bad_sonar_settings_are_refused(flat: MjWorld) -> None:
    for bad in ({"max_range": 0.0}, {"range_sigma": -1.0}, {"rate_hz": 0.0}, {"swath_deg": 200.0}):
        with pytest.raises(ValueError):
            fan(flat, **bad)


def test_frame_helpers_round_trip_and_keep_handedness() -> None:
    rng = np.random.default_rng(3)
    p = rng.normal(size=(20, 3))
    np.testing.assert_array_equal(mj_to_ned(ned_to_mj(p)), p)
    np.testing.assert_array_equal(ned_to_mj(mj_to_ned(p)), p)
    np.testing.assert_array_equal(mj_dir_to_ned(ned_dir_to_mj(p)), p)
    assert ned_to_mj(np.array([1.0, 2.0, 3.0])).tolist() == [2.0, 1.0, -3.0]  # x east, y north, z up
    np.testing.assert_allclose(ned_to_mj(p), p @ R_MJ_NED.T)
    assert math.isclose(np.linalg.det(R_MJ_NED), 1.0)
    a, b = p[:10], p[10:]
    np.testing.assert_allclose(ned_dir_to_mj(np.cross(a, b)), np.cross(ned_dir_to_mj(a), ned_dir_to_mj(b)))


def _vertical_depths(world: MjWorld, north: np.ndarray, east: np.ndarray) -> np.ndarray:
    out = []
    for n, e in zip(north, east, strict=True):
        dist, geom = world.cast_fan(np.array([n, e, 0.0]), np.array([[0.0, 0.0, 1.0]]), 500.0, objects=False)
        assert geom[0] == world.seabed_geom
        out.append(dist[0])
    return np.array(out)


def test_hfield_reproduces_the_height_field_at_grid_nodes() -> None:
    scene = build_scene(World.model_validate({
        "name": "rough",
        "seabed": {"north": [0, 80], "east": [-30, 90], "resolution": 2.0, "mean_depth": 35,
                   "slope": {"north": 0.03, "east": -0.02}, "roughness": {"amplitude": 1.5, "wavelength": 10}},
    }))
    field, world = scene.seabed, MjWorld(scene)
    rng = np.random.default_rng(1)
    rows, cols = field.depth.shape  # the outermost nodes sit on the field's edge, a micro-cell off (HFIELD_JITTER)
    i = np.r_[1, rows - 2, rng.integers(1, rows - 1, 40)]
    j = np.r_[1, cols - 2, rng.integers(1, cols - 1, 40)]
    north, east = field.grid()
    np.testing.assert_allclose(_vertical_depths(world, north[i], east[j]), field.depth[i, j], atol=1e-4)


def test_reference_world_model_matches_its_height_field_and_parts() -> None:
    scene = build_scene(load_world(REFERENCE_WORLD))
    world = mjworld_for(scene)
    assert mjworld_for(scene) is world
    field = scene.seabed
    north, east = field.grid()
    i, j = np.array([1, 120, 250, 400, 499]), np.array([599, 310, 298, 77, 1])
    np.testing.assert_allclose(_vertical_depths(world, north[i], east[j]), field.depth[i, j], atol=1e-4)
    signs = np.array([[a, b, c] for a in (-1, 1) for b in (-1, 1) for c in (-1, 1)], dtype=float)
    for obj in scene.objects:
        for k, placed in enumerate(obj.parts):
            gid = world.model.geom(f"{obj.id}/{k}").id
            assert world.object_of_geom[gid] == obj.id and world.part_of_geom[gid] == k
            if placed.part.shape != "box":
                continue
            R = world.data.geom_xmat[gid].reshape(3, 3)
            corners = mj_to_ned(world.data.geom_xpos[gid] + (signs * world.model.geom_size[gid]) @ R.T)
            gap = np.linalg.norm(corners[:, None, :] - placed.corners_world[None, :, :], axis=2).min(axis=1)
            assert gap.max() < 1e-9
