"""IES LM-63 photometry (`camgen.world.ies`): the parser, the symmetries, the flux of known
distributions, and the refusals; and an IES lamp rendered over a grey plane against E = I(γ, C)·cos γ / d²."""

from __future__ import annotations

import math

import numpy as np
import pytest

from camgen.world.ies import flux_lm, grid_intensity_cd, intensity_grid_cd, parse_ies


def ies_text(vertical, horizontal, candela, *, multiplier=1.0, ballast=1.0, kind=1, tilt="NONE") -> str:
    """An LM-63-2002 file's text for a candela table (rows: horizontal angles), values wrapped 7 a line."""
    numbers = [*vertical, *horizontal, *np.ravel(candela)]
    lines = [" ".join(f"{x:g}" for x in numbers[i : i + 7]) for i in range(0, len(numbers), 7)]
    return "\n".join(
        [
            "IESNA:LM-63-2002",
            "[TEST] camgen test luminaire",
            "[MANUFAC] none",
            f"TILT={tilt}",
            f"1 -1 {multiplier:g} {len(vertical)} {len(horizontal)} {kind} 2 0.3 0.6 0",
            f"{ballast:g} 1 50",
            *lines,
            "",
        ]
    )


def test_an_isotropic_source_has_4_pi_lumens_per_candela():
    """100 cd in every direction (γ 0–180° every 10°, C = 0 only): Φ = 4π·100 = 1256.6 lm within 1e-4."""
    vertical = np.arange(0, 181, 10.0)
    photometry = parse_ies(ies_text(vertical, [0], np.full((1, len(vertical)), 100.0)))
    assert flux_lm(intensity_grid_cd(photometry)) == pytest.approx(400 * math.pi, rel=1e-4)


def test_a_lambertian_downlight_has_pi_lumens_per_peak_candela_and_the_multipliers_apply():
    """I = I₀ cos γ below the horizontal (γ 0–90° every 5°, quadrant-symmetric 0–90° in C), with
    candela multiplier 2 and ballast factor 0.9 (I₀ = 500 · 2 · 0.9 = 900 cd): Φ = π·900 within 1e-3."""
    vertical = np.arange(0, 91, 5.0)
    horizontal = [0.0, 45.0, 90.0]
    candela = np.tile(500 * np.cos(np.radians(vertical)), (3, 1))
    photometry = parse_ies(ies_text(vertical, horizontal, candela, multiplier=2.0, ballast=0.9))
    assert photometry.intensity_cd(0.0, 123.0) == pytest.approx(900.0)
    assert photometry.intensity_cd(120.0, 0.0) == 0.0  # above the table: dark
    assert flux_lm(intensity_grid_cd(photometry)) == pytest.approx(math.pi * 900.0, rel=1e-3)


@pytest.mark.parametrize(
    ("horizontal", "c_deg", "same_as_deg"),
    [([0.0, 90.0], 200.0, 20.0), ([0.0, 90.0], 290.0, 70.0), ([0.0, 90.0, 180.0], 300.0, 60.0)],
)
def test_the_files_symmetries_fold_c_into_its_range(horizontal, c_deg, same_as_deg):
    vertical = [0.0, 45.0, 90.0]
    candela = np.array([[100.0 + h, 50.0 + h, 10.0] for h in horizontal])
    photometry = parse_ies(ies_text(vertical, horizontal, candela))
    assert photometry.intensity_cd(30.0, c_deg) == pytest.approx(float(photometry.intensity_cd(30.0, same_as_deg)))


