"""The native network file: ``.npz`` with a format version, patches and their sharing arrays.

Contents
--------
A zip archive of ``.npy`` members, the container ``numpy.savez`` writes (``numpy.load`` reads
it): ``header`` (a 0-d string, the JSON ``{"format": "g1patch-network", "version": …,
"provenance": {…}}``), ``patch_kind`` (``"bicubic"`` or ``"gregory"``), the patches' arrays
(:meth:`PatchSet.to_arrays`: ``control`` and ``form``; :meth:`GregoryPatchSet.to_arrays`:
``points``), the sharing arrays of :class:`PatchNetwork` (``corner_ids``, ``edge_ids``,
``edge_reversed``, ``neighbor``, ``neighbor_edge``, ``same_direction``, ``edge_collapsed``,
``seam``) and, when the network has them, ``vertices`` and ``vertex_normals``.

Version 2 stores the patches in their local coordinates and, when they have one, their frame as
the arrays ``frame_centre`` (3,) and ``frame_scale`` () (see :mod:`g1patch.frame`): the file holds
exactly the numbers the construction made. Version 3 adds ``seam`` (P, 4) bool, the patch edges
that are sharp on purpose (:attr:`PatchNetwork.seam`). Version 4 adds the optional
``uv`` (P, 4, 2) float, each patch's texture coordinates at its corners (:attr:`PatchNetwork.uv`,
from the mesh's ``vt``; finite, checked like the coordinates). Version 5 adds the optional pair
``hanging_sides`` (H, 4) int and ``hanging_span`` (H, 2) float, the T-junctions of a
feature-adaptive network (:class:`~g1patch.network.HangingEdges`: fine patch and edge, coarse
patch and edge, the coarse fractions at the fine edge's ends; H ≤ 4 P, both members or neither).
Version 6 adds the optional face groups (:class:`~g1patch.mesh.groups.FaceGroups`, all three
members or none): ``group`` (P,) int, each patch's group in −1 … G − 1 (−1: none),
``group_names`` a 0-d string, the JSON list of the G names (at most 4 per patch, each non-empty
printable text), and ``group_colour`` (G, 3) float, RGB in [0, 1] or a row of NaN.
The distance reached and the cage a network came from ride in the header's provenance
(``limit_distance``, ``tolerance``, ``source``). Version 1 files (no frame), version 2 files (no
seams), version 3 files (no texture coordinates), version 4 files (no hanging edges) and version 5
files (no groups) are read as before: seam-free, without UVs, conforming, without groups.

Container: stored, not compressed
---------------------------------
Measured by ``benchmarks/bench_files.py`` on a 1 M-quad Gregory network
(``build_network(shapes.large_torus(1_000_000))``: 1 000 000 patches, 670 MB of arrays), best of 3
on the shared 2-core development machine, every format read back by :func:`load_network`:

======================================  ========  ========  ========  =========
container                               size      save      load      build
======================================  ========  ========  ========  =========
``np.savez_compressed`` (until now)      324 MB    42.3 s     6.6 s    10.7 s
zipfile ``ZIP_DEFLATED``, level 1        328 MB    19.1 s    15.7 s    10.7 s
``np.savez`` (``ZIP_STORED``)            670 MB     1.19 s    0.93 s   10.7 s
this module (stored, see below)          670 MB     0.77 s    0.74 s   10.7 s
======================================  ========  ========  ========  =========

The machine was shared with other jobs (load 3–6 on its 2 cores) and first touches of fresh
memory are slow and erratic in its VM, so figures spread between runs: over four runs this
module saved in 0.71–1.87 s and loaded in 0.74–2.17 s, ``np.savez_compressed`` saved in 38–45 s
(20.7 s and a 2.9 s load in a quieter hour, when ``build`` took 33 s). Compression halves the
file and costs 25–50× the time to save: float64 control points with busy mantissas deflate by
2:1 at best, at ~35 MB/s even at level 1. So members are stored (``ZIP_STORED``): each ``.npy``
member is written straight from the array's memory (no copy) while a second thread computes its
CRC-32, and read back with ``readinto`` at its offset in 64 MB steps, each step's CRC computed on a
second thread while the next is read and the arrays are validated.
Arrays keep the dtypes :class:`PatchNetwork` holds (int64 indices, so loading allocates nothing
but the arrays themselves). The container is unchanged — a zip of ``.npy`` members, what
``np.load`` reads — so the version stayed 3 then, and compressed files (every earlier release's) are
still read.

Loading validates, before and after reading
-------------------------------------------
Nothing is decompressed or allocated before the zip directory and the ``.npy`` headers agree with
a network: every member must be a known ``.npy`` array of this version (stored or deflated, not
encrypted, named once); its declared size (``ZipInfo.file_size``) is capped, and must equal its
``.npy`` header plus shape × itemsize. The caps, checked in this order:

* absolute: :data:`MAX_BYTES` (32 GiB) per member and in all, :data:`MAX_PATCHES` (2²⁵ patches: a
  4 M-quad split4 network is 16 M);
  the JSON header at most :data:`MAX_HEADER_BYTES` (1 MiB), the other strings 1 KiB;
* per patch: with ``P`` patches (at most ``corner_ids``' size / 4 bytes before its ``.npy``
  header is read, exactly its first axis after), every array has the shape its role gives
  (``(P, 4)``, ``(P, 20, 3)``, ``(P, 4, 4, 3)``, ``(E,)`` and ``(V, 3)`` with E, V ≤ 4 P, ``(3,)``,
  ``()``) at most 8 bytes an element, so a file holds at most ``PER_PATCH_BYTES`` (1 KiB) of arrays
  per patch plus the headers (a Gregory network takes 670 bytes a patch), checked in all too. A
  member declaring more is refused by name with its claimed size: a zip bomb is refused before it
  expands.

Then the values, vectorised (one pass of ``min``/``max`` per array, no loop over patches):
integer arrays of an integer type, boolean arrays of type bool holding only 0 and 1 bytes,
coordinates of a floating type; ``corner_ids`` in ``0..V−1`` (``0..4P−1`` without vertices),
``edge_ids`` in ``0..E−1``, ``neighbor`` in ``−1..P−1``, ``neighbor_edge`` in ``−1..3``, −1 in both
at the same places, every neighbour pointing back and naming the same edge id; every coordinate
(control points, Gregory points, vertices, their normals, the frame centre) finite and of
magnitude at most :data:`MAX_COORDINATE` = 1e30, in world coordinates (``|c| + s·max|x|`` with a
frame, whose scale must be positive and at most the bound). 1e30 mm is larger than the observable
universe, above any surface built from a mesh 1e29 in size (its frame stores it), and keeps every
power the numerics form finite: OpenCASCADE's G1 measurement squares the cross product of two
unnormalised normals, an eighth power of the coordinates (1e240 here; the check measures in the
patches' unit box, frame-free ones too, so their size does not matter to it). Any violation is one
:class:`FormatError` naming the file, the member and the problem. A file of another kind (a mesh, a
``.bpt``, a text file renamed ``.npz``, anything not a zip archive) is refused with what was
expected instead. :func:`save_network` runs the same checks first, so it never writes a file it
would not read.
"""

from __future__ import annotations

from .read import describe_file, load_network
from .schema import (
    FORMAT_VERSION,
    MAX_BYTES,
    MAX_COORDINATE,
    MAX_HEADER_BYTES,
    MAX_PATCHES,
    PER_PATCH_BYTES,
    READABLE_VERSIONS,
)
from .write import save_network, save_network_in_background

__all__ = [
    "FORMAT_VERSION",
    "READABLE_VERSIONS",
    "MAX_COORDINATE",
    "MAX_PATCHES",
    "MAX_BYTES",
    "PER_PATCH_BYTES",
    "MAX_HEADER_BYTES",
    "save_network",
    "save_network_in_background",
    "load_network",
    "describe_file",
]
