"""What a person wears, checked on the rest body (no rendering): skin colour against the ColorChecker's
skin patches (colour-science), tops hemmed level, no slit between top and trousers, trouser legs as
wide as real ones at the hem, a handbag beside the hip, and sleeves that follow a pinned top."""

from __future__ import annotations

import dataclasses

import colour
import numpy as np
import pytest
from scipy.spatial import ConvexHull

from camgen.actors import makehuman as mh
from camgen.actors import person
from camgen.actors.appearance import draw_appearance, skin_rgb
from camgen.actors.skeleton import INDEX, JOINTS

ARM_JOINTS = [name for name in JOINTS if "arm" in name or "hand" in name]


def _colourchecker_linear_srgb(name: str) -> np.ndarray:
    checker = colour.CCS_COLOURCHECKERS["ColorChecker 2005"]
    xyz = colour.xyY_to_XYZ(checker.data[name])
    return colour.XYZ_to_sRGB(xyz, checker.illuminant, apply_cctf_encoding=False)


def test_skin_tones_pass_through_the_colourcheckers_skin_patches():
    np.testing.assert_allclose(skin_rgb(2), _colourchecker_linear_srgb("light skin"), atol=2e-3)
    np.testing.assert_allclose(skin_rgb(7), _colourchecker_linear_srgb("dark skin"), atol=2e-3)
    tones = np.array([skin_rgb(t) for t in range(1, 11)])
    assert np.all(np.diff(tones, axis=0) < 0)  # darker at every step, in every channel
    # Skin is red-dominated at every tone (the patches' R/G is 1.94 and 2.11); a grey swatch is not skin.
    assert np.all((tones[:, 0] / tones[:, 1] > 1.8) & (tones[:, 0] / tones[:, 1] < 2.4))


def test_a_pinned_jacket_has_long_sleeves():
    drawn = draw_appearance(5)
    assert drawn.top == "tshirt" and not drawn.long_sleeves
    assert draw_appearance(5, pinned={"top": "jacket"}).long_sleeves
    assert not draw_appearance(5, pinned={"top": "jacket", "long_sleeves": False}).long_sleeves


@pytest.fixture(scope="module", params=["tshirt", "jacket"])
def dressed(request):
    look = dataclasses.replace(draw_appearance(5), top=request.param, bottom="trousers", bag="handbag")
    vertices = person.shaped_vertices(look)
    joints = person.rest_joints(vertices)
    dominant = np.array(JOINTS)[person._skin_weights()[0][:, 0]]
    cover = person._regions(vertices, person._skin_weights()[0][:, 0], joints, look)
    return look, vertices, joints, dominant, cover


def test_a_top_is_hemmed_level_not_down_to_the_crotch(dressed):
    """The top's lowest point between the legs and at the hips lie at the same height (within a helper
    face's 2 cm), not a leotard's V whose point is at the crotch."""
    _, vertices, _, dominant, cover = dressed
    tights = np.zeros(len(vertices), bool)
    tights[mh.base_mesh().faces_by_group["helper-tights"]] = True
    top = cover["top"] & tights & ~np.isin(dominant, ARM_JOINTS)
    y, z = vertices[:, 1], vertices[:, 2]
    centre, side = z[top & (np.abs(y) < 0.03)].min(), z[top & (np.abs(y) > 0.12)].min()
    assert abs(centre - side) < 0.02, (centre, side)


def test_every_helper_face_at_the_waist_belongs_to_the_top_or_the_trousers(dressed):
    """Between the hem and the waist each face of the tights helper is wholly in one garment: a ring in
    neither is a slit through the body (the skin under the garments is not drawn)."""
    _, vertices, joints, dominant, cover = dressed
    tights = mh.base_mesh().faces_by_group["helper-tights"]
    hip_z = joints[INDEX["thigh_l"], 2]
    band = (np.abs(vertices[:, 2] - hip_z) < 0.15) & ~np.isin(dominant, ARM_JOINTS)
    faces = tights[band[tights].all(axis=1)]
    assert len(faces) > 200
    whole = cover["top"][faces].all(axis=1) | cover["bottom"][faces].all(axis=1)
    assert whole.all(), vertices[faces[~whole]].reshape(-1, 3)


def test_a_trouser_leg_is_as_wide_at_the_hem_as_a_straight_leg_trousers(dressed):
    """The trouser shell's girth 3 cm above the ankle: 38–50 cm (a straight leg's hem opening of 42–46 cm,
    21–23 cm laid flat in trousers' size charts; following the tights' taper it was 32 cm)."""
    _, vertices, joints, _, cover = dressed
    tights = mh.base_mesh().faces_by_group["helper-tights"]
    piece = person._surface(vertices, tights, cover["bottom"], (0, 0, 0), person._trousers_offset_m(vertices, joints))
    ankle_z = joints[INDEX["foot_l"], 2]
    ring = piece.points_m[(np.abs(piece.points_m[:, 2] - ankle_z - 0.03) < 0.01) & (piece.points_m[:, 1] > 0)]
    hull = ConvexHull(ring[:, :2])
    assert 0.38 < hull.area < 0.50, hull.area  # a 2-D hull's "area" is its perimeter


def test_a_handbag_hangs_beside_the_hip(dressed):
    """Its inner face within 2 cm of the hip's outer surface (the arms, out at hip height in the rest
    A-pose, are no part of the hip)."""
    look, vertices, joints, dominant, _ = dressed
    (bag,) = person._carried(look, vertices, joints)
    hip_z = joints[INDEX["thigh_l"], 2]
    trunk = ~np.isin(dominant, ARM_JOINTS) & (np.abs(vertices[:, 2] - hip_z) < 0.04)
    gap_m = bag.points_m[:, 1].min() - vertices[trunk, 1].max()
    assert 0.0 < gap_m < 0.02, gap_m