def test_the_grid_lookup_matches_the_table_at_its_nodes():
    vertical = np.arange(0, 181, 5.0)
    horizontal = np.arange(0, 361, 30.0)
    candela = np.array([[1 + (v / 180) * (1 + math.sin(math.radians(h))) for v in vertical] for h in horizontal])
    photometry = parse_ies(ies_text(vertical, horizontal, candela))
    grid = intensity_grid_cd(photometry)
    for gamma, c in ((10.0, 30.0), (95.0, 120.0), (180.0, 330.0)):
        assert grid_intensity_cd(grid, gamma, c) == pytest.approx(float(photometry.intensity_cd(gamma, c)), rel=1e-9)


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        ({"tilt": "INCLUDE"}, "only TILT=NONE is supported"),
        ({"kind": 3}, "only type C"),
        ({"horizontal": [0.0, 45.0]}, "supported are 0 alone, 0–90, 0–180 or 0–360°"),
        ({"vertical": [0.0, 90.0, 45.0]}, "the vertical angles must increase within 0–180°"),
        ({"short": True}, "need 20 numbers after TILT=NONE, got 19"),
        ({"candela": -1.0}, "negative candela values"),
    ],
)
def test_bad_files_are_refused_with_the_reason(edit, message):
    vertical, horizontal = edit.get("vertical", [0.0, 45.0, 90.0]), edit.get("horizontal", [0.0])
    candela = np.full((len(horizontal), len(vertical)), edit.get("candela", 100.0))
    text = ies_text(vertical, horizontal, candela, kind=edit.get("kind", 1), tilt=edit.get("tilt", "NONE"))
    if edit.get("short"):
        text = text.rsplit(" ", 1)[0]
    with pytest.raises(ValueError, match=message):
        parse_ies(text)
    with pytest.raises(ValueError, match="no TILT= line"):
        parse_ies("IESNA:LM-63-2002\n1 2 3\n")


HEIGHT_M = 6.0
F_PX = 150.0
"""Straight down from 30 m: 20 cm per pixel on the ground, image x along world x, image y along −y."""


@pytest.fixture(scope="module")
def street_side_lamp(renderer, tmp_path_factory):
    """A lantern whose table (γ 0–90° every 5°, C 0–360° every 15°) throws 2.6× more light to its
    street side (C = 90°) than behind it, with C = 0 turned to +Y (c0_azimuth_deg 90, so the street
    side is −X), 6 m over a grey plane (ρ 0.5, roughness 1), scaled to 4000 lm."""
    from camgen.render.renderer import View
    from camgen.render.scene_graph import build_scene_graph
    from tests.render.conftest import camera_matrix, look_at, scene_from

    vertical = np.arange(0, 91, 5.0)
    horizontal = np.arange(0, 361, 15.0)
    candela = np.array(
        [
            [
                800
                * math.cos(math.radians(v)) ** 0.5
                * (1 + 0.8 * math.sin(math.radians(h)) * math.sin(math.radians(v)))
                if v < 85
                else 0.0
                for v in vertical
            ]
            for h in horizontal
        ]
    )
    directory = tmp_path_factory.mktemp("ies")
    (directory / "lantern.ies").write_text(ies_text(vertical, horizontal, candela), encoding="latin-1")
    scene = scene_from(
        environment={
            "meshes": [
                {
                    "type": "plane",
                    "name": "ground",
                    "size_m": [100, 100],
                    "material": {"color_rgb": [0.5] * 3, "roughness": 1.0},
                }
            ],
            "shadows": False,
        },
        lights=[
            {
                "type": "lamp",
                "position_m": [0, 0, HEIGHT_M],
                "ies_file": "lantern.ies",
                "c0_azimuth_deg": 90,
                "flux_lm": 4000,
            }
        ],
    )
    graph = build_scene_graph(scene, lambda path: directory / path)
    view = View(camera_matrix(F_PX, F_PX, 79.5, 59.5), look_at((0.0, 0.0, 30.0), (0.0, 0.0, 0.0)), 160, 120)
    photometry = parse_ies(ies_text(vertical, horizontal, candela))
    return renderer.draw(graph, view, ("radiance",)).radiance, intensity_grid_cd(photometry)


