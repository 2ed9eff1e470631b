"""Snow over a rendered frame (camgen.render.snow): each flake's streak, footprint and IR radiance from its
own position, speed and size; a seeded, depth-tested frame brighter on dark ground; Rasmussen's haze beyond
15 m unless the scene sets fog; the plan's depth pass; and a compiled 160×120 camera by day and in IR
night mode, where the near flakes are the brightest things in the frame."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.spatial import cKDTree

from camgen.config import load_scene
from camgen.plan import PlanSettings, compile_scene
from camgen.render.renderer import View
from camgen.world.snow import illuminated_flake_radiance, snow_visibility_m
from tests.conftest import FIXED_PROFILE, write
from tests.render.conftest import camera_matrix, look_at, scene_from

WIDTH, HEIGHT = 160, 120
F_PX = 150.0
ROAD = {
    "type": "plane",
    "name": "road",
    "size_m": [40, 60],
    "position_m": [0, 20, 0],
    "material": {"color_rgb": [0.08, 0.08, 0.08]},
}
WALL = {  # 0.25 m ahead, on the left half of the view: nearer than NEAR_M, so every drawn flake is behind it
    "type": "box",
    "name": "wall",
    "size_m": [2.0, 0.01, 2.0],
    "position_m": [-1.0, 0.255, 1.5],
    "material": {"color_rgb": [0.5, 0.5, 0.5]},
}
AMBIENT = [{"type": "ambient", "illuminance_lux": 5000.0}]


def _graph(environment: dict, lights: list[dict] = AMBIENT):
    from camgen.render.scene_graph import build_scene_graph

    return build_scene_graph(scene_from(environment=environment, lights=lights))


def _view() -> View:
    K = camera_matrix(F_PX, F_PX, (WIDTH - 1) / 2, (HEIGHT - 1) / 2)
    return View(K, look_at((0.0, 0.0, 1.5), (0.0, 10.0, 1.0)), WIDTH, HEIGHT)


def _state(time_s: float = 1.0, exposure_time_s: float = 1 / 50, night_mode: bool = False) -> SimpleNamespace:
    return SimpleNamespace(
        time_s=time_s,
        exposure_time_s=exposure_time_s,
        focal_length_mm=4.0,
        f_number=1.6,
        focus_distance_m=8.0,
        night_mode=night_mode,
    )


SNOW = SimpleNamespace(rate_mm_h=2.0, seed=3, kind="dry")
WIND = SimpleNamespace(speed_m_s=3.0, direction_deg=20.0)


def test_each_flake_streaks_spreads_and_glows_by_its_own_numbers(monkeypatch):
    """What `snow_layers` hands the shared streak drawing, against the formulas: the flakes are the seeded
    population's (in the camera frame, within each class's range and the frustum); each falls (u, w, −v)·T
    turned into the camera frame; its footprint σ = √((D f/z)² + (A f |1/z − 1/s|)²)/4; and in an
    illuminator of I cd and half-angle θₒ its radiance is (2/3) ω I b(θ)/(π d²), b pyrender's spot falloff."""
    import camgen.render.snow as snow_module
    from camgen.world.snow import flakes_in_box, wind_drift_m_s

    captured = {}

    def capture(positions_cam, diameters_mm, fall_cam, K, depth, **options):
        captured.update(positions=positions_cam, diameters=diameters_mm, fall=fall_cam, **options)
        return np.zeros(depth.shape, np.float32), np.zeros(depth.shape, np.float32)

    monkeypatch.setattr(snow_module, "streak_layers", capture)
    view, state = _view(), _state()
    depth = np.full((HEIGHT, WIDTH), np.inf, np.float32)
    snow_module.snow_layers(view, depth, state, SNOW, WIND, 0.0, 500.0, math.radians(30.0))
    p, d = captured["positions"], captured["diameters"]
    assert len(p) > 1000 and np.all(p[:, 2] > 0.3) and np.linalg.norm(p, axis=1).max() <= 15.0
    # Every one is a flake of the population, at its world position.
    T = view.T_world_from_cam
    world = p @ T[:3, :3].T + T[:3, 3]
    everyone = flakes_in_box(
        world.min(axis=0) - 1e-6, world.max(axis=0) + 1e-6, 1.0, 2.0, 3, "dry", wind_drift_m_s(WIND)
    )

    assert cKDTree(everyone[0]).query(world)[0].max() < 1e-9
    speeds = np.interp(d, *np.unique(np.column_stack([everyone[1], everyone[2]]), axis=0).T)
    u, w = wind_drift_m_s(WIND)
    expected_fall = np.column_stack([np.full(len(d), u), np.full(len(d), w), -speeds]) * state.exposure_time_s
    np.testing.assert_allclose(captured["fall"], expected_fall @ T[:3, :3], atol=1e-12)
    aperture_m = 4e-3 / 1.6
    sigma = np.hypot(d * 1e-3 * F_PX / p[:, 2], aperture_m * F_PX * np.abs(1 / p[:, 2] - 1 / 8.0)) / 4
    np.testing.assert_allclose(captured["spread_px"], sigma, rtol=1e-9)
    distance = np.linalg.norm(p, axis=1)
    cos_angle = p[:, 2] / distance
    outer, inner = math.cos(math.radians(30.0)), math.cos(0.8 * math.radians(30.0))
    beam = np.clip((cos_angle - outer) / (inner - outer), 0, 1) ** 2
    np.testing.assert_allclose(captured["values"], 2 / 3 * 0.9 * 500.0 * beam / (math.pi * distance**2), rtol=1e-9)
    assert np.sum(beam == 0) > 0 and np.sum(beam == 1) > 0  # flakes outside and inside the beam


