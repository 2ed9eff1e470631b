"""Scene: the world (meshes, lights), what moves in it (actors) and the cameras that watch it.

World frame: right-handed, Z up, metres, ground at z = 0 (DESIGN.md "Conventions").
"""

from __future__ import annotations

import itertools
import math
from datetime import date, datetime, timedelta
from typing import Annotated, Any, Literal

from pydantic import (
    ConfigDict,
    Field,
    ValidationError,
    ValidatorFunctionWrapHandler,
    field_validator,
    model_validator,
)

from camgen.config.base import Model, Why, invalid
from camgen.config.kerbs import Kerb, kerb_names
from camgen.config.markings import Marking, marking_names
from camgen.config.profile import ZoomSweepTime
from camgen.config.props import Prop, ScatterRule
from camgen.config.ptz_program import FollowProgram, PtzPreset, PtzProgram, program_presets
from camgen.config.validation import show_value
from camgen.config.world import WORLD_EXTENT_M, Length, Point2, Point3

# Lights the renderer shades per type. Sun and spot lights each need a shadow-map texture unit;
# OpenGL 3.3 guarantees 16 units, of which pyrender reserves 6, so 4 of each fit anywhere.
MAX_LIGHTS = {"sun": 4, "spot": 4, "point": 16}
"""Lamps are spot lights to the renderer: `spot` counts spot and lamp lights together."""

PositiveFloat = Annotated[float, Field(gt=0)]
NonNegativeFloat = Annotated[float, Field(ge=0)]
Fraction = Annotated[float, Field(ge=0, le=1)]
Angles3 = tuple[float, float, float]
Name = Annotated[str, Field(min_length=1, max_length=64, pattern=r"^[A-Za-z0-9_.-]+$")]
Luminance = Annotated[
    float,
    Field(ge=0, le=2e9),
    Why("nothing a camera sees is brighter than the sun's disc, 1.6e9 cd/m², so 0–2e9 cd/m²"),
]
"""A luminance, cd/m²."""
Intensity = Annotated[
    float,
    Field(gt=0, le=1e8),
    Why("the brightest lamps, lighthouse and searchlight beams, reach about 1e7 cd, so at most 1e8 cd"),
]
"""A luminous intensity, cd."""
Speed = Annotated[
    float,
    Field(ge=0.01, le=100),
    Why("an actor moves at 0.01–100 m/s (1 cm/s to a fast car); one that stands still has a single waypoint"),
]
"""An actor's speed, m/s."""


class SurfaceTexture(Model):
    """A procedural texture over a plane's or a box's faces (`camgen.world.textures` cites sizes and
    reflectances): the material's colour is its mean reflectance, the texture the variation around it."""

    type: Literal["asphalt", "paving", "concrete", "grass", "gravel", "brick", "facade"]
    seed: Annotated[int, Field(ge=0)] = 0
    """Draws the texture's grain, patches and cracks; two surfaces with one seed look alike."""
    tile_m: (
        Annotated[float, Field(ge=0.5, le=100), Why("one repeat of a pattern: from 0.5 m to a 100 m site")] | None
    ) = None
    """Size of one repeat of the texture, m; null: the type's own (8 m of asphalt, 4 m of paving, …)."""


TileLength = Annotated[
    float,
    Field(gt=0, le=1000),
    Why("one repeat of an image on the surface: more than 0 m (a photo of a few bricks is about 1 m), at most 1 km"),
]


class FileTexture(Model):
    """A texture from image files over a plane's or a box's faces (a photo-scanned asphalt or brick set,
    such as ambientCG's or Poly Haven's CC0 ones): base colour, and optionally a normal and a roughness
    map of the same size. Paths are relative to the scene file. The image's top edge lies along the
    face's +v edge: +Y on a level plane, up the wall on a box's sides (`camgen.render.scene_graph`)."""

    type: Literal["file"]
    base_color_file: Annotated[str, Field(min_length=1)]
    """An 8- or 16-bit PNG, JPEG or TIFF, sRGB-encoded (as photos and glTF base-colour maps are), RGB,
    RGBA (alpha ignored) or grey; its decoded (linear) texels are the surface's reflectance."""
    normal_file: Annotated[str, Field(min_length=1)] | None = None
    """A tangent-space normal map, OpenGL convention (+X right, +Y up the image, +Z out of the surface;
    a DirectX map, "-Y", has its green channel inverted: flip it first), stored linearly, RGB."""
    roughness_file: Annotated[str, Field(min_length=1)] | None = None
    """A grey roughness map (stored linearly, 0 smooth to 1 rough); null: the material's roughness."""
    tile_m: TileLength | tuple[TileLength, TileLength]
    """Size of one repeat of the image on the surface, m: its width (the height follows from the image's
    aspect ratio) or [width, height]. ambientCG and Poly Haven give each set's real-world size."""


class Material(Model):
    """A PBR metallic-roughness material; colours are linear (not sRGB-encoded) reflectances."""

    color_rgb: tuple[Fraction, Fraction, Fraction] = (0.5, 0.5, 0.5)
    """Mean linear reflectance; with a texture and no colour given, the texture type's typical one, or
    a file texture's own (its base colour's decoded mean); given, a file's texels are scaled per channel
    to this mean (to calibrate a photo whose exposure is unknown)."""
    roughness: Fraction = 0.8
    metallic: Fraction = 0.0
    emission_cd_m2: Luminance = 0.0
    """Luminance the surface emits by itself (signs, screens, lamps), cd/m²."""
    texture: Annotated[SurfaceTexture | FileTexture, Field(discriminator="type")] | None = None
    """A procedural texture, or image files (`type: file`); planes and boxes (other shapes keep the
    plain colour)."""
    nir_reflectance: Fraction | None = None
    """Reflectance at 850 nm, what a camera in IR night mode sees (vegetation ≈ 0.45, skin ≈ 0.6,
    asphalt ≈ 0.14, carbon-black paint ≈ 0.05); null: the texture type's (`camgen.world.night.
    NIR_REFLECTANCE_BY_TEXTURE`), or else the colour's red reflectance (`default_nir_reflectance`)."""


class Placement(Model):
    position_m: Point3 = (0.0, 0.0, 0.0)
    rotation_deg: Angles3 = (0.0, 0.0, 0.0)
    """Rotation about the world X, Y, then Z axes (extrinsic), degrees."""
    material: Material = Material()


class BoxMesh(Placement):
    type: Literal["box"]
    name: Name
    size_m: tuple[Length, Length, Length]
    """Extents along the local X, Y, Z axes, m; the box is centred on position_m."""


class CylinderMesh(Placement):
    type: Literal["cylinder"]
    name: Name
    radius_m: Length
    height_m: Length
    """Along the local Z axis, centred on position_m."""


class SphereMesh(Placement):
    type: Literal["sphere"]
    name: Name
    radius_m: Length


class PlaneMesh(Placement):
    type: Literal["plane"]
    name: Name
    size_m: tuple[Length, Length]
    """Extents along the local X and Y axes, m; the plane faces local +Z."""


class CheckerboardMesh(Placement):
    type: Literal["checkerboard"]
    name: Name
    squares: tuple[Annotated[int, Field(ge=2, le=100)], Annotated[int, Field(ge=2, le=100)]]
    """Squares along local X and Y (a board with 10×7 squares has 9×6 inner corners)."""
    square_size_m: Length
    """Edge of one square, m. The board lies in its local XY plane, facing +Z, centred on position_m."""
    border_m: (
        Annotated[float, Field(ge=0, le=2 * WORLD_EXTENT_M), Why(f"at most the world's {2 * WORLD_EXTENT_M:g} m")]
        | None
    ) = None
    """Width of the light margin around the squares (detectors need it), m; null is one square."""
    dark_color_rgb: tuple[Fraction, Fraction, Fraction] = (0.03, 0.03, 0.03)
    """Linear reflectance of the dark squares; the light squares and the margin use material.color_rgb."""

    @property
    def border_width_m(self) -> float:
        return self.square_size_m if self.border_m is None else self.border_m


class CharacterAnimation(Model):
    """How an actor's glTF character is animated (`camgen.actors.character`): a clip played by the
    distance walked while the actor moves, another (or the same pose held) while it stands."""

    clip: Annotated[str, Field(min_length=1)] | None = None
    """The animation played while the actor moves; null: the file's first animation."""
    idle_clip: Annotated[str, Field(min_length=1)] | None = None
    """The animation played, in time, while the actor stands; null: the moving clip holds its pose."""
    clip_speed_m_s: (
        Annotated[float, Field(gt=0, le=15), Why("a person runs at most about 12 m/s (Bolt's peak, 2009)")] | None
    ) = None
    """Ground speed the moving clip was animated for, m/s; one loop then covers this × its duration.
    null: measured from the clip's own travel (a clip that walks in place needs it)."""


class FileMesh(Placement):
    type: Literal["file"]
    name: Name
    path: str
    """Mesh file (glTF, OBJ, PLY, STL, …), relative to the scene file. An actor's glTF file with a
    skin or animations is a character: skinned and animated (`animation`) as the actor walks. glTF's
    axes (+Y up, front +Z) become the actor's (z up, x forward)."""
    scale: Annotated[
        float,
        Field(ge=1e-6, le=1000),
        Why("a scale turns the file's units into metres: 0.001 for millimetres, 1000 for kilometres; 1e-6–1000"),
    ] = 1.0
    animation: CharacterAnimation | None = None
    """For an actor's glTF character: which clips play (null: the file's first, by distance walked)."""


Mesh = Annotated[
    BoxMesh | CylinderMesh | SphereMesh | PlaneMesh | CheckerboardMesh | FileMesh,
    Field(discriminator="type"),
]


