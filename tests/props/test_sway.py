"""Trees and bushes in the wind (`camgen.props.sway`): a crown point sways at the tree's natural frequency
(Moore & Maguire 2004's f ∝ D/H², found here by an FFT), its lean grows as the drag (U²), the trunk's
foot stays put, the same seed gives the same motion and two trees sway out of phase; rendered (OpenGL),
the crown and its shadow change between two times while the trunk's foot, the sky and the ground away
from the tree do not; a calm wind changes nothing; the moving regions and a kept static background stay
exact with a swaying tree in view; the plan blurs a tree that moves far enough in an exposure."""

from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np
import pytest

from camgen.config.scene import Wind
from camgen.props.sway import prop_sway, wind_gusts
from camgen.props.types import build_prop

TREE_SEED = 2
TREE_HEIGHT_M = 7.0
SAMPLE_S = 0.1
DURATION_S = 100.0


def _sway(speed_m_s=6.0, turbulence=0.3, seed=TREE_SEED, height_m=TREE_HEIGHT_M, kind="tree", wind_seed=7):
    model = build_prop(kind, seed, height_m=height_m)
    wind = Wind(speed_m_s=speed_m_s, direction_deg=30.0, turbulence_intensity=turbulence, seed=wind_seed)
    return model, prop_sway(model, np.eye(4), wind_gusts(wind, scene_seed=0))


def _crown_track(model, sway, times_s):
    """(T, 3) displacement of the crown's top vertex (a leafy one: bending and flutter) at `times_s`."""
    vertices, normals = model.arrays()[:2]
    top = int(np.argmax(vertices[:, 2]))
    assert sway.leafy[top]
    groups = None if sway.flutter_groups is None else sway.flutter_groups[top : top + 1]
    one = dataclasses.replace(sway, leafy=sway.leafy[top : top + 1], flutter_groups=groups)
    rest = vertices[top : top + 1]
    return np.array([one.deformed(rest, normals[top : top + 1], float(t))[0][0] - rest[0] for t in times_s])


def _peak_hz(signal, above_hz=0.0):
    x = (signal - signal.mean()) * np.hanning(len(signal))
    spectrum = np.abs(np.fft.rfft(x))
    frequencies = np.fft.rfftfreq(len(x), SAMPLE_S)
    spectrum[frequencies <= above_hz] = 0.0
    return float(frequencies[np.argmax(spectrum)])


@pytest.mark.parametrize("height_m", [5.0, 12.0])
@pytest.mark.parametrize("turbulence", [0.0, 0.3])
def test_a_crown_point_sways_at_the_trees_natural_frequency(height_m, turbulence):
    model, sway = _sway(turbulence=turbulence, height_m=height_m)
    expected_hz = 110.0 * model.dims["trunk_diameter_m"] / height_m**2  # f = k·DBH/H² (Moore & Maguire 2004)
    assert 0.2 <= expected_hz <= 1.2
    times = np.arange(0.0, DURATION_S, SAMPLE_S)
    track = _crown_track(model, sway, times)
    downwind = np.array([math.cos(math.radians(30.0)), math.sin(math.radians(30.0)), 0.0])
    # Along the wind the gusts' slow lean (periods of 3 s and more) lies below 0.34 Hz.
    above = 0.4 if turbulence > 0 and expected_hz > 0.45 else 0.0
    assert _peak_hz(track @ downwind, above) == pytest.approx(expected_hz, rel=0.1)
    crosswind = np.array([-downwind[1], downwind[0], 0.0])
    assert _peak_hz(track @ crosswind) == pytest.approx(expected_hz, rel=0.1)


def test_a_bush_sways_faster_than_a_tree():
    model, sway = _sway(kind="bush", height_m=1.0)
    times = np.arange(0.0, 60.0, SAMPLE_S)
    vertices = model.arrays()[0]
    assert sway.natural_frequency_hz == pytest.approx(1.5)
    assert _peak_hz(sway.tip_displacement_m(times) @ sway.downwind) == pytest.approx(1.5, rel=0.1)
    assert vertices[:, 2].max() == pytest.approx(1.0, abs=0.01)


