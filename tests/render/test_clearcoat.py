"""A car's clear-coated paint (`camgen.render.scene_graph.ClearcoatMaterial`, the shader's `clearcoat_ambient`):
under a uniform sky the paint's radiance is the coat's mirror reflection F·L_env plus the base's diffuse
ambient (1 − F)·ρ·A, F Schlick's Fresnel reflectance of the view angle with F0 = 0.04 (a dielectric of index
1.5), the environment the sky (radiance A = E/π) above the horizon and the ground (albedo 0.15 under that sky)
below it. Checked against that closed form on a black sedan's flat roof seen from straight above and at a
grazing 70° (where it mirrors four times more sky) and on its flank seen from 45° above (which mirrors the
ground); the ground plane, which has no coat, stays Lambertian (ρ·A at any view)."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from camgen.render.renderer import View
from camgen.render.scene_graph import build_scene_graph
from camgen.vehicles.body import PROFILES
from camgen.vehicles.look import PAINTS, draw_look
from tests.render.conftest import camera_matrix, look_at, scene_from

pytestmark = pytest.mark.opengl

AMBIENT_LUX = 15000.0
GROUND_RHO = 0.1
F0 = 0.04
GROUND_ALBEDO = 0.15
"""The shader's CLEARCOAT_F0 and CLEARCOAT_GROUND_ALBEDO."""
SIZE_PX, F_PX = 64, 300.0
DISTANCE_M = 6.0
K_PX = camera_matrix(F_PX, F_PX, (SIZE_PX - 1) / 2, (SIZE_PX - 1) / 2)


def schlick(cos_theta: float) -> float:
    return F0 + (1.0 - F0) * (1.0 - cos_theta) ** 5


def _scene(sky: str = "uniform", sky_luminance_cd_m2: float = AMBIENT_LUX / math.pi):
    return scene_from(
        environment={
            "sky": sky,
            "sky_luminance_cd_m2": sky_luminance_cd_m2,
            "shadows": False,
            "meshes": [
                {"type": "plane", "name": "ground", "size_m": [60, 60], "material": {"color_rgb": [GROUND_RHO] * 3}}
            ],
        },
        lights=[{"type": "ambient", "illuminance_lux": AMBIENT_LUX}],
        actors=[
            {
                "name": "car",
                "class": "car",
                # Seed 3: a roof all paint (no glass roof or shark fin: `camgen.vehicles.roof.roof_kit`).
                "vehicle": {"seed": 3, "body_type": "sedan", "colour": "black", "driver": False},
                "path": {"waypoints_m": [[0, 0]]},
            }
        ],
    )


@pytest.fixture(scope="module")
def coat(renderer):
    """{view name: (radiance (H, W, 3), the target's pixel (x, y), the cosine of the view angle)}."""
    return _coat(renderer, build_scene_graph(_scene()))


def _coat(renderer, graph) -> dict:
    T_vehicle = graph.vehicles[0].T_world_from_vehicle
    look = draw_look(3, "car", pinned={"body_type": "sedan", "colour": "black"})
    flat = [u for u, z in PROFILES["sedan"].top if z == 1.0]
    roof = np.array([(np.mean(flat) - 0.5) * look.length_m, 0.0, look.height_m, 1.0])
    # The flank at the middle of the wheelbase, half-way up the section (its widest point: normal ±y).
    side_x = (look.front_axle_x_m + look.rear_axle_x_m) / 2
    flank = np.array([side_x, -look.width_m / 2, (look.height_m + PROFILES["sedan"].clearance_m) / 2, 1.0])

    # Seen from the car's right (−y): the roof from straight above and from 20° up (70° off its normal), the flank from
    # 45° up.
    def towards(elevation_deg: float) -> tuple[float, float, float]:
        return (0.0, -math.cos(math.radians(elevation_deg)), math.sin(math.radians(elevation_deg)))

    targets = {"above": (roof, (0.0, 0.0, 1.0)), "grazing": (roof, towards(20.0)), "flank": (flank, towards(45.0))}
    out = {}
    for name, (point, direction) in targets.items():
        target = (T_vehicle @ point)[:3]
        position = target + DISTANCE_M * np.asarray(direction)
        T = look_at(position, target) if name != "above" else _straight_down(position)
        passes = renderer.draw(graph, View(K_PX, T, SIZE_PX, SIZE_PX), ("radiance",))
        T_cam = np.linalg.inv(T)
        pixel, _ = cv2.projectPoints(target[None], cv2.Rodrigues(T_cam[:3, :3])[0], T_cam[:3, 3], K_PX, None)
        normal = np.array([0.0, 0.0, 1.0]) if name != "flank" else -T_vehicle[:3, 1]
        out[name] = (passes.radiance, np.round(pixel.reshape(2)).astype(int), float(np.dot(normal, direction)))
    return out