def _illuminance_from_site(schema: dict[str, Any]) -> None:
    """JSON Schema: illuminance_lux may be left out, for a scene's `environment.site` gives it (the scene
    fills it in before its lights are validated, `Scene._daylight_from_site`)."""
    schema["required"] = [key for key in schema.get("required", []) if key != "illuminance_lux"]


class SunLight(Model):
    model_config = ConfigDict(json_schema_extra=_illuminance_from_site)

    type: Literal["sun"]
    illuminance_lux: Annotated[float, Field(gt=0, le=200_000)]
    """Illuminance on a surface facing the sun, lux (clear noon ≈ 100 000). With `environment.site`
    it may be left out: the site's clear-sky model gives it (`camgen.world.daylight`)."""
    azimuth_deg: float = 135.0
    """Direction of the sun from the scene, counter-clockwise from +X, degrees. With
    `environment.site` leave it (and elevation_deg) out: the site places the sun."""
    elevation_deg: Annotated[float, Field(gt=0, le=90)] = 45.0
    color_rgb: tuple[Fraction, Fraction, Fraction] = (1.0, 1.0, 1.0)


class PointLight(Model):
    type: Literal["point"]
    position_m: Point3
    intensity_cd: Intensity
    """Luminous intensity, candela (a 1000 lm isotropic lamp ≈ 80 cd). Casts no shadows."""
    color_rgb: tuple[Fraction, Fraction, Fraction] = (1.0, 1.0, 1.0)


class SpotLight(Model):
    type: Literal["spot"]
    position_m: Point3
    target_m: Point3
    intensity_cd: Intensity
    cone_half_angle_deg: Annotated[float, Field(gt=0, lt=90)] = 30.0
    """Where the beam ends; it is at full intensity within 80 % of this angle and fades to the edge."""
    color_rgb: tuple[Fraction, Fraction, Fraction] = (1.0, 1.0, 1.0)


class LampLight(Model):
    """A street lamp by its luminous flux: a round beam of the spot light's shape whose peak intensity
    carries `flux_lm` lumens (`camgen.world.night.peak_intensity_cd`); casts shadows like a spot."""

    type: Literal["lamp"]
    position_m: Point3
    """The lamp head's light centre (a street lantern: 4–12 m up)."""
    target_m: Point3 | None = None
    """Where the beam's axis points; null: straight down, to the ground under the head."""
    flux_lm: (
        Annotated[
            float,
            Field(gt=0, le=2e6),
            Why(
                "street and area lights emit about 1 000–60 000 lm, stadium floodlights up to about 2e5; at most 2e6 lm"
            ),
        ]
        | None
    ) = None
    """Luminous flux leaving the luminaire, lm (a residential LED lantern ≈ 3000–6000, a main road 10 000–20 000).
    With `ies_file` it rescales the file's table to this flux; null: the file's own."""
    ies_file: Annotated[str, Field(min_length=1)] | None = None
    """An IES LM-63 photometric file (type C, TILT=NONE; `camgen.world.ies`), relative to the scene's
    directory: the lamp's intensity I(γ, C) is the file's table (γ from the beam axis, C about it), in
    place of the round cone. Shadows are cast within 85° of the axis (the shadow map's field of view)."""
    c0_azimuth_deg: Annotated[float, Field(ge=-360, le=360), Why("a direction, −360° to 360°")] = 0.0
    """Where the file's C = 0° plane points (a street lantern's: along the road), counter-clockwise
    from +X, degrees; C grows counter-clockwise seen from above (C = 90°: the street side)."""
    cone_half_angle_deg: Annotated[
        float,
        Field(gt=1, lt=89),
        Why("a beam's half angle lies between 1° and 89° (a lamp lighting a hemisphere is a point light)"),
    ] = 70.0
    """Where the beam ends; full intensity within 80 % of it. 70°: a street lantern (EN 13201-2 G-classes
    limit the intensity above 70°). Unused with `ies_file` (the table shapes the beam)."""
    color_rgb: tuple[Fraction, Fraction, Fraction] = (1.0, 1.0, 1.0)

    @property
    def direction(self) -> tuple[float, float, float]:
        """Unit-free vector along the beam's axis, world."""
        target = self.target_m if self.target_m is not None else (self.position_m[0], self.position_m[1], 0.0)
        return tuple(t - p for t, p in zip(target, self.position_m, strict=True))

    @model_validator(mode="after")
    def _check(self) -> LampLight:
        if self.flux_lm is None and self.ies_file is None:
            raise invalid(
                "flux_lm", "is missing: give the lamp's luminous flux in lumens, or an ies_file whose table gives it"
            )
        if all(abs(c) < 1e-9 for c in self.direction):
            raise invalid(
                "target_m" if self.target_m is not None else "position_m",
                "leaves the beam no direction (the target is the lamp's own position, or the lamp stands on "
                "the ground with no target): give a target_m away from position_m, or raise the lamp",
            )
        return self


class AmbientLight(Model):
    model_config = ConfigDict(json_schema_extra=_illuminance_from_site)

    type: Literal["ambient"]
    illuminance_lux: Annotated[float, Field(gt=0, le=200_000)]
    """Uniform illuminance from the whole sky, lux (overcast day ≈ 10 000, dusk ≈ 10). With
    `environment.site` it may be left out: the sky's horizontal illuminance at the site's time."""


Light = Annotated[SunLight | PointLight | SpotLight | LampLight | AmbientLight, Field(discriminator="type")]


class Site(Model):
    """Where on Earth and when the scene is. The sun light's direction follows (`camgen.world.sun`,
    NOAA's solar calculator), and so do, where the scene leaves them out, the sun light's and an ambient
    light's illuminance and the sky's zenith luminance (`camgen.world.daylight`: the IES daylight model
    for the scene's sky; `uniform` takes the clear sky's). The values are the first frame's; the sun
    moves on with the sequence's time, and when daylight changes over it by more than 0.5° or 1 %
    (`camgen.world.site.daylight_change`) each frame is lit for its own time, every light and the sky
    scaled as the model's value (an illuminance the scene gives itself sets the level). The model ends
    at sunset: a sequence that starts or ends with the sun below the horizon is refused, unless the
    scene is a night scene (`Environment.night_sky`), whose sun must then stay 12° or more below it."""

    latitude_deg: Annotated[float, Field(ge=-90, le=90), Why("latitudes run from −90 (south pole) to 90 (north)")]
    """Degrees north of the equator (south negative)."""
    longitude_deg: Annotated[
        float, Field(ge=-180, le=180), Why("longitudes run from −180 to 180, east of Greenwich positive")
    ]
    """Degrees east of Greenwich (west negative)."""
    time: datetime
    """When the scene's first frame is, with its UTC offset (ISO 8601): '2026-06-21T14:30:00+02:00'."""
    north_deg: Annotated[float, Field(ge=-360, le=360), Why("a direction, −360° to 360°")] = 90.0
    """Where geographic north lies in the scene, counter-clockwise from +X, degrees; the default
    puts north along +Y and east along +X, as on a map."""

    @field_validator("time", mode="wrap")
    @classmethod
    def _aware_time(cls, value: Any, handler: ValidatorFunctionWrapHandler) -> datetime:
        example = "write it as '2026-06-21T14:30:00+02:00' (Z for UTC)"
        if isinstance(value, date) and not isinstance(value, datetime):
            raise invalid("", f"must be a date and time, got the date {value.isoformat()} alone; {example}")
        try:
            time = handler(value)
        except ValidationError:
            raise invalid("", f"must be a date and time, got {value!r}; {example}") from None
        if time.tzinfo is None or time.utcoffset() is None:
            raise invalid(
                "", f"must say its UTC offset (the sun depends on it), got {time.isoformat()} without one; {example}"
            )
        return time


class Fog(Model):
    """Fog or haze over the whole scene: Koschmieder's law on each pixel's distance (`camgen.world.fog`)."""

    visibility_m: Annotated[
        float,
        Field(ge=1, le=200_000),
        Why("visual ranges run from a few metres in the thickest fog to about 200 km in the cleanest air; 1 m–200 km"),
    ]
    """Visual range V, m: the distance at which a black object's contrast against the horizon falls to
    2 % (Koschmieder: transmittance exp(−3.912 d / V)); the WMO's meteorological optical range (5 %) is
    0.766 V. Fog is under 1000 m, mist and haze 1–10 km, clear air 20 km and more."""


class Rain(Model):
    """Rain over the whole scene (`camgen.world.rain`): Marshall–Palmer drops falling at their terminal
    speed, drawn as streaks in each frame's exposure near the camera and as haze beyond; the ground is wet."""

    rate_mm_h: Annotated[
        float,
        Field(gt=0, le=500),
        Why("rain rates run from a drizzle's 0.1 mm/h to about 300 mm/h in the heaviest hourly downpours; 0–500"),
    ]
    """Rain rate R, mm/h: light up to 2.5, moderate 2.5–7.6, heavy above 7.6 (AMS Glossary; WMO-No. 8 §14.2.1)."""
    seed: Annotated[int, Field(ge=0)] = 0
    """Draws the drops; the same seed gives the same rain."""


