"""The still frame's blur test (`CameraRenderer._blurred_groups`) at a fraction of its cost, deciding as before:
the bound on a node's image path (`_path_bound_px`) is never below the path measured vertex by vertex, a node
whose look version holds (`SceneGraph.look_versions`) looks the same, and the groups equal those of projecting
every vertex and shadow of every moving node at the exposure's start, middle and end."""

from __future__ import annotations

import math

import numpy as np
import pytest

from camgen.optics.motion_blur import sub_frame_count
from camgen.render.renderer import NEAR_CLIP_M, View
from camgen.render.scene_graph import _look_along
from camgen.render.sequence import _near_view, _node_pixels, _path_bound_px
from tests.conftest import write
from tests.render.conftest import camera_matrix, look_at, scene_from
from tests.render.test_moving_regions import SMALL_PROFILE


class _Light:
    """A light node as `_node_pixels` and `_path_bound_px` read it (its pose is given beside it)."""

    def __init__(self, kind: str):
        from pyrender.light import DirectionalLight, SpotLight

        self.light = DirectionalLight() if kind == "sun" else SpotLight()


def _measured_path_px(vertices_m, view, casting, poses, lowest_z_m) -> float | None:
    """The longest path of `_blurred_groups` over the counted points, vertex by vertex; None when none counts."""
    (uv0, f0), (uv1, f1), (uv2, f2) = (_node_pixels(v, view, casting, poses, lowest_z_m) for v in vertices_m)
    seen = f0 & f1 & f2 & _near_view(uv1, view)
    if not seen.any():
        return None
    return float((np.hypot(*(uv1 - uv0)[:, seen]) + np.hypot(*(uv2 - uv1)[:, seen])).max())


def _random_case(rng):
    """A random view, a node's vertices at three times (moved rigidly and deformed) and a sun."""
    w, h = int(rng.integers(64, 2000)), int(rng.integers(64, 1200))
    f = float(rng.uniform(0.3, 20.0)) * w
    K = camera_matrix(f, f * rng.uniform(0.9, 1.1), rng.uniform(0, w), rng.uniform(0, h))
    K[0, 1] = rng.normal(0.0, 0.01 * f)
    target = rng.normal(0.0, 5.0, 3)
    T = look_at(target + rng.normal(0.0, 15.0, 3) + [0.0, 0.0, 4.0], target)
    if rng.random() < 0.5:  # a cloud: some points behind the camera, some far out
        middle = target + rng.normal(0.0, rng.uniform(0.1, 8.0), (200, 3))
    else:  # a few points anywhere in the counted box (−W, 2W) × (−H, 2H), near or far: the bound's worst cases
        uv = rng.uniform([-w, -h], [2 * w, 2 * h], (3, 2))
        rays = np.column_stack([uv, np.ones(3)]) @ np.linalg.inv(K).T
        middle = T[:3, 3] + (rays * rng.uniform(0.2, 30.0, (3, 1))) @ T[:3, :3].T
    speed = 10.0 ** rng.uniform(-5, 0)  # m per half exposure, from a crawl to a racing car's long exposure

    def moved(sign):
        R = _rotation(sign * speed * rng.normal(0.0, 1.0, 3) / 2.0)
        shift = sign * speed * rng.normal(0.0, 1.0, 3)
        return (middle - target) @ R.T + target + shift + rng.normal(0.0, speed / 4, middle.shape)

    d = rng.normal(0.0, 1.0, 3)
    d[2] = -abs(d[2]) - 0.02
    d /= np.linalg.norm(d)
    sun = _look_along(d)
    return View(K, T, w, h), [moved(-1), middle, moved(1)], sun, float(rng.uniform(-1.0, 0.5))


def _rotation(axis_angle: np.ndarray) -> np.ndarray:
    angle = float(np.linalg.norm(axis_angle))
    x, y, z = axis_angle / angle
    C = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    return np.eye(3) + math.sin(angle) * C + (1.0 - math.cos(angle)) * C @ C


def test_the_bound_is_never_below_the_measured_path():
    rng = np.random.default_rng(21)
    counted, under = 0, 0
    for _ in range(400):
        view, vertices, sun, lowest_z_m = _random_case(rng)
        for casting, poses in (([], []), ([_Light("sun")], [sun])):
            measured = _measured_path_px(vertices, view, casting, poses, lowest_z_m)
            bound = _path_bound_px(vertices, view, casting, poses, lowest_z_m)
            if measured is None:
                continue
            counted += 1
            assert measured <= bound, (measured, bound)
            under += bound <= 0.5
    assert counted > 600 and under > 50  # both sides of a threshold of 0.5 px are tried


