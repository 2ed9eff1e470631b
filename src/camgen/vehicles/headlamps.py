"""Headlamps as photometric lights: a low (passing) beam's luminous intensity and when the lamps switch on.

A lit vehicle's head lamps light the road as a spot light (`camgen.render.scene_graph`) whose intensity is
the table `low_beam_table` on the renderer's IES grid (`camgen.world.ies`), aimed level along the vehicle's
heading, the table's C = 0° plane up (C = 90° to the vehicle's left). The beam is a smooth fit to the test
points of UN ECE Regulation No. 112 (headlamps emitting an asymmetrical passing beam, 01 series, §6.2, class
B, right-hand traffic; `R112_CLASS_B_CD`): a hot spot of 18 000 cd at 1.5° right and 1.5° down, a sharp
cut-off at 0.57° down on the left rising at 15° on the right, about 250 cd of glare above it (zone III and
B50L allow ≤ 625 and ≤ 350 cd), and a foreground falling off below the hot spot. Its flux is about 570 lm a
lamp (`low_beam_flux_lm`): a halogen H7 bulb gives 1 350–1 500 lm, of which a reflector headlamp sends
roughly 40 % into the beam (an estimate; LED low beams emit a like flux). Right-hand traffic: a scene in
a left-hand-traffic country shows the beam mirrored from the truth (the cut-off steps up on the wrong side).

A car's two head lamps, 1.1–1.5 m apart, are one light midway between them carrying both beams (the renderer
shades at most `camgen.config.scene.MAX_LIGHTS["spot"]` spot lights with their shadow maps): at a point d
metres ahead the two lamps' directions differ by about 0.7 m / d, so beyond a few metres the pool is the
pair's; nearer, it lacks the two lamps' separate lobes. A motorcycle has one lamp of the same beam (UN ECE
R113 class B–D motorcycle passing beams are of that order, an estimate). A bicycle's lamp (about 10 cd,
`camgen.vehicles.LAMP_LUMINANCE_CD_M2`) lights the road too little to draw: it only glows. Tail, brake and
indicator lamps (4–350 cd, UN ECE R7 and R6) only glow as well: at 2 m their light adds under 0.1 lx.

`auto` lamps (`camgen.config.scene.VehicleIdentity.lights_on`) switch on where the daylight on the ground
is under `AUTO_ON_BELOW_LUX`, for a vehicle that is driven (a parked car stays dark). Nothing here touches
OpenGL or files.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from datetime import timedelta
from functools import lru_cache

import numpy as np

from camgen.config.scene import AmbientLight, Scene, SunLight
from camgen.world.ies import flux_lm, grid_angles_deg

AUTO_ON_BELOW_LUX = 1000.0
"""Horizontal daylight illuminance under which `auto` head lamps are lit, lux: UN ECE Regulation No. 48
(06 series, §6.2.7.6.2, automatic switching of the passing beam) requires the passing beam on within 2 s
below 1 000 lx of ambient light and off again within 5–300 s above 7 000 lx; one level here (no hysteresis)."""
BEAM_VISIBLE_FRACTION = 0.01
"""A headlamp's light is drawn (a spot light of the renderer) only where its brightest illuminance on the
road is at least this share of the daylight's horizontal illuminance at some time of the sequence
(`beam_drawn`): below it the pool is invisible (DESIGN: skip what a scene does not need), and a spot light
costs a shadow-map pass a draw."""
R112_CLASS_B_CD = {
    "B50L": (-3.43, 0.57, None, 350.0),
    "BR": (2.5, 1.0, None, 1750.0),
    "75R": (1.15, -0.57, 10_100.0, None),
    "75L": (-3.43, -0.57, None, 10_600.0),
    "50L": (-3.43, -0.86, None, 13_200.0),
    "50R": (1.72, -0.86, 10_100.0, None),
    "50V": (0.0, -0.86, 5_100.0, None),
    "25L": (-9.0, -1.72, 1_700.0, None),
    "25R": (9.0, -1.72, 1_700.0, None),
}
"""UN ECE Regulation No. 112 (01 series), §6.2, the passing beam's test points for a class B headlamp in
right-hand traffic: name → (horizontal angle, degrees, positive to the right; vertical angle, degrees,
positive up; minimum cd or None; maximum cd or None). Zone III (above the cut-off, towards oncoming drivers'
eyes) allows at most `R112_ZONE_III_MAX_CD`."""
R112_ZONE_III_MAX_CD = 625.0
LOW_BEAM_PEAK_CD = 18_000.0
"""The hot spot's intensity of one lamp, cd (R112 class B: at least 10 100 cd at 75R and 50R; current
halogen and LED low beams peak at 15–25 kcd, an estimate from published isocandela plots)."""
CUT_OFF_DEG = -0.57
"""The cut-off's level part, degrees from the horizontal (R112 aims the 75R and 75L points 0.57° down)."""
CUT_OFF_RISE_DEG = 15.0
"""The cut-off's rise on the right (kerb) side, degrees from the horizontal, up to `CUT_OFF_TOP_DEG`."""
CUT_OFF_TOP_DEG = 1.0
CUT_OFF_SOFTNESS_DEG = 0.3
"""The cut-off's gradient: intensity falls from the beam's to the glare's over this, degrees."""
GLARE_CD = 250.0
"""The light above the cut-off, cd (under zone III's 625 cd and B50L's 350 cd)."""
BEAM_CONE_DEG = 60.0
"""The beam ends here, degrees from the lamp's axis (the spot light's cone, which sets its shadow map's
field of view: 2·60° + 30° = 150°)."""
HEADLAMP_AHEAD_M = 0.3
"""The light stands this far ahead of the lenses, so the vehicle's own front casts no shadow over its beam: the
light holds still over an exposure (`camgen.render.scene_graph.Headlamp`) while the vehicle drives on, 0.28 m
in half of a 1/25 s exposure at 50 km/h."""