class Snow(Model):
    """Snow over the whole scene (`camgen.world.snow`): Gunn–Marshall aggregate flakes falling at their
    Locatelli–Hobbs speed and drifting with `wind`, drawn as short soft streaks in each frame's exposure near
    the camera and as haze beyond (the visibility of Rasmussen et al. 1999, unless `fog` sets one)."""

    rate_mm_h: Annotated[
        float,
        Field(gt=0, le=25),
        Why(
            "snowfall rates run, as melted water, from a flurry's 0.1 mm/h to about 10 mm/h in the heaviest "
            "snowstorms (heavy snow: visibility under 0.5 km, Rasmussen et al. 1999); 0–25 mm/h"
        ),
    ]
    """Snowfall rate as liquid-water equivalent (the water a gauge melts it into), mm/h. The US NWS names
    snow light at a visibility of 1 km or more, moderate at 0.5–1 km, heavy under 0.5 km; through Rasmussen et
    al.'s relation (`camgen.world.snow`) dry snow is light under 0.8 mm/h, heavy over 1.6. 1 mm/h of water is
    about 1 cm/h of fresh snow on the ground (the rule of thumb of 10:1)."""
    seed: Annotated[int, Field(ge=0)] = 0
    """Draws the flakes; the same seed gives the same snow."""
    kind: Literal["dry", "wet"] = "dry"
    """dry: cold snow of light dendrite aggregates (bulk density 0.017 g cm⁻² / D, falling about 1 m/s);
    wet: near-melting or rimed snow, denser (0.072 g cm⁻² / D) and falling about 2 m/s, so half as large
    for the same water and about 8 times clearer (Rasmussen et al. 1999)."""


class Wind(Model):
    """Wind over the whole scene: trees and bushes sway in it and their leaves flutter
    (`camgen.props.sway`); its gusts are drawn from the scene's seed (or `seed`). Calm (no wind, or
    speed_m_s 0) leaves every prop still and every frame as without it."""

    speed_m_s: Annotated[
        float,
        Field(ge=0, le=40),
        Why("mean wind speeds run from calm (0) to hurricane force (Beaufort 12, ≥ 32.7 m/s; WMO-No. 8); 0–40 m/s"),
    ]
    """Mean wind speed near the crowns, m/s. Beaufort (WMO-No. 8): 3.4–5.4 gentle breeze (leaves and twigs
    in constant motion), 8.0–10.7 fresh breeze (small trees in leaf sway), 13.9–17.1 near gale (whole
    trees in motion)."""
    direction_deg: Annotated[float, Field(ge=-360, le=360), Why("a direction, −360° to 360°")] = 0.0
    """The direction the wind blows towards, counter-clockwise from +X like the scene's other azimuths,
    degrees (a meteorological wind direction names where it comes from: add 180° and turn it into the
    scene's frame)."""
    turbulence_intensity: Annotated[
        float,
        Field(ge=0, le=0.6),
        Why(
            "the turbulence intensity σ_u/U is 0.1–0.2 over open country and 0.3–0.45 among buildings "
            "(EN 1991-1-4 §4.4, I_v = 1/ln(z/z0)); 0–0.6"
        ),
    ] = 0.3
    """Gustiness: the standard deviation of the wind speed over its mean (σ_u/U); EN 1991-1-4 §4.4 gives
    I_v = 1/ln(z/z0) at height z over terrain of roughness length z0: 0.29 at 10 m in suburbs (z0 =
    0.3 m), 0.43 in city centres (z0 = 1 m). 0: a steady wind (the trees still sway at their own
    frequency)."""
    seed: Annotated[int, Field(ge=0)] | None = None
    """Draws the gusts; null derives it from the scene's seed. The same seed gives the same gusts."""


class Environment(Model):
    sky_luminance_cd_m2: Luminance = 0.0
    """Luminance of the background where no geometry is hit, cd/m² (clear day sky ≈ 5000); for a CIE
    sky (`sky`), the zenith's. With a `site` it may be left out: the zenith luminance whose sky gives the
    site's sky illuminance."""
    site: Site | None = None
    """Where and when the scene is: places the sun light and gives the daylight levels left out."""
    fog: Fog | None = None
    """Fog or haze by meteorological visibility; null: clear air."""
    rain: Rain | None = None
    """Rain by its rate (`camgen.world.rain`); null: dry."""
    snow: Snow | None = None
    """Snow by its melted rate (`camgen.world.snow`); null: none. Not with `rain` (sleet is not modelled)."""
    wind: Wind | None = None
    """Wind by its speed, direction and gustiness: trees and bushes sway and their leaves flutter
    (`camgen.props.sway`); null: calm, every prop still."""
    wet: bool | None = None
    """Wet ground: level planes facing up darken and get smoother (`camgen.world.rain.WET_ALBEDO_FACTOR`,
    `WET_ROUGHNESS_FACTOR`); null: wet while it rains."""
    sky: Literal["uniform", "clear", "partly_cloudy", "overcast"] = "uniform"
    """How the sky's luminance and colour vary over it: one luminance everywhere, or a CIE standard
    general sky (`camgen.world.sky`: clear, type 12; partly cloudy, type 7; overcast, type 1) whose
    sun is the scene's sun light."""
    meshes: list[Mesh] = []
    props: list[Prop] = []
    """Trees, bushes, benches, bins, bollards, lamp posts, signs and fences (`camgen.config.props`), each
    ``{type, position_m, heading_deg, seed, …}``: environment geometry that casts and receives shadows
    (trees and bushes sway in `wind`), with instance ids after the meshes' (not annotated)."""
    scatter: list[ScatterRule] = []
    """Props placed by rule (`camgen.props.scatter`): ``{type, along: [[x, y], …], spacing_m}`` or
    ``{type, region_m: [[x0, y0], [x1, y1]], count}``, with ``seed`` and ``min_gap_m``; the same seed
    places the same props. Their instance ids follow the props'."""
    markings: list[Marking] = []
    """Painted road markings (`camgen.config.markings`): ``{type: line, along_m: [[x, y], …]}`` (solid, or
    dashed with ``dash_m`` and ``gap_m``), ``{type: bays, first_centre_m, heading_deg, count}`` (a row of
    parking bays) and ``{type: crossing, from_m, to_m}`` (a zebra crosswalk from kerb to kerb), white or
    yellow, worn from a seed. Ground, not occluders: they receive shadows but cast none, leave coverage and
    the far ground alone, and take instance ids after the props' (`<type>_<index>` unless named)."""
    kerbs: list[Kerb] = []
    """Kerbs at the road's edge (`camgen.config.kerbs`): ``{along_m: [[x, y], …], road_side}``, the foot of a
    precast concrete kerb's road face (a half-battered HB2, 125 mm upstand, by default) with an open joint every
    914 mm unit. Solid: they cast and receive shadows and hide what lies behind them; instance ids after the
    markings' (`kerb_<index>` unless named). Coverage counts them as occluders (`camgen.coverage.occlusion`)."""
    night_sky: Literal["natural", "rural", "suburban", "urban"] | None = None
    """A night scene: the moonless sky's luminance for its setting (`camgen.world.night.
    NIGHT_SKY_LUMINANCE_CD_M2`: 0.17 mcd/m² natural to 10 mcd/m² urban skyglow) fills in
    sky_luminance_cd_m2 and an ambient light's illuminance (π·L) where they are left out, and a `site`
    is then allowed after dusk: its sun must stay 12° or more below the horizon through the sequence.
    null: a day scene."""
    ground_to_horizon: bool = True
    """Continue the scene's largest level ground plane (facing up, at least 10 × 10 m) to the horizon as a
    uniform backdrop of its mean reflectance (`camgen.render.scene_graph.FarGround`), so that no camera
    sees the plane's edge against the sky; false leaves the sky under the horizon (a stage, a platform)."""
    shadows: bool = True
    """Sun and spot lights cast shadows (shadow maps); point lights never do. Shadows of moving actors
    fall on the environment, so a static camera then renders every frame in full."""

    @model_validator(mode="after")
    def _check_precipitation(self) -> Environment:
        if self.rain is not None and self.snow is not None:
            raise invalid(
                "snow",
                "is set together with rain, but mixed rain and snow (sleet) is not modelled; keep one of "
                "environment.rain and environment.snow",
            )
        return self

    @model_validator(mode="after")
    def _check_marking_names(self) -> Environment:
        taken = {mesh.name for mesh in self.meshes} | {
            prop.name or f"{prop.type}_{i}" for i, prop in enumerate(self.props)
        }
        seen: set[str] = set()
        for key, items, names, others in (
            ("markings", self.markings, marking_names(self.markings), "mesh, prop or marking"),
            ("kerbs", self.kerbs, kerb_names(self.kerbs), "mesh, prop, marking or kerb"),
        ):
            for i, name in enumerate(names):
                if name in taken or name in seen:
                    raise invalid(
                        f"{key}[{i}]" + (".name" if items[i].name else ""),
                        f"is the instance {name!r}, a name another {others} has already; give the {key[:-1]} "
                        "another name",
                    )
                seen.add(name)
        return self