@pytest.mark.opengl
def test_snowy_frame_is_seeded_brighter_on_the_dark_road_and_depth_tested(renderer):
    """The same seed and time give the same frame, another time another; flakes over the dark road raise its
    radiance (a flake's ω(L_sky + L_ground)/2 is far above a road of reflectance 0.08), never over a wall
    nearer than any flake (its pixels stay exactly as drawn: no haze within 15 m either)."""
    from camgen.render.snow import snowy_radiance

    graph = _graph({"sky_luminance_cd_m2": 1600.0, "meshes": [ROAD, WALL], "snow": {"rate_mm_h": 2.0, "seed": 3}})
    view = _view()
    drawn = renderer.draw(graph, view, ("radiance", "depth_m", "instance_id"))
    wall, road = drawn.instance_id == 2, drawn.instance_id == 1
    assert 0.3 < wall.mean() < 0.6 and road.sum() > 1000
    snowy = snowy_radiance(graph, view, drawn.radiance, drawn.depth_m, _state())
    assert np.array_equal(snowy, snowy_radiance(graph, view, drawn.radiance, drawn.depth_m, _state()))
    assert not np.array_equal(snowy, snowy_radiance(graph, view, drawn.radiance, drawn.depth_m, _state(1.04)))
    np.testing.assert_array_equal(snowy[wall], drawn.radiance[wall])
    brighter = snowy[road].mean(axis=-1) / drawn.radiance[road].mean(axis=-1)
    assert brighter.mean() > 1.05 and np.mean(brighter > 1.5) > 0.01 and brighter.min() > 0.999


@pytest.mark.opengl
def test_snow_haze_is_rasmussens_visibility_beyond_the_streaks_unless_the_scene_sets_fog(renderer, monkeypatch):
    """Without the near flakes (drawn or left out), snow is a haze of V = 796 m / R beyond 15 m (Koschmieder
    over each pixel's distance, the far ground's where no mesh is hit); a scene with its own fog gets no snow
    haze (its fog is the visibility in the snow), the frame as drawn."""
    import camgen.render.snow as snow_module
    from camgen.render.renderer import far_ground_depth_m, ray_lengths

    def no_flakes(view, depth_m, *args):
        return np.zeros(depth_m.shape, np.float32), None

    def none_left_out(view, distance_m, *args):
        return np.ones(distance_m.shape, np.float32), None

    monkeypatch.setattr(snow_module, "snow_layers", no_flakes)
    monkeypatch.setattr(snow_module, "left_out_flakes", none_left_out)
    view = _view()
    graph = _graph({"sky_luminance_cd_m2": 2000.0, "meshes": [ROAD], "snow": {"rate_mm_h": 4.0}})
    drawn = renderer.draw(graph, view, ("radiance", "depth_m"))
    hazy = snow_module.snowy_radiance(graph, view, drawn.radiance, drawn.depth_m, _state())
    distance_m = np.where(
        np.isinf(drawn.depth_m), far_ground_depth_m(graph.far_ground, view), drawn.depth_m
    ) * ray_lengths(view)
    t = np.exp(-3.912023 * np.maximum(distance_m - 15.0, 0.0) / snow_visibility_m(4.0))[..., None]
    assert snow_visibility_m(4.0) == pytest.approx(199.0, rel=0.01)
    np.testing.assert_allclose(hazy, 2000.0 + (drawn.radiance - 2000.0) * t, rtol=1e-4)
    assert (t < 0.5).mean() > 0.05  # the haze is visible here
    foggy = _graph(
        {"sky_luminance_cd_m2": 2000.0, "meshes": [ROAD], "snow": {"rate_mm_h": 4.0}, "fog": {"visibility_m": 300}}
    )
    drawn = renderer.draw(foggy, view, ("radiance", "depth_m"))
    np.testing.assert_array_equal(
        snow_module.snowy_radiance(foggy, view, drawn.radiance, drawn.depth_m, _state()), drawn.radiance
    )


