"""Kerb geometry (`camgen.world.kerbs`) against closed forms: the HB2 profile's cross-section area, the swept
mesh's volume (area × length) and its polyline's length, joints every 914 mm unit in the texture, faces wound
outward with (u, v, normal) right-handed, and mitred bends."""

from __future__ import annotations

import math

import numpy as np
import pytest

from camgen.config.kerbs import BATTER_RISE_M, HB2_WIDTH_M, UNIT_LENGTH_M, UPSTAND_M, Kerb
from camgen.world.kerbs import (
    joint_positions_m,
    kerb_geometry,
    kerb_mesh,
    kerb_profile,
    polyline_length_m,
    profile_area_m2,
)
from camgen.world.textures import KERB_JOINT_ALBEDO, KERB_UNITS_PER_TILE, kerb_surface_maps


def test_hb2_profile_has_its_standard_size():
    profile = kerb_profile()
    x, z = profile.points.T
    assert (x.min(), x.max(), z.min(), z.max()) == pytest.approx((0.0, 0.125, 0.0, 0.125))
    assert HB2_WIDTH_M == 0.125 and UPSTAND_M == 0.125 and UNIT_LENGTH_M == 0.914
    # The road face: vertical up to the batter's foot, then leaning back 50 mm over 100 mm.
    assert tuple(profile.points[1]) == pytest.approx((0.0, UPSTAND_M - BATTER_RISE_M))
    np.testing.assert_allclose(np.linalg.norm(profile.normals, axis=2), 1.0, atol=1e-12)


@pytest.mark.parametrize(
    ("width", "upstand", "setback", "rise", "radius"),
    [
        (0.125, 0.125, 0.05, 0.1, 0.015),
        (0.125, 0.1, 0.05, 0.1, 0.0),
        (0.15, 0.125, 0.0, 0.0, 0.02),
        (0.3, 0.2, 0.1, 0.05, 0.03),
    ],
)
def test_cross_section_area_matches_its_closed_form(width, upstand, setback, rise, radius):
    expected = profile_area_m2(width, upstand, setback, rise, radius)
    # By hand for the HB2: 0.125² − ½·0.05·0.1 less the fillet of a 116.57° corner of radius 15 mm.
    if (width, upstand, setback, rise, radius) == (0.125, 0.125, 0.05, 0.1, 0.015):
        alpha = math.radians(180 - 63.434949)
        assert expected == pytest.approx(
            0.015625 - 0.0025 - 0.015**2 * (1 / math.tan(alpha / 2) - (math.pi - alpha) / 2)
        )
    fine = kerb_profile(width, upstand, setback, rise, radius, arc_segments=512)
    assert fine.area_m2() == pytest.approx(expected, rel=1e-6)
    # The default 4 facets of the arris cut the circle's segments off: under 0.1 % of the area.
    coarse = kerb_profile(width, upstand, setback, rise, radius)
    assert coarse.area_m2() == pytest.approx(expected, rel=1e-3)
    assert coarse.area_m2() <= expected + 1e-12


def _signed_volume_m3(mesh, base_height_m: float) -> float:
    """Σ (p0 − o)·((p1 − o) × (p2 − o)) / 6 with o on the road: the mesh is open only along the road plane,
    whose missing faces would add nothing from such an o."""
    o = np.array([0.0, 0.0, base_height_m])
    p = mesh.vertices_m.astype(np.float64)[mesh.faces] - o
    return float(np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() / 6)


@pytest.mark.parametrize("road_side", ["left", "right"])
def test_a_straight_kerb_sweeps_area_times_length(road_side):
    profile = kerb_profile()
    mesh = kerb_mesh([[1.0, 2.0], [7.0, 10.0]], profile, road_side=road_side, base_height_m=0.011)
    assert mesh.length_m == pytest.approx(10.0)
    assert _signed_volume_m3(mesh, 0.011) == pytest.approx(profile.area_m2() * 10.0, rel=1e-5)
    assert mesh.vertices_m[:, 2].min() == pytest.approx(0.011) and mesh.vertices_m[:, 2].max() == pytest.approx(0.136)
    # The kerb lies behind its road face, away from the road: left of the line walking with the road on the right.
    along = np.array([0.6, 0.8])
    left = np.array([-0.8, 0.6])
    offsets = (mesh.vertices_m[:, :2] - [1.0, 2.0]) @ left
    behind = offsets if road_side == "right" else -offsets
    assert behind.min() == pytest.approx(0.0, abs=1e-6) and behind.max() == pytest.approx(HB2_WIDTH_M, abs=1e-6)
    # u runs the kerb's length from its first point walking with the road on the right.
    faces_along = np.abs(mesh.normals[:, :2] @ along) < 1e-6
    start = np.array([1.0, 2.0]) if road_side == "right" else np.array([7.0, 10.0])
    direction = along if road_side == "right" else -along
    u_expected = (mesh.vertices_m[faces_along, :2] - start) @ direction
    np.testing.assert_allclose(mesh.uv_m[faces_along, 0], u_expected, atol=1e-5)