def test_the_lean_grows_as_the_drag_and_the_sway_with_the_wind():
    """Below 10 m/s the mean lean is ∝ U² (the same gusts at every speed); the RMS motion grows with U."""
    times = np.arange(0.0, 120.0, SAMPLE_S)
    means, rms = [], []
    for speed in (2.0, 4.0, 8.0, 16.0):
        model, sway = _sway(speed_m_s=speed)
        tip = sway.tip_displacement_m(times) @ sway.downwind
        means.append(tip.mean())
        track = _crown_track(model, sway, times[::4])
        rms.append(np.sqrt(np.mean(np.sum((track - track.mean(axis=0)) ** 2, axis=1))))
    assert means[1] / means[0] == pytest.approx(4.0, rel=1e-9)
    assert means[2] / means[1] == pytest.approx(4.0, rel=1e-9)
    assert 2.0 < means[3] / means[2] < 4.0  # crowns streamline above 10 m/s (Vogel)
    assert all(b > 1.5 * a for a, b in itertools.pairwise(rms))
    # Beaufort 3 (gentle breeze): centimetres, not metres, at a 7 m tree's top.
    assert 0.01 < rms[1] < 0.1


def test_the_trunks_foot_never_moves_and_the_crown_does():
    model, sway = _sway(speed_m_s=12.0)
    vertices, normals = model.arrays()[:2]
    foot = vertices[:, 2] <= 1e-9
    assert foot.sum() >= 16
    crown = sway.leafy
    for t in (0.0, 1.3, 7.7):
        moved, turned = sway.deformed(vertices, normals, t)
        assert np.array_equal(moved[foot], vertices[foot])
        assert np.allclose(turned[foot], normals[foot], atol=1e-12)
        assert np.linalg.norm(moved[crown] - vertices[crown], axis=1).max() > 0.05
        assert np.allclose(np.linalg.norm(turned, axis=1), 1.0)
        assert np.linalg.norm(moved - vertices, axis=1).max() <= sway.reach_m()


def test_no_vertex_moves_faster_than_the_planned_bound():
    """The plan blurs by `speed_max_m_s` (over the sequence's gusts): finite differences over 20 s stay under
    it, and reach a third of it (a bound, not a guess)."""
    model, sway = _sway(speed_m_s=8.0)
    vertices, normals = model.arrays()[:2]
    step_s = 0.01
    fastest = 0.0
    for t in np.arange(0.0, 20.0, 0.25):
        a, _ = sway.deformed(vertices, normals, float(t))
        b, _ = sway.deformed(vertices, normals, float(t) + step_s)
        fastest = max(fastest, float(np.linalg.norm(b - a, axis=1).max()) / step_s)
    bound = sway.speed_max_m_s(20.0)
    assert fastest <= bound <= sway.speed_max_m_s()
    assert fastest > bound / 3


@pytest.mark.parametrize(("speed_m_s", "turbulence"), [(3.0, 0.1), (8.0, 0.3), (20.0, 0.6)])
def test_the_moved_bound_holds_for_every_vertex_and_is_near_the_largest_move(speed_m_s, turbulence):
    """`moved_bound_m` (the blur test settles a swaying prop by it): every vertex's move between two times, as
    `deformed` bends it in float64, stays under it, for gaps from a tenth of a millisecond to seconds, and it is
    within 4x of the largest move (a bound that is tight enough to settle a tree in a short exposure)."""
    model, sway = _sway(speed_m_s=speed_m_s, turbulence=turbulence)
    vertices, normals = model.arrays()[:2]
    height_frac_max = max(0.0, float(vertices[:, 2].max()) / sway.height_m)
    rng = np.random.default_rng(3)
    ratios = []
    for gap_s in (1e-4, 5e-3, 0.02, 0.5, 3.0):
        for t in rng.uniform(0.0, 60.0, 4):
            a, _ = sway.deformed(vertices, normals, float(t))
            b, _ = sway.deformed(vertices, normals, float(t) + gap_s)
            moved = float(np.linalg.norm(b - a, axis=1).max())
            bound = sway.moved_bound_m(float(t), float(t) + gap_s, height_frac_max)
            assert moved <= bound, (gap_s, t)
            if gap_s <= 0.02 and moved > 0.0:  # (in a lull the gusts' factor is 0 and nothing moves)
                ratios.append(bound / moved)
    assert max(ratios) < 4.0
    assert sway.moved_bound_m(5.0, 5.0, height_frac_max) < 1e-8  # no time between: the rounding margin alone


