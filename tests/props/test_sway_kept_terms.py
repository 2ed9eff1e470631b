"""`PropSway.deformed` keeps what does not change with time (`_RestTerms`) for the rest vertices it was last
given: every deformation equals the model's formula written out term by term (the code before the terms were
kept) bit for bit, at times asked in any order and again, for a tree, a bush and leafy vertices in several
runs; new rest arrays, or the same arrays changed in place, get their own terms."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from camgen.config.scene import Wind
from camgen.props.sway import bendable, group_centres_m, prop_sway, wind_gusts
from camgen.props.types import build_prop


def _formula(sway, vertices_m, normals, time_s):
    """The deformation of `camgen.props.sway` written out, every term from the rest arrays at each call."""
    s = np.clip(vertices_m[:, 2] / sway.height_m, 0.0, None)
    D = sway.tip_displacement_m(time_s)
    moved = vertices_m + (s**2)[:, None] * D
    moved[:, 2] -= (2.0 / 3.0) * float(D @ D) * s**3 / sway.height_m
    turned = normals.copy()
    turned[:, 2] -= (2.0 * s / sway.height_m) * (normals @ D)
    if sway.leafy.any():
        rest = vertices_m[sway.leafy]
        if sway.flutter_groups is not None:  # a group (a twig's leaves) by its leafy vertices' mean
            rest, row = group_centres_m(rest, sway.flutter_groups[sway.leafy])
        g = float(sway.gusts.factor(time_s, sway.along_m))
        theta = (
            rest @ sway.flutter_wave_vectors_rad_m.T
            + 2 * math.pi * sway.flutter_frequencies_hz * time_s
            + sway.flutter_phases_rad
        )
        amplitude = g * sway.flutter_m
        shift = (amplitude * np.sin(theta)) @ sway.flutter_axes
        slope = amplitude * np.cos(theta)
        if sway.flutter_groups is not None:
            shift, slope = shift[row], slope[row]
        moved[sway.leafy] += shift
        tilt = slope * (normals[sway.leafy] @ sway.flutter_axes.T)
        turned[sway.leafy] -= tilt @ sway.flutter_wave_vectors_rad_m
    turned /= np.linalg.norm(turned, axis=1, keepdims=True)
    return moved, turned


def _plant(kind, seed=3, height_m=6.0):
    model = bendable(build_prop(kind, seed, height_m=height_m))
    wind = Wind(speed_m_s=9.0, direction_deg=75.0, turbulence_intensity=0.4, seed=11)
    T = np.eye(4)
    T[:2, 3] = (12.0, -4.0)
    sway = prop_sway(model, T, wind_gusts(wind, scene_seed=0))
    vertices, normals = model.arrays()[:2]
    return sway, vertices, normals


def _same_bits(a, b):
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


TIMES_S = (0.0, 3.7, 0.0, 12.25, 3.7, -1.5, 400.125, 12.25, 0.04)


@pytest.mark.parametrize("kind", ["tree", "bush"])
def test_deformations_in_any_order_equal_the_formula_bit_for_bit(kind):
    sway, vertices, normals = _plant(kind, height_m=7.0 if kind == "tree" else 1.5)
    assert sway.leafy.any()
    shapes = {}
    for t in TIMES_S:
        moved, turned = sway.deformed(vertices, normals, t)
        expected = _formula(sway, vertices, normals, t)
        assert _same_bits(moved, expected[0]) and _same_bits(turned, expected[1]), t
        shapes.setdefault(t, moved)
    # The times give different shapes (a kept term that froze the time would not).
    assert not np.array_equal(shapes[0.0], shapes[3.7])
    assert not np.array_equal(shapes[3.7], shapes[12.25])


def test_leafy_vertices_in_several_runs_bend_as_the_formula():
    sway, vertices, normals = _plant("tree")
    scattered = dataclasses.replace(sway, leafy=sway.leafy & (np.arange(len(sway.leafy)) % 3 != 1))
    assert scattered.leafy.any()
    for t in TIMES_S:
        moved, turned = scattered.deformed(vertices, normals, t)
        expected = _formula(scattered, vertices, normals, t)
        assert _same_bits(moved, expected[0]) and _same_bits(turned, expected[1]), t


def test_other_rest_arrays_get_their_own_terms():
    sway, vertices, normals = _plant("tree")
    sway.deformed(vertices, normals, 1.0)
    # The same arrays changed in place: a taller crown, other normals.
    changed_v, changed_n = vertices.copy(), normals.copy()
    sway.deformed(changed_v, changed_n, 1.0)
    changed_v[:, 2] *= 1.1
    changed_n[:, :2] = changed_n[:, ::-1][:, :2]
    changed_n /= np.linalg.norm(changed_n, axis=1, keepdims=True)
    for v, n in ((changed_v, changed_n), (vertices, normals), (changed_v, normals), (vertices, changed_n)):
        moved, turned = sway.deformed(v, n, 2.5)
        expected = _formula(sway, v, n, 2.5)
        assert _same_bits(moved, expected[0]) and _same_bits(turned, expected[1])
    # −0.0 equals 0.0 but is another vertex to bit-for-bit arithmetic.
    signed = vertices.copy()
    signed[signed == 0.0] = -0.0
    assert sway._rest_terms(vertices, normals) is not sway._rest_terms(signed, normals)


def test_the_rest_arrays_are_not_changed_and_the_kept_terms_cannot_be():
    sway, vertices, normals = _plant("bush", height_m=1.5)
    before = vertices.copy(), normals.copy()
    sway.deformed(vertices, normals, 0.5)
    moved, _ = sway.deformed(vertices, normals, 0.75)
    moved += 1.0  # the caller's own array
    assert _same_bits(vertices, before[0]) and _same_bits(normals, before[1])
    kept = sway._rest_terms(vertices, normals)
    with pytest.raises(ValueError):
        kept.vertices_m[0, 0] = 5.0
    expected = _formula(sway, vertices, normals, 0.75)
    assert _same_bits(sway.deformed(vertices, normals, 0.75)[0], expected[0])
