"""A rendered kerb (`environment.kerbs`) under the sun alone: each face of its HB2 profile as bright as a
Lambertian surface of the kerb's reflectance tilted as that face is, ρ·E·cos θ/π, and the road behind a
kerb lit from the footway side in its shadow for h / tan(elevation) and lit beyond."""

from __future__ import annotations

import math

import numpy as np
import pytest

from camgen.config.kerbs import BATTER_RISE_M, BATTER_SETBACK_M, JOINT_M, UNIT_LENGTH_M, UPSTAND_M
from camgen.render.renderer import View
from camgen.render.scene_graph import build_scene_graph
from camgen.world.kerbs import kerb_profile
from camgen.world.textures import TYPICAL_ALBEDO_RGB, kerb_surface_maps
from tests.render.conftest import camera_matrix, look_at, scene_from

pytestmark = pytest.mark.opengl

SUN_LUX, ELEVATION_DEG = 60000.0, 30.0
ROAD_RGB = (0.2, 0.2, 0.2)
F_PX, WIDTH_PX, HEIGHT_PX = 2000.0, 640, 480
EYE_M, TARGET_M = (0.0, -1.5, 0.5), (0.0, 0.0, 0.06)


def _draw(renderer, sun_azimuth_deg: float, kerb: bool = True) -> tuple[np.ndarray, View]:
    """A kerb along x (its road face on y = 0, the road at y < 0), seen from the road, under the sun alone."""
    scene = scene_from(
        environment={
            "ground_to_horizon": False,
            "meshes": [
                {"type": "plane", "name": "road", "size_m": [20, 20], "material": {"color_rgb": list(ROAD_RGB)}}
            ],
            "kerbs": [{"name": "kerb", "along_m": [[-4, 0], [4, 0]]}] if kerb else [],
        },
        lights=[
            {"type": "sun", "illuminance_lux": SUN_LUX, "azimuth_deg": sun_azimuth_deg, "elevation_deg": ELEVATION_DEG}
        ],
    )
    view = View(
        camera_matrix(F_PX, F_PX, (WIDTH_PX - 1) / 2, (HEIGHT_PX - 1) / 2),
        look_at(EYE_M, TARGET_M),
        WIDTH_PX,
        HEIGHT_PX,
    )
    return renderer.draw(build_scene_graph(scene), view, ("radiance",)).radiance.astype(np.float64), view


SAMPLES_X_M = np.linspace(-0.2, 0.2, 41)
"""Where along the kerb the faces are sampled: between two joints (x = −0.344 and 0.570: the units start at the
first point, x = −4)."""


def _samples(radiance: np.ndarray, view: View, y_m: float, z_m: float) -> np.ndarray:
    """(41, 3) the radiance of the pixels seeing the points (x, y_m, z_m), x in `SAMPLES_X_M`."""
    world = np.column_stack([SAMPLES_X_M, np.full_like(SAMPLES_X_M, y_m), np.full_like(SAMPLES_X_M, z_m)])
    T = view.T_world_from_cam
    cam = (world - T[:3, 3]) @ T[:3, :3]
    px = (cam[:, :2] / cam[:, 2:]) * F_PX + [(WIDTH_PX - 1) / 2, (HEIGHT_PX - 1) / 2]
    cols, rows = np.round(px).astype(int).T
    return radiance[rows, cols]


def _albedo(y_m: float, z_m: float) -> np.ndarray:
    """(41, 3) the kerb texture's reflectance at the same points: u = x + 4 m along the kerb, v the distance
    around the profile to the profile's point nearest (y, z)."""
    profile = kerb_profile()
    a, b = profile.points[:-1], profile.points[1:]
    d = b - a
    t = np.clip(((np.array([y_m, z_m]) - a) * d).sum(axis=1) / (d * d).sum(axis=1), 0.0, 1.0)
    nearest = np.argmin(np.linalg.norm(a + t[:, None] * d - [y_m, z_m], axis=1))
    v = profile.arc_length_m[nearest] + t[nearest] * np.linalg.norm(d[nearest])
    maps = kerb_surface_maps(0, UNIT_LENGTH_M, JOINT_M)
    texels = maps.albedo.shape[0]
    cols = np.floor((SAMPLES_X_M + 4.0) / maps.tile_m * texels).astype(int) % texels
    row = int(v / maps.tile_m * texels) % texels
    return maps.albedo[row, cols] * np.asarray(TYPICAL_ALBEDO_RGB["concrete"])