def test_a_bendable_trunk_is_the_same_surface_in_bands():
    import trimesh

    from camgen.props.sway import TRUNK_BAND_M, bendable

    for form in (None, "conifer"):
        model = build_prop("tree", 3, form=form, height_m=9.0)
        banded = bendable(model)
        (before,) = [p for p in model.parts if p.name == "trunk"]
        (after,) = [p for p in banded.parts if p.name == "trunk"]
        volumes = []
        for part in (before, after):
            mesh = trimesh.Trimesh(part.vertices_m, part.faces)
            mesh.merge_vertices()
            assert mesh.is_watertight and mesh.is_winding_consistent
            volumes.append(mesh.volume)
        assert volumes[1] == pytest.approx(volumes[0], rel=1e-9)
        rings = np.unique(np.round(after.vertices_m[:, 2], 9))
        assert np.diff(rings).max() <= TRUNK_BAND_M + 1e-9 and len(rings) > 4
        assert [p.name for p in banded.parts] == [p.name for p in model.parts]
        assert all(a is b for a, b in zip(model.parts, banded.parts, strict=True) if a.name != "trunk")
    bush = build_prop("bush", 3)
    assert bendable(bush) is bush


def test_a_bent_normal_stays_perpendicular_to_the_bent_surface():
    """The normals turn with the surface (n′ ∝ (I − ∇uᵀ)n): across each triangle of a bent bush's core (a
    smooth closed blob, each vertex fluttering by its own place) the face normal and the mean of its vertices'
    normals agree as well as they do at rest. (Leaf cards flutter a twig at a time, moved along while their
    normals wobble with the wave's slope: a leaf's turning, shown in its shading only.)"""
    model, sway = _sway(speed_m_s=16.0, kind="bush", height_m=1.8)
    vertices, normals, faces = model.arrays()[:3]
    first = 0
    for part in model.parts:  # the core's triangles only
        if part.name == "foliage_core":
            faces = part.faces + first
            break
        first += len(part.vertices_m)

    def misfit(v, n):
        face = np.cross(v[faces[:, 1]] - v[faces[:, 0]], v[faces[:, 2]] - v[faces[:, 0]])
        face /= np.linalg.norm(face, axis=1, keepdims=True)
        mean = n[faces].mean(axis=1)
        mean /= np.linalg.norm(mean, axis=1, keepdims=True)
        return float(np.median(np.einsum("ij,ij->i", face, mean)))

    moved, turned = sway.deformed(vertices, normals, 2.0)
    rest_fit = misfit(vertices, normals)
    assert misfit(moved, turned) >= rest_fit - 0.002
    assert misfit(moved, normals) < misfit(moved, turned) - 0.002  # keeping the rest normals is worse


def test_same_seed_same_motion_and_two_trees_sway_out_of_phase():
    times = np.arange(0.0, 60.0, SAMPLE_S)
    a1 = _sway()[1].tip_displacement_m(times)
    a2 = _sway()[1].tip_displacement_m(times)
    assert np.array_equal(a1, a2)
    one, other = _sway(seed=TREE_SEED)[1], _sway(seed=TREE_SEED + 1)[1]
    assert one.phase_rad != other.phase_rad
    other = dataclasses.replace(other, natural_frequency_hz=one.natural_frequency_hz, lean_m=one.lean_m)
    x, y = (s.tip_displacement_m(times) @ s.downwind for s in (one, other))
    assert not np.allclose(x, y, atol=1e-3 * one.lean_m)
    # Another wind seed, other gusts.
    g1 = _sway(wind_seed=7)[1].gusts.factor(times)
    g2 = _sway(wind_seed=8)[1].gusts.factor(times)
    assert not np.allclose(g1, g2)


