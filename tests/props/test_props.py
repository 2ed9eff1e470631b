"""Procedural props (`camgen.props`): dimensions within the cited ranges, closed parts, per-seed variety,
the scatter rules, the NIR reflectance of foliage, and a small render (OpenGL) whose instance ids, depth and
a bollard's height in pixels agree with the pinhole's f·h/d."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
import trimesh

from camgen.config.props import PROP_HEIGHT_RANGE_M, ScatterRule
from camgen.config.scene import Environment
from camgen.errors import ConfigError
from camgen.props import placed_props, prop_box_corners, prop_names
from camgen.props.scatter import scatter_spots
from camgen.props.types import LAMP_HEIGHTS_M, LEAF_CARD_PARTS, LEAF_NIR, build_prop

KINDS = [("tree", None), ("tree", "conifer"), ("bush", None), ("bench", None), ("bin", None), ("bollard", None),
         ("lamp_post", None), ("sign", None), ("fence", None)]  # fmt: skip
SEEDS = range(6)


@pytest.fixture(scope="module")
def models():
    return {(kind, form, seed): build_prop(kind, seed, form=form) for kind, form in KINDS for seed in SEEDS}


def test_same_seed_same_prop_other_seed_other_prop():
    for kind, form in KINDS:
        a, b, c = (build_prop(kind, s, form=form).arrays() for s in (4, 4, 5))
        assert all(np.array_equal(x, y) for x, y in zip(a, b, strict=True)), kind
        assert len(a[0]) != len(c[0]) or not np.allclose(a[0], c[0]), kind


def test_every_part_is_closed_and_wound_outwards(models):
    """Solid parts (and the envelopes leaves fill) are closed and wound outwards; leaves (a broadleaf crown, a
    bush's foliage) are cards of two sides, each triangle's twin the same corners wound the other way."""
    for (kind, form, seed), model in models.items():
        cards = [part for part in model.parts if part.name in LEAF_CARD_PARTS]
        for part in cards:
            corners = part.vertices_m[part.faces].reshape(-1, 4, 3, 3)  # per card: front, front, back, back
            front, back = corners[:, :2].reshape(-1, 3, 3), corners[:, 2:].reshape(-1, 3, 3)
            n_front = np.cross(front[:, 1] - front[:, 0], front[:, 2] - front[:, 0])
            n_back = np.cross(back[:, 1] - back[:, 0], back[:, 2] - back[:, 0])
            assert np.allclose(n_front, -n_back, atol=1e-12), (kind, seed)  # the same card, facing away
            assert np.array_equal(np.sort(front.reshape(-1, 9), axis=1), np.sort(back.reshape(-1, 9), axis=1))
        assert (kind in ("tree", "bush") and form is None) == bool(cards), (kind, form)
        for part in [p for p in model.parts if p.name not in LEAF_CARD_PARTS] + model.envelope:
            mesh = trimesh.Trimesh(part.vertices_m, part.faces)  # merges the split (hard-edged) vertices
            assert mesh.is_watertight, (kind, form, seed, part.name)
            assert mesh.volume > 0, (kind, form, seed, part.name)  # outward normals: positive volume


def test_heights_and_dimensions_lie_in_the_cited_ranges(models):
    for (kind, _form, seed), model in models.items():
        vertices = model.arrays()[0]
        low, high = PROP_HEIGHT_RANGE_M[kind]
        assert low - 1e-9 <= model.height_m <= high + 1e-9, (kind, seed)
        assert vertices[:, 2].max() == pytest.approx(model.height_m, abs=1e-6), (kind, seed)
        assert vertices[:, 2].min() > -0.05, (kind, seed)
        d = model.dims
        parts = {p.name: p for p in model.parts}
        if kind == "tree":
            assert 0.2 <= d["trunk_diameter_m"] <= 0.5
            trunk = parts["trunk"].vertices_m
            assert 2 * np.hypot(trunk[:, 0], trunk[:, 1]).max() == pytest.approx(d["trunk_diameter_m"], rel=1e-9)
        elif kind == "bench":
            assert 0.45 <= d["seat_height_m"] <= 0.475
            assert parts["seat"].vertices_m[:, 2].max() == pytest.approx(d["seat_height_m"])
            assert np.ptp(parts["seat"].vertices_m[:, 0]) == pytest.approx(d["length_m"])
            assert 1.5 <= d["length_m"] <= 2.0
        elif kind in ("bollard", "bin"):
            radius = np.hypot(vertices[:, 0], vertices[:, 1]).max()
            assert 2 * radius == pytest.approx(d["diameter_m"], abs=0.005)
            lo, hi = (0.1, 0.2) if kind == "bollard" else (0.4, 0.6)
            assert lo <= d["diameter_m"] <= hi
        elif kind == "lamp_post":
            assert model.height_m in LAMP_HEIGHTS_M
            assert 0.5 <= d["outreach_m"] <= 1.5
            assert vertices[:, 0].max() > d["outreach_m"]  # the lantern hangs beyond the bracket
        elif kind == "sign":
            assert 2.1 <= d["plate_lower_edge_m"] <= 2.5
            assert parts["plate"].vertices_m[:, 2].min() == pytest.approx(d["plate_lower_edge_m"])
        elif kind == "fence":
            posts = sorted({round(float(p.vertices_m[:, 0].mean()), 6) for p in model.parts if p.name == "post"})
            assert max(np.diff(posts)) <= 3.0 + 1e-9
            bars = sorted(float(p.vertices_m[:, 0].min()) for p in model.parts if p.name == "bar")
            widths = [np.ptp(p.vertices_m[:, 0]) for p in model.parts if p.name == "bar"]
            assert max(np.diff(bars)) - max(widths) <= 0.1 + 1e-9  # BS 6180: gaps of 100 mm at most


def _outline_radius(vertices: np.ndarray, bins: int = 36) -> np.ndarray:
    """The crown's horizontal outline: the farthest vertex from its vertical axis in each azimuth bin."""
    centre = vertices[:, :2].mean(axis=0)
    offset = vertices[:, :2] - centre
    azimuth = np.floor((np.arctan2(offset[:, 1], offset[:, 0]) + math.pi) / (2 * math.pi) * bins).astype(int) % bins
    radius = np.hypot(offset[:, 0], offset[:, 1])
    return np.array([radius[azimuth == b].max() for b in range(bins)])


def test_crowns_are_irregular_and_differ_per_seed():
    outlines = []
    for seed in range(4):
        model = build_prop("tree", seed)
        crown = np.concatenate([p.vertices_m for p in model.parts if p.name.startswith("crown")])
        outline = _outline_radius(crown)
        assert outline.max() / outline.min() > 1.1, seed  # a sphere's outline would be round (ratio ≈ 1.0)
        outlines.append(outline / outline.mean())
        leaves = np.concatenate([p.nir_reflectance for p in model.parts if p.name.startswith("crown")])
        assert LEAF_NIR[0] * 0.95 <= leaves.min() and leaves.max() <= LEAF_NIR[1] * 1.05
        colours = np.concatenate([p.colours_rgb for p in model.parts if p.name.startswith("crown")])
        assert np.all(colours[:, 1] > colours[:, 0]) and np.all(colours[:, 1] > colours[:, 2])  # green
        assert colours[:, 1].std() / colours[:, 1].mean() > 0.05  # not one flat colour
    for a, b in itertools.combinations(outlines, 2):
        assert np.abs(a - b).max() > 0.05


def test_scatter_along_a_line_is_evenly_spaced_and_reproducible():
    rule = ScatterRule(type="bollard", along=[(0.0, 0.0), (10.0, 0.0), (10.0, 5.0)], spacing_m=1.5, seed=3)
    spots = scatter_spots(rule)
    assert len(spots) == math.floor(15 / 1.5) + 1
    xy = np.array([s.position_m for s in spots])
    on_first = xy[xy[:, 1] == 0.0]
    assert np.allclose(np.diff(on_first[:, 0]), 1.5)
    assert spots[0].heading_deg == 0.0 and spots[-1].heading_deg == pytest.approx(90.0)
    assert spots == scatter_spots(rule)
    # Across the bend two spots come 1.5/√2·… closer than the spacing: min_gap_m leaves the later out.
    gapped = scatter_spots(rule.model_copy(update={"min_gap_m": 1.4}))
    xy = np.array([s.position_m for s in gapped])
    distances = np.linalg.norm(xy[:, None] - xy[None], axis=2)[np.triu_indices(len(xy), 1)]
    assert distances.min() >= 1.4 and len(gapped) == len(spots) - 1


def test_scatter_in_a_region_keeps_count_bounds_and_gap():
    rule = ScatterRule(type="tree", region_m=((-10.0, 2.0), (10.0, 12.0)), count=18, min_gap_m=2.5, seed=11)
    spots = scatter_spots(rule)
    xy = np.array([s.position_m for s in spots])
    assert len(spots) == 18
    assert np.all((xy[:, 0] >= -10) & (xy[:, 0] <= 10) & (xy[:, 1] >= 2) & (xy[:, 1] <= 12))
    distances = np.linalg.norm(xy[:, None] - xy[None], axis=2)[np.triu_indices(len(xy), 1)]
    assert distances.min() >= 2.5
    assert spots == scatter_spots(rule)
    other = np.array([s.position_m for s in scatter_spots(rule.model_copy(update={"seed": 12}))])
    assert not np.allclose(xy, other)
    assert len({s.seed for s in spots}) == 18  # every prop its own identity


def test_a_region_too_small_for_its_count_is_refused():
    with pytest.raises(ValueError, match="at most 12 props 1 m apart"):
        ScatterRule(type="bush", region_m=((0, 0), (4, 5)), count=30, min_gap_m=1.0)
    # Under the validator's bound, dart throwing that jams still names the rule.
    rule = ScatterRule.model_construct(
        type="bush", seed=0, along=None, spacing_m=None, region_m=((0, 0), (2, 2)), count=40, min_gap_m=1.0,
        heading_deg=None, elevation_m=0.0, form=None, height_m=None,
    )  # fmt: skip
    with pytest.raises(ConfigError, match=r"environment.scatter\[3\].count: only"):
        scatter_spots(rule, where="environment.scatter[3]")


def test_placed_props_names_seeds_and_poses():
    environment = Environment.model_validate(
        {
            "props": [
                {"type": "bench", "position_m": [1, 2], "heading_deg": 90},
                {"type": "tree", "position_m": [5, 5], "form": "conifer", "name": "pine"},
            ],
            "scatter": [{"type": "bollard", "along": [[0, -3], [4, -3]], "spacing_m": 2}],
        }
    )
    placed = placed_props(environment, scene_seed=7)
    assert (
        [p.name for p in placed]
        == prop_names(environment)
        == ["bench_0", "pine", "bollard_scatter0.0", "bollard_scatter0.1", "bollard_scatter0.2"]
    )
    assert placed[0].model.seed == placed_props(environment, scene_seed=7)[0].model.seed
    assert placed[0].model.seed != placed_props(environment, scene_seed=8)[0].model.seed
    T = placed[0].T_world_from_prop
    assert np.allclose(T[:3, 0], (0, 1, 0)) and np.allclose(T[:3, 3], (1, 2, 0))
    assert [p.T_world_from_prop[0, 3] for p in placed[2:]] == [0.0, 2.0, 4.0]
    # The plan's depth boxes hold every vertex of their prop, in the world.
    for prop, corners in zip(placed, prop_box_corners(environment, scene_seed=7), strict=True):
        T = prop.T_world_from_prop
        world = prop.model.arrays()[0] @ T[:3, :3].T + T[:3, 3]
        assert np.all(world >= corners.min(axis=0) - 1e-9) and np.all(world <= corners.max(axis=0) + 1e-9)
        assert np.allclose(corners.min(axis=0)[2], world[:, 2].min()) and np.allclose(
            corners.max(axis=0)[2], world[:, 2].max()
        )


W, H = 160, 120
F_PX = 200.0
CAMERA_Z_M = 0.5
BOLLARD_X_M = 5.0


@pytest.fixture(scope="module")
def drawn(renderer):
    from camgen.render.renderer import View
    from camgen.render.scene_graph import build_scene_graph, instance_table
    from tests.render.conftest import camera_matrix, look_at, scene_from

    scene = scene_from(
        seed=3,
        environment={
            "meshes": [
                {"type": "plane", "name": "ground", "size_m": [40, 40], "material": {"color_rgb": [0.2, 0.2, 0.2]}}
            ],
            "props": [
                {"type": "bollard", "position_m": [BOLLARD_X_M, 0.0], "seed": 5},
                {"type": "tree", "position_m": [14.0, 4.0], "seed": 2},
            ],
            "scatter": [{"type": "bush", "region_m": [[10, -6], [14, -3]], "count": 2, "min_gap_m": 1.5, "seed": 1}],
        },
        lights=[{"type": "sun", "illuminance_lux": 50000, "azimuth_deg": 200, "elevation_deg": 40},
                {"type": "ambient", "illuminance_lux": 10000}],
    )  # fmt: skip
    graph = build_scene_graph(scene)
    T = look_at((0.0, 0.0, CAMERA_Z_M), (10.0, 0.0, CAMERA_Z_M))
    view = View(camera_matrix(F_PX, F_PX, (W - 1) / 2, (H - 1) / 2), T, W, H)
    passes = renderer.draw(graph, view, ("radiance", "depth_m", "instance_id"))
    return scene, graph, instance_table(scene), passes


def test_rendered_bollard_has_its_id_depth_and_height_in_pixels(drawn):
    scene, _, table, passes = drawn
    ids = {i.name: i.instance_id for i in table}
    assert set(ids) == {"ground", "bollard_0", "tree_1", "bush_scatter0.0", "bush_scatter0.1"}
    assert all(i.kind == "environment" for i in table)
    model = placed_props(scene.environment, scene_seed=scene.seed)[0].model
    height, diameter = model.height_m, model.dims["diameter_m"]
    column = passes.instance_id[:, W // 2]  # the optical axis passes through the bollard's axis
    rows = np.flatnonzero(column == ids["bollard_0"])
    cy = (H - 1) / 2
    # The top: the cap's flat top, nearest edge at 0.25·D; the foot: the column's front on the ground.
    top_v = cy - F_PX * (height - CAMERA_Z_M) / (BOLLARD_X_M - 0.25 * diameter)
    foot_v = cy + F_PX * CAMERA_Z_M / (BOLLARD_X_M - diameter / 2)
    assert rows.min() == pytest.approx(top_v, abs=1.0)
    assert rows.max() == pytest.approx(foot_v, abs=1.0)
    assert len(rows) == rows.max() - rows.min() + 1  # one unbroken run
    depth = passes.depth_m[round(cy), W // 2]
    assert depth == pytest.approx(BOLLARD_X_M - diameter / 2, abs=0.005)
    for name in ("tree_1", "bush_scatter0.0", "bush_scatter0.1"):
        assert (passes.instance_id == ids[name]).sum() > 20, name


def test_props_cast_shadows_on_the_ground(drawn, renderer):
    """The same view without props: the ground beside them gets darker where their shadows fall."""
    from camgen.render.renderer import View
    from camgen.render.scene_graph import build_scene_graph
    from tests.render.conftest import camera_matrix, look_at

    scene, _, table, passes = drawn
    bare = scene.model_copy(update={"environment": scene.environment.model_copy(update={"props": []})})
    T = look_at((0.0, 0.0, CAMERA_Z_M), (10.0, 0.0, CAMERA_Z_M))
    view = View(camera_matrix(F_PX, F_PX, (W - 1) / 2, (H - 1) / 2), T, W, H)
    plain = renderer.draw(build_scene_graph(bare), view, ("radiance",)).radiance
    ground_id = next(i.instance_id for i in table if i.name == "ground")
    ground = passes.instance_id == ground_id
    ratio = passes.radiance[..., 1][ground] / plain[..., 1][ground]
    assert ratio.min() < 0.5  # some ground lies in a prop's shadow
    assert np.median(ratio) == pytest.approx(1.0, abs=0.01)  # and most of it is lit as before


def test_foliage_is_bright_in_the_near_infrared_pass():
    from camgen.config.profile import Profile
    from camgen.render.nir import build_nir_graph
    from tests.render.conftest import scene_from

    profile = Profile.model_validate(
        {
            "sensor": {"width_px": 160, "height_px": 120, "pixel_pitch_um": 3.0, "full_well_e": 10000,
                       "conversion_gain_dn_per_e": 0.4},
            "lens": {"focal_length_mm": 4.0, "f_number": 2.0},
            "night_mode": {"ir_illuminator": {"radiant_intensity_mw_sr": 500, "half_angle_deg": 40}},
        }
    )  # fmt: skip
    scene = scene_from(
        environment={"props": [{"type": "tree", "position_m": [5, 0], "seed": 1},
                               {"type": "bollard", "position_m": [3, 0], "seed": 5}]},
        lights=[{"type": "ambient", "illuminance_lux": 1}],
    )  # fmt: skip
    graph = build_nir_graph(scene, profile)
    tree_node, bollard_node = graph.environment_nodes
    tree = build_prop("tree", 1)
    grey = np.asarray(tree_node.mesh.primitives[0].color_0)
    assert np.allclose(grey[:, 0], tree.arrays()[4], atol=1e-6)  # the prop's own 850 nm reflectance
    leaves = np.concatenate([p.nir_reflectance for p in tree.parts if p.name.startswith("crown")])
    assert 0.42 <= leaves.mean() <= 0.53
    assert np.asarray(bollard_node.mesh.primitives[0].color_0)[:, 0].max() <= 0.8 + 1e-6


def test_foliage_renders_as_bright_as_its_reflectance_in_the_ir_pass(renderer):
    """Under the camera's illuminator alone, the crown's pixels and a sphere's of ρ₈₅₀ = the leaves' mean,
    side by side at 20 m, agree within 30 % (measured 1.03; the lumps face the light less squarely than a
    sphere); by its green colour's red channel (0.05) the crown would be ten times darker."""
    from camgen.config.profile import Profile
    from camgen.render.nir import aim_illuminator, build_nir_graph
    from camgen.render.renderer import View
    from camgen.render.scene_graph import instance_table
    from tests.render.conftest import camera_matrix, look_at, scene_from

    profile = Profile.model_validate(
        {
            "sensor": {"width_px": 160, "height_px": 120, "pixel_pitch_um": 3.0, "full_well_e": 10000,
                       "conversion_gain_dn_per_e": 0.4},
            "lens": {"focal_length_mm": 4.0, "f_number": 2.0},
            "night_mode": {"ir_illuminator": {"radiant_intensity_mw_sr": 500, "half_angle_deg": 40}},
        }
    )  # fmt: skip
    tree = build_prop("tree", 1, height_m=7.0)
    leaves = np.concatenate([p.nir_reflectance for p in tree.parts if p.name.startswith("crown")])
    crown_z = tree.dims["crown_base_m"] + (7.0 - tree.dims["crown_base_m"]) / 2
    scene = scene_from(
        environment={
            "meshes": [{"type": "sphere", "name": "ball", "radius_m": 1.5, "position_m": [20, 3.5, crown_z],
                        "material": {"color_rgb": [0.05, 0.1, 0.03], "nir_reflectance": float(leaves.mean())}}],
            "props": [{"type": "tree", "position_m": [20, -3.5], "seed": 1, "height_m": 7.0}],
        },
        lights=[{"type": "ambient", "illuminance_lux": 1}],
    )  # fmt: skip
    graph = build_nir_graph(scene, profile)
    T = look_at((0.0, 0.0, crown_z), (20.0, 0.0, crown_z))
    aim_illuminator(graph, T)
    passes = renderer.draw(graph, View(camera_matrix(300, 300, 79.5, 59.5), T, W, H), ("radiance", "instance_id"))
    ids = {i.name: i.instance_id for i in instance_table(scene)}
    ball = passes.radiance[..., 0][passes.instance_id == ids["ball"]]
    crown_rows = np.arange(H)[:, None] < 59.5 - 300 * 0.5 / 20  # 0.5 m over the crown's middle and up: no trunk
    crown = passes.radiance[..., 0][(passes.instance_id == ids["tree_0"]) & crown_rows]
    assert len(ball) > 200 and len(crown) > 200
    assert float(np.mean(crown)) == pytest.approx(float(np.mean(ball)), rel=0.3)


def test_coverage_sight_lines_are_blocked_by_a_crown_and_pass_beside_it():
    """`camgen.coverage` sees a tree by its trunk and the convex hull of its crown: a line through the
    crown's middle is blocked, one passing a metre outside the crown's widest reach is not, and the hull
    holds every vertex of the crown (it never hides less than the render does)."""
    from camgen.coverage.occlusion import scene_occluders, sight_blocked
    from tests.render.conftest import scene_from

    scene = scene_from(environment={"props": [{"type": "tree", "position_m": [10, 0], "seed": 2, "height_m": 8}]},
                       lights=[{"type": "ambient", "illuminance_lux": 1}])  # fmt: skip
    (occluder,) = scene_occluders(scene)
    model = placed_props(scene.environment, scene_seed=scene.seed)[0].model
    crown = np.concatenate([p.vertices_m for p in model.parts if p.name.startswith("crown")])
    hard = sum(len(p.faces) for p in model.parts if not p.name.startswith("crown"))
    hull = occluder.triangles_m[hard:]  # the crown's hull follows the trunk's triangles
    normals = np.cross(hull[:, 1] - hull[:, 0], hull[:, 2] - hull[:, 0])
    outside = np.einsum("fk,vfk->vf", normals, crown[:, None, :] - hull[None, :, 0])
    assert outside.max() <= 1e-9 * np.abs(outside).max()  # every crown vertex on the inner side of every face
    centre_z = float(crown[:, 2].mean())
    reach = float(np.hypot(crown[:, 0], crown[:, 1]).max())
    origin = np.array([0.0, 0.0, centre_z + 0.37])  # not level: a ray parallel to a face warns (0/0)
    targets = np.array([[20.0, 0.0, centre_z], [20.0, 2 * (reach + 1.0), centre_z], [10.0, 0.0, 0.5]])
    assert sight_blocked(origin, targets, [occluder]).tolist() == [True, False, True]  # crown, beside, trunk
    assert len(occluder.triangles_m) < len(model.arrays()[2]) / 5


def test_a_camera_mounted_inside_a_lamp_posts_column_sees_out_and_the_post_still_hides_from_outside():
    """A camera on a lamp post sits inside its column, as the renderer (which culls back faces) lets it:
    sight lines leaving through the column's inner faces are not blocked, while one passing through the
    column from outside is (props are wound outward, `test_every_part_is_closed_and_wound_outwards`)."""
    from camgen.coverage.occlusion import scene_occluders, sight_blocked
    from tests.render.conftest import scene_from

    scene = scene_from(environment={"props": [{"type": "lamp_post", "position_m": [0, 0], "seed": 1, "height_m": 8}]},
                       lights=[{"type": "ambient", "illuminance_lux": 1}])  # fmt: skip
    (occluder,) = scene_occluders(scene)
    assert occluder.entering_only
    inside_column = np.array([0.0, 0.0, 6.0])
    ground = np.array([[10.0, 3.0, 0.0], [-8.0, -5.0, 0.0], [2.0, -9.0, 0.0]])
    assert not sight_blocked(inside_column, ground, [occluder]).any()
    # From outside, a line through the column at 2 m height is hidden by it.
    assert sight_blocked(np.array([-5.0, 0.01, 2.0]), np.array([[5.0, 0.01, 2.0]]), [occluder]).tolist() == [True]