@pytest.mark.opengl
@pytest.mark.parametrize("ground_xy_m", [(0.0, 0.0), (-3.0, 0.0), (3.0, 0.0), (0.0, 3.0), (-5.0, 4.0), (6.0, -6.0)])
def test_an_ies_lamps_pool_follows_its_table(street_side_lamp, ground_xy_m):
    """Ground luminance equals ρ/π · I(γ, C)·cos γ / d² with I the file's table (scaled to 4000 lm) within
    3 % (the specular lobe at roughness 1 adds 2.0–2.5 %), at points all round the lamp: the street side
    (−X here) gets the table's C = 90° light, the back (+X) its C = 270°."""
    radiance, grid = street_side_lamp
    scale = 4000.0 / flux_lm(grid)
    column, row = round(79.5 + ground_xy_m[0] * F_PX / 30), round(59.5 - ground_xy_m[1] * F_PX / 30)
    x, y = (column - 79.5) * 30 / F_PX, -(row - 59.5) * 30 / F_PX
    d = math.sqrt(x * x + y * y + HEIGHT_M**2)
    gamma = math.degrees(math.acos(HEIGHT_M / d))
    c = math.degrees(math.atan2(-x, y))  # C counter-clockwise from +Y seen from above: −X is 90°
    expected = 0.5 / math.pi * scale * float(grid_intensity_cd(grid, gamma, c)) * (HEIGHT_M / d) / d**2
    assert float(radiance[row, column].mean()) == pytest.approx(expected, rel=0.03)


@pytest.mark.opengl
def test_the_street_side_is_brighter_than_the_back(street_side_lamp):
    radiance, _ = street_side_lamp
    street, back = radiance[60, round(79.5 - 3 * F_PX / 30)].mean(), radiance[60, round(79.5 + 3 * F_PX / 30)].mean()
    assert street > 1.5 * back


def test_a_missing_ies_file_is_a_config_error(tmp_path):
    from camgen.errors import ConfigError
    from camgen.render.scene_graph import build_scene_graph
    from tests.render.conftest import scene_from

    scene = scene_from(lights=[{"type": "lamp", "position_m": [0, 0, 6], "ies_file": "nowhere.ies"}])
    with pytest.raises(ConfigError, match=r"nowhere\.ies' cannot be read"):
        build_scene_graph(scene, lambda path: tmp_path / path)


@pytest.mark.opengl
def test_an_ies_lamp_casts_shadows(renderer, tmp_path):
    """With shadows on, a 3 m post 0.3 m square at (2, 2) under a rotationally symmetric IES lamp 6 m up
    shadows the ground from its foot to (4, 4) (the ray over its top), while the ground beside it keeps
    the table's illuminance (within 3 %)."""
    from camgen.render.renderer import View
    from camgen.render.scene_graph import build_scene_graph
    from tests.render.conftest import camera_matrix, look_at, scene_from

    vertical = np.arange(0, 91, 5.0)
    candela = np.array([[1000 * math.cos(math.radians(v)) ** 0.5 if v < 85 else 0.0 for v in vertical]])
    (tmp_path / "round.ies").write_text(ies_text(vertical, [0.0], candela), encoding="latin-1")
    scene = scene_from(
        environment={
            "meshes": [
                {
                    "type": "plane",
                    "name": "ground",
                    "size_m": [100, 100],
                    "material": {"color_rgb": [0.5] * 3, "roughness": 1.0},
                },
                {"type": "box", "name": "post", "size_m": [0.3, 0.3, 3.0], "position_m": [2, 2, 1.5]},
            ]
        },
        lights=[{"type": "lamp", "position_m": [0, 0, HEIGHT_M], "ies_file": "round.ies"}],
    )
    view = View(camera_matrix(F_PX, F_PX, 79.5, 59.5), look_at((0.0, 0.0, 30.0), (0.0, 0.0, 0.0)), 160, 120)
    radiance = renderer.draw(build_scene_graph(scene, lambda path: tmp_path / path), view, ("radiance",)).radiance
    grid = intensity_grid_cd(parse_ies(ies_text(vertical, [0.0], candela)))

    def ground(x_m, y_m):
        column, row = round(79.5 + x_m * F_PX / 30), round(59.5 - y_m * F_PX / 30)
        x, y = (column - 79.5) * 30 / F_PX, -(row - 59.5) * 30 / F_PX
        d = math.sqrt(x * x + y * y + HEIGHT_M**2)
        lit = (
            0.5 / math.pi * float(grid_intensity_cd(grid, math.degrees(math.acos(HEIGHT_M / d)), 0.0)) * HEIGHT_M / d**3
        )
        return float(radiance[row, column].mean()), lit

    for t in (2.6, 3.0, 3.6):
        measured, lit = ground(t, t)
        assert measured < 0.05 * lit
    measured, lit = ground(-3.0, 0.0)
    assert measured == pytest.approx(lit, rel=0.03)
