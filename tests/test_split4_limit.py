"""split4 in ``limit`` mode follows the Catmull–Clark limit targets as closely as Gregory does.

Its free choices (centres, crosses, seam tangents, twists) are the targets' bicubic's detail over
what the split curves predict, moved by G1 only; before (issue 10) they were bilinear heuristics
and the targets' interiors were dropped wherever a face did not meet the G1 conditions exactly.

Measured p99 normal turn over OpenSubdiv's reference (``compare_fairness``), split4 / Gregory:

| mesh | r | before | after |
|---|---|---|---|
| catmark_cube | 0 | 1.228 / 1.040 | 1.002 / 1.040 |
| catmark_xord_interior | 0 | 1.706 / 1.128 | 1.149 / 1.128 |
| catmark_xord_boundary | 0 | 2.069 / 1.117 | 0.954 / 1.117 |
| catmark_xord_boundary | 1 | 2.837 / 1.105 | 1.069 / 1.105 |

So split4 ≤ 1.05 × Gregory holds after (worst 1.019) and failed before by 1.18–2.6×. The cube's
max distance to the limit went from 3.0× Gregory's to 0.98×, then 1.50× when Gregory's edge fit
took a smaller parametric share (its edge curves follow the limit more closely; split4's regular
stars and sheared midpoints cannot take all of it); the bound 1.6× Gregory's also leaves room for
the boundary mesh, whose regular stars cannot follow the fitted fans (1.19×).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from g1patch.build import build_network
from g1patch.compare import (
    compare_fairness,
    load_reference,
    mesh_distance,
    patch_samples,
    surface_samples,
)
from g1patch.continuity import check
from g1patch.io.meshfile import read_mesh

#: split4's p99 turn ratio may exceed Gregory's by this factor (worst measured 1.019)
FAIRNESS_FACTOR = 1.05
#: and its max distance to the reference Gregory's by this one (worst measured 1.50, the cube)
DISTANCE_FACTOR = 1.6

CASES = [
    ("catmark_cube", 0),
    ("catmark_xord_interior", 0),
    ("catmark_xord_boundary", 0),
    ("catmark_xord_boundary", 1),
]


@pytest.mark.slow
@pytest.mark.parametrize(("name", "refine"), CASES)
def test_split4_limit_is_as_fair_as_gregory(shared_data: Path, name: str, refine: int) -> None:
    mesh = read_mesh(shared_data / f"{name}.obj")
    reference = load_reference(shared_data / "reference" / f"{name}.limit.npz")
    reference = dataclasses.replace(
        reference, levels=reference.levels - refine
    )  # the same step per refined face
    ratio, distance = {}, {}
    for method in ("gregory", "split4"):
        network = build_network(mesh, method, "limit", refine=refine, tolerance=None)  # type: ignore[arg-type]
        report = check(network, samples=max(9, 33 >> refine))
        assert (
            max(report.max_edge_angle_deg, report.max_corner_angle_deg) <= 1e-9
            and report.folds == 0
        )
        ratio[method] = compare_fairness(network, reference).p99_ratio
        samples, _ = surface_samples(network, patch_samples(network, 8 >> refine))
        distance[method] = float(
            mesh_distance(samples.reshape(-1, 3), reference.points, reference.faces).max()
        )
    assert ratio["split4"] <= FAIRNESS_FACTOR * ratio["gregory"], ratio
    assert distance["split4"] <= DISTANCE_FACTOR * distance["gregory"], distance