class ActorPath(Model):
    """Motion along ground waypoints, pausing at each: straight legs at constant speed, or a vehicle's
    curve (see `motion`)."""

    waypoints_m: Annotated[list[Point2], Field(min_length=1)]
    """[[x, y], …] on the ground, m. One waypoint: the actor stands still."""
    speed_m_s: Speed = 1.4
    start_s: NonNegativeFloat = 0.0
    """When the actor leaves the first waypoint, s."""
    loop: bool = False
    """Return to the first waypoint and repeat; otherwise stop at the last one."""
    heading_deg: Annotated[float, Field(ge=-360, le=360), Why("a direction, −360° to 360°")] | None = None
    """Which way an actor with a single waypoint (standing or parked) faces, counter-clockwise from +X,
    degrees; null faces +X. An actor that moves faces along its path."""
    pause_s: NonNegativeFloat | list[NonNegativeFloat] = 0.0
    """How long the actor stands at each waypoint it reaches before walking on, s: one number for every
    waypoint, or a list with one per waypoint. A loop also pauses at the first waypoint on each return;
    the wait before the first departure is start_s. The actor keeps the heading it arrived with."""
    motion: Literal["vehicle", "linear"] | None = None
    """vehicle: drive like a vehicle (`camgen.motion.vehicle_route`): corners rounded with the class's
    minimum turning radius, passing near the inner waypoints rather than through them, speed_m_s the
    cruise speed, easing into turns, starting from rest and braking to a stop at pauses and at the end.
    linear: constant speed along straight legs, the heading turning at each waypoint. null: vehicle for
    the VEHICLE_CLASSES (car, truck, bus, motorcycle, bicycle), linear for the others."""

    @field_validator("pause_s", mode="wrap")
    @classmethod
    def _one_pause_error(cls, value: Any, handler: ValidatorFunctionWrapHandler) -> float | list[float]:
        # Both forms of the union would report a failure; report it once, for the form that was meant.
        try:
            return handler(value)
        except ValidationError:
            pass
        if isinstance(value, list):
            for i, item in enumerate(value):
                if not _is_number(item) or item < 0:
                    raise invalid(f"[{i}]", f"must be a number ≥ 0 (seconds at waypoint {i}), got {item!r}") from None
        if _is_number(value):
            raise invalid("", f"must be ≥ 0, got {value:g}; give the seconds to stand at each waypoint") from None
        raise invalid(
            "",
            f"must be a number of seconds ≥ 0 or a list of them (one per waypoint), got {value!r}",
        ) from None

    @model_validator(mode="after")
    def _check(self) -> ActorPath:
        points = self.waypoints_m
        for i in range(1, len(points)):
            if points[i] == points[i - 1]:
                raise invalid(
                    f"waypoints_m[{i}]",
                    f"repeats the previous waypoint {list(points[i])}; remove it (use pause_s or start_s to wait)",
                )
        if self.heading_deg is not None and len(points) > 1:
            raise invalid(
                "heading_deg",
                f"sets the facing of an actor that stands on one waypoint, but this path has {len(points)}, along "
                "which the actor faces; remove heading_deg, or keep a single waypoint",
            )
        if isinstance(self.pause_s, list) and len(self.pause_s) != len(points):
            raise invalid(
                "pause_s",
                f"must have one pause per waypoint ({len(points)}), got {len(self.pause_s)}: "
                f"[{', '.join(f'{p:g}' for p in self.pause_s)}]; add or remove values, or give one number "
                "for every waypoint",
            )
        return self


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


RANDOM_WALK_MIN_M = 0.1
"""Shortest random-walk leg and smallest region side, m."""


class RandomWalk(Model):
    """Wandering inside a rectangle on the ground: straight legs of random heading and length, each
    followed by a random pause.

    Each leg draws a heading uniformly, a length uniformly in leg_length_m and a pause uniformly in
    pause_s. A leg that would leave the region is shortened to end on its edge; from an edge, a heading
    that points out of the region is mirrored back into it. The walk is resolved into waypoints once
    per scene, so the same seed always gives the same walk.
    """

    region_m: tuple[Point2, Point2]
    """[[x_min, y_min], [x_max, y_max]]: the rectangle (aligned with the world axes) the actor stays in, m."""
    start_m: Point2 | None = None
    """[x, y] where the walk starts, inside region_m, m; null is the region's centre."""
    speed_m_s: Speed = 1.4
    leg_length_m: tuple[Length, Length] = (3.0, 10.0)
    """[min, max] length of one straight leg, m (shorter where the region's edge stops it)."""
    pause_s: tuple[NonNegativeFloat, NonNegativeFloat] = (0.0, 2.0)
    """[min, max] time the actor stands still after each leg, s."""
    start_s: NonNegativeFloat = 0.0
    """When the actor leaves its start point, s."""
    seed: Annotated[int, Field(ge=0)] | None = None
    """Seed of this walk; null derives one from the scene's seed and the actor's place in the scene."""

    @model_validator(mode="after")
    def _check(self) -> RandomWalk:
        (x_min, y_min), (x_max, y_max) = self.region_m
        if not (x_min < x_max and y_min < y_max):
            raise invalid(
                "region_m",
                f"must be [[x_min, y_min], [x_max, y_max]] with x_min < x_max and y_min < y_max, got "
                f"[[{x_min:g}, {y_min:g}], [{x_max:g}, {y_max:g}]]; give the lower-left corner first",
            )
        if min(x_max - x_min, y_max - y_min, self.leg_length_m[0]) < RANDOM_WALK_MIN_M:
            raise invalid(
                "leg_length_m" if self.leg_length_m[0] < RANDOM_WALK_MIN_M else "region_m",
                f"must give legs and a region of at least {RANDOM_WALK_MIN_M:g} m (a walk of shorter legs "
                "would need millions of them), got legs from "
                f"{self.leg_length_m[0]:g} m in a {x_max - x_min:g} × {y_max - y_min:g} m region",
            )
        if self.start_m is not None:
            x, y = self.start_m
            if not (x_min <= x <= x_max and y_min <= y <= y_max):
                raise invalid(
                    "start_m",
                    f"must lie inside region_m [[{x_min:g}, {y_min:g}], [{x_max:g}, {y_max:g}]], got "
                    f"[{x:g}, {y:g}]; move it inside, or use null to start at the region's centre",
                )
        for key, unit in (("leg_length_m", "m"), ("pause_s", "s")):
            low, high = getattr(self, key)
            if low > high:
                raise invalid(
                    key, f"must be ordered [min, max] with min ≤ max, got [{low:g}, {high:g}] {unit}; swap them"
                )
        return self


ClothColour = Literal["black", "white", "gray", "red", "green", "blue", "yellow", "purple", "brown", "pink"]
HairColour = Literal["black", "dark_brown", "brown", "blond", "red", "grey", "white"]


class PersonAppearance(Model):
    """Who a procedural person is. Everything not given is drawn from the identity seed
    (`camgen.actors.appearance` cites the distributions); a given value pins that attribute only."""

    seed: Annotated[int, Field(ge=0)] | None = None
    """Identity seed; null derives one from the scene's seed and the actor's place in the scene."""
    season: Literal["summer", "winter", "mixed"] = "mixed"
    """Which clothing statistics the draws follow (summer: Market-1501, winter: DukeMTMC)."""
    sex: Literal["female", "male"] | None = None
    age_group: Literal["child", "adult", "senior"] | None = None
    stature_m: Annotated[float, Field(ge=1.0, le=2.1)] | None = None
    """Standing height without shoes, m."""
    build: Annotated[float, Field(ge=0, le=1)] | None = None
    """0 thin … 1 heavy (MakeHuman's weight parameter)."""
    skin_tone: Annotated[int, Field(ge=1, le=10)] | None = None
    """Monk skin tone scale, 1 lightest … 10 darkest."""
    hair_style: Literal["short", "long", "bald"] | None = None
    hair_colour: HairColour | None = None
    top: Literal["tshirt", "shirt", "jacket", "coat"] | None = None
    top_colour: ClothColour | None = None
    long_sleeves: bool | None = None
    bottom: Literal["trousers", "shorts", "skirt"] | None = None
    bottom_colour: ClothColour | None = None
    shoe_colour: ClothColour | None = None
    bag: Literal["none", "backpack", "handbag"] | None = None
    hat: bool | None = None

    def pinned(self) -> dict[str, Any]:
        """The attributes this block fixes (field → value)."""
        return {
            key: value
            for key, value in self.model_dump().items()
            if key not in ("seed", "season") and value is not None
        }


VEHICLE_BODY_TYPES: dict[str, tuple[str, ...]] = {
    "car": ("sedan", "hatchback", "estate", "suv", "pickup"),
    "truck": ("van", "box_truck"),
    "bus": ("bus",),
    "bicycle": ("bicycle",),
    "motorcycle": ("motorcycle",),
}
"""The procedural vehicle's body types of each actor class (`camgen.vehicles.look` draws among them)."""
RIDDEN_CLASSES = ("bicycle", "motorcycle")
"""Classes a procedural person can ride (`Actor.rides`)."""
PLATE_CHARACTERS = "ABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789"
VehicleColour = Literal["white", "black", "grey", "silver", "blue", "red", "green", "beige", "yellow", "orange"]