def test_faces_wind_outward_with_right_handed_texture_axes():
    mesh = kerb_mesh([[0, 0], [5, 0], [8, 3], [8, 9]], kerb_profile())
    p = mesh.vertices_m.astype(np.float64)[mesh.faces]
    geometric = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    shading = mesh.normals[mesh.faces].mean(axis=1)
    assert np.all(np.einsum("ij,ij->i", geometric, shading) > 0)
    # ∂p/∂u × ∂p/∂v along each face's normal (the shader's bitangent, normal × tangent, is then +v).
    t = mesh.uv_m.astype(np.float64)[mesh.faces]
    d1, d2 = t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]
    e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    det = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
    dp_du = (e1 * d2[:, 1:2] - e2 * d1[:, 1:2]) / det[:, None]
    dp_dv = (e2 * d1[:, 0:1] - e1 * d2[:, 0:1]) / det[:, None]
    assert np.all(np.einsum("ij,ij->i", np.cross(dp_du, dp_dv), shading) > 0)


def test_a_bend_is_mitred_and_the_polyline_length_is_its_segments():
    points = [[0.0, 0.0], [4.0, 0.0], [4.0, 3.0]]  # a 90° left turn, the road on the right (outside)
    assert polyline_length_m(points) == pytest.approx(7.0)
    profile = kerb_profile()
    mesh = kerb_mesh(points, profile)
    assert mesh.length_m == pytest.approx(7.0)
    # The back face's corner lies on the bisector, √2·w from the bend.
    corner = np.array([4.0 - HB2_WIDTH_M, HB2_WIDTH_M])
    assert np.min(np.linalg.norm(mesh.vertices_m[:, :2] - corner, axis=1)) < 1e-6
    # Volume: each straight piece of a mitred prism holds area × the length of its centroid's path, which
    # inside a bend of θ is shorter by 2·x̄·tan(θ/2) (x̄: the centroid's distance behind the road face).
    x, z = profile.points.T
    closed_x, closed_z = np.append(x, x[0]), np.append(z, z[0])
    cross = closed_x[:-1] * closed_z[1:] - closed_x[1:] * closed_z[:-1]
    x_bar = float(np.sum((closed_x[:-1] + closed_x[1:]) * cross) / (6 * np.sum(cross) / 2))
    expected = profile.area_m2() * (7.0 - 2 * x_bar * math.tan(math.pi / 4))
    assert _signed_volume_m3(mesh, 0.0) == pytest.approx(expected, rel=1e-5)


def test_joints_fall_every_unit_from_the_first_point():
    np.testing.assert_allclose(joint_positions_m(4.0), [0.914, 1.828, 2.742, 3.656])
    np.testing.assert_allclose(joint_positions_m(3.656), [0.914, 1.828, 2.742])
    assert len(joint_positions_m(0.5)) == 0
    maps = kerb_surface_maps(0, UNIT_LENGTH_M, 0.003, texels=1024)
    assert maps.tile_m == pytest.approx(KERB_UNITS_PER_TILE * UNIT_LENGTH_M)
    # Dark columns (the joints) across the whole tile at u = 0 and every 914 mm, nowhere else.
    column_mean = maps.albedo[..., 0].mean(axis=0)
    dark = np.flatnonzero(column_mean < (1 + KERB_JOINT_ALBEDO) / 2)
    expected = np.round(np.arange(KERB_UNITS_PER_TILE) * UNIT_LENGTH_M / maps.tile_m * 1024).astype(int)
    np.testing.assert_array_equal(dark, expected)
    # Recessed: the joint's edges lean towards it in the normal map (u only; no relief across v).
    assert maps.normal[:, 1, 0].mean() < -0.3 and maps.normal[:, 1023, 0].mean() > 0.3
    np.testing.assert_allclose(maps.normal[..., 1], 0.0, atol=1e-6)
    units = column_mean[np.abs(np.arange(1024) - expected[:, None]).min(axis=0) > 3]
    assert units.mean() == pytest.approx(1.0, abs=0.01)


def test_a_configured_kerb_builds_its_geometry():
    kerb = Kerb(along_m=[[0, 0], [3, 0]], upstand_m=0.1, batter_setback_m=0.0, batter_rise_m=0.0, arris_radius_m=0.0)
    mesh = kerb_geometry(kerb)
    assert _signed_volume_m3(mesh, 0.0) == pytest.approx(HB2_WIDTH_M * 0.1 * 3.0, rel=1e-6)  # a square kerb


def test_every_accepted_kerb_profile_stays_on_the_road_and_behind_its_face():
    """Whatever sizes the config accepts, the profile lies within its width behind the road face and between the
    road and its upstand: an arris too large for its face would dip below the road or bulge into it."""
    from pydantic import ValidationError

    accepted = 0
    for upstand in (0.01, 0.025, 0.05, 0.125):
        for setback, rise in ((0.0, 0.0), (0.005, 0.005), (0.01, 0.02), (0.05, 0.1)):
            for radius in (0.0, 0.005, 0.015, 0.05):
                try:
                    kerb = Kerb(
                        along_m=[[0, 0], [1, 0]], width_m=0.2, upstand_m=upstand, batter_setback_m=setback,
                        batter_rise_m=rise, arris_radius_m=radius,
                    )  # fmt: skip
                except ValidationError:
                    continue
                accepted += 1
                sizes = (kerb.width_m, kerb.upstand_m, kerb.batter_setback_m, kerb.batter_rise_m, kerb.arris_radius_m)
                x, z = kerb_profile(*sizes).points.T
                assert x.min() >= -1e-12 and z.min() >= -1e-12, (upstand, setback, rise, radius)
                assert x.max() <= 0.2 + 1e-12 and z.max() <= upstand + 1e-12, (upstand, setback, rise, radius)
    assert accepted >= 20