def test_plan_draws_depth_for_snow_and_says_why():
    from pathlib import Path

    loaded = load_scene(Path(__file__).parents[2] / "scenes/snowy_street.yaml")
    camera = compile_scene(loaded, PlanSettings()).cameras[0]
    assert "depth_m" in camera.render.passes
    decisions = {decision.stage: decision for decision in camera.decisions}
    assert decisions["render.snow"].included and "1.5 mm/h of dry snow" in decisions["render.snow"].reason
    assert "532 m" in decisions["render.snow"].reason
    assert "snow's depth test" in decisions["pass.depth_m"].reason


IR_PROFILE = (
    FIXED_PROFILE.replace("width_px: 640", f"width_px: {WIDTH}")
    .replace("height_px: 480", f"height_px: {HEIGHT}")
    .replace("pixel_pitch_um: 3.0", "pixel_pitch_um: 12.0")
    + "night_mode:\n  switch_lux: 2.0\n  ir_illuminator: {radiant_intensity_mw_sr: 2000, half_angle_deg: 40}\n"
)


def _street(ambient_lux: float, snow: str) -> str:
    return f"""\
duration_s: 0.1
fps: 10
environment:
  sky_luminance_cd_m2: {ambient_lux / math.pi:g}
  {snow}
  meshes:
    - {{type: plane, name: road, size_m: [60, 60], material: {{color_rgb: [0.08, 0.08, 0.08], nir_reflectance: 0.12}}}}
lights:
  - {{type: ambient, illuminance_lux: {ambient_lux}}}
outputs: {{video: false, annotations: [], frames: png}}
cameras:
  - {{name: cam, profile: ir, mount: {{position_m: [0, 0, 2.5], yaw_deg: 90, pitch_deg: -10}}}}
"""


@pytest.mark.opengl
@pytest.mark.parametrize("ambient_lux", [3000.0, 0.05])
def test_a_compiled_camera_sees_the_snow_by_day_and_in_its_illuminator_at_night(tmp_path, renderer, ambient_lux):
    """A 160×120 camera over a dark road, drawn by the sequence renderer with and without snow: the snowy frame
    is brighter over the road by day; at night (IR mode) the flakes in the illuminator's beam are brighter
    still against the road, and the brightest pixels are the near flakes' (the road's own IR return is far
    below what a flake a metre away sends back: (2/3) ω I/π at 1 m)."""
    from camgen.render.scene_graph import build_scene_graph
    from camgen.render.sequence import CameraRenderer

    write(tmp_path, "profiles/ir.yaml", IR_PROFILE)
    frames = {}
    for name, snow in (("dry", ""), ("snowy", "snow: {rate_mm_h: 2.0, seed: 1}")):
        path = write(tmp_path, f"scenes/{name}.yaml", _street(ambient_lux, snow))
        job = compile_scene(load_scene(path), PlanSettings(supersampling=1))
        (camera,) = job.cameras
        assert camera.states[0].night_mode is (ambient_lux < 2.0)
        frames[name] = CameraRenderer(renderer, build_scene_graph(job.scene), camera).frame(0).passes.radiance
    dry, snowy = frames["dry"].mean(axis=-1), frames["snowy"].mean(axis=-1)
    ratio = snowy / dry
    assert ratio.mean() > 1.05 and np.mean(ratio > 1.5) > 0.01
    if ambient_lux < 2.0:
        from camgen.world.night import nir_equivalent_intensity_cd

        one_metre = float(illuminated_flake_radiance(nir_equivalent_intensity_cd(2000, 0.35)))
        assert snowy.max() > 10 * dry.max() and snowy.max() < one_metre / 0.3**2