def test_gusts_have_the_turbulence_intensity_and_arrive_downwind_later():
    gusts = _sway(turbulence=0.3)[1].gusts
    times = np.arange(0.0, 3600.0, 0.5)
    g = gusts.factor(times)
    assert g.mean() == pytest.approx(1.0, abs=0.03)
    assert g.std() == pytest.approx(0.3, rel=0.15)
    assert g.max() <= gusts.factor_max(3600.0) <= gusts.factor_max()
    # A gust at the origin reaches a place 30 m downwind 30 m / 6 m/s = 5 s later.
    assert np.allclose(gusts.factor(times + 5.0, along_m=30.0), g)


def test_calm_air_and_other_props_do_not_sway():
    assert wind_gusts(None, scene_seed=1) is None
    assert wind_gusts(Wind(speed_m_s=0.0), scene_seed=1) is None
    gusts = wind_gusts(Wind(speed_m_s=5.0), scene_seed=1)
    assert prop_sway(build_prop("bench", 1), np.eye(4), gusts) is None
    assert prop_sway(build_prop("tree", 1), np.eye(4), None) is None


# ---- Rendered (OpenGL) ----------------------------------------------------------------------------------

W, H = 160, 120
F_PX = 130.0
TREE_AT_M = (12.0, 0.0)


def _tree_scene(wind: dict | None, props: bool = True):
    from tests.render.conftest import scene_from

    environment = {
        "sky_luminance_cd_m2": 3000.0,
        "meshes": [{"type": "plane", "name": "ground", "size_m": [80, 80], "material": {"color_rgb": [0.3, 0.3, 0.3]}}],
        "props": [{"type": "tree", "position_m": list(TREE_AT_M), "seed": TREE_SEED, "height_m": TREE_HEIGHT_M}]
        if props
        else [],
    }
    if wind is not None:
        environment["wind"] = wind
    return scene_from(
        environment=environment,
        lights=[{"type": "sun", "illuminance_lux": 50000, "azimuth_deg": 150, "elevation_deg": 35},
                {"type": "ambient", "illuminance_lux": 10000}],
    )  # fmt: skip


@pytest.fixture(scope="module")
def swaying_frames(renderer):
    """The tree in a 10 m/s wind drawn at two times, the bare ground, and the view (one shadow fit)."""
    from camgen.render.renderer import ShadowFit, View
    from camgen.render.scene_graph import build_scene_graph, instance_table
    from tests.render.conftest import camera_matrix, look_at

    scene = _tree_scene({"speed_m_s": 10.0, "direction_deg": 90.0})
    graph = build_scene_graph(scene)
    assert len(graph.swaying) == 1
    view = View(camera_matrix(F_PX, F_PX, (W - 1) / 2, (H - 1) / 2), look_at((0, 0, 3), (12, 0, 3.5)), W, H)
    shared = {
        "clip_range_m": (0.1, 100.0),
        "shadow_fit": ShadowFit(view, np.array([-40, -40, 0.0]), np.array([40, 40, 9.0])),
    }
    drawn = []
    for t in (0.0, 0.8):
        graph.place_actors(t)
        drawn.append(renderer.draw(graph, view, ("radiance", "instance_id"), **shared))
    plain = renderer.draw(build_scene_graph(_tree_scene(None, props=False)), view, ("radiance",), **shared).radiance
    ids = {i.name: i.instance_id for i in instance_table(scene)}
    return drawn, plain, ids