class VehicleIdentity(Model):
    """Who a procedural vehicle (a car, truck, bus, bicycle or motorcycle without a shape) is. Everything
    not given is drawn
    from the identity seed (`camgen.vehicles.look` cites the distributions); a given value pins that
    attribute only."""

    seed: Annotated[int, Field(ge=0)] | None = None
    """Identity seed; null derives one from the scene's seed and the actor's place in the scene."""
    body_type: (
        Literal["sedan", "hatchback", "estate", "suv", "pickup", "van", "box_truck", "bus", "bicycle", "motorcycle"]
        | None
    ) = None
    """car: sedan, hatchback, estate, suv or pickup; truck: van or box_truck; bus: bus; bicycle: bicycle;
    motorcycle: motorcycle."""
    colour: VehicleColour | None = None
    """Paint colour (drawn from the Axalta 2022 shares otherwise)."""
    plate_text: str | None = None
    """The registration on both plates (a motorcycle's one rear plate, in two lines; a bicycle has none);
    null draws one in the UK's current format, "AB12 CDE"."""
    lights_on: bool | Literal["auto"] = "auto"
    """Head and tail lamps lit (the lenses glow; the low beams light the road as photometric lights,
    `camgen.vehicles.headlamps`; brake lamps and indicators follow the driving); a bicycle's front white and
    rear red lamps. auto: lit while the vehicle is driven and the daylight on the ground is under 1 000 lx
    (UN ECE R48's automatic passing-beam switching), so by day and on a parked vehicle they stay dark."""
    driver: bool | None = None
    """A car's, truck's or bus's driver seated at the wheel, seen through the glass (part of the vehicle,
    not annotated as a person: `camgen.vehicles.cabin`); null: a driver when the vehicle drives its
    route, none when it is parked. A bicycle's or motorcycle's rider is a person actor that `rides` it."""

    @field_validator("lights_on", mode="before")
    @classmethod
    def _lights_on(cls, value: Any) -> Any:
        if isinstance(value, bool) or value == "auto":
            return value
        raise invalid(
            "",
            f"must be true, false or auto (auto: lit while the vehicle is driven in under 1 000 lx of daylight), "
            f"got {show_value(value)}",
        )

    @field_validator("plate_text")
    @classmethod
    def _plate(cls, value: str | None) -> str | None:
        groups = value.split(" ") if value is not None else []
        if value is not None and not (
            len(groups) in (1, 2) and all(1 <= len(g) <= 4 and set(g) <= set(PLATE_CHARACTERS) for g in groups)
        ):
            raise invalid(
                "",
                f"must be one or two groups of 1–4 capital letters or digits, like the UK's 'AB12 CDE' (it must "
                f"fit the plate), got {value!r}",
            )
        return value

    def pinned(self) -> dict[str, Any]:
        """The attributes this block fixes (field → value)."""
        return {
            key: value
            for key, value in self.model_dump().items()
            if key in ("body_type", "colour", "plate_text") and value is not None
        }


ActorClass = Literal["person", "car", "truck", "bus", "bicycle", "motorcycle", "other"]
VEHICLE_CLASSES = ("car", "truck", "bus", "motorcycle", "bicycle")
"""Actor classes that drive along their paths by default (`ActorPath.motion`)."""
ActorShape = Annotated[BoxMesh | CylinderMesh | SphereMesh | FileMesh, Field(discriminator="type")]


class PersonAction(Model):
    """A named action of a procedural person over a time window (`camgen.actors.actions` cites the
    postures and timings): wave and phone while walking or standing; sit and fall only standing."""

    type: Literal["wave", "phone", "sit", "fall"]
    start_s: Annotated[float, Field(ge=0)]
    """When the action begins, s (it fades in from here)."""
    duration_s: Annotated[float, Field(gt=0, le=86_400)]
    """How long it lasts, s, fading out at its end (a fallen person lies until then, then rises)."""
    side: Literal["left", "right"] = "right"
    """The hand that waves or holds the phone."""
    direction: Literal["forward", "backward", "left", "right"] = "forward"
    """Which way a fall goes, relative to the way the person faces."""
    seat_height_m: Annotated[
        float, Field(ge=0.3, le=0.8), Why("seats from a low bench (0.3 m) to a bar stool (0.8 m)")
    ] = 0.45
    """Height of the seat the person sits on, m (public benches: 0.40–0.48 m, BS 8300)."""


class Actor(Model):
    """Something that moves and is annotated: it gets a track id, a class, boxes and masks."""

    name: Name
    cls: ActorClass = Field(alias="class")
    """Object class written to MOTChallenge and COCO."""
    shape: ActorShape | None = None
    """Geometry in the actor's frame (x forward, z up, origin on the ground): shapes are centred on their
    position_m, so give z = height/2 to stand on the ground. null: a procedural person (person) or vehicle
    (car, truck, bus, bicycle, motorcycle), a 1 m box otherwise (other)."""
    path: ActorPath | None = None
    """Waypoints to follow; give either this or random_walk."""
    random_walk: RandomWalk | None = None
    """A region to wander in; give either this or path."""
    appearance: PersonAppearance | None = None
    """For a person without a shape: its identity seed and any attribute to pin (null: all drawn)."""
    actions: list[PersonAction] = []
    """For a person without a shape: named actions (wave, phone, sit, fall) at given times; they must
    not overlap."""
    vehicle: VehicleIdentity | None = None
    """For a car, truck, bus, bicycle or motorcycle without a shape (a procedural vehicle): its identity
    seed and any attribute to pin (null: all drawn)."""
    rides: Name | None = None
    """For a person without a shape: the name of the bicycle or motorcycle actor (procedural, without a
    shape) this person rides, seated, hands on the grips, feet on the pedals or footpegs, moving with it
    (no path of its own). Annotated as a person of its own, as COCO labels riders; MOT17's class 2,
    person on vehicle, in MOTChallenge's gt.txt."""

    @model_validator(mode="after")
    def _check(self) -> Actor:
        if self.rides is not None:
            self._check_rider()
        elif self.path is None and self.random_walk is None:
            raise invalid(
                "",
                "needs a path or a random_walk, got neither; add path: {waypoints_m: [[x, y], …]} or "
                "random_walk: {region_m: [[x_min, y_min], [x_max, y_max]]}",
            )
        if self.path is not None and self.random_walk is not None:
            raise invalid("random_walk", "cannot be given together with path; keep one of the two")
        if self.random_walk is not None and self.cls in VEHICLE_CLASSES:
            raise invalid(
                "random_walk",
                f"is a walk for people: a {self.cls} cannot turn on the spot as its random legs would; give it a "
                "path: {waypoints_m: [[x, y], …]} to drive along",
            )
        if self.path is not None and self.path.motion == "vehicle" and self.cls not in VEHICLE_CLASSES:
            raise invalid(
                "path.motion",
                f"is vehicle, but this actor is a {self.cls!r}, which has no turning circle; use one of the classes "
                f"{', '.join(VEHICLE_CLASSES)}, or motion: linear",
            )
        if self.actions and (self.cls != "person" or self.shape is not None):
            raise invalid(
                "actions",
                "are for a procedural person, but this actor is "
                + (f"a {self.cls!r}" if self.cls != "person" else "given a shape")
                + "; remove actions, or make it a person without a shape",
            )
        ordered = sorted(range(len(self.actions)), key=lambda k: self.actions[k].start_s)
        for a, b in itertools.pairwise(ordered):
            first, second = self.actions[a], self.actions[b]
            if second.start_s < first.start_s + first.duration_s:
                raise invalid(
                    f"actions[{b}].start_s",
                    f"is {second.start_s:g} s, inside actions[{a}] ({first.type}, {first.start_s:g}–"
                    f"{first.start_s + first.duration_s:g} s); a person does one action at a time: start it at "
                    f"{first.start_s + first.duration_s:g} s or later",
                )
        if self.vehicle is not None and (self.cls not in VEHICLE_BODY_TYPES or self.shape is not None):
            raise invalid(
                "vehicle",
                "describes a procedural vehicle, but this actor is "
                + (f"a {self.cls!r}" if self.cls not in VEHICLE_BODY_TYPES else "given a shape")
                + f"; remove vehicle, or make it a {', '.join(VEHICLE_BODY_TYPES)} without a shape",
            )
        body_type = self.vehicle.body_type if self.vehicle is not None else None
        if body_type is not None and body_type not in VEHICLE_BODY_TYPES[self.cls]:
            owner = next(cls for cls, types in VEHICLE_BODY_TYPES.items() if body_type in types)
            raise invalid(
                "vehicle.body_type",
                f"is {body_type}, a body of class {owner!r}, but this actor is a {self.cls!r}: use one of "
                f"{', '.join(VEHICLE_BODY_TYPES[self.cls])}, or make the actor class {owner}",
            )
        if self.appearance is not None and (self.cls != "person" or self.shape is not None):
            raise invalid(
                "appearance",
                "describes a procedural person, but this actor is "
                + (f"a {self.cls!r}" if self.cls != "person" else "given a shape")
                + "; remove appearance, or make it a person without a shape",
            )
        if self.cls == "bicycle" and self.vehicle is not None and self.vehicle.plate_text is not None:
            raise invalid(
                "vehicle.plate_text",
                f"is {self.vehicle.plate_text!r}, but a bicycle carries no licence plate; remove plate_text",
            )
        if self.cls in RIDDEN_CLASSES and self.vehicle is not None and self.vehicle.driver is not None:
            raise invalid(
                "vehicle.driver",
                f"is set, but a {self.cls}'s rider is a person actor of its own (class: person, rides: "
                f"{self.name}); remove driver",
            )
        return self

    def _check_rider(self) -> None:
        if self.cls != "person" or self.shape is not None:
            raise invalid(
                "rides",
                f"names {self.rides!r} for a procedural person to ride, but this actor is "
                + (f"a {self.cls!r}" if self.cls != "person" else "given a shape")
                + "; remove rides, or make it a person (class: person) without a shape",
            )
        for key in ("path", "random_walk"):
            if getattr(self, key) is not None:
                raise invalid(
                    key,
                    f"is given, but this person rides {self.rides!r} and moves with it; remove {key} (the "
                    f"route is {self.rides}'s)",
                )
        if self.actions:
            raise invalid("actions", f"are for a person on foot, but this person rides {self.rides!r}; remove them")


class Mount(Model):
    """Where a camera (or its PTZ head) is fixed and which way its zero position looks."""

    position_m: Point3
    yaw_deg: float = 0.0
    """Heading, counter-clockwise from +X seen from above, degrees."""
    pitch_deg: Annotated[float, Field(ge=-90, le=90)] = 0.0
    """Elevation of the optical axis, degrees; negative looks down."""
    roll_deg: Annotated[float, Field(ge=-180, le=180)] = 0.0
    """Rotation of the camera about its optical axis, degrees; positive turns the camera clockwise as
    seen from behind it, so the picture's content turns counter-clockwise."""