def test_cells_left_out_of_the_frustum_change_no_flake(monkeypatch):
    """`snow_layers` asks only for the cells that reach into the view's frustum (`particles_in_box`' planes):
    the frame's flakes are exactly those found looking through every cell of each class's box."""
    import camgen.render.snow as snow_module
    import camgen.world.snow as world_snow

    view, state = _view(), _state()
    depth = np.full((HEIGHT, WIDTH), np.inf, np.float32)
    planned, _ = snow_module.snow_layers(view, depth, state, SNOW, WIND, 0.0)
    everywhere = world_snow.particles_in_box

    def every_cell(*args):
        return everywhere(*args[:7])

    monkeypatch.setattr(world_snow, "particles_in_box", every_cell)
    whole, _ = snow_module.snow_layers(view, depth, state, SNOW, WIND, 0.0)
    assert planned.sum() > 1.0 and np.array_equal(planned, whole)


def test_the_flakes_left_out_are_their_mean_coverage_and_glow(monkeypatch):
    """At 160 px across (f = 150 px) most classes stop within a few metres (`flake_ranges_m`): the veil that
    stands in for the rest covers each sky pixel's ray by what drawing every class to 15 m covers on average
    (within 5 %, Poisson noise of ~5000 flakes), and in an illuminator it glows by the same flakes' mean
    (2/3) ω I/(π z²), within 10 %."""
    import camgen.render.snow as snow_module

    view, state = _view(), _state()
    depth = np.full((HEIGHT, WIDTH), np.inf, np.float32)
    distance = np.full((HEIGHT, WIDTH), np.inf, np.float32)
    ranges = snow_module.flake_ranges_m(SNOW, F_PX)
    assert ranges.max() < 15.0 and ranges.min() < 1.0
    transmittance, glow = snow_module.left_out_flakes(view, distance, SNOW, 500.0, math.radians(60.0))
    drawn, lit = snow_module.snow_layers(view, depth, state, SNOW, None, -np.inf, 500.0, math.radians(60.0))
    monkeypatch.setattr(snow_module, "FLAKE_AREA_MIN_PX2", 1e-9)  # every class to 15 m
    assert np.all(snow_module.flake_ranges_m(SNOW, F_PX) == 15.0)
    every, every_lit = snow_module.snow_layers(view, depth, state, SNOW, None, -np.inf, 500.0, math.radians(60.0))
    # Means over the middle of the frame (a flake near an edge is half drawn), away from the clipping at 1.
    middle = (slice(20, -20), slice(20, -20))
    assert (every - drawn)[middle].mean() == pytest.approx((1 - transmittance)[middle].mean(), rel=0.05)
    assert (every_lit - lit)[middle].mean() == pytest.approx(glow[middle].mean(), rel=0.1)
    # A lamp 4 m ahead and 3 m up (its light on a flake 1/(1 + d²) in each channel): the veil's lamp light, summed
    # along coarse rays, against what drawing every class adds.
    lamp = np.array([0.0, 4.0, 4.5])

    def lamps(points_m):
        return np.repeat(1.0 / (1.0 + np.sum((points_m - lamp) ** 2, axis=1)), 3).reshape(-1, 3) * [1.0, 0.5, 0.25]

    every_lamp = snow_module.snow_layers(view, depth, state, SNOW, None, -np.inf, lamps=lamps)[1]
    monkeypatch.setattr(snow_module, "FLAKE_AREA_MIN_PX2", 0.04)
    drawn_lamp = snow_module.snow_layers(view, depth, state, SNOW, None, -np.inf, lamps=lamps)[1]
    veil_lamp = snow_module.left_out_flakes(view, distance, SNOW, lamps=lamps)[1]
    assert veil_lamp.shape == (HEIGHT, WIDTH, 3)
    np.testing.assert_allclose(
        (every_lamp - drawn_lamp)[middle].mean(axis=(0, 1)), veil_lamp[middle].mean(axis=(0, 1)), rtol=0.1
    )