@pytest.mark.opengl
def test_the_crown_and_its_shadow_move_the_foot_sky_and_far_ground_do_not(swaying_frames):
    import cv2

    (a, b), plain, ids = swaying_frames
    tree = (a.instance_id == ids["tree_0"]) | (b.instance_id == ids["tree_0"])
    tolerance = 1e-4 * a.radiance.max()
    changed = np.abs(a.radiance - b.radiance).max(axis=2) > tolerance
    rows = np.flatnonzero(tree.any(axis=1))
    crown = tree.copy()
    crown[rows.max() - 25 :] = False  # the crown: all but the trunk's lower rows
    assert changed[crown].mean() > 0.5, "the crown's leaves and outline move"
    foot = tree & (np.arange(H)[:, None] >= rows.max() - 2)  # the trunk's lowest 3 rows: its foot
    assert foot.sum() >= 3
    assert np.array_equal(a.instance_id[foot], b.instance_id[foot])
    assert np.allclose(a.radiance[foot], b.radiance[foot], rtol=0.01)
    sky = (a.instance_id == 0) & (b.instance_id == 0)
    assert sky.sum() > 1000 and not changed[sky].any()
    ground = (a.instance_id == ids["ground"]) & (b.instance_id == ids["ground"])
    # penumbra too: a leaf's faint fleck darkens the ground by less than 0.1 %, but by more than what counts as a change
    shade = np.minimum(a.radiance[..., 1], b.radiance[..., 1]) < plain[..., 1] - tolerance
    # The shadow follows the crown: ground that changed lies in the tree's shadow at one of the times.
    moved_shadow = changed & ground
    assert moved_shadow.sum() >= 10
    assert shade[moved_shadow].all()
    # Everything that changed is the tree (its outline grown by a pixel) or its shadow.
    near_tree = cv2.dilate(tree.astype(np.uint8), np.ones((3, 3), np.uint8)).astype(bool)
    assert not (changed & ~near_tree & ~(ground & shade)).any()
    assert not changed[ground & ~shade].any()


@pytest.mark.opengl
def test_calm_air_draws_what_no_wind_draws(renderer):
    """`wind` left out and a wind of 0 m/s build the same graph (nothing sways, nothing moves into the
    actors' draws) and draw the same pixels, bit for bit."""
    from camgen.render.renderer import View
    from camgen.render.scene_graph import build_scene_graph
    from tests.render.conftest import camera_matrix, look_at

    view = View(camera_matrix(F_PX, F_PX, (W - 1) / 2, (H - 1) / 2), look_at((0, 0, 3), (12, 0, 3.5)), W, H)
    drawn = []
    for wind in (None, {"speed_m_s": 0.0, "direction_deg": 45.0}):
        graph = build_scene_graph(_tree_scene(wind))
        assert graph.swaying == []
        assert graph.moving_nodes is graph.actor_nodes and graph.still_nodes is graph.environment_nodes
        graph.place_actors(1.0)
        drawn.append(renderer.draw(graph, view, ("radiance", "depth_m", "instance_id")))
    for name in ("radiance", "depth_m", "instance_id"):
        assert np.array_equal(getattr(drawn[0], name), getattr(drawn[1], name)), name


PROFILE = """\
sensor: {width_px: 160, height_px: 120, pixel_pitch_um: 12.0, full_well_e: 10000, conversion_gain_dn_per_e: 0.4}
lens: {focal_length_mm: 4.0, f_number: 2.0}
exposure: {mode: manual, exposure_time_s: 0.033}
"""
SEQUENCE = """\
duration_s: 2
fps: 10
environment:
  shadows: {shadows}
  sky_luminance_cd_m2: 3000
  meshes:
    - {{type: plane, name: ground, size_m: [60, 60], material: {{color_rgb: [0.3, 0.3, 0.3]}}}}
  props:
    - {{type: tree, position_m: [3, 16], height_m: 5, seed: 2}}
  wind: {{speed_m_s: 15, direction_deg: 0}}
lights:
  - {{type: sun, illuminance_lux: 50000, azimuth_deg: 235, elevation_deg: 30}}
  - {{type: ambient, illuminance_lux: 3000}}
actors:
  - {{name: standing, class: person, path: {{waypoints_m: [[1.5, 17]]}}}}
outputs: {{annotations: []}}
cameras:
  - {{name: cam, profile: fixed, mount: {{position_m: [0, -4, 4], yaw_deg: 90, pitch_deg: -5}}}}
"""


