"""The limits every mission, world and model file is read under, and the physical ranges of the schema.

One place for the numbers the README states ("Mission limits"): the reader (`mission.language.reading`), the
YAML composer (`mission.language.source`), the models and the cross-checks all take them from here.
"""

from __future__ import annotations

# Reading and parsing (missions, worlds, multi-view models alike).
MAX_FILE_BYTES = 8 * 1024 * 1024  # a larger file is refused before it is read
MAX_DEPTH = 64  # nesting of mappings and lists
MAX_ALIASES = 100  # uses of `*alias` in one document
MAX_NODES = 250_000  # values in one document, counting each alias as the values it repeats
MAX_ITEMS = 100_000  # entries in one list or mapping
PSEUDO_FILE_ROOTS = ("/proc", "/sys", "/dev")  # kernel and device files are never read as documents

# Collections in the schema.
MAX_POLYGON_VERTICES = 5_000  # geofence, survey areas, no-go zones
MAX_EXCLUSION_ZONES = 100
MAX_POINTS_PER_SET = 1_000
MAX_POINTS_PER_OBJECT = 1_000  # characteristic points of one object, all sets together
MAX_POINT_SETS = 100
MAX_TARGETS = 100  # per object (each target's viewpoint is checked against the object's points)
MAX_OBJECTS = 1_000
MAX_ROUTE_ELEMENTS = 10_000
MAX_OFFSETS = 100
MAX_WORLD_PARTS = 1_000
MAX_DIAGNOSTICS = 200  # problems printed for one file; the rest are counted

# Physical ranges (SI units; angles in degrees).
MIN_SPEED = 0.05  # m/s: slower is not a transit, and the timeouts that follow from it would be unbounded
MAX_SPEED = 10.0  # m/s (about 19 knots)
MAX_VERTICAL_SPEED = 5.0  # m/s
MIN_VERTICAL_SPEED = 0.01  # m/s
MAX_ACCELERATION = 10.0  # m/s²
MAX_YAW_RATE = 180.0  # deg/s
MIN_YAW_RATE = 0.5  # deg/s
MAX_CURRENT = 5.0  # m/s, each component
MAX_DEPTH_M = 11_000.0  # the deepest ocean
MAX_ALTITUDE = 1_000.0  # m
MAX_EXTENT = 1.0e6  # m: |north|, |east| of any point in the local frame
MAX_HEADING = 360.0  # |heading|, |pitch|, |roll| in degrees
MAX_RANGE = 1_000.0  # m, of any sensor
MAX_RATE_HZ = 100.0
MIN_RATE_HZ = 0.01
MIN_RESOLUTION = 0.01  # m, seabed grid and survey voxels
MAX_RESOLUTION = 100.0  # m, seabed grid
MAX_SEABED_CELLS = 4_000_000
MAX_ROUGHNESS_WORK = 2.0e9  # seabed cells × roughness-filter taps: the filter's cost
MAX_SIZE = 1_000.0  # m, of any object or part
MAX_DURATION_S = 7 * 86_400.0  # max_duration, element timeouts and budgets
MAX_LINK_TIMEOUT_S = 3_600.0
MAX_ENERGY_WH = 1.0e7
MAX_POWER_W = 1.0e6
MAX_IMAGE_SIDE = 8_192  # pixels
MAX_BEAMS = 4_096
MAX_PHOTOS = 1_000
MAX_SEED = 2**32 - 1
MAX_SURVEY_LINES = 10_000
