"""A kerb in the near-infrared pass (`camgen.render.nir`): precast concrete at concrete's 850 nm reflectance, as a
concrete-textured mesh beside it is, not the red channel of its visible colour."""

from __future__ import annotations

import pytest

from camgen.config.profile import Profile
from camgen.render.nir import build_nir_graph
from camgen.world.night import NIR_REFLECTANCE_BY_TEXTURE, default_nir_reflectance
from camgen.world.textures import decode_srgb8
from tests.render.conftest import scene_from

PROFILE = {
    "sensor": {"width_px": 160, "height_px": 120, "pixel_pitch_um": 3.0, "full_well_e": 10000,
               "conversion_gain_dn_per_e": 0.4},
    "lens": {"focal_length_mm": 4.0, "f_number": 2.0},
    "night_mode": {},
}  # fmt: skip


def _mean_nir(node) -> float:
    (primitive,) = node.mesh.primitives
    texture = decode_srgb8(primitive.material.baseColorTexture.source[..., :3])
    return float(texture[..., 0].mean() * primitive.material.baseColorFactor[0])


@pytest.mark.parametrize(
    ("color_rgb", "expected"), [(None, NIR_REFLECTANCE_BY_TEXTURE["concrete"]), ((0.5, 0.4, 0.3), 0.5)]
)
def test_a_kerb_takes_concretes_nir_reflectance(color_rgb, expected):
    kerb = {"along_m": [[0, 0], [4, 0]]} | ({} if color_rgb is None else {"color_rgb": list(color_rgb)})
    scene = scene_from(
        environment={
            "meshes": [{"type": "box", "name": "slab", "size_m": [2, 2, 0.1], "position_m": [0, 3, 0.05],
                        "material": {"texture": {"type": "concrete"}}}],
            "kerbs": [kerb],
        },
        lights=[{"type": "ambient", "illuminance_lux": 1}],
    )  # fmt: skip
    graph = build_nir_graph(scene, Profile.model_validate(PROFILE))
    slab, kerb_node = graph.environment_nodes
    assert kerb_node.name == "environment:kerb_0"
    # the texture's mean, joints included, is the reflectance (8-bit sRGB: within 1 %)
    assert _mean_nir(kerb_node) == pytest.approx(expected, rel=0.01)
    if color_rgb is None:  # as the concrete slab beside it, not its visible red (0.28)
        assert _mean_nir(kerb_node) == pytest.approx(_mean_nir(slab), rel=0.02)
        assert abs(_mean_nir(kerb_node) - float(default_nir_reflectance((0.28, 0.27, 0.255)))) > 0.05
