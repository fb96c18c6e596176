"""The surface mesh a database object may name (`objects[].mesh`: `auv reconstruct`'s `mesh.ply` or `mesh.glb`):
what the loader checks of it. Only the file's kind and header are read here (never the whole mesh): a PLY file
starts with the line `ply` and a `format` line; a binary glTF file with the magic `glTF` and version 2.
"""

from __future__ import annotations

from pathlib import Path

MESH_SUFFIXES = (".ply", ".glb")


def mesh_file_problem(path: Path) -> str:
    """Why a mesh file cannot be used ('' when it can): a suffix other than .ply or .glb, unreadable, or a header
    that is not PLY's or binary glTF 2's.

    >>> import tempfile, os
    >>> with tempfile.TemporaryDirectory() as d:
    ...     good, bad = Path(d, "m.ply"), Path(d, "m.glb")
    ...     _ = good.write_bytes(b"ply\\nformat binary_little_endian 1.0\\nend_header\\n")
    ...     _ = bad.write_bytes(b"not a mesh")
    ...     mesh_file_problem(good), mesh_file_problem(bad)
    ('', 'not a binary glTF 2 file (expected the magic `glTF`, version 2)')
    """
    suffix = path.suffix.lower()
    if suffix not in MESH_SUFFIXES:
        return f"expected a mesh file ending in {' or '.join(MESH_SUFFIXES)}, got '{path.suffix or path.name}'"
    try:
        with path.open("rb") as f:
            head = f.read(256)
    except OSError as exc:
        return f"cannot read it ({exc.strerror or exc})"
    if suffix == ".ply":
        lines = head.split(b"\n", 2)
        if lines[0].strip() != b"ply" or len(lines) < 2 or not lines[1].startswith(b"format "):
            return "not a PLY file (expected the lines `ply` and `format ...` first)"
        return ""
    if head[:4] != b"glTF" or int.from_bytes(head[4:8], "little") != 2:
        return "not a binary glTF 2 file (expected the magic `glTF`, version 2)"
    return ""


__all__ = ["MESH_SUFFIXES", "mesh_file_problem"]
