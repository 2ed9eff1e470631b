"""The background seen through glass (`camgen.render.renderer.composite_background`): the sky and the far
ground are filled in after the draw, so the draw keeps, in its alpha, the share 1 − τ of each pixel that
surfaces cover (glass blends its alpha as coverage), and a pixel seen through a sedan's two side windows
is its glass's reflection R plus τ times the sky or far ground behind, and in fog Koschmieder's law over
both stretches of air, before and behind the glass (`fogged_radiance`).

R and τ are measured from the GPU's blend itself: over a uniform clear colour S the pixel is R + τ·S, so
two draws at S₁ and S₂ give τ = (L₁ − L₂)/(S₁ − S₂) and R = L₁ − τ·S₁."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from camgen.render.renderer import View
from camgen.render.scene_graph import build_scene_graph
from camgen.vehicles.cabin import FRONT_SIDE_T
from tests.render.conftest import camera_matrix, look_at, scene_from

pytestmark = pytest.mark.opengl

WIDTH_PX, HEIGHT_PX, F_PX = 200, 120, 420.0
S1_CD_M2, S2_CD_M2 = 4000.0, 8000.0
FOG_VISIBILITY_M = 40.0
VIEWS = {
    # From 0.6 m, looking up through both side windows at the sky; from 1.8 m, down through them at the
    # ground beyond the 12 m plane (the far ground, from 13 m in front of the camera on).
    "sky": look_at((0.3, -7.0, 0.6), (0.3, 0.0, 1.2)),
    "ground": look_at((0.3, -7.0, 1.8), (0.3, 0.0, 1.1)),
}
K_PX = camera_matrix(F_PX, F_PX, (WIDTH_PX - 1) / 2, (HEIGHT_PX - 1) / 2)


def _scene(*, car: bool = True, sky: str = "uniform", sky_cd_m2: float = S1_CD_M2, far_ground: bool = False, fog=False):
    environment = {
        "sky": sky,
        "sky_luminance_cd_m2": sky_cd_m2,
        "shadows": False,
        "ground_to_horizon": far_ground,
        "meshes": [{"type": "plane", "name": "ground", "size_m": [12, 12], "material": {"color_rgb": [0.1] * 3}}],
    }
    if fog:
        environment["fog"] = {"visibility_m": FOG_VISIBILITY_M}
    vehicle = {"seed": 1, "body_type": "sedan", "colour": "white", "driver": False}
    return scene_from(
        environment=environment,
        lights=[
            {"type": "ambient", "illuminance_lux": 15000},
            {"type": "sun", "illuminance_lux": 60000, "elevation_deg": 40, "azimuth_deg": 200},
        ],
        actors=[{"name": "car", "class": "car", "vehicle": vehicle, "path": {"waypoints_m": [[0, 0]]}}] if car else [],
    )


@pytest.fixture(scope="module")
def glass(renderer):
    """Per view: τ (H, W), R (H, W, 3), the glass's depth (H, W), the pixels seen through both windows,
    the alpha the draw left there, and the draws of the cases. The glass mirrors a uniform sky throughout (the
    CIE sky's map left unused: `SkyMap.update`), so that R measured under the uniform sky is the glass's
    reflection under the clear sky too; what a CIE sky adds to a reflection is tests/render/test_clearcoat.py's."""
    from camgen.render.renderer import SkyMap

    def no_map(self, graph) -> None:
        self.used = False

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(SkyMap, "update", no_map)
        return _glass(renderer)


def _glass(renderer) -> dict:
    out = {}
    for name, T in VIEWS.items():
        view = View(K_PX, T, WIDTH_PX, HEIGHT_PX)

        def draw(view=view, **kwargs):
            passes = renderer.draw(build_scene_graph(_scene(**kwargs)), view, ("radiance", "depth_m", "instance_id"))
            target = renderer._scratch[(("main", None), WIDTH_PX, HEIGHT_PX, ("radiance", "depth_m", "instance_id"))]
            return passes, target.coverage.copy()  # the draw's alpha

        (one, alpha), (two, _) = draw(sky_cd_m2=S1_CD_M2), draw(sky_cd_m2=S2_CD_M2)
        tau = (one.radiance[..., 1] - two.radiance[..., 1]) / (S1_CD_M2 - S2_CD_M2)
        case = {
            "view": view,
            "tau": tau,
            "R": one.radiance - tau[..., None] * S1_CD_M2,
            "alpha": alpha,
            "opaque_alike": np.array_equal(one.radiance[alpha == 1.0], two.radiance[alpha == 1.0]),
            "depth_m": one.depth_m,
            # Through both side panes (one pane passes at most 0.72), not through paint or the cabin.
            "through": (tau > 0.3) & (tau < 0.6) & (one.instance_id != 0),
        }
        if name == "sky":
            behind = draw(car=False, sky="clear")[0]
            case["seen"] = draw(sky="clear")[0].radiance
            case["fogged"] = draw(sky="clear", fog=True)[0].radiance
            case["airlight"] = draw(car=False, sky="clear", fog=True)[0].radiance  # the sky becomes airlight
        else:
            behind = draw(car=False, far_ground=True)[0]
            case["seen"] = draw(far_ground=True)[0].radiance
            case["fogged"] = draw(far_ground=True, fog=True)[0].radiance
            case["airlight"] = np.full_like(case["R"], S1_CD_M2)  # a uniform sky's
            case["through"] &= behind.instance_id == 0  # the far ground, not the plane
        case["behind"] = behind.radiance
        out[name] = case
    return out


def test_the_draw_s_alpha_is_the_coverage_of_the_glass(glass):
    for name, case in glass.items():
        through, tau = case["through"], case["tau"]
        assert case["opaque_alike"]  # the clear colour changes nothing drawn opaque
        assert through.sum() >= 150, name
        # 1 − alpha is the share of the clear colour the blend kept: (T (1 − F))² per two panes of
        # side glass, F ≥ 4 % Schlick's Fresnel reflectance (about 4 % at the near-normal view).
        assert np.abs(1.0 - case["alpha"][through] - tau[through]).max() < 1e-4
        two_panes = (FRONT_SIDE_T * (1.0 - 0.04)) ** 2
        print(f"{name}: τ median {np.median(tau[through]):.4f}, two panes at normal incidence {two_panes:.4f}")
        assert two_panes * 0.9 < np.median(tau[through]) <= two_panes * 1.001


def _check(measured, expected, wrong, label):
    error = np.abs(measured - expected) / expected
    print(f"{label}: {measured.shape[0]} px, max relative error {error.max():.2e}; the old composite off by "
          f"{np.median(np.abs(wrong - expected) / expected):.2f}")  # fmt: skip
    assert error.max() < 0.02
    assert np.median(np.abs(wrong - expected) / expected) > 0.05  # the case tells the fix from the bug


def test_the_cie_sky_shows_through_the_windows(glass):
    case = glass["sky"]
    up = case["through"]  # the sky view's rays all rise…
    behind = case["behind"][up]
    assert np.all(behind != S1_CD_M2)  # …to the CIE sky, not the clear colour
    expected = case["R"][up] + case["tau"][up][:, None] * behind
    clear = case["R"][up] + case["tau"][up][:, None] * S1_CD_M2  # the bug: the clear colour behind
    _check(case["seen"][up], expected, clear, "CIE sky")


def test_the_far_ground_shows_through_the_windows(glass):
    case = glass["ground"]
    through = case["through"]
    behind = case["behind"][through]
    expected = case["R"][through] + case["tau"][through][:, None] * behind
    clear = case["R"][through] + case["tau"][through][:, None] * S1_CD_M2
    _check(case["seen"][through], expected, clear, "far ground")


def _lengths(view: View) -> np.ndarray:
    """(H, W) |K⁻¹(u, v, 1)|: ray length per metre of camera z."""
    v, u = np.mgrid[0 : view.height_px, 0 : view.width_px].astype(np.float64)
    return np.sqrt(((u - K_PX[0, 2]) / F_PX) ** 2 + ((v - K_PX[1, 2]) / F_PX) ** 2 + 1.0)


def _ground_distance_m(view: View) -> np.ndarray:
    """(H, W) distance along each pixel's ray to the level ground z = 0 (inf where the ray rises)."""
    v, u = np.mgrid[0 : view.height_px, 0 : view.width_px].astype(np.float64)
    rays = np.stack([(u - K_PX[0, 2]) / F_PX, (v - K_PX[1, 2]) / F_PX, np.ones_like(u)], axis=-1)
    world = rays @ view.T_world_from_cam[:3, :3].T
    with np.errstate(divide="ignore"):
        depth = np.where(world[..., 2] < 0, view.T_world_from_cam[2, 3] / -world[..., 2], np.inf)
    return depth * np.linalg.norm(rays, axis=-1)


@pytest.mark.parametrize("name", ["sky", "ground"])
def test_fog_lies_before_and_behind_the_glass(glass, name):
    """L = t_g·R + τ·(t_B·B + (t_g − t_B)·A) + (1 − t_g)·A, Koschmieder's t = exp(−ln 50·d/V) over the
    glass's distance d_g and the background's d_B (the sky: t_B = 0); A the airlight (the horizon sky's
    radiance in the pixel's azimuth: the sky itself in fog)."""
    case = glass[name]
    through = case["through"]
    beta = math.log(50.0) / FOG_VISIBILITY_M
    t_g = np.exp(-beta * (case["depth_m"] * _lengths(case["view"])))[through][:, None]
    d_b = _ground_distance_m(case["view"])[through] if name == "ground" else np.full(through.sum(), np.inf)
    assert np.all(np.isfinite(d_b)) == (name == "ground")
    t_b = np.exp(-beta * d_b)[:, None]
    tau, R, A, B = (case[key][through] for key in ("tau", "R", "airlight", "behind"))
    tau = tau[:, None]
    assert np.all(A != S1_CD_M2) == (name == "sky")  # a clear sky's airlight is not its zenith's
    expected = t_g * R + tau * (t_b * B + (t_g - t_b) * A) + (1.0 - t_g) * A
    # The bugs: under the sky, the clear colour behind the glass, fogged at the glass; over the ground,
    # the far ground fogged as if it lay at the glass.
    wrong = t_g * (R + tau * (S1_CD_M2 if name == "sky" else B)) + (1.0 - t_g) * A
    _check(case["fogged"][through], expected, wrong, f"fog, {name}")


def test_glass_casts_no_shadow(renderer, monkeypatch):
    """A low sun across the sedan shines through both side windows onto the ground beyond, lit there as if
    nothing stood in the way (glass passes about 75 %: nearer the truth than the full shadow that the
    windows cast when the shadow-map pass drew them, as pyrender's does)."""
    import pyrender

    from camgen.render import renderer as renderer_module

    def scene(shadows: bool):
        return scene_from(
            environment={
                "sky_luminance_cd_m2": 5000,
                "shadows": shadows,
                "ground_to_horizon": False,
                "meshes": [
                    {"type": "plane", "name": "ground", "size_m": [16, 16], "material": {"color_rgb": [0.3] * 3}}
                ],
            },
            lights=[
                {"type": "ambient", "illuminance_lux": 10000},
                {"type": "sun", "illuminance_lux": 60000, "elevation_deg": 20, "azimuth_deg": 90},
            ],
            actors=[
                {
                    "name": "car",
                    "class": "car",
                    "vehicle": {"seed": 1, "body_type": "sedan", "driver": False},
                    "path": {"waypoints_m": [[0, 0]]},
                }
            ],
        )

    view = View(camera_matrix(150, 150, 79.5, 59.5), look_at((0.0, 0.0, 12.0), (0.0, 0.01, 0.0)), 160, 120)
    passes = ("radiance", "instance_id")
    lit = renderer.draw(build_scene_graph(scene(True)), view, passes)
    unshadowed = renderer.draw(build_scene_graph(scene(False)), view, passes).radiance[..., 1]
    own = renderer_module._PassRenderer._bind_and_draw_primitive

    def glass_in_the_shadow_maps(self, primitive, pose, program, flags):
        if flags & renderer_module.RenderFlags.DEPTH_ONLY:
            return pyrender.Renderer._bind_and_draw_primitive(self, primitive, pose, program, flags)
        return own(self, primitive, pose, program, flags)

    monkeypatch.setattr(renderer_module._PassRenderer, "_bind_and_draw_primitive", glass_in_the_shadow_maps)
    blocked = renderer.draw(build_scene_graph(scene(True)), view, passes).radiance[..., 1]
    car = lit.instance_id[60, 80]
    ground = (lit.instance_id != 0) & (lit.instance_id != car)
    shadow = ground & (blocked < 0.5 * unshadowed)  # the car's shadow with its windows opaque to the sun
    through = shadow & (lit.radiance[..., 1] > 0.98 * unshadowed)
    print(f"the car's shadow {shadow.sum()} px, lit through the windows {through.sum()} px")
    assert shadow.sum() > 1000 and through.sum() >= 30
    # Elsewhere the ground is as it was, but for the soft (filtered) edges of the shadow.
    changed = ground & (lit.radiance[..., 1] != blocked)
    near_shadow = cv2.dilate(shadow.astype(np.uint8), np.ones((5, 5), np.uint8)).astype(bool)
    assert changed.sum() >= through.sum() and np.all(near_shadow[changed])