class HeadPositions(Model):
    """Where a (mechanical or virtual) PTZ starts, its stored presets and its program."""

    pan_deg: float = 0.0
    """Counter-clockwise about the mount's up axis, degrees."""
    tilt_deg: float = 0.0
    """Up about the mount's right axis, degrees; negative looks down."""
    zoom_x: Annotated[float, Field(ge=1)] = 1.0
    presets: list[PtzPreset] = []
    """Named positions stored in this camera (for `preset` and `tour` programs)."""
    program: PtzProgram | None = None
    """What the head does over time; null holds the position above (which is also where any
    program starts)."""

    @model_validator(mode="after")
    def _check_presets(self) -> HeadPositions:
        names: dict[str, int] = {}
        for i, preset in enumerate(self.presets):
            if preset.name in names:
                raise invalid(
                    f"presets[{i}].name",
                    f"must be unique, got {preset.name!r} again (first at presets[{names[preset.name]}])",
                )
            names[preset.name] = i
        for path, name in program_presets(self.program):
            if name not in names:
                known = ", ".join(repr(n) for n in names) or "none"
                raise invalid(
                    f"program.{path}",
                    f"names preset {name!r}, which this camera does not have (presets: {known}); add it under presets",
                )
        return self


class PtzPosition(HeadPositions):
    """Position of a PTZ head relative to its mount, and speed limits set on this camera.

    zoom_x is the optical zoom: focal length = wide-end focal length × zoom_x."""

    pan_max_deg_s: PositiveFloat | None = None
    """Pan speed limit configured on this camera, deg/s; null uses the head's maximum."""
    tilt_max_deg_s: PositiveFloat | None = None


class Eptz(HeadPositions):
    """Virtual PTZ (ePTZ): a window cropped from a fixed high-resolution sensor and scaled to the
    output size, as the seed paper describes. Nothing moves physically.

    Pan and tilt aim the window's centre along that direction from the mount (the window is centred
    on where the lens images it); zoom_x = 1 is the largest window of the output's aspect ratio that
    fits the sensor, zoom_x = z one z times smaller. The window never leaves the sensor (it is
    stopped at the border). The stream is `output_size_px`; beyond the sensor's native resolution
    (window smaller than the output) the scaler interpolates, as real cameras do."""

    output_size_px: tuple[Annotated[int, Field(ge=16, le=16384)], Annotated[int, Field(ge=16, le=16384)]]
    """[width, height] of the stream, px."""
    zoom_max_x: Annotated[float, Field(ge=1, le=64)] = 4.0
    """Largest digital zoom."""
    pan_max_deg_s: PositiveFloat = 30.0
    """Fastest virtual pan, deg/s."""
    tilt_max_deg_s: PositiveFloat = 30.0
    accel_deg_s2: PositiveFloat = 120.0
    """Acceleration of the virtual pan and tilt, deg/s²."""
    zoom_wide_to_tele_s: ZoomSweepTime = 2.0
    """Time for the full digital zoom range, s (constant rate in log scale)."""

    @model_validator(mode="after")
    def _check_zoom(self) -> Eptz:
        zooms = [("zoom_x", self.zoom_x)] + [(f"presets[{i}].zoom_x", p.zoom_x) for i, p in enumerate(self.presets)]
        for key, zoom in zooms:
            if zoom > self.zoom_max_x + 1e-9:
                raise invalid(key, f"must be ≤ zoom_max_x ({self.zoom_max_x:g}), got {zoom:g}")
        return self


class Camera(Model):
    name: Name
    profile: Annotated[str, Field(min_length=1)]
    """A profile name (looked up in the profile directories) or a path to a profile YAML."""
    serial: Annotated[int, Field(ge=0)] | None = None
    """Serial seed of this unit's fixed-pattern noise; null uses the profile's."""
    mount: Mount
    ptz: PtzPosition | None = None
    """Head position for PTZ cameras; a fixed camera is aimed by its mount alone."""
    eptz: Eptz | None = None
    """Virtual PTZ on a fixed camera: the stream is a moving crop of the sensor."""
    focal_length_mm: PositiveFloat | None = None
    """Installed focal length of a varifocal (non-PTZ) lens, mm; null uses the wide end."""
    focus_distance_m: PositiveFloat | None = None
    """Overrides the profile's focus distance, m."""
    night_mode: Literal["auto"] | bool = "auto"
    """IR night mode (the profile's `night_mode`): auto switches below its `switch_lux`; true (YAML's on)
    and false (off) force it."""
    metering_region_frac: tuple[Fraction, Fraction, Fraction, Fraction] | None = None
    """The exposure zone an installer set on this unit (Axis calls it the exposure zone, Hikvision the BLC
    area): [x0, y0, x1, y1] of the auto-exposure's metering window as fractions of the sensor's width and
    height (of the whole sensor, also for a virtual PTZ, whose stream is a crop of it); null keeps the
    profile's `exposure.auto.metering_region_frac` (by default the whole frame). A camera that sees a bright
    sky meters the ground below it this way, instead of filming the street as silhouettes."""

    @model_validator(mode="after")
    def _check_heads(self) -> Camera:
        if self.ptz is not None and self.eptz is not None:
            raise invalid(
                "eptz", "must not be set together with ptz: a camera has a mechanical or a virtual head; drop one"
            )
        if self.metering_region_frac is not None:
            x0, y0, x1, y1 = self.metering_region_frac
            if not (x0 < x1 and y0 < y1):
                raise invalid(
                    "metering_region_frac",
                    f"must be [x0, y0, x1, y1] with x0 < x1 and y0 < y1, got [{x0:g}, {y0:g}, {x1:g}, {y1:g}]; "
                    "e.g. [0, 0.4, 1, 1] meters the lower 60 % of the frame",
                )
        return self

    @property
    def head(self) -> HeadPositions | None:
        """The camera's (mechanical or virtual) PTZ settings, if any."""
        return self.ptz if self.ptz is not None else self.eptz


class Outputs(Model):
    """What a render of this scene writes; the plan renders only the passes these need."""

    video: bool = True
    frames: Literal["png", "tiff", "exr"] | None = None
    raw_dng: bool = False
    raw: Literal["png16", "tiff16", "exr"] | None = None
    """Also write the sensor's raw mosaic per frame as it left the ADC (DN, black level included, one
    channel, CFA unchanged) under raw/: 16-bit PNG or TIFF (lossless, as stored) or a float EXR, with
    raw/raw.json naming the CFA, black and white levels and bit depth; the DNG (raw_dng) carries the
    same samples with their colour metadata."""
    depth: Literal["png16", "exr"] | None = None
    radiance: Literal["png16", "tiff16", "exr"] | None = None
    """Also write the scene-referred radiance per frame under radiance/: the renderer's linear RGB
    (BT.709 primaries, scaled so that 0.2126 R + 0.7152 G + 0.0722 B is the luminance in cd/m²) seen
    through each output pixel (the lens's distortion places it, as depth and ids), before the lens's
    blurs, lateral CA and vignetting and before the sensor. png16 and tiff16 store DN = radiance / scale
    with one scale per camera in radiance/radiance.json; exr stores float32 cd/m². With motion blur
    planned it is the exposure's mean, as the renderer integrates it. frames: exr is the image-plane
    radiance instead, after the lens's blurs and vignetting (`camgen.io.radiance`)."""
    flow: Literal["flo"] | None = None
    """Also write the forward optical flow of each frame but the last under flow/: where the surface
    point seen at each output pixel is in the next frame, px, through the same camera model as the
    pixels (pose, PTZ head, zoom, distortion, a virtual PTZ's crop), as Middlebury .flo
    (`camgen.annotate.flow`)."""
    scene_flow: bool = False
    """Also write the scene flow of each frame but the last under scene_flow/: the world displacement
    (x, y, z, m) of the surface point seen at each output pixel until the next frame, as float EXR;
    NaN where no surface is seen (the sky)."""
    annotations: list[Literal["mot", "coco", "reid", "yolo"]] = ["mot", "coco"]
    """mot: a MOTChallenge sequence as MOT17 ships one (img1/ of the delivered frames counted from 1,
    gt/gt.txt, seqinfo.ini; gt/keypoints.jsonl when people are filmed); coco: coco.json; reid: crops
    of each person from the delivered frames, named as Market-1501's (reid/); yolo: Ultralytics YOLO
    labels (images/, labels/, data.yaml). mot, reid and yolo need the delivered 8-bit frames, so they
    run the sensor and ISP even without a video."""
    annotation_images: Literal["jpg", "png"] = "jpg"
    """Format of the frames written beside the MOT and YOLO labels (img1/, images/): jpg as MOT17
    ships them (`camgen.io.annotations.SEQUENCE_JPEG_QUALITY`), or png (lossless, larger)."""
    mot_detections: bool = False
    """Also write det/det.txt beside a MOT sequence: OpenCV's HOG people detector's boxes on the
    delivered frames, as MOTChallenge's public detections (for trackers that take them). Slow: about
    5 s a 1080p frame on 2 cores."""
    camera_metadata: bool = True

    @model_validator(mode="after")
    def _check(self) -> Outputs:
        if self.mot_detections and "mot" not in self.annotations:
            raise invalid(
                "mot_detections",
                "writes det/det.txt into a MOT sequence, but outputs.annotations has no 'mot': add it, "
                "or drop mot_detections",
            )
        return self