@pytest.mark.opengl
@pytest.mark.parametrize(
    "lamp",
    [
        {
            "type": "lamp",
            "position_m": [1.0, 6.0, 5.0],
            "target_m": [2.0, 7.0, 0.0],
            "flux_lm": 6000.0,
            "color_rgb": [1.0, 0.82, 0.62],
        },
        {"type": "lamp", "position_m": [0.0, 8.0, 5.0], "ies_file": "ies/street_lantern_synthetic.ies"},
        {"type": "point", "position_m": [-1.0, 7.0, 3.0], "intensity_cd": 800.0},
    ],
    ids=["spot lamp", "IES lamp", "point"],
)
def test_lamps_light_a_flake_as_the_shader_lights_the_ground(renderer, lamp):
    """The illuminance a flake gets from a lamp (`lamp_illuminance_lx`, normal to the lamp's direction) times
    the cosine of the ground's incidence is what the renderer's own lit shader gives a white matte ground,
    L·π/ρ, at every lit pixel (the rendered ground 0–5 % brighter: the glossy lobe of roughness 1, most at
    grazing light), the same beam shape, IES table, colour and 1/d²."""
    from pathlib import Path

    from camgen.render.scene_graph import build_scene_graph
    from camgen.render.snow import lamp_illuminance_lx

    ground = {
        "type": "plane",
        "name": "ground",
        "size_m": [60, 60],
        "position_m": [0, 10, 0],
        "material": {"color_rgb": [0.5, 0.5, 0.5], "roughness": 1.0},
    }
    scenes = Path(__file__).parents[2] / "scenes"
    scene = scene_from(environment={"meshes": [ground], "shadows": False}, lights=[lamp])
    graph = build_scene_graph(scene, lambda path: scenes / path)
    view = View(
        camera_matrix(F_PX, F_PX, (WIDTH - 1) / 2, (HEIGHT - 1) / 2), look_at((0, 0, 6), (0, 8, 0)), WIDTH, HEIGHT
    )
    drawn = renderer.draw(graph, view, ("radiance", "depth_m"))
    v, u = np.mgrid[:HEIGHT, :WIDTH]
    rays = np.stack([u, v, np.ones_like(u)], axis=-1) @ np.linalg.inv(view.K_px).T
    points = (rays * drawn.depth_m[..., None]).reshape(-1, 3) @ view.T_world_from_cam[:3, :3].T
    points += view.T_world_from_cam[:3, 3]
    light = lamp["position_m"]
    towards = np.asarray(light) - points
    cosine = towards[:, 2] / np.linalg.norm(towards, axis=1)
    expected = (lamp_illuminance_lx(graph, points) * cosine[:, None]).reshape(HEIGHT, WIDTH, 3)
    rendered = drawn.radiance * math.pi / 0.5
    lit = expected[..., 1] > 0.05 * expected[..., 1].max()
    assert lit.mean() > 0.2
    ratio = rendered[lit][:, 1] / expected[lit][:, 1]
    assert 0.995 < np.median(ratio) < 1.03 and 0.99 < ratio.min() and ratio.max() < 1.06
    np.testing.assert_allclose(
        rendered[lit][:, 0] / rendered[lit][:, 1], expected[lit][:, 0] / expected[lit][:, 1], rtol=1e-5
    )


def test_a_flake_is_lit_by_the_sky_the_ground_and_the_sun_whichever_way_the_camera_looks():
    """ω [(L_sky + L_ground)/2 + E_sun/(4π)] with L_sky the ambient light's E/π, L_ground the far ground's
    reflectance under sky and sun, ρ (E_sky + E_sun sin h)/π: one value for two different frames."""
    from camgen.render.snow import environment_flake_radiance

    sun = {"type": "sun", "illuminance_lux": 40000.0, "azimuth_deg": 30.0, "elevation_deg": 30.0}
    graph = _graph({"sky_luminance_cd_m2": 3000.0, "meshes": [ROAD]}, [*AMBIENT, sun])
    depth = np.full((HEIGHT, WIDTH), 5.0, np.float32)
    dark, bright = np.full((HEIGHT, WIDTH, 3), 10.0, np.float32), np.full((HEIGHT, WIDTH, 3), 900.0, np.float32)
    flake = environment_flake_radiance(graph, dark, depth)
    np.testing.assert_array_equal(flake, environment_flake_radiance(graph, bright, depth))
    sky = 5000.0 / math.pi
    ground = 0.08 * (5000.0 + 40000.0 * 0.5) / math.pi
    np.testing.assert_allclose(flake, 0.9 * ((sky + ground) / 2 + 40000.0 / (4 * math.pi)), rtol=1e-5)
