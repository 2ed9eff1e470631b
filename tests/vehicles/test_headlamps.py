"""Headlamps as photometric lights (`camgen.vehicles.headlamps`, `camgen.render.scene_graph.add_headlamps`).

- The low beam meets UN ECE R112's class B test points and zone III, and carries a lamp's flux.
- Rendered: the road ahead of a lit car, seen straight down, has the luminance ρ/π · E of the illuminance
  E = 2·I(h, v)·cos(incidence)/d² the closed form of the beam gives at each point (the two lamps as one light),
  the renderer's specular share measured under a point light at the same place.
- `auto`: lamps dark by day (the daytime frame is the one with lamps off, bit for bit) and on a parked car,
  lit at night; the switching level is R48's 1 000 lx.
- The light moves with the car; more lit cars than the renderer's spot lights give a warning naming them.
- Bad input is refused with the key path and the fix.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from camgen.config.scene import MAX_LIGHTS
from camgen.errors import ConfigError
from camgen.vehicles.headlamps import (
    AUTO_ON_BELOW_LUX,
    R112_CLASS_B_CD,
    R112_ZONE_III_MAX_CD,
    daylight_horizontal_lux,
    low_beam_flux_lm,
    low_beam_intensity_cd,
    low_beam_table,
    table_angles_to_lamp_deg,
)
from tests.render.conftest import camera_matrix, look_at, scene_from

ALBEDO = 0.5
CM_PER_PX = 10.0
NIGHT = [{"type": "ambient", "illuminance_lux": 0.001}]
DAY = [{"type": "sun", "illuminance_lux": 60_000, "elevation_deg": 40}, {"type": "ambient", "illuminance_lux": 15_000}]


def _car(name="car", waypoints=((0.0, 0.0),), **vehicle):
    path = {"waypoints_m": [list(w) for w in waypoints]}
    if len(waypoints) > 1:
        path["speed_m_s"] = 10.0
    else:
        path["heading_deg"] = 0.0
    return {"name": name, "class": "car", "vehicle": {"seed": 3, "body_type": "sedan", **vehicle}, "path": path}


def _ground():
    return {
        "meshes": [
            {
                "type": "plane",
                "name": "road",
                "size_m": [200, 200],
                "material": {"color_rgb": [ALBEDO] * 3, "roughness": 1.0},
            }
        ],
        "shadows": False,
    }


def test_the_low_beam_meets_r112_class_b():
    for name, (h_deg, v_deg, least_cd, most_cd) in R112_CLASS_B_CD.items():
        value = float(low_beam_intensity_cd(h_deg, v_deg))
        assert least_cd is None or value >= least_cd, (name, value)
        assert most_cd is None or value <= most_cd, (name, value)
    # Zone III, above the cut-off towards oncoming traffic (here: the left from the horizontal up, and above
    # the 15° kink's top on the right, 8° each side, to 4° up).
    for h_range, v_low in (((-8, 0), 0.0), ((0, 8), 1.35)):
        h, v = np.meshgrid(np.linspace(*h_range, 17), np.linspace(v_low, 4, 12))
        assert float(low_beam_intensity_cd(h, v).max()) <= R112_ZONE_III_MAX_CD
    assert 400.0 < low_beam_flux_lm() < 900.0  # a halogen H7's 1350-1500 lm through a reflector's ~40 %


def test_the_table_is_the_beam_in_the_lamps_axes():
    """The table's (γ, C) directions, turned back to (h, v), give the closed form; C = 90° is the left."""
    table = low_beam_table()
    h, v = table_angles_to_lamp_deg(np.array([5.0, 5.0, 3.0]), np.array([90.0, 270.0, 180.0]))
    np.testing.assert_allclose(h, [-5.0, 5.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(v, [0.0, 0.0, -3.0], atol=1e-9)
    np.testing.assert_allclose(table[3, 36], low_beam_intensity_cd(0.0, -3.0), rtol=1e-12)


POINT_CD = 10_000.0
"""The reference point light's intensity, cd (`beam_on_road`)."""


@pytest.mark.opengl
@pytest.mark.parametrize(
    "ahead_m, aside_m", [(4.0, 0.0), (6.0, 0.0), (9.0, 0.0), (6.0, 1.5), (12.0, 1.5), (12.0, -1.5)]
)
def test_the_road_under_the_beam_follows_the_cosine_inverse_square_law(beam_on_road, ahead_m, aside_m):
    """Ground luminance under the beam over ρ/π · 2·I(h, v)·cos(incidence)/d² of the closed-form beam (the
    two lamps as one light) is the same ratio within 2 % as under an isotropic point light at the lamp over
    ρ/π · I·cos/d²: the renderer's specular lobe at roughness 1 and grazing light adds 3–5 % to both, and the
    beam is looked up in the renderer's 1° × 5° table. The ratio itself stays within 6 % of 1."""
    beam, point_lit, lamp_m, f_px, centre_m = beam_on_road
    point = np.array([lamp_m[0] + ahead_m, aside_m, 0.0])
    towards = point - lamp_m
    d = float(np.linalg.norm(towards))
    h_deg = math.degrees(math.atan2(-towards[1], towards[0]))  # positive to the car's right (−y)
    v_deg = math.degrees(math.asin(towards[2] / d))
    cosine_over_d2 = (lamp_m[2] / d) / d**2
    expected = ALBEDO / math.pi * 2 * float(low_beam_intensity_cd(h_deg, v_deg)) * cosine_over_d2
    reference = ALBEDO / math.pi * POINT_CD * cosine_over_d2
    column, row = _project(point, centre_m, f_px)
    measured, measured_reference = (_bilinear(image, column, row) for image in (beam, point_lit))
    assert measured / expected == pytest.approx(measured_reference / reference, rel=0.02), (ahead_m, aside_m)
    assert measured == pytest.approx(expected, rel=0.06)


def _bilinear(image: np.ndarray, column: float, row: float) -> float:
    c0, r0 = math.floor(column), math.floor(row)
    tc, tr = column - c0, row - r0
    patch = image[r0 : r0 + 2, c0 : c0 + 2, 1].astype(np.float64)
    return float(np.array([1 - tr, tr]) @ patch @ np.array([1 - tc, tc]))


def _project(point, centre_m, f_px) -> tuple[float, float]:
    """(column, row) of a world point in `beam_on_road`'s view (OpenCV pixel centres)."""
    T = look_at((centre_m[0], centre_m[1], 30.0), (centre_m[0], centre_m[1], 0.0))
    p = np.linalg.inv(T) @ np.append(point, 1.0)
    return 99.5 + f_px * p[0] / p[2], 59.5 + f_px * p[1] / p[2]


@pytest.fixture(scope="module")
def beam_on_road(renderer):
    """A sedan with its lamps on at night over a grey (ρ = 0.5, roughness 1) road, seen straight down from
    30 m over a point 8 m ahead of it, 10 cm a pixel, 200 × 120; and the same road lit instead by a point
    light of `POINT_CD` where the beam's light stands, the car's lamps off."""
    from camgen.render.renderer import View
    from camgen.render.scene_graph import build_scene_graph

    graph = build_scene_graph(scene_from(environment=_ground(), lights=NIGHT, actors=[_car(lights_on=True)]))
    (headlamp,) = graph.headlamps
    T = graph.vehicles[0].T_world_from_vehicle
    lamp_m = T[:3, :3] @ headlamp.point_m + T[:3, 3]
    centre_m = (lamp_m[0] + 8.0, 0.0)
    f_px = 30.0 * 100 / CM_PER_PX
    view = View(camera_matrix(f_px, f_px, 99.5, 59.5), look_at((*centre_m, 30.0), (*centre_m, 0.0)), 200, 120)
    beam = renderer.draw(graph, view, ("radiance",)).radiance
    point = {"type": "point", "position_m": [float(c) for c in lamp_m], "intensity_cd": POINT_CD}
    reference = scene_from(environment=_ground(), lights=[*NIGHT, point], actors=[_car(lights_on=False)])
    point_lit = renderer.draw(build_scene_graph(reference), view, ("radiance",)).radiance
    return beam, point_lit, lamp_m, f_px, centre_m


@pytest.mark.opengl
def test_auto_lamps_change_no_daytime_frame(renderer):
    """By day a driving car's `auto` lamps stay dark: its frame is the one with lights_on false, bit for bit."""
    from camgen.render.renderer import View
    from camgen.render.scene_graph import build_scene_graph

    view = View(camera_matrix(150, 150, 79.5, 59.5), look_at((-8.0, -4.0, 4.0), (4.0, 0.0, 0.0)), 160, 120)
    frames = []
    for vehicle in ({}, {"lights_on": False}):
        scene = scene_from(environment=_ground(), lights=DAY, actors=[_car(waypoints=((0, 0), (50, 0)), **vehicle)])
        graph = build_scene_graph(scene)
        assert graph.headlamps == [] and not graph.vehicles[0].lit["head"]
        frames.append(renderer.draw(graph, view, ("radiance",)).radiance)
    np.testing.assert_array_equal(frames[0], frames[1])


def test_auto_lamps_light_a_driven_vehicle_at_night_only():
    from camgen.motion.trajectory import actor_routes
    from camgen.vehicles import vehicle_rigs

    actors = [_car("driving", waypoints=((0, 0), (50, 0))), _car("parked", waypoints=((0, 5),))]
    night = scene_from(environment=_ground(), lights=NIGHT, actors=actors)
    rigs = vehicle_rigs(night, actor_routes(night))
    assert rigs["driving"].lamps(0.5)["head"] and rigs["driving"].lamps(0.5)["tail"]
    assert not rigs["parked"].lamps(0.5)["head"]  # nobody drives it
    for lux, lit in ((0.5 * AUTO_ON_BELOW_LUX, True), (2 * AUTO_ON_BELOW_LUX, False)):
        scene = scene_from(environment=_ground(), lights=[{"type": "ambient", "illuminance_lux": lux}], actors=actors)
        assert daylight_horizontal_lux(scene)(0.0) == pytest.approx(lux)
        assert vehicle_rigs(scene, actor_routes(scene))["driving"].lamps(0.0)["head"] is lit


def test_the_light_moves_with_the_car():
    from camgen.render.scene_graph import build_scene_graph

    scene = scene_from(environment=_ground(), lights=NIGHT, actors=[_car(waypoints=((0, 0), (50, 0)))])
    graph = build_scene_graph(scene)
    (headlamp,) = graph.headlamps
    assert scene.fps == 25
    poses = []
    for time_s in (0.2, 0.6):  # frame times
        graph.place_actors(time_s)
        poses.append(graph.scene.get_pose(headlamp.node).copy())
        T = graph.vehicles[0].T_world_from_vehicle
        np.testing.assert_allclose(poses[-1][:3, 3], T[:3, :3] @ headlamp.point_m + T[:3, 3], atol=1e-9)
        np.testing.assert_allclose(-poses[-1][:3, 2], [1.0, 0.0, 0.0], atol=1e-9)  # aimed along the heading
    graph.place_actors(0.6 + 0.015)  # within the frame's exposure the light holds still, the car drives on
    np.testing.assert_array_equal(graph.scene.get_pose(headlamp.node), poses[-1])
    assert graph.vehicles[0].T_world_from_vehicle[0, 3] > poses[-1][0, 3] - headlamp.point_m[0]
    assert poses[1][0, 3] - poses[0][0, 3] > 0.3  # it drove on (easing away from its start)
    assert headlamp.node.light.intensity == pytest.approx(2 * float(low_beam_table().max()))


def test_more_lit_cars_than_spot_lights_are_named():
    from camgen.render.scene_graph import build_scene_graph

    lamps = [{"type": "lamp", "position_m": [0, 10 * k, 8], "flux_lm": 5000} for k in range(MAX_LIGHTS["spot"] - 1)]
    cars = [_car("first", waypoints=((0, 0), (50, 0))), _car("second", waypoints=((0, 5), (50, 5)))]
    scene = scene_from(environment=_ground(), lights=NIGHT + lamps, actors=cars)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        graph = build_scene_graph(scene)
    assert [graph.actors[h.actor_index].name for h in graph.headlamps] == ["first"]
    assert len(graph.scene.spot_light_nodes) == MAX_LIGHTS["spot"]
    assert any("second light no road" in str(w.message) for w in caught)


def test_bad_lights_on_is_located_and_explained(tmp_path):
    from camgen.config.loader import load_scene

    path = tmp_path / "bad.yaml"
    path.write_text(
        "duration_s: 1\nfps: 10\nlights:\n  - {type: ambient, illuminance_lux: 1}\nactors:\n"
        "  - name: car\n    class: car\n    vehicle: {lights_on: dusk}\n    path: {waypoints_m: [[0, 0]]}\n"
        "cameras:\n  - {name: cam, profile: unused, mount: {position_m: [0, 0, 1]}}\n",
        encoding="utf-8",
    )
    with pytest.raises(ConfigError) as caught:
        load_scene(path)
    message = str(caught.value)
    assert "bad.yaml:8" in message and "actors[0].vehicle.lights_on" in message
    assert "must be true, false or auto" in message and "'dusk'" in message