class Region(Model):
    """An area of interest on the ground (an entrance, a gate) and the IEC 62676-4 class it must be seen at
    (`camgen.coverage`)."""

    name: Name
    polygon_m: list[Point2]
    """[[x, y], …] corners of the polygon on the ground, m (at least 3; closed implicitly)."""
    required_class: Literal["detect", "observe", "recognise", "identify"]
    """The DORI class (IEC 62676-4) a person in the region must be seen at."""

    @model_validator(mode="after")
    def _check(self) -> Region:
        if len(self.polygon_m) < 3:
            raise invalid(
                "polygon_m",
                f"must have at least 3 corners [[x, y], …] to enclose an area, got {len(self.polygon_m)}; add corners",
            )
        return self


class Scene(Model):
    description: str = ""
    duration_s: Annotated[float, Field(gt=0, le=86_400)]
    fps: Annotated[
        float,
        Field(ge=0.001, le=240),
        Why(
            "the video stores the frame rate as a fraction with a denominator of at most 1001 (io.video), so "
            "at least one frame per 1000 s; and no sensor profile here runs faster than 240 Hz"
        ),
    ] = 25.0
    seed: Annotated[int, Field(ge=0)] = 0
    environment: Environment = Environment()
    lights: list[Light] = []
    actors: list[Actor] = []
    cameras: Annotated[
        list[Camera],
        Field(min_length=1),
        Why(
            "a scene is seen through its cameras ({name, profile, mount}); camgen layout, which chooses them, "
            "replaces the scene's cameras, so any one will do there"
        ),
    ]
    outputs: Outputs = Outputs()
    regions: list[Region] = []
    """Areas of interest with the class they must be seen at (`camgen coverage`, `camgen layout`)."""

    @property
    def frame_count(self) -> int:
        return max(1, math.floor(self.duration_s * self.fps + 1e-9))

    @model_validator(mode="before")
    @classmethod
    def _daylight_from_site(cls, data: Any) -> Any:
        return _with_site_daylight(data)

    @model_validator(mode="after")
    def _check(self) -> Scene:
        for key, items in (
            ("environment.meshes", self.environment.meshes),
            ("actors", self.actors),
            ("cameras", self.cameras),
            ("regions", self.regions),
        ):
            seen: dict[str, int] = {}
            for i, item in enumerate(items):
                if item.name in seen:
                    raise invalid(
                        f"{key}[{i}].name",
                        f"must be unique, got {item.name!r} again (first at {key}[{seen[item.name]}])",
                    )
                seen[item.name] = i
        instance_names = {mesh.name: f"environment.meshes[{i}]" for i, mesh in enumerate(self.environment.meshes)}
        for i, prop in enumerate(self.environment.props):  # a prop's instance name: its own or <type>_<index>
            name = prop.name or f"{prop.type}_{i}"
            if name in instance_names:
                raise invalid(
                    f"environment.props[{i}]" + (".name" if prop.name else ""),
                    f"is the instance {name!r}, a name {instance_names[name]} has already; give the prop another name",
                )
            instance_names[name] = f"environment.props[{i}]"
        for i, mesh in enumerate(self.environment.meshes):
            if isinstance(mesh, FileMesh) and mesh.animation is not None:
                raise invalid(
                    f"environment.meshes[{i}].animation",
                    "animates an actor's glTF character, but this is a fixed mesh of the environment; "
                    "remove animation, or make the mesh an actor's shape",
                )
        actor_names = [actor.name for actor in self.actors]
        _check_riders(self.actors)
        for i, camera in enumerate(self.cameras):
            program = camera.head.program if camera.head is not None else None
            if isinstance(program, FollowProgram) and program.target not in actor_names:
                known = ", ".join(repr(n) for n in actor_names) or "none"
                raise invalid(
                    f"cameras[{i}].{'ptz' if camera.ptz is not None else 'eptz'}.program.target",
                    f"names actor {program.target!r}, which the scene does not have (actors: {known})",
                )
        if self.environment.sky in ("clear", "partly_cloudy") and not any(light.type == "sun" for light in self.lights):
            raise invalid(
                "environment.sky",
                f"is {self.environment.sky}, a sky lit by the sun, but the scene has no sun light to place it; "
                "add a {type: sun, …} light, or use sky: overcast or uniform",
            )
        for kind, limit in MAX_LIGHTS.items():
            indices = [i for i, light in enumerate(self.lights) if _renderer_kind(light.type) == kind]
            if len(indices) > limit:
                raise invalid(
                    f"lights[{indices[limit]}]",
                    f"is {kind} light number {limit + 1}; the renderer shades at most {limit} {kind} lights: "
                    "merge or remove some" + (" (a lamp is a spot light to the renderer)" if kind == "spot" else ""),
                )
        if (
            not self.lights
            and self.environment.sky_luminance_cd_m2 == 0
            and not any(m.material.emission_cd_m2 > 0 for m in self.environment.meshes)
        ):
            raise invalid(
                "lights",
                "must hold at least one light (the scene has no sky luminance and no emitting mesh, "
                "so every frame would be black)",
            )
        return self


def _check_riders(actors: list[Actor]) -> None:
    """Each rider names a procedural bicycle or motorcycle of the scene, and no two ride the same one."""
    by_name = {actor.name: actor for actor in actors}
    ridden: dict[str, int] = {}
    for i, actor in enumerate(actors):
        if actor.rides is None:
            continue
        target = by_name.get(actor.rides)
        if target is None:
            candidates = [a.name for a in actors if a.cls in RIDDEN_CLASSES]
            raise invalid(
                f"actors[{i}].rides",
                f"names {actor.rides!r}, which the scene does not have; give the name of a bicycle or "
                f"motorcycle actor (the scene's: {', '.join(repr(n) for n in candidates) or 'none'})",
            )
        if target.cls not in RIDDEN_CLASSES or target.shape is not None:
            raise invalid(
                f"actors[{i}].rides",
                f"names {actor.rides!r}, a {target.cls}"
                + (" given a shape" if target.shape is not None else "")
                + "; a person rides a procedural bicycle or motorcycle (class bicycle or motorcycle, no shape)",
            )
        if actor.rides in ridden:
            raise invalid(
                f"actors[{i}].rides",
                f"names {actor.rides!r}, which actors[{ridden[actor.rides]}] already rides; one rider per "
                "two-wheeler (a pillion is not modelled)",
            )
        ridden[actor.rides] = i


def _renderer_kind(light_type: str) -> str:
    """The renderer's light a scene's light type becomes (a lamp is a spot)."""
    return "spot" if light_type == "lamp" else light_type


SITE_SUN_MIN_LUX = 1.0
"""A site's sun must give at least this direct illuminance (lux) to be a light: the IES model's beam
fades to nothing in the last degree above the horizon."""


def _with_site_daylight(data: Any) -> Any:
    """A scene's data (as written) with what its `environment.site` gives filled in: each sun light's
    azimuth and elevation, and, where left out, the sun's and an ambient light's illuminance and the
    sky's zenith luminance (`Site`). Data the fields will refuse anyway is passed on unchanged, so
    that the refusal is reported where it stands."""
    from camgen.world.site import site_daylight
    from camgen.world.sky import SKY_TYPES
    from camgen.world.sun import sunrise_sunset

    if not isinstance(data, dict) or not isinstance(data.get("environment"), dict):
        return data
    environment = data["environment"]
    if environment.get("night_sky") is not None:
        return _with_night_sky(data)
    sky = environment.get("sky", "uniform")
    lights = data.get("lights", [])
    if environment.get("site") is None or not isinstance(lights, list) or sky not in ("uniform", *SKY_TYPES):
        return data
    try:
        site = Site.model_validate(environment["site"])
    except ValidationError:
        return data
    daylight = site_daylight(site.latitude_deg, site.longitude_deg, site.time, site.north_deg, sky)
    suns = [i for i, light in enumerate(lights) if isinstance(light, dict) and light.get("type") == "sun"]
    if daylight.elevation_deg <= 0 or (suns and daylight.sun_illuminance_lux < SITE_SUN_MIN_LUX and sky != "overcast"):
        days = sunrise_sunset(site.latitude_deg, site.longitude_deg, site.time)
        when = (
            f"(that day the sun rises at {days[0]:%H:%M} and sets at {days[1]:%H:%M} there)"
            if days
            else "(the sun does not rise that day there)"
        )
        where = "below" if daylight.elevation_deg <= 0 else "above"
        raise invalid(
            "environment.site.time",
            f"puts the sun {abs(daylight.elevation_deg):.2f}° {where} the horizon at {site.time.isoformat()} "
            f"{when}; camgen's daylight model needs the sun up (above 1° with a sun light, no twilight): choose "
            "a time in daylight, or make it a night scene (environment.night_sky, with lamps; the sun then "
            "12° or more below the horizon)",
        )
    duration_s = data.get("duration_s")
    if _is_number(duration_s) and duration_s > 0:
        end = site.time + timedelta(seconds=duration_s)
        last = site_daylight(site.latitude_deg, site.longitude_deg, end, site.north_deg, sky)
        if last.elevation_deg <= 0 or (suns and last.sun_illuminance_lux < SITE_SUN_MIN_LUX and sky != "overcast"):
            days = sunrise_sunset(site.latitude_deg, site.longitude_deg, end)
            sunset = f" (sunset at {days[1]:%H:%M})" if days else ""
            raise invalid(
                "duration_s",
                f"ends the sequence at {end.isoformat()}, when the sun stands {abs(last.elevation_deg):.2f}° "
                f"{'below' if last.elevation_deg <= 0 else 'above'} the horizon{sunset}; camgen's daylight model "
                "needs the sun up (above 1° with a sun light, no twilight) to the last frame: start earlier "
                "(environment.site.time) or shorten duration_s",
            )
    filled = []
    for i, light in enumerate(lights):
        if isinstance(light, dict) and light.get("type") == "sun":
            if sky == "overcast":
                raise invalid(
                    f"lights[{i}]",
                    "is a sun light, but an overcast sky lets no direct sunlight through (IES RP-21); remove it, "
                    "or use sky: clear or partly_cloudy",
                )
            site_direction = {"azimuth_deg": daylight.azimuth_deg, "elevation_deg": daylight.elevation_deg}
            for key, value in site_direction.items():
                given = light.get(key)
                if given is not None and not (_is_number(given) and abs(given - value) < 1e-9):
                    raise invalid(
                        f"lights[{i}].{key}",
                        f"is {show_value(given)}, but environment.site puts the sun at azimuth "
                        f"{daylight.azimuth_deg:.2f}°, elevation {daylight.elevation_deg:.2f}°; leave out "
                        "azimuth_deg and elevation_deg (the site places the sun), or remove the site",
                    )
            light = {"illuminance_lux": daylight.sun_illuminance_lux, **light, **site_direction}
        elif isinstance(light, dict) and light.get("type") == "ambient":
            light = {"illuminance_lux": daylight.sky_illuminance_lux, **light}
        filled.append(light)
    return {
        **data,
        "lights": filled,
        "environment": {"sky_luminance_cd_m2": daylight.zenith_luminance_cd_m2, **environment},
    }