def test_the_bound_is_near_the_path_of_a_small_mover_in_the_middle_of_the_view():
    """A 40 cm object 10 m ahead moving 1 mm across the view (a walker over a short exposure): the bound is
    within a few times the measured path, so it settles most such nodes without projecting them."""
    w, h, f = 1408, 812, 1100.0
    view = View(camera_matrix(f, f, (w - 1) / 2, (h - 1) / 2), look_at((0, -10, 1), (0, 0, 1)), w, h)
    rng = np.random.default_rng(3)
    middle = np.array([0.0, 0.0, 1.0]) + rng.uniform(-0.2, 0.2, (500, 3))
    step = np.array([1e-3, 0.0, 0.0])
    vertices = [middle - step, middle, middle + step]
    sun = _look_along(np.array([0.3, 0.8, -0.6]) / np.linalg.norm([0.3, 0.8, -0.6]))
    for casting, poses in (([], []), ([_Light("sun")], [sun])):
        measured = _measured_path_px(vertices, view, casting, poses, 0.0)
        bound = _path_bound_px(vertices, view, casting, poses, 0.0)
        assert measured <= bound <= 4.0 * measured


def test_a_spot_light_or_points_at_infinity_give_no_bound():
    w, h = 320, 240
    view = View(camera_matrix(300.0, 300.0, 160.0, 120.0), look_at((0, -10, 1), (0, 0, 1)), w, h)
    vertices = [np.zeros((4, 3)), np.zeros((4, 3)), np.zeros((4, 3))]
    spot = _look_along(np.array([0.0, 0.0, -1.0]), np.array([0.0, 0.0, 5.0]))
    assert _path_bound_px(vertices, view, [_Light("spot")], [spot], 0.0) == math.inf
    vertices[2] = np.full((4, 3), np.nan)
    assert _path_bound_px(vertices, view, [], [], 0.0) == math.inf
    assert _path_bound_px([np.zeros((0, 3))] * 3, view, [], [], 0.0) == 0.0


MIXED_ACTORS = [
    {"name": "walker", "class": "person", "path": {"waypoints_m": [[-4, 6], [4, 6]], "speed_m_s": 1.4}},
    {"name": "car", "class": "car", "path": {"waypoints_m": [[-20, 10], [20, 10]], "speed_m_s": 8.0}},
    {"name": "parked", "class": "car", "vehicle": {"seed": 3}, "path": {"waypoints_m": [[5, 14]], "heading_deg": 0}},
    {"name": "bicycle", "class": "bicycle", "path": {"waypoints_m": [[-15, 8], [15, 8]], "speed_m_s": 4.0}},
    {"name": "cyclist", "class": "person", "rides": "bicycle"},
    {
        "name": "crate",
        "class": "car",
        "shape": {"type": "box", "name": "crate", "size_m": [1, 1, 1], "position_m": [0, 0, 0.5]},
        "path": {"waypoints_m": [[-3, 12], [3, 12]], "speed_m_s": 2.0, "motion": "linear"},
    },
]


def test_a_node_whose_look_version_holds_looks_the_same():
    """Placed at times in any order (again at one, back to an earlier one), every moving node (people, a car, a
    parked car, a bicycle and its rider, a moving shape, a tree in the wind) whose version did not rise draws
    the same pose, vertices, normals and lamps; the parked car's never rises (the blur test skips it)."""
    from camgen.render.scene_graph import build_scene_graph
    from camgen.render.sequence import _actor_look, _same_arrays

    scene = scene_from(
        environment={
            "meshes": [{"type": "plane", "name": "ground", "size_m": [60, 60], "material": {"color_rgb": [0.3] * 3}}],
            "props": [{"type": "tree", "position_m": [6, 18], "seed": 2, "height_m": 6}],
            "wind": {"speed_m_s": 6.0, "direction_deg": 30.0},
        },
        lights=[{"type": "sun", "illuminance_lux": 50000, "azimuth_deg": 150, "elevation_deg": 35}],
        actors=MIXED_ACTORS,
        duration_s=4.0,
    )
    graph = build_scene_graph(scene)
    assert len(graph.look_versions) == len(graph.moving_nodes) == len(MIXED_ACTORS) + 1
    parked = graph.actor_nodes.index(next(n for n in graph.actor_nodes if n.name == "actor:parked"))
    before = (list(graph.look_versions), [_actor_look(graph.scene, n) for n in graph.moving_nodes])
    rose = [False] * len(graph.moving_nodes)
    for time_s in (0.5, 0.5, 0.5001, 1.0, 0.5, 0.5, 2.0, 2.0 + 1e-9, 0.0):
        graph.place_actors(time_s)
        now = (list(graph.look_versions), [_actor_look(graph.scene, n) for n in graph.moving_nodes])
        for k in range(len(graph.moving_nodes)):
            if now[0][k] == before[0][k]:
                assert _same_arrays(now[1][k], before[1][k]), graph.moving_nodes[k].name
            else:
                rose[k] = True
        before = now
    assert not rose[parked]
    assert sum(rose) == len(rose) - 1  # every other node moved, and said so