def _straight_down(position: np.ndarray) -> np.ndarray:
    """T_world_from_cam looking straight down, image right = world +x."""
    T = np.eye(4)
    T[:3, :3] = np.column_stack([[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]])
    T[:3, 3] = position
    return T


def _at(radiance: np.ndarray, pixel: np.ndarray) -> np.ndarray:
    x, y = pixel
    return np.median(radiance[y - 1 : y + 2, x - 1 : x + 2].reshape(-1, 3), axis=0)


@pytest.mark.parametrize("name", ["above", "grazing", "flank"])
def test_paint_is_a_fresnel_weighted_mirror_of_sky_and_ground_over_its_diffuse_base(coat, name):
    radiance, pixel, cos_theta = coat[name]
    sky = AMBIENT_LUX / math.pi
    rho = np.asarray(PAINTS["black"].color_rgb)
    F = schlick(cos_theta)
    environment = sky if name != "flank" else GROUND_ALBEDO * sky  # the flank seen from above mirrors the ground
    expected = (1.0 - F) * rho * sky + F * environment
    print(name, f"cos {cos_theta:.3f} F {F:.4f}", _at(radiance, pixel), expected)
    np.testing.assert_allclose(_at(radiance, pixel), expected, rtol=0.03)


def test_a_roof_mirrors_more_sky_at_grazing_views(coat):
    above = _at(*coat["above"][:2])[1]
    grazing = _at(*coat["grazing"][:2])[1]
    assert grazing > 2.5 * above  # F 0.04 -> 0.30 at 70° off the normal: 0.057 -> 0.17 of A for black paint


def test_the_ground_has_no_coat(coat):
    radiance, _, _ = coat["grazing"]
    ground = radiance[:3, :8].reshape(-1, 3)  # the plane beyond the car, above its roof in the view
    np.testing.assert_allclose(np.median(ground, axis=0), GROUND_RHO * AMBIENT_LUX / math.pi, rtol=0.02)


OVERCAST_ZENITH_CD_M2 = 4000.0


def test_under_a_cie_sky_the_paint_mirrors_the_sky_in_the_reflected_direction(renderer):
    """Under the CIE overcast sky (type 1: three times brighter at the zenith than at the horizon) the roof seen
    at a grazing 20° mirrors the sky 20° up beyond the car, not the uniform sky's E/π: against a uniform sky of
    the same ambient light the paint differs by exactly F·(L_sky(r) − E/π), L_sky from `camgen.world.sky`
    (`renderer.SkyMap`); the flank, which mirrors the ground, does not change."""
    from camgen.world.sky import sky_radiance

    cie = _coat(renderer, build_scene_graph(_scene("overcast", OVERCAST_ZENITH_CD_M2)))
    uniform = _coat(renderer, build_scene_graph(_scene("uniform", OVERCAST_ZENITH_CD_M2)))
    radiance, pixel, cos_theta = cie["grazing"]
    # Seen from the car's right (−y) 20° up, a level roof mirrors the ray 20° up towards +y (the car's left).
    T_vehicle = build_scene_graph(_scene()).vehicles[0].T_world_from_vehicle
    left = T_vehicle[:3, 1]
    reflected = math.cos(math.radians(20.0)) * left + np.array([0.0, 0.0, math.sin(math.radians(20.0))])
    sky = sky_radiance(reflected[None], np.array([0.0, 0.0, 1.0]), "overcast", OVERCAST_ZENITH_CD_M2)[0]
    assert sky[1] < 0.6 * OVERCAST_ZENITH_CD_M2  # 20° up the overcast sky is half the zenith's
    difference = _at(radiance, pixel) - _at(*uniform["grazing"][:2])
    expected = schlick(cos_theta) * (sky - AMBIENT_LUX / math.pi)
    np.testing.assert_allclose(difference, expected, rtol=0.03)
    np.testing.assert_allclose(_at(*cie["flank"][:2]), _at(*uniform["flank"][:2]), rtol=1e-5)


