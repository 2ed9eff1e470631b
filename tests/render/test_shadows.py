"""Sun shadows land where the geometry of the sun puts them, at a resolution set by what the view
sees, not by how big the scene is."""

from __future__ import annotations

import math

import numpy as np
import pytest

from camgen.render.renderer import View, directional_shadow_matrices, frustum_corners_m
from tests.render.conftest import camera_matrix, look_at, scene_from

pytestmark = pytest.mark.opengl

CM_PER_PX = 1.0


def _shadow_scene(ground_m: float, elevation_deg: float):
    from camgen.render.scene_graph import build_scene_graph

    return build_scene_graph(
        scene_from(
            environment={
                "meshes": [
                    {"type": "plane", "name": "ground", "size_m": [ground_m, ground_m]},
                    {"type": "box", "name": "pole", "size_m": [0.1, 0.1, 3.0], "position_m": [0, 0, 1.5]},
                ]
            },
            lights=[
                {"type": "sun", "illuminance_lux": 50000, "azimuth_deg": 0.0, "elevation_deg": elevation_deg},
                {"type": "ambient", "illuminance_lux": 5000},
            ],
        )
    )


def _overhead(centre_x_m: float) -> View:
    """Straight down from 20 m onto (centre_x_m, 0), 1 cm per pixel at the ground, image x along world x."""
    f_px = 20.0 * 100 / CM_PER_PX
    T = look_at((centre_x_m, 0.0, 20.0), (centre_x_m, 0.0, 0.0))
    return View(camera_matrix(f_px, f_px, 199.5, 99.5), T, 400, 200)


@pytest.mark.parametrize("ground_m", [20.0, 400.0])
def test_a_pole_casts_its_shadow_where_the_sun_puts_it(renderer, ground_m):
    """A 3 m pole, 10 cm square, under a sun 40° high in the +x direction: its shadow runs along −x to
    the shadow of the top's far edge, 0.05 + 3 / tan 40° = 3.63 m from the axis, 10 cm wide. On a
    400 m ground, pyrender's own shadow box (a square twice the scene's diagonal over 2048 texels:
    55 cm each) would blur the pole away; fitted to the view, the shadow's tip and width come out
    within 2 and 3 cm on either ground."""
    elevation = 40.0
    graph = _shadow_scene(ground_m, elevation)
    length_m = 3.0 / math.tan(math.radians(elevation))
    view = _overhead(-length_m)  # the tip at the image centre
    radiance = renderer.draw(graph, view, ("radiance",)).radiance
    luminance = radiance @ np.array([0.2126, 0.7152, 0.0722])
    lit = np.median(luminance)
    shaded = luminance < 0.5 * lit
    row = shaded[100]  # the image row through the pole's axis (world y = 0)
    columns = np.flatnonzero(row)
    # World x of a column: image x runs along world x; the image centre is at −length.
    tip_x_m = -length_m + (columns.min() - 199.5) * CM_PER_PX / 100
    assert tip_x_m == pytest.approx(-(0.05 + length_m), abs=0.02)
    width_m = np.count_nonzero(shaded[:, 250]) * CM_PER_PX / 100  # across the shadow, 0.5 m from its tip
    assert width_m == pytest.approx(0.1, abs=0.03)


def test_the_shadow_box_holds_the_view_and_the_whole_scene_depth():
    rng = np.random.default_rng(3)
    scene = np.array([[x, y, z] for x in (-50, 50) for y in (-40, 40) for z in (0, 12)], float)
    view = View(camera_matrix(1000, 1000, 639.5, 359.5), look_at((10, -5, 4), (12, 10, 0)), 1280, 720)
    focus = frustum_corners_m(view, 0.05, 30.0)
    towards_sun = np.array([0.3, -0.5, 0.8])
    z = towards_sun / np.linalg.norm(towards_sun)
    x = np.cross([0.0, 1.0, 0.0], z)
    x /= np.linalg.norm(x)
    R = np.column_stack([x, np.cross(z, x), z])
    V, P = directional_shadow_matrices(R, scene, focus)
    # Points the view sees inside the scene project inside the map, at depths within it.
    inside = focus[np.all((focus >= scene.min(axis=0)) & (focus <= scene.max(axis=0)), axis=1)]
    samples = np.concatenate([inside, rng.uniform(scene.min(axis=0), scene.max(axis=0), (200, 3))])
    seen = samples[[np.all(np.abs((P @ V @ np.append(p, 1.0))[:2]) <= 1) for p in samples]]
    ndc = np.array([P @ V @ np.append(p, 1.0) for p in np.concatenate([inside, scene])])
    assert np.all(np.abs(ndc[: len(inside), :2]) <= 1.0)
    assert np.all(np.abs(ndc[:, 2]) <= 1.0)  # every caster of the scene is within the depth range
    assert len(seen) < len(samples)  # and the map does not cover the whole scene: it is fitted


