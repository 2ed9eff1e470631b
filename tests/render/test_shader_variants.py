"""The lit shader's programs by kind of material, and the sun cascades' bias scales worked out per draw."""

from __future__ import annotations

import numpy as np
import pyrender
import pytest
from scipy.spatial.transform import Rotation

from camgen.render.renderer import directional_shadow_matrices, material_defines, sun_cascade_scales
from camgen.render.scene_graph import ClearcoatMaterial


def test_each_kind_of_material_has_its_own_paths():
    plain = pyrender.MetallicRoughnessMaterial(baseColorFactor=(0.5, 0.5, 0.5, 1.0))
    glass = pyrender.MetallicRoughnessMaterial(baseColorFactor=(0.1, 0.1, 0.1, 0.3), alphaMode="BLEND")
    paint = ClearcoatMaterial(baseColorFactor=(0.6, 0.1, 0.1, 1.0))
    coated_glass = ClearcoatMaterial(baseColorFactor=(0.6, 0.1, 0.1, 0.5), alphaMode="BLEND")
    assert material_defines(plain) == ()
    assert material_defines(glass) == ("TRANSMISSIVE_MATERIAL",)
    assert material_defines(paint) == ("CLEARCOATED_MATERIAL",)
    assert material_defines(coated_glass) == ("CLEARCOATED_MATERIAL", "TRANSMISSIVE_MATERIAL")


@pytest.mark.parametrize("seed", range(4))
def test_cascade_scales_are_the_matrix_row_lengths(seed):
    """Depth scale = |row 2| of P·V (map depth units per metre), texel = 2 / (size |row 0|), the coarser
    axis: against a float64 reading of the same matrices (the map's metres per texel from its width)."""
    rng = np.random.default_rng(seed)
    R = Rotation.random(random_state=rng).as_matrix()
    corners = rng.uniform(-40, 40, size=(8, 3))
    cascades = []
    for k in range(3):
        focus = rng.uniform(-5 * (k + 1), 5 * (k + 1), size=(8, 3))
        cascades.append(directional_shadow_matrices(R, corners, focus))
    size = 2048
    scales = sun_cascade_scales(cascades, size)
    assert scales.dtype == np.float32 and scales.shape == (3, 2)
    for (_, P), (depth_scale, texel_m) in zip(cascades, scales, strict=True):
        width_m, height_m = 2.0 / P[0, 0], 2.0 / P[1, 1]  # an orthographic map's extent
        depth_m = 2.0 / abs(P[2, 2])
        assert depth_scale == pytest.approx(2.0 / depth_m, rel=1e-6)
        assert texel_m == pytest.approx(max(width_m, height_m) / size, rel=1e-6)