def low_beam_intensity_cd(h_deg: np.ndarray | float, v_deg: np.ndarray | float) -> np.ndarray:
    """One low-beam lamp's luminous intensity towards (h, v), cd; any matching shapes.

    h_deg: horizontal angle from straight ahead, degrees, positive to the right; v_deg: vertical angle,
    degrees, positive up. I = I_peak · min(H(h), 1) · V(v) · S(cut(h) − v) + glare, with H a hot spot of
    3° spread at 1.5° right plus a 12° wide spread of 0.35 of it, V a Gaussian of 1.2° above and 3.5° below
    1.5° down, S a ramp over `CUT_OFF_SOFTNESS_DEG`, glare `GLARE_CD` tapering to 0 at 10° down and 30° up.
    Meets `R112_CLASS_B_CD` (tested)."""
    h = np.asarray(h_deg, dtype=np.float64)
    v = np.asarray(v_deg, dtype=np.float64)
    rise = math.tan(math.radians(CUT_OFF_RISE_DEG))
    cut = np.where(h <= 0, CUT_OFF_DEG, np.minimum(CUT_OFF_DEG + h * rise, CUT_OFF_TOP_DEG))
    spread = np.exp(-0.5 * ((h - 1.5) / 3.0) ** 2) + 0.35 * np.exp(-0.5 * (h / 12.0) ** 2)
    vertical = np.where(v > -1.5, np.exp(-0.5 * ((v + 1.5) / 1.2) ** 2), np.exp(-0.5 * ((v + 1.5) / 3.5) ** 2))
    below = np.clip((cut - v) / CUT_OFF_SOFTNESS_DEG, 0.0, 1.0)
    glare = GLARE_CD * np.exp(-0.5 * (h / 20.0) ** 2) * np.clip((v + 10.0) / 10.0, 0, 1) * np.clip((30 - v) / 30, 0, 1)
    return LOW_BEAM_PEAK_CD * np.minimum(spread, 1.0) * vertical * below + glare