SUN_SCENE = """\
duration_s: 3
fps: 10
environment:
  sky: clear
  meshes:
    - {type: plane, name: ground, size_m: [80, 80], material: {color_rgb: [0.5, 0.5, 0.5]}}
lights:
  - {type: sun, illuminance_lux: 50000, azimuth_deg: 235, elevation_deg: 25}
  - {type: ambient, illuminance_lux: 3000}
actors:
  - name: racer
    class: car
    shape: {type: box, name: body, size_m: [1.6, 0.8, 1.4], position_m: [0, 0, 0.7],
            material: {color_rgb: [0.8, 0.1, 0.1]}}
    path: {waypoints_m: [[-60, 9], [30, 9]], speed_m_s: 30, motion: linear}
  - name: stroller
    class: person
    path: {waypoints_m: [[-3, 12], [3, 12]], speed_m_s: 0.3, motion: linear}
  - name: parked
    class: car
    vehicle: {seed: 4}
    path: {waypoints_m: [[4, 14]], heading_deg: 20}
outputs: {annotations: []}
cameras:
  - {name: cam, profile: fixed, mount: {position_m: [0, -4, 4], yaw_deg: 90, pitch_deg: -15}}
"""


def _reference_groups(drawer, state, view) -> dict[int, set[int]]:
    """The blur test by brute force: every vertex of every moving node, and its shadow on the lowest surface in
    each sun, projected through K at the exposure's start, middle and end (placed in that order)."""
    graph, p = drawer.graph, drawer._motion
    scene, z_low = graph.scene, drawer._lowest_z_m
    suns = [n for n in scene.light_nodes if type(n.light).__name__ == "DirectionalLight"]
    K, T = view.K_px, view.T_world_from_cam
    pixels = []
    for offset in (-0.5, 0.0, 0.5):
        graph.place_actors(state.time_s + offset * state.exposure_time_s)
        at = []
        for node in graph.moving_nodes:
            pose = scene.get_pose(node)
            local = np.concatenate([np.asarray(part.positions, np.float64) for part in node.mesh.primitives])
            v = local @ pose[:3, :3].T + pose[:3, 3]
            points, counted = [v], [np.ones(len(v), bool)]
            for sun in suns:
                d = -scene.get_pose(sun)[:3, 2]
                points.append(v + ((v[:, 2] - z_low) / -d[2])[:, None] * d)
                counted.append(v[:, 2] >= z_low)
            camera = (np.concatenate(points) - T[:3, 3]) @ T[:3, :3]
            with np.errstate(divide="ignore", invalid="ignore"):
                uv = (camera @ K.T)[:, :2] / camera[:, 2:]
            at.append((uv, np.concatenate(counted) & (camera[:, 2] >= NEAR_CLIP_M)))
        pixels.append(at)
    groups: dict[int, set[int]] = {}
    w, h = view.width_px, view.height_px
    for k in range(len(graph.moving_nodes)):
        (uv0, c0), (uv1, c1), (uv2, c2) = (pixels[i][k] for i in range(3))
        near = (uv1[:, 0] > -w) & (uv1[:, 0] < 2 * w) & (uv1[:, 1] > -h) & (uv1[:, 1] < 2 * h)
        seen = c0 & c1 & c2 & near
        if not seen.any():
            continue
        path = np.linalg.norm(uv1[seen] - uv0[seen], axis=1) + np.linalg.norm(uv2[seen] - uv1[seen], axis=1)
        n = sub_frame_count(
            float(path.max()), step_px=p["sample_step_px"], samples_max=p["samples_max"], threshold_px=p["threshold_px"]
        )
        if n > 1:
            groups.setdefault(n, set()).add(k)
    return groups