def test_each_face_is_lit_as_its_normal_faces_the_sun(renderer):
    radiance, view = _draw(renderer, sun_azimuth_deg=-90.0)  # the sun over the road, 30° up
    towards_sun = np.array([0.0, -math.cos(math.radians(ELEVATION_DEG)), math.sin(math.radians(ELEVATION_DEG))])
    batter = np.array([0.0, -BATTER_RISE_M, BATTER_SETBACK_M]) / math.hypot(BATTER_RISE_M, BATTER_SETBACK_M)
    faces = {  # (a point on the face's mid-line (y, z), its outward normal)
        "road face": ((0.0, (UPSTAND_M - BATTER_RISE_M) / 2), np.array([0.0, -1.0, 0.0])),
        "batter": ((BATTER_SETBACK_M * 0.45, UPSTAND_M - BATTER_RISE_M * 0.55), batter),
        "top": ((0.1, UPSTAND_M), np.array([0.0, 0.0, 1.0])),
    }
    ratios, measured = {}, {}
    for name, ((y, z), normal) in faces.items():
        lambert = _albedo(y, z) * SUN_LUX * float(normal @ towards_sun) / math.pi
        ratios[name] = np.median(_samples(radiance, view, y, z) / lambert, axis=0)
        # Lambert's ρ·E·cos θ/π plus a rough dielectric's specular lobe (F0 = 0.04, roughness 0.85), which adds up
        # to ~8 % seen from the sun's side (the road face and the batter, n·h ≈ 0.9; the top 0.4: ~0); the texture
        # is filtered, the reference is its texels.
        np.testing.assert_array_less(0.97, ratios[name], err_msg=name)
        np.testing.assert_array_less(ratios[name], 1.10, err_msg=name)
        measured[name] = np.median(_samples(radiance, view, y, z)[:, 1])
    # The batter and the road face, seen alike, share their sheen: their ratio is cos θ's within 2 %.
    np.testing.assert_allclose(ratios["batter"], ratios["road face"], rtol=0.02)
    # cos θ: batter 0.999, road face 0.866, top 0.5 — the batter brightest, the top darkest.
    assert measured["batter"] > measured["road face"] > measured["top"]


def test_a_kerb_lit_from_behind_shades_its_face_and_casts_its_shadow_on_the_road(renderer):
    radiance, view = _draw(renderer, sun_azimuth_deg=90.0)  # the sun over the footway, 30° up
    bare, _ = _draw(renderer, sun_azimuth_deg=90.0, kerb=False)
    # The shadow's edge: the top's front arris (BATTER_SETBACK_M back, UPSTAND_M up) cast down the sun's slope.
    edge_y = BATTER_SETBACK_M - UPSTAND_M / math.tan(math.radians(ELEVATION_DEG))  # −0.167 m
    road = np.median(_samples(bare, view, edge_y / 2, 0.0)[:, 1])
    assert np.median(_samples(radiance, view, edge_y / 2, 0.0)[:, 1]) < 0.05 * road
    np.testing.assert_allclose(  # beyond the shadow, the road as without the kerb
        _samples(radiance, view, 1.5 * edge_y, 0.0), _samples(bare, view, 1.5 * edge_y, 0.0), rtol=1e-3
    )
    top = np.median(_samples(radiance, view, 0.1, UPSTAND_M)[:, 1])
    face = np.median(_samples(radiance, view, 0.0, (UPSTAND_M - BATTER_RISE_M) / 2)[:, 1])
    batter = np.median(_samples(radiance, view, BATTER_SETBACK_M * 0.45, UPSTAND_M - BATTER_RISE_M * 0.55)[:, 1])
    lit_top = TYPICAL_ALBEDO_RGB["concrete"][1] * SUN_LUX * math.sin(math.radians(ELEVATION_DEG)) / math.pi
    assert top > 0.97 * lit_top  # lit (and brighter still by the sheen of a sun ahead of the camera)
    assert face < 0.02 * top and batter < 0.02 * top  # turned away from the sun, the only light