def _with_night_sky(data: dict) -> dict:
    """A night scene's data (`Environment.night_sky`) with the sky's luminance and each ambient light's
    illuminance (π·L) filled in where left out; a site's sun must stay below
    `camgen.world.night.NIGHT_SUN_MAX_ELEVATION_DEG` to the last frame, and no light may be a sun."""
    from camgen.world.night import NIGHT_SKY_LUMINANCE_CD_M2, NIGHT_SUN_MAX_ELEVATION_DEG, night_sky_illuminance_lux
    from camgen.world.sun import solar_position, unix_time_s

    environment = data["environment"]
    level = environment["night_sky"]
    lights = data.get("lights", [])
    if level not in NIGHT_SKY_LUMINANCE_CD_M2 or not isinstance(lights, list):
        return data  # the field refuses it
    if environment.get("sky", "uniform") != "uniform":
        raise invalid(
            "environment.sky",
            f"is {environment['sky']}, a daylight sky, but environment.night_sky makes this a night scene, whose "
            "skyglow camgen draws uniform: use sky: uniform (or leave it out), or remove night_sky",
        )
    for i, light in enumerate(lights):
        if isinstance(light, dict) and light.get("type") == "sun":
            raise invalid(
                f"lights[{i}]",
                "is a sun light, but environment.night_sky makes this a night scene (the sun is down): remove it "
                "and light the scene with lamps, or remove night_sky",
            )
    site = environment.get("site")
    if site is not None:
        try:
            site = Site.model_validate(site)
        except ValidationError:
            return data
        duration_s = data.get("duration_s")
        checks = [("environment.site.time", site.time)]
        if _is_number(duration_s) and duration_s > 0:
            checks.append(("duration_s", site.time + timedelta(seconds=duration_s)))
        for key, time in checks:
            elevation = float(solar_position(site.latitude_deg, site.longitude_deg, unix_time_s(time)).elevation_deg)
            if elevation > NIGHT_SUN_MAX_ELEVATION_DEG:
                what = "starts" if key == "environment.site.time" else "ends"
                raise invalid(
                    key,
                    f"{what} the night scene at {time.isoformat()}, when the sun stands {elevation:.2f}° from the "
                    f"horizon; a night sky needs it {-NIGHT_SUN_MAX_ELEVATION_DEG:g}° or more below (after nautical "
                    "dusk: camgen does not model twilight): choose a later time, or remove night_sky for a day scene",
                )
    luminance_cd_m2 = NIGHT_SKY_LUMINANCE_CD_M2[level]
    filled = [
        {"illuminance_lux": night_sky_illuminance_lux(luminance_cd_m2), **light}
        if isinstance(light, dict) and light.get("type") == "ambient"
        else light
        for light in lights
    ]
    return {**data, "lights": filled, "environment": {"sky_luminance_cd_m2": luminance_cd_m2, **environment}}


# Class-typical sizes (m) used when an actor gives no shape and is not procedural (class other)
_DEFAULT_BOX_SIZE_M: dict[str, tuple[float, float, float]] = {"other": (1.0, 1.0, 1.0)}


PERSON_ENVELOPE_RADIUS_M = 0.6
PERSON_ENVELOPE_HEIGHT_M = 2.15


PERSON_NOMINAL_HEIGHT_M = 1.75
PERSON_NOMINAL_RADIUS_M = 0.25


def nominal_shape(actor: Actor) -> BoxMesh | CylinderMesh | SphereMesh | FileMesh:
    """What a controller aims at: for a procedural person a standing adult's cylinder (1.75 m tall,
    0.5 m wide; a PTZ head's tracker knows no stature), otherwise the actor's shape."""
    if is_procedural_person(actor):
        return _standing_cylinder(actor.name, PERSON_NOMINAL_RADIUS_M, PERSON_NOMINAL_HEIGHT_M)
    return actor_shape(actor)


def _standing_cylinder(name: str, radius_m: float, height_m: float) -> CylinderMesh:
    """An upright cylinder standing on the actor's ground point."""
    return CylinderMesh(
        type="cylinder", name=name, radius_m=radius_m, height_m=height_m, position_m=(0.0, 0.0, height_m / 2)
    )


VEHICLE_ENVELOPE_M: dict[str, tuple[tuple[float, float, float], tuple[float, float, float]]] = {
    "car": ((-1.4, -1.2, 0.0), (4.6, 1.2, 1.95)),
    "truck": ((-2.6, -1.6, 0.0), (6.5, 1.6, 3.75)),
    "bus": ((-3.6, -1.6, 0.0), (9.1, 1.6, 3.2)),
    "bicycle": ((-0.5, -0.5, 0.0), (1.6, 0.5, 1.25)),
    "motorcycle": ((-0.6, -0.6, 0.0), (2.0, 0.6, 1.35)),
}
"""(low, high) corners of the box, in the actor's frame, that holds every procedural vehicle of a class
(`camgen.vehicles`): its rear axle's middle stands on the actor's ground point (as a kinematic bicycle
model's reference point), so the box reaches from the longest rear overhang (an estate's 1.1 m, a box
truck's 2.4 m, a city bus's 3.5 m) to the longest wheelbase and front overhang (a pickup's 4.3 m, a box
truck's 6.2 m, a bus's 8.7 m and 9.02 m to its mirrors' heads ahead of it), over the widest wheels steered
to the class's lock (about 0.6 rad) and door mirrors (`camgen.vehicles.body.MIRRORS`), and to the tallest roof
of its body types (`camgen.vehicles.look` cites the dimensions); a bicycle's and a motorcycle's from the rear tyre to
the front tyre steered to its lock, over the widest handlebar and mirrors."""
RIDER_ENVELOPE_M = ((-0.6, -0.75, 0.0), (1.7, 0.75, 2.1))
"""(low, high) corners of the box, in the ridden vehicle's frame on its route's point (the rear axle),
that holds a rider of any stature on a bicycle or motorcycle: from behind the rear axle to the hands on
the bars and a handbag swinging off the arm, up to the head of a tall rider sitting on a motorcycle's seat."""


def is_procedural_vehicle(actor: Actor) -> bool:
    """Whether an actor is drawn as camgen's procedural vehicle (a car, truck, bus, bicycle or motorcycle
    given no shape)."""
    return actor.cls in VEHICLE_ENVELOPE_M and actor.shape is None


def is_procedural_person(actor: Actor) -> bool:
    """Whether an actor is drawn as camgen's procedural person (a person given no shape)."""
    return actor.cls == "person" and actor.shape is None


GLTF_SUFFIXES = (".glb", ".gltf")


def is_character(actor: Actor) -> bool:
    """Whether an actor is a glTF character: a shape read from a .glb or .gltf file, posed (and, with
    a skin and animations, animated) by `camgen.actors.character` in the actor's axes."""
    return isinstance(actor.shape, FileMesh) and actor.shape.path.lower().endswith(GLTF_SUFFIXES)


def actor_shape(actor: Actor) -> BoxMesh | CylinderMesh | SphereMesh | FileMesh:
    """The actor's geometry in its own frame (x forward, z up, origin on the ground)."""
    if actor.shape is not None:
        return actor.shape
    if actor.cls == "person" and actor.rides is not None:
        low, high = RIDER_ENVELOPE_M
        centre = tuple((a + b) / 2 for a, b in zip(low, high, strict=True))
        extent = tuple(b - a for a, b in zip(low, high, strict=True))
        return BoxMesh(type="box", name=actor.name, size_m=extent, position_m=centre)
    if actor.cls == "person":
        # The procedural person's envelope (`is_procedural_person`): the tallest stature with hair and
        # shoes, and the reach of a running stride and swinging arms.
        return _standing_cylinder(actor.name, PERSON_ENVELOPE_RADIUS_M, PERSON_ENVELOPE_HEIGHT_M)
    if is_procedural_vehicle(actor):
        # The procedural vehicle's envelope (`VEHICLE_ENVELOPE_M`), on the actor's ground point.
        low, high = VEHICLE_ENVELOPE_M[actor.cls]
        centre = tuple((a + b) / 2 for a, b in zip(low, high, strict=True))
        extent = tuple(b - a for a, b in zip(low, high, strict=True))
        return BoxMesh(type="box", name=actor.name, size_m=extent, position_m=centre)
    size = _DEFAULT_BOX_SIZE_M[actor.cls]
    return BoxMesh(type="box", name=actor.name, size_m=size, position_m=(0.0, 0.0, size[2] / 2))