def table_angles_to_lamp_deg(gamma_deg: np.ndarray, c_deg: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(h, v) degrees of the directions (γ, C) of the headlamp's table: γ from the lamp's axis (level,
    straight ahead), C about it from up (C = 0°) towards the vehicle's left (C = 90°)."""
    g, c = np.radians(gamma_deg), np.radians(c_deg)
    up, left, ahead = np.sin(g) * np.cos(c), np.sin(g) * np.sin(c), np.cos(g)
    return np.degrees(np.arctan2(-left, ahead)), np.degrees(np.arcsin(np.clip(up, -1.0, 1.0)))


def low_beam_table() -> np.ndarray:
    """One lamp's I(γ, C) on `camgen.world.ies.grid_angles_deg`'s grid (181, 72), cd, 0 beyond `BEAM_CONE_DEG`."""
    gamma, c = grid_angles_deg()
    G, C = np.meshgrid(gamma, c, indexing="ij")
    h, v = table_angles_to_lamp_deg(G, C)
    return np.where(G <= BEAM_CONE_DEG, low_beam_intensity_cd(h, v), 0.0)


def low_beam_flux_lm() -> float:
    """One lamp's luminous flux, lm, integrated over its table (about 570 lm)."""
    return flux_lm(low_beam_table())


def peak_road_illuminance_lux(height_m: float, lamps: int) -> float:
    """The brightest horizontal illuminance `lamps` lamps at `height_m` give on level ground straight ahead,
    lux: max over d of lamps·I(0, −atan(h/d))·h/(d² + h²)^1.5 (inverse-square cosine law)."""
    d = np.linspace(0.5, 100.0, 2000)
    v = -np.degrees(np.arctan2(height_m, d))
    return float(np.max(lamps * low_beam_intensity_cd(0.0, v) * height_m / (d**2 + height_m**2) ** 1.5))


def daylight_horizontal_lux(scene: Scene) -> Callable[[float], float]:
    """time_s → the daylight's illuminance on level ground at `scene`'s time `time_s` after its first frame,
    lux: each sun light's E·sin(elevation) and each ambient light's E, street lamps and headlamps excluded
    (a car's light sensor looks at the sky). With a site whose daylight changes (not a night sky) the suns'
    and sky's levels follow the site's model as the renderer's do (`camgen.render.scene_graph.SiteDaylightTrack`:
    each scaled by the model's value over its first frame's)."""
    suns = [light for light in scene.lights if isinstance(light, SunLight)]
    ambient_lux = sum(light.illuminance_lux for light in scene.lights if isinstance(light, AmbientLight))
    held = sum(s.illuminance_lux * math.sin(math.radians(s.elevation_deg)) for s in suns) + ambient_lux
    site, sky = scene.environment.site, scene.environment.sky
    if site is None or scene.environment.night_sky is not None:
        return lambda time_s: held
    from camgen.world.site import site_daylight

    start = site_daylight(site.latitude_deg, site.longitude_deg, site.time, site.north_deg, sky)

    @lru_cache(maxsize=256)  # each time is asked for by every vehicle, at each of its placements
    def at(time_s: float) -> float:
        now = site_daylight(
            site.latitude_deg, site.longitude_deg, site.time + timedelta(seconds=time_s), site.north_deg, sky
        )
        sun_ratio = now.sun_illuminance_lux / start.sun_illuminance_lux if start.sun_illuminance_lux > 0 else 0.0
        sky_ratio = now.sky_illuminance_lux / start.sky_illuminance_lux if start.sky_illuminance_lux > 0 else 0.0
        elevation = math.radians(max(now.elevation_deg, 0.0))
        return sum(s.illuminance_lux for s in suns) * sun_ratio * math.sin(elevation) + ambient_lux * sky_ratio

    return at


class AutoHeadlamps:
    """`lights_on: auto`: a driven vehicle's lamps lit while the daylight is under `AUTO_ON_BELOW_LUX`."""

    def __init__(self, daylight_lux: Callable[[float], float], driven: bool):
        self.daylight_lux, self.driven = daylight_lux, driven

    def __call__(self, time_s: float) -> bool:
        return self.driven and self.daylight_lux(time_s) < AUTO_ON_BELOW_LUX


def lit_at(lights_on: bool | Callable[[float], bool], time_s: float) -> bool:
    """Whether head and tail lamps switched `lights_on` (a fixed choice or `AutoHeadlamps`) shine at `time_s`."""
    return bool(lights_on(time_s)) if callable(lights_on) else bool(lights_on)


__all__ = [
    "AUTO_ON_BELOW_LUX",
    "BEAM_CONE_DEG",
    "BEAM_VISIBLE_FRACTION",
    "HEADLAMP_AHEAD_M",
    "LOW_BEAM_PEAK_CD",
    "R112_CLASS_B_CD",
    "R112_ZONE_III_MAX_CD",
    "AutoHeadlamps",
    "daylight_horizontal_lux",
    "lit_at",
    "low_beam_flux_lm",
    "low_beam_intensity_cd",
    "low_beam_table",
    "peak_road_illuminance_lux",
]
