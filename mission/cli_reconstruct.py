"""`auv reconstruct RUN_DIR --object ID [--element ID] [--out DIR] [--target NAME=N,E,D[:STANDOFF]]...`: a mesh of
an explored object from the run folder's stereo recording, and its database entry (`mission.reconstruct`)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any


def _reconstruct(args: argparse.Namespace) -> int:
    from mission.extras import MissingExtraError, has, require
    from mission.reconstruct import parse_target, reconstruct_run

    for module in ("skimage", "trimesh"):  # marching cubes; PLY and glTF files
        if not has(module):
            raise MissingExtraError(f"`auv reconstruct` needs {module}, which is not installed: "
                                    "pip install 'auv-mission[recon]'")
    require("matplotlib", "the mesh picture (`auv reconstruct`)")
    targets = tuple(parse_target(t) for t in args.target)
    report = reconstruct_run(Path(args.run), args.object, Path(args.out) if args.out else None, args.voxel, targets,
                             args.element, args.poses, args.max_sigma or None)
    extent = report["object_extent"]
    print(f"{report['object']}: {report['frames']} frame(s) from {report['recording']} ({report['pose_file']}), "
          f"{report['triangles']:,} triangles, {report['area_m2']:.1f} m²"
          + (f", {extent['height_m']:.2f} m above the seabed" if extent else ""))
    print(f"written to {report['out']}: {', '.join(report['files'])}")
    return 0


def add_reconstruct_command(sub: Any) -> None:
    p = sub.add_parser("reconstruct", help="a 3D mesh of an explored object from a run's stereo recording")
    p.add_argument("run", help="run folder (its stereo recording: see `mission.reconstruct`)")
    p.add_argument("--object", required=True, help="id of the explored object")
    p.add_argument("--element", help="read the recording of this route element (RUN/stereo/ELEMENT: an explore "
                                     "element's `model` action) instead of looking it up by the object's id")
    p.add_argument("--out", help="output folder (default RUN/models/OBJECT/reconstruction)")
    p.add_argument("--poses", choices=("anchored", "navigation"), default="anchored",
                   help="fuse at the navigation poses held together by stereo odometry (anchored, the default: a pose "
                        "graph of the frames' relative motions and revisits, anchored to navigation) or at the "
                        "recording's navigation poses as they are")
    p.add_argument("--max-sigma", type=float, default=0.06, metavar="M",
                   help="mesh only where the fused distance is this sure, in metres (default 0.06; 0 meshes every "
                        "observed voxel: for a low-resolution camera, whose single views are never that sure)")
    p.add_argument("--voxel", type=float, default=0.02, help="voxel size in metres (default 0.02)")
    p.add_argument("--target", action="append", default=[], metavar="NAME=N,E,D[:STANDOFF]",
                   help="a target for the database entry, in world NED metres (standoff in metres, default 2); "
                        "repeatable; converted to the entry's object frame and referenced to the nearest point set")
    p.set_defaults(func=_reconstruct)