def test_a_straight_shadow_edge_stays_straight_and_sharp_near_the_camera(renderer):
    """A wide camera 1.6 m up over a 400 m ground: one sun map over all it sees to the horizon had texels of
    tens of centimetres, while the ground 3 m ahead is under a centimetre a pixel. A long wall at 30° to the
    map's axes casts a straight shadow edge there, across the sun's cascades (texels 1-3 cm near the
    camera). The edge's row changes smoothly from column to column (RMS second difference 0.093 px, at most
    0.36 px: no step where one cascade hands over to the next; the one map's 4-texel filter gave 0.024 px
    over its blur, pyrender's one lookup 0.265 px) and, on the near ground, rises from 10 % to 90 % within
    3-4 rows (about 4 cm, the sun's own penumbra 3.5 m behind the wall's top is 3.3 cm); the one map blurred
    it over 21-23 rows."""
    from camgen.render.scene_graph import build_scene_graph

    graph = build_scene_graph(
        scene_from(
            environment={
                "meshes": [
                    {"type": "plane", "name": "ground", "size_m": [400.0, 400.0]},
                    {
                        "type": "box",
                        "name": "wall",
                        "size_m": [40.0, 0.2, 2.0],
                        "position_m": [0, 6.0, 1.0],
                        "rotation_deg": [0, 0, 30],
                    },
                ]
            },
            lights=[
                {"type": "sun", "illuminance_lux": 50000, "azimuth_deg": 90.0, "elevation_deg": 35.0},
                {"type": "ambient", "illuminance_lux": 5000},
            ],
        )
    )
    view = View(camera_matrix(300.0, 300.0, 319.5, 239.5), look_at((0.0, 0.0, 1.6), (0.0, 3.0, 0.0)), 640, 480)
    radiance = renderer.draw(graph, view, ("radiance",)).radiance
    luminance = radiance @ np.array([0.2126, 0.7152, 0.0722])
    lit, shaded = np.percentile(luminance, 95), np.percentile(luminance, 5)
    level = (lit + shaded) / 2
    crossings = []  # the edge runs across the image: a shadow-to-lit crossing down each column
    for column in range(640):
        values = luminance[:, column]
        down = np.flatnonzero((values[:-1] < level) & (values[1:] >= level))
        if len(down):  # the lowest one: the ground's shadow edge (the wall's lit top is a crossing above it)
            v = down[-1]
            crossings.append((column, v + (level - values[v]) / (values[v + 1] - values[v])))
    columns, rows = np.array(crossings).T
    assert len(columns) > 600
    # Roughness: the edge's row from one column to the next changes smoothly; a staircase jumps.
    second = np.diff(rows, 2)
    roughness_px = np.sqrt(np.mean(second**2))
    print(f"straight edge: {len(columns)} columns, roughness {roughness_px:.3f} px, worst {np.abs(second).max():.2f}")
    assert roughness_px < 0.15
    assert np.abs(second).max() < 0.6
    for column in (0, 40, 80):  # the near ground: from 10 % to 90 % of the step within a few rows
        row = int(np.rint(rows[columns == column][0]))
        values = luminance[row - 40 : row + 41, column]
        values = (values - values.min()) / (values.max() - values.min())
        assert np.flatnonzero(values > 0.9).min() - np.flatnonzero(values < 0.1).max() <= 6