def _job(tmp_path, shadows: bool, wind: bool = True):
    from camgen.config import load_scene
    from camgen.plan import PlanSettings, compile_scene
    from tests.conftest import write

    write(tmp_path, "profiles/fixed.yaml", PROFILE)
    text = SEQUENCE.format(shadows=str(shadows).lower())
    if not wind:
        text = text.replace("  wind: {speed_m_s: 15, direction_deg: 0}\n", "")
    return compile_scene(load_scene(write(tmp_path, "scenes/s.yaml", text)), PlanSettings(supersampling=1))


@pytest.mark.opengl
def test_a_swaying_tree_is_blurred_and_its_moving_region_composites_exactly(renderer, tmp_path):
    """The plan blurs the swaying tree (no actor moves); the frame composited from the moving regions
    equals every sub-frame drawn whole, and the regions hold the tree and its shadow, not the frame."""
    from camgen.render.scene_graph import build_scene_graph
    from camgen.render.sequence import CameraRenderer, render_view, sub_frame_offsets

    calm = _job(tmp_path / "calm", shadows=True, wind=False).cameras[0]
    assert not any(stage.name == "optics.motion_blur" for stage in calm.stages)
    job = _job(tmp_path / "windy", shadows=True)
    camera = job.cameras[0]
    assert any(stage.name == "optics.motion_blur" for stage in camera.stages)
    assert any(d.stage == "render.wind" and d.included for d in camera.decisions)
    graph = build_scene_graph(job.scene)
    composited = CameraRenderer(renderer, graph, camera)
    state = camera.states[5]
    samples = composited.motion_samples(state)
    assert samples >= 2  # the crown's measured path over the exposure (`_blurred_groups`)
    view = render_view(state, camera.render)
    rects = composited.moving_rects_px(state, view, list(sub_frame_offsets(samples)), composited.shadow_fit(view))
    assert rects, "the swaying tree is a moving region"
    assert sum((x1 - x0) * (y1 - y0) for x0, y0, x1, y1 in rects) < 0.6 * view.width_px * view.height_px
    fast = composited.frame(5).passes.radiance
    reference = CameraRenderer(renderer, graph, camera, moving_regions=False).frame(5).passes.radiance
    # The standing person shifts its weight by less than the blur threshold during the exposure: the
    # composite draws it sharp at the frame time, the reference blurs every sub-frame; compare elsewhere.
    tree, person = (graph.moving_nodes.index(n) for n in (graph.swaying[0].node, graph.actor_nodes[0]))
    assert {k for ks in composited._blurred_groups(state, view).values() for k in ks} == {tree}
    outside = np.ones((view.height_px, view.width_px), bool)
    fit = composited.shadow_fit(view)
    for x0, y0, x1, y1 in composited.moving_rects_px(state, view, [-0.5, 0.0, 0.5], fit, only={person}):
        outside[y0:y1, x0:x1] = False
    assert outside.mean() > 0.8
    assert np.abs(fast - reference)[outside].max() <= 1e-5 * reference.max()


@pytest.mark.opengl
def test_a_kept_static_background_leaves_the_swaying_tree_out(renderer, tmp_path):
    """Without shadows the plan keeps the environment's draw; the tree is drawn over it each frame, so each
    frame equals the whole scene drawn at its time, and two frames differ in the crown."""
    from camgen.render.scene_graph import build_scene_graph
    from camgen.render.sequence import CameraRenderer, render_view

    job = _job(tmp_path, shadows=False)
    camera = job.cameras[0].model_copy(
        update={"stages": tuple(s for s in job.cameras[0].stages if s.name != "optics.motion_blur")}
    )
    assert camera.render.static_background
    (decision,) = [d for d in camera.decisions if d.stage == "render.static_background"]
    assert "swaying in the wind are drawn with the actors" in decision.reason
    graph = build_scene_graph(job.scene)
    drawer = CameraRenderer(renderer, graph, camera)
    frames = []
    for index in (3, 8):
        frames.append(drawer.frame(index).passes.radiance)
        view = render_view(camera.states[index], camera.render)
        graph.place_actors(camera.states[index].time_s)
        whole = renderer.draw(graph, view, ("radiance",), clip_range_m=drawer.clip_range_m(view)).radiance
        assert np.abs(frames[-1] - whole).max() <= 1e-5 * whole.max()
    assert (np.abs(frames[0] - frames[1]).max(axis=2) > 1e-3 * frames[0].max()).sum() > 50