@pytest.mark.parametrize("sun_azimuth_deg", [0.0, 60.0, 135.0, -100.0])
def test_under_a_clear_sky_the_paint_mirrors_the_sky_at_the_reflected_rays_azimuth(renderer, sun_azimuth_deg):
    """The clear CIE sky is brightest around the sun: with the sun 25° up at azimuths around the compass, the
    roof seen at a grazing 20° differs from its uniform-sky self by F·(L_sky(r) − E/π) within 3 %, L_sky at the
    reflected ray's own azimuth (`camgen.world.sky`'s atan2(y, x) convention: the overcast sky above has none,
    so a map turned or mirrored in azimuth passes there and fails here)."""
    from camgen.world.sky import sky_radiance

    azimuth, elevation = math.radians(sun_azimuth_deg), math.radians(25.0)
    sun = np.array(
        [math.cos(elevation) * math.cos(azimuth), math.cos(elevation) * math.sin(azimuth), math.sin(elevation)]
    )
    graph = build_scene_graph(_scene("overcast", OVERCAST_ZENITH_CD_M2))
    graph.sky, graph.sun_direction = "clear", sun  # the sky's sun alone (a sun light would light the roof too)
    cie = _coat(renderer, graph)
    uniform = _coat(renderer, build_scene_graph(_scene("uniform", OVERCAST_ZENITH_CD_M2)))
    radiance, pixel, cos_theta = cie["grazing"]
    left = graph.vehicles[0].T_world_from_vehicle[:3, 1]
    reflected = math.cos(math.radians(20.0)) * left + np.array([0.0, 0.0, math.sin(math.radians(20.0))])
    sky = sky_radiance(reflected[None], sun, "clear", OVERCAST_ZENITH_CD_M2)[0]
    difference = _at(radiance, pixel) - _at(*uniform["grazing"][:2])
    np.testing.assert_allclose(difference, schlick(cos_theta) * (sky - AMBIENT_LUX / math.pi), rtol=0.03)


@pytest.mark.parametrize("sky", ["uniform", "overcast"])
def test_the_first_draw_under_a_sky_is_the_draw_after_it(renderer, sky):
    """A uniform sky's first lit draw makes the sky map's placeholder texture (`SkyMap.bind`) on the sampler's
        own unit: made on the unit active before it (the last spot-light table's, a street lamp's IES profile),
        it replaced that table for the first primitive drawn, which a fresh renderer then lit otherwise than every
        later draw of the same view (the night street's first frame: 136 px of a car 0.35 % darker). A CIE sky's
    map, made before the draw (`SkyMap.update`), is checked likewise."""
    from pathlib import Path

    scene = scene_from(
        environment={
            "sky": sky,
            "sky_luminance_cd_m2": 0.01,
            "shadows": False,
            "meshes": [
                {"type": "plane", "name": "ground", "size_m": [30, 30], "material": {"color_rgb": [0.3] * 3}},
                {"type": "box", "name": "block", "size_m": [2, 2, 2], "position_m": [0, 3, 1]},
            ],
        },
        lights=[
            {"type": "ambient", "illuminance_lux": 0.03},
            {
                "type": "lamp",
                "position_m": [2.0, 0.0, 6.0],
                "ies_file": "ies/street_lantern_synthetic.ies",
                "flux_lm": 6000,
            },
        ],
    )
    graph = build_scene_graph(scene, lambda path: Path(__file__).parents[2] / "scenes" / path)
    view = View(K_PX, look_at(np.array([0.0, -8.0, 4.0]), np.array([0.0, 3.0, 0.5])), SIZE_PX, SIZE_PX)
    renderer._renderer.sky_map.delete()  # as a fresh renderer's: no sky texture yet
    first = renderer.draw(graph, view, ("radiance",)).radiance.copy()
    second = renderer.draw(graph, view, ("radiance",)).radiance
    assert first.max() > 0.1  # the lamp lights the scene
    np.testing.assert_array_equal(first, second)