def test_sun_cascades_split_the_view_and_keep_their_texels_as_the_camera_pans():
    """Three maps over slices of the view's depth (Zhang et al.'s practical splits), finest first: each holds
    the part of the scene its slice sees, and their texels grow with the slice's distance. Panning the camera
    by a degree keeps each map's texel and moves its rectangle by whole texels (a stable fit: the shadows'
    edges do not crawl); the shader holds as many maps as the renderer fits."""
    from camgen.render.renderer import SHADER_DIR, SUN_CASCADES, cascade_splits_m, sun_cascade_matrices

    shader = (SHADER_DIR / "linear_mesh.frag").read_text()
    assert f"const int SUN_EXTRA_CASCADES = {SUN_CASCADES - 1};" in shader
    low, high = np.array([-150.0, -150.0, 0.0]), np.array([150.0, 150.0, 12.0])
    towards_sun = np.array([0.3, -0.5, 0.8])
    z = towards_sun / np.linalg.norm(towards_sun)
    x = np.cross([0.0, 1.0, 0.0], z)
    x /= np.linalg.norm(x)
    R = np.column_stack([x, np.cross(z, x), z])

    def view_panned(pan_deg: float) -> View:
        a = math.radians(pan_deg)
        return View(
            camera_matrix(1000, 1000, 639.5, 359.5),
            look_at((0.0, 0.0, 6.0), (20 * math.sin(a), 20 * math.cos(a), 0.0)),
            1280,
            720,
        )

    view = view_panned(0.0)
    cascades = sun_cascade_matrices(R, (low, high), view, 0.05, 400.0, 2048)
    assert len(cascades) == SUN_CASCADES
    texels_m = [2.0 / (P[0, 0] * 2048) for _, P in cascades]
    assert texels_m == sorted(texels_m) and texels_m[-1] > 3 * texels_m[0]
    splits = cascade_splits_m(1.0, 100.0, 3)
    log, uniform = 100.0 ** (np.arange(4) / 3), 1.0 + 33.0 * np.arange(4)  # between 1 m and 100 m
    assert splits == pytest.approx(0.75 * log + 0.25 * uniform)
    # Ground points the view sees: each lies inside one of the maps, and those nearer than 15 m (the first
    # split lies beyond 16 m for any far end past 100 m) inside the finest.
    rng = np.random.default_rng(5)
    pixels = rng.uniform([0, 380], [1280, 720], (300, 2))
    rays = (np.linalg.inv(view.K_px) @ np.column_stack([pixels, np.ones(300)]).T).T
    rays_world = rays @ view.T_world_from_cam[:3, :3].T
    t = -view.T_world_from_cam[2, 3] / rays_world[:, 2]
    ground = view.T_world_from_cam[:3, 3] + rays_world * t[:, None]
    near = rays[:, 2] * t < 15.0
    assert 10 < near.sum() < 290
    inside = []
    for V, P in cascades:
        ndc = np.c_[ground, np.ones(len(ground))] @ (P @ V).T
        inside.append(np.all(np.abs(ndc[:, :2]) < 1.0, axis=1))
    assert np.all(np.any(inside, axis=0))
    assert np.all(inside[0][near])
    panned = sun_cascade_matrices(R, (low, high), view_panned(1.0), 0.05, 400.0, 2048)
    for (_, P), (_, Q) in zip(cascades, panned, strict=True):
        assert Q[0, 0] == P[0, 0] and Q[1, 1] == P[1, 1]
        shift_texels = (P[:2, 3] - Q[:2, 3]) * 2048 / 2  # NDC spans 2 over 2048 texels
        assert np.abs(shift_texels).max() > 0.5  # the view moved the maps
        assert shift_texels == pytest.approx(np.round(shift_texels), abs=1e-6)


@pytest.mark.parametrize("azimuth_deg", [45.0, 135.0, 300.0])
def test_open_sunlit_ground_does_not_shadow_itself(renderer, azimuth_deg):
    """Flat ground with nothing on it, under a high sun, seen from 1.6 m where the sun's map is fitted to a
    small view: every pixel gets the light it gets with shadows off. The PCF lookup compares texels up to
    2√2 texels away, deeper into the ground's depth slope than the bias covered at 1.5 texels: stripes
    down to 0.92 of the light here (0.37 with pyrender's lookup, at azimuth 300°)."""
    from camgen.render.scene_graph import build_scene_graph

    view = View(camera_matrix(150.0, 150.0, 79.5, 59.5), look_at((0.0, 0.0, 1.6), (0.0, 4.6, 0.0)), 160, 120)
    green = {}
    for shadows in (True, False):
        graph = build_scene_graph(
            scene_from(
                environment={
                    "shadows": shadows,
                    "meshes": [{"type": "plane", "name": "ground", "size_m": [400.0, 400.0]}],
                },
                lights=[{"type": "sun", "illuminance_lux": 50000, "azimuth_deg": azimuth_deg, "elevation_deg": 75.0}],
            )
        )
        green[shadows] = renderer.draw(graph, view, ("radiance",)).radiance[..., 1]
    ground = green[False] > 0
    assert ground.mean() > 0.5
    ratio = green[True][ground] / green[False][ground]
    assert ratio.min() > 0.999, f"darkest ground pixel at {ratio.min():.4f} of its light"