@pytest.mark.opengl
def test_optical_flow_carries_the_sway(renderer, tmp_path):
    """The scene flow of a swaying tree's trunk is its bend between the two frames, (z/H)²·ΔD and its drop
    (the trunk drawn with rings every 0.5 m, so it curves rather than tilting straight); the crown moves,
    the ground and the sky do not."""
    from camgen.annotate.flow import surface_points_m
    from camgen.plan.flow import FlowField
    from camgen.plan.lens_stages import LensStages
    from camgen.render.renderer import View
    from camgen.render.scene_graph import build_scene_graph, instance_table
    from camgen.render.sequence import CameraRenderer

    job = _job(tmp_path, shadows=False)
    camera = job.cameras[0]
    graph = build_scene_graph(job.scene)
    state, later = camera.states[4], camera.states[5]
    view = View(np.array(state.K_px), np.array(state.T_world_from_cam), camera.width_px, camera.height_px)
    graph.place_actors(state.time_s)
    passes = renderer.draw(graph, view, ("depth_m", "instance_id"))
    field = FlowField(CameraRenderer(renderer, graph, camera), LensStages(camera))
    displacement = field.displacement_m(state, later.time_s, passes)
    ids = {i.name: i.instance_id for i in instance_table(job.scene)}
    tree = passes.instance_id == ids["tree_0"]
    assert np.linalg.norm(displacement[tree], axis=1).max() > 0.01
    assert np.all(displacement[passes.instance_id == ids["ground"]] == 0.0)
    assert np.isnan(displacement[passes.instance_id == 0]).all()
    (prop,) = graph.swaying
    sway = prop.sway
    D0, D1 = sway.tip_displacement_m(state.time_s), sway.tip_displacement_m(later.time_s)
    R = graph.scene.get_pose(prop.node)[:3, :3]
    rows, cols = np.nonzero(tree)
    rays = field.rays(state)[rows, cols]
    world = surface_points_m(rays, passes.depth_m[tree], np.array(state.T_world_from_cam))
    foot = np.array([3.0, 16.0])
    trunk = (world[:, 2] < 0.8 * trunk_crown_base(job)) & (np.linalg.norm(world[:, :2] - foot, axis=1) < 0.3)
    assert trunk.sum() >= 5
    s = world[trunk, 2] / sway.height_m
    bend = (s**2)[:, None] * (D1 - D0)
    bend[:, 2] -= (2.0 / 3.0) * (D1 @ D1 - D0 @ D0) * s**3 / sway.height_m
    expected = bend @ R.T
    scale = float(np.linalg.norm(D1 - D0))
    error = np.linalg.norm(displacement[tree][trunk] - expected, axis=1) / scale
    # Rings every 0.5 m: a chord of (z/H)² strays by (0.5 m)²/(4H²) = 0.25 % of ΔD at most; the foot's pixels
    # may take the bottom cap's (fixed) triangle.
    assert np.median(error) < 0.003 and error.max() < 0.015
    assert np.linalg.norm(expected, axis=1).max() > 0.04 * scale  # up the trunk, it moves
    straight = (s / s.max())[:, None] * expected[np.argmax(s)]  # a trunk tilting straight from its foot
    assert np.median(np.linalg.norm(displacement[tree][trunk] - straight, axis=1) / scale) > 3 * np.median(error)


def trunk_crown_base(job) -> float:
    from camgen.props import placed_props

    return placed_props(job.scene.environment, scene_seed=job.scene.seed)[0].model.dims["crown_base_m"]