@pytest.mark.opengl
def test_the_blur_test_decides_as_projecting_every_vertex(tmp_path, renderer, monkeypatch):
    """Frames with the racer far out of view, passing in front and gone, at exposures from 0.1 to 40 ms (the
    stroller blurs at the longest): the groups are the brute-force ones, some nodes settled by the bound alone."""
    from camgen.config import load_scene
    from camgen.plan import PlanSettings, compile_scene
    from camgen.render import sequence
    from camgen.render.scene_graph import build_scene_graph
    from camgen.render.sequence import CameraRenderer, render_view

    write(tmp_path, "profiles/fixed.yaml", SMALL_PROFILE)
    job = compile_scene(load_scene(write(tmp_path, "scenes/s.yaml", SUN_SCENE)), PlanSettings(supersampling=2))
    camera = job.cameras[0]
    drawer = CameraRenderer(renderer, build_scene_graph(job.scene), camera)
    bounds = []
    bound = sequence._path_bound_px

    def counted(*args):
        bounds.append(bound(*args))
        return bounds[-1]

    monkeypatch.setattr(sequence, "_path_bound_px", counted)
    decided = []
    for frame in (0, 3, 19, 20, 21, 29):
        for exposure_s in (1e-4, 2e-3, 0.02, 0.04):
            state = camera.states[frame].model_copy(update={"exposure_time_s": exposure_s})
            view = render_view(state, camera.render)
            groups = drawer._blurred_groups(state, view)
            assert groups == _reference_groups(drawer, state, view), (frame, exposure_s)
            decided.append(groups)
    assert any(decided) and not all(decided)
    assert min(bounds) < 0.5 < max(bounds)  # some nodes settled by the bound, others projected


@pytest.mark.opengl
@pytest.mark.parametrize("exposure_s", [2e-3, 0.04])
def test_swaying_trees_settled_without_bending_them_decide_as_projecting_every_vertex(
    tmp_path, renderer, monkeypatch, exposure_s
):
    """Two trees in a 6 m/s wind beside the racer: the groups are the brute-force ones (every vertex of every tree
    bent to the exposure's start, middle and end). At 2 ms `_sway_bound_px` settles the trees from their
    frame-time vertices alone, and they are bent once a frame; at 40 ms the nearer tree's crown blurs, so the
    bound cannot settle it, and it is bent to the exposure's ends and projected."""
    from camgen.config import load_scene
    from camgen.plan import PlanSettings, compile_scene
    from camgen.props.sway import PropSway
    from camgen.render.scene_graph import build_scene_graph
    from camgen.render.sequence import CameraRenderer, render_view

    scene = SUN_SCENE.replace(
        "lights:",
        "  props:\n"
        "    - {type: tree, position_m: [-4, 12], seed: 2, height_m: 6}\n"
        "    - {type: tree, position_m: [5, 20], seed: 3, height_m: 8}\n"
        "  wind: {speed_m_s: 6.0, direction_deg: 30.0, turbulence_intensity: 0.3}\n"
        "lights:",
    )
    write(tmp_path, "profiles/fixed.yaml", SMALL_PROFILE)
    job = compile_scene(load_scene(write(tmp_path, "scenes/s.yaml", scene)), PlanSettings(supersampling=2))
    camera = job.cameras[0]
    drawer = CameraRenderer(renderer, build_scene_graph(job.scene), camera)
    trees = set(range(len(drawer.graph.actor_nodes), len(drawer.graph.moving_nodes)))
    assert len(trees) == 2
    bends, settled, bent_to_ends = [0], [], []
    deformed, bound, bent = PropSway.deformed, CameraRenderer._sway_bound_px, CameraRenderer._bent_vertices_m

    def counted_deformed(self, *args):
        bends[0] += 1
        return deformed(self, *args)

    def counted_bound(self, k, *args):
        settled.append(bound(self, k, *args) <= self._motion["threshold_px"])
        return bound(self, k, *args)

    def counted_bent(self, k, times_s):
        bent_to_ends.append(k)
        return bent(self, k, times_s)

    monkeypatch.setattr(PropSway, "deformed", counted_deformed)
    monkeypatch.setattr(CameraRenderer, "_sway_bound_px", counted_bound)
    monkeypatch.setattr(CameraRenderer, "_bent_vertices_m", counted_bent)
    blurred = set()
    for frame in (3, 20, 21):
        state = camera.states[frame].model_copy(update={"exposure_time_s": exposure_s})
        view = render_view(state, camera.render)
        bends[0] = 0
        groups = drawer._blurred_groups(state, view)
        assert bends[0] <= len(trees) + 3 * len(bent_to_ends)  # each tree to the frame time; to the ends if unsettled
        assert groups == _reference_groups(drawer, state, view), frame
        blurred |= {k for nodes in groups.values() for k in nodes} & trees
        bent_to_ends.clear()
    if exposure_s < 0.01:
        assert all(settled) and not blurred
    else:
        assert not all(settled) and blurred