def test_sun_cascades_split_what_a_camera_above_every_caster_sees():
    """A camera 20 m straight above ground whose casters reach 3 m sees nothing nearer than 17 m: the split
    depths run over the seen part's depths, so every cascade covers part of it, each with texels no coarser
    than one map over all of it. Splitting from 1 m left the two nearer slices empty, fitted to the frustum's
    corners high above the ground (texels 1.1 cm against 0.15-0.3 cm), and the shader, taking the first map
    that holds a point, read the ground from those."""
    from camgen.render.renderer import seen_part_of_box_m, sun_cascade_matrices

    low, high = np.array([-10.0, -10.0, 0.0]), np.array([10.0, 10.0, 3.0])
    view = _overhead(-3.58)
    z = np.array([math.cos(math.radians(40.0)), 0.0, math.sin(math.radians(40.0))])  # towards the sun
    x = np.cross([0.0, 1.0, 0.0], z)
    R = np.column_stack([x / np.linalg.norm(x), [0.0, 1.0, 0.0], z])
    seen = seen_part_of_box_m(view, 0.05, 40.0, low, high)
    corners = np.array([[a, b, c] for a in (low[0], high[0]) for b in (low[1], high[1]) for c in (low[2], high[2])])
    _, P_one = directional_shadow_matrices(R, corners, seen)
    one_texel_m = 2.0 / (min(P_one[0, 0], P_one[1, 1]) * 2048)
    for V, P in sun_cascade_matrices(R, (low, high), view, 0.05, 40.0, 2048):
        assert 2.0 / (min(P[0, 0], P[1, 1]) * 2048) <= one_texel_m * 2 ** (1 / 8)  # the texel ladder's step
        ndc = np.c_[seen, np.ones(len(seen))] @ (P @ V).T
        assert np.any(np.all(np.abs(ndc[:, :2]) <= 1.0, axis=1))  # it holds some of what the view sees


def test_a_draw_takes_the_cascades_fitted_to_its_own_view_box_and_map_size(renderer):
    """The renderer keeps the cascades it fitted lately (`_PassRenderer._cascade_matrices`): draws through two
    views, two shadow boxes and two sizes, taking turns, each shade with `sun_cascade_matrices` of its own view,
    box, clip range and map size, bit for bit, whether fitted afresh or kept."""
    from camgen.render.renderer import ShadowFit, shadow_map_size_texels, sun_cascade_matrices

    graph = _shadow_scene(40.0, 40.0)
    sun = next(node for node in graph.scene.light_nodes if type(node.light).__name__ == "DirectionalLight")
    views = [
        View(camera_matrix(300.0, 300.0, 159.5, 99.5), look_at((-6.0, -8.0, 5.0), (0.0, 0.0, 0.0)), 320, 200),
        View(camera_matrix(300.0, 300.0, 159.5, 99.5), look_at((6.0, -8.0, 5.0), (0.0, 1.0, 0.0)), 320, 200),
        View(camera_matrix(700.0, 700.0, 639.5, 399.5), look_at((6.0, -8.0, 5.0), (0.0, 1.0, 0.0)), 1280, 800),
    ]
    boxes = [
        (np.array([-20.0, -20.0, 0.0]), np.array([20.0, 20.0, 3.0])),
        (np.array([-5.0, -5.0, 0.0]), np.array([5.0, 5.0, 3.0])),
    ]
    clip_m = (0.1, 60.0)
    draws = [(0, 0), (1, 0), (0, 1), (0, 0), (2, 0), (1, 0), (2, 0)]
    fitted = []
    for v, b in draws:
        fit = ShadowFit(views[v], *boxes[b])
        renderer.draw(graph, views[v], ("radiance",), shadow_fit=fit, clip_range_m=clip_m)
        size = renderer._renderer.shadow_map_texels
        assert size == shadow_map_size_texels(views[v])
        expected = sun_cascade_matrices(graph.scene.get_pose(sun)[:3, :3], boxes[b], views[v], *clip_m, size)
        drawn = renderer._renderer._sun_cascades[id(sun)]
        for (V, P), (V_expected, P_expected) in zip(drawn, expected, strict=True):
            assert np.array_equal(V, V_expected) and np.array_equal(P, P_expected)
        fitted.append(drawn)
    assert fitted[3] is fitted[0] and fitted[5] is fitted[1]  # kept, not fitted again
    assert len({id(cascades) for cascades in fitted}) == 4
