"""The network file's layout: versions, members, their shapes and the limits every reader and
writer keeps (the format itself is described in :mod:`g1patch.io.network_file`)."""

from __future__ import annotations

from ...gregory import GregoryPatchSet

#: the version :func:`save_network` writes
FORMAT_VERSION = 6
#: the versions :func:`load_network` reads (1: no frame, 2: no seams, 3: no texture coordinates,
#: 4: no hanging edges, 5: no face groups)
READABLE_VERSIONS = (1, 2, 3, 4, 5, 6)
_ARRAYS = (
    "corner_ids",
    "edge_ids",
    "edge_reversed",
    "neighbor",
    "neighbor_edge",
    "same_direction",
    "edge_collapsed",
)
#: the first version with a frame
FRAME_VERSION = 2
#: the first version with seams
SEAM_VERSION = 3
#: the first version with texture coordinates (``uv``, optional)
UV_VERSION = 4
#: the first version with hanging edges (``hanging_sides`` and ``hanging_span``, optional)
HANGING_VERSION = 5
#: the members of the hanging edges (both or neither)
HANGING_ARRAYS = ("hanging_sides", "hanging_span")
#: the first version with face groups (``group``, ``group_names``, ``group_colour``, optional)
GROUP_VERSION = 6
#: the members of the face groups (all or none)
GROUP_ARRAYS = ("group", "group_names", "group_colour")
#: largest ``group_names`` member (the JSON list of the names)
MAX_GROUP_NAMES_BYTES = 2**24

#: largest magnitude of a coordinate in world units (see the module docstring)
MAX_COORDINATE = 1e30
#: most patches a network file may hold
MAX_PATCHES = 2**25
#: most bytes of arrays, per member and in all
MAX_BYTES = 2**35
#: bytes of arrays a file may hold per patch, headers aside (a Gregory network needs ≈ 600)
PER_PATCH_BYTES = 1024
#: largest JSON header
MAX_HEADER_BYTES = 2**20
#: largest other string member (patch kind, form)
_MAX_NAME_BYTES = 1024
#: elements per chunk of the value checks: their temporaries stay in the cache
_CHUNK = 1 << 17
#: bytes per read of a stored member, whose CRC runs on the second thread while the next is read
_READ_STEP = 1 << 26
#: room for one ``.npy`` header (numpy reads at most 10 000 bytes of one) and its preamble
_NPY_HEADER_BYTES = 10_000 + 16

_INDEX_ARRAYS = ("corner_ids", "edge_ids", "neighbor", "neighbor_edge", "hanging_sides", "group")
_BOOL_ARRAYS = ("edge_reversed", "same_direction", "edge_collapsed", "seam")
_FLOAT_ARRAYS = (
    "points",
    "control",
    "vertices",
    "vertex_normals",
    "frame_centre",
    "frame_scale",
    "uv",
    "hanging_span",
    "group_colour",
)
_STRING_ARRAYS = ("header", "patch_kind", "form", "group_names")
#: shape of every array member, by its dimensions: P patches, E edges, V vertices, H hanging links,
#: G groups
_SHAPES: dict[str, tuple[str | int, ...]] = {
    "corner_ids": ("P", 4),
    "edge_ids": ("P", 4),
    "neighbor": ("P", 4),
    "neighbor_edge": ("P", 4),
    "edge_reversed": ("P", 4),
    "same_direction": ("P", 4),
    "seam": ("P", 4),
    "edge_collapsed": ("E",),
    "points": ("P", 20, 3),
    "control": ("P", 4, 4, 3),
    "vertices": ("V", 3),
    "vertex_normals": ("V", 3),
    "uv": ("P", 4, 2),
    "hanging_sides": ("H", 4),
    "hanging_span": ("H", 2),
    "group": ("P",),
    "group_colour": ("G", 3),
    "group_names": (),
    "frame_centre": (3,),
    "frame_scale": (),
    "header": (),
    "patch_kind": (),
    "form": (),
}
_KIND_ARRAYS = {"bicubic": ("control", "form"), GregoryPatchSet.kind: ("points",)}

_NETWORK = "a network file (.npz) written by g1patch build"
_SUFFIX_KINDS = {
    ".obj": "a Wavefront OBJ mesh",
    ".ply": "a PLY mesh",
    ".stl": "an STL mesh",
    ".off": "an OFF mesh",
    ".bpt": "a Bézier patch file (.bpt)",
    ".step": "a STEP file",
    ".stp": "a STEP file",
    ".iges": "an IGES file",
    ".igs": "an IGES file",
    ".png": "a PNG picture",
    ".npy": "a single NumPy array (.npy)",
}
_MESH_SUFFIXES = (".obj", ".ply", ".stl", ".off")
