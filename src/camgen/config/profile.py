"""Camera profile: the hardware — sensor, noise model, lens, exposure, ISP, codec and PTZ head.

Every physical quantity carries its unit in its key. The noise terms follow DESIGN.md "Sensor model"
(EMVA 1288 quantities; the seed paper's eq. 5 after Irie et al.).
"""

from __future__ import annotations

import math
from typing import Annotated, Literal

import numpy as np
from pydantic import Field, model_validator

from camgen.config.base import Model, Why, invalid
from camgen.optics.distortion import fold_inside
from camgen.optics.intrinsics import camera_matrix_px, corner_radius_normalized
from camgen.optics.projection import LensInversionError, undistort_points

PositiveFloat = Annotated[float, Field(gt=0)]
NonNegativeFloat = Annotated[float, Field(ge=0)]
Fraction = Annotated[float, Field(ge=0, le=1)]
Rgb = tuple[float, float, float]

SENSOR_SIDE_MAX_PX = 16384
"""Most pixels along one side of a sensor: line-scan sensors reach 16k; the largest area sensors sold
(151 MP, Sony IMX411: 14192 × 10640) stay below it."""
SENSOR_PIXELS_MAX = 160_000_000
"""Most pixels on a sensor: the largest area sensors sold have 151 MP (Sony IMX411/IMX461)."""
TEMPERATURE_RANGE_C = (-40.0, 105.0)
"""Temperatures a working image sensor reaches, °C: cameras are rated for −40 °C ambient (outdoor
surveillance housings: −40…+60 °C), and the die runs warmer than the air around it, up to the +105 °C of
AEC-Q100 grade 2 (automotive) sensors; consumer and industrial sensor datasheets stop at +85 °C."""
DARK_CURRENT_MAX_E_PER_S = 1e8
"""Most dark current a pixel may have at the operating temperature, e⁻/s: it would fill even the deepest
wells (`full_well_e` ≤ 10 Me⁻) in 0.1 s and a typical 10 ke⁻ well in 0.1 ms; hot real sensors stay below
~10⁵ e⁻/s (50 e⁻/s at 25 °C doubling every 6.5 °C gives 2.5·10⁵ e⁻/s at 105 °C)."""
DYNAMIC_RANGE_MIN = 10.0
"""Smallest full well over read noise (EMVA 1288's dynamic range μ_e.sat/σ_d, here 20 dB): far below
any real sensor (55–80 dB), far above a well that one read-noise σ fills."""
FOCAL_LENGTH_RANGE_MM = (0.5, 2000.0)
"""Focal lengths of real camera lenses, mm: from the shortest rectilinear lenses on small sensors
(≈ 0.8 mm) to the longest long-range surveillance and broadcast zooms (1000–2000 mm tele end)."""


class QuantumEfficiency(Model):
    """Quantum efficiency η per CFA colour at its peak wavelength (electrons per photon, 0–1)."""

    r: Fraction = 0.6
    g: Fraction = 0.7
    b: Fraction = 0.55


NoiseScale = Annotated[
    float,
    Field(ge=0, le=10),
    Why("a channel's noise is 0–10 times the physical model's (measured cameras differ by tens of per cent)"),
]


class ChannelNoiseScale(Model):
    """Per-channel multipliers on the temporal noise (seed paper Fig. 5); 1 is the physical model, 0–10."""

    r: NoiseScale = 1.0
    g: NoiseScale = 1.0
    b: NoiseScale = 1.0


class Noise(Model):
    """Every term of N_cap = (I·PRNU + SN_ph + FPN + SN_dark + N_read)·N_D·N_filt + N_Q, in electrons.

    A term set to 0 (or false) is off; the plan leaves it out.
    """

    shot_noise: bool = True
    """Photon shot noise (Poisson on the collected photo-electrons)."""
    read_noise_e: NonNegativeFloat = 2.0
    """Temporal read noise σ_read, electrons rms (EMVA 1288 σ_d at zero exposure, minus quantisation)."""
    read_noise_tail_dof: Annotated[float, Field(gt=2)] | None = None
    """Degrees of freedom of a Student-t read-noise tail (RTS/popcorn noise); null for Gaussian."""
    prnu_pct: Annotated[float, Field(ge=0, le=100)] = 0.5
    """Photo-response non-uniformity, % rms of the signal (fixed pattern, keyed by the camera serial)."""
    dsnu_e: NonNegativeFloat = 0.5
    """Dark-signal non-uniformity, electrons rms (fixed pattern)."""
    row_fpn_e: NonNegativeFloat = 0.0
    """Row-wise offset fixed-pattern noise, electrons rms."""
    column_fpn_e: NonNegativeFloat = 0.0
    """Column-wise offset fixed-pattern noise, electrons rms."""
    dark_current_e_per_s: NonNegativeFloat = 1.0
    """Mean dark current at `dark_current_reference_c`, electrons per second per pixel."""
    dark_current_reference_c: Annotated[
        float,
        Field(ge=TEMPERATURE_RANGE_C[0], le=TEMPERATURE_RANGE_C[1]),
        Why("an image sensor works from −40 °C (outdoor cameras' rating) to +105 °C (AEC-Q100 grade 2)"),
    ] = 25.0
    """Temperature at which `dark_current_e_per_s` holds, °C (datasheets: 25–60 °C)."""
    dark_current_doubling_c: Annotated[
        float,
        Field(ge=2, le=20),
        Why(
            "silicon's dark current doubles every 3–14 °C over −40…+105 °C (from diffusion to generation "
            "current, Eg = 1.12 eV; 5–10 °C in real sensors), so 2–20 °C"
        ),
    ] = 6.5
    """Temperature rise that doubles the dark current, °C; 2–20 °C allowed. From the temperature
    dependence of silicon's dark current (Janesick, Scientific Charge-Coupled Devices, SPIE 2001):
    diffusion current ∝ T³·exp(−Eg/kT) doubles every ≈ 3 °C at −40 °C and ≈ 4.5 °C at 25 °C,
    depletion (generation) current ∝ T^1.5·exp(−Eg/2kT) every ≈ 9 °C at 25 °C and ≈ 14 °C at 105 °C;
    CMOS image sensors measure 5–10 °C."""
    hot_pixel_fraction: Fraction = 0.0
    """Fraction of pixels with elevated dark current."""
    hot_pixel_dark_current_e_per_s: NonNegativeFloat = 0.0
    """Dark current of a hot pixel at the reference temperature, e⁻/s."""
    dead_pixel_fraction: Fraction = 0.0
    """Fraction of pixels that do not respond to light."""
    blooming: bool = True
    """Charge above full well spills into neighbouring pixels instead of being lost."""
    channel_scale: ChannelNoiseScale = ChannelNoiseScale()


class Sensor(Model):
    """The image sensor: geometry, colour filter array and the electron → DN chain."""

    qe_850nm_rel: Annotated[
        float,
        Field(ge=0, le=2),
        Why("a silicon sensor's QE at 850 nm is 0–2 times its visible QE (front-illuminated 0.2, NIR-enhanced 1.5)"),
    ] = 0.35
    """Quantum efficiency at 850 nm relative to the visible QE of `quantum_efficiency`, with the IR-cut
    filter out (night mode, `Profile.night_mode`). 0.35: Sony STARVIS sensors' published spectral
    response (IMX291/IMX327 datasheets' figure: R, G and B meet at about 30–40 % of the green peak near
    850 nm); NIR-enhanced parts (STARVIS 2, "NIR+") reach 0.6–1.0."""

    model: str = ""
    """Sensor part number, for people (not used in computation)."""
    format: str = ""
    """Optical format as sold, e.g. 1/2.8" (not used in computation: the pitch and resolution are)."""
    width_px: Annotated[
        int,
        Field(gt=0, le=SENSOR_SIDE_MAX_PX),
        Why(f"no sensor has more than {SENSOR_SIDE_MAX_PX} pixels along a side (16k line-scan sensors)"),
    ]
    """Effective (output) pixels horizontally (`SENSOR_SIDE_MAX_PX`; `SENSOR_PIXELS_MAX` in all)."""
    height_px: Annotated[
        int,
        Field(gt=0, le=SENSOR_SIDE_MAX_PX),
        Why(f"no sensor has more than {SENSOR_SIDE_MAX_PX} pixels along a side (16k line-scan sensors)"),
    ]
    """Effective (output) pixels vertically."""
    pixel_pitch_um: Annotated[float, Field(gt=0, le=100)]
    """Horizontal pixel pitch, µm."""
    pixel_pitch_y_um: Annotated[float, Field(gt=0, le=100)] | None = None
    """Vertical pixel pitch, µm, for non-square pixels; null means square."""
    principal_point_offset_px: tuple[float, float] = (0.0, 0.0)
    """Optical axis offset from the sensor centre, pixels (x right, y down)."""
    cfa: Literal["RGGB", "BGGR", "GRBG", "GBRG", "mono"] = "RGGB"
    """Colour filter array, read from the top-left 2×2 block row by row."""
    bit_depth: Annotated[int, Field(ge=8, le=16)] = 12
    """ADC resolution, bits."""
    full_well_e: Annotated[
        float,
        Field(ge=100, le=1e7),
        Why(
            "real wells hold 100 e⁻ to 10 Me⁻ (sub-µm phone pixels ~1 ke⁻, large scientific pixels "
            "~1 Me⁻); give electrons, not DN"
        ),
    ]
    """Charge a pixel holds before it clips, electrons (100 e⁻ … 10 Me⁻, and at least `DYNAMIC_RANGE_MIN`
    times the read noise). An EMVA 1288 measurement places the saturation
    capacity μ_e.sat at the peak of the photon-transfer variance, where shot noise and PRNU have
    started clipping pixels: about 4 % below this figure for 10 ke⁻ and 1 % PRNU (tests/sensor).
    Enter a datasheet's μ_e.sat a few σ higher."""
    conversion_gain_dn_per_e: Annotated[
        float,
        Field(ge=1e-4, le=100),
        Why(
            "system gains K run from 1e-4 DN/e⁻ (a 12-bit ADC over a 10 Me⁻ well) to ~10 DN/e⁻ "
            "(photon-counting qCMOS), so 1e-4…100 DN/e⁻; give DN per electron, not electrons per DN"
        ),
    ]
    """System gain K at 0 dB analog gain, DN per electron (EMVA 1288's K), 1e-4 … 100."""
    black_level_dn: NonNegativeFloat = 0.0
    """Offset added before the ADC clip, DN."""
    analog_gain_max_db: Annotated[float, Field(ge=0, le=72)] = 0.0
    """Largest analog/digital gain the camera applies, dB (20·log10)."""
    temperature_c: Annotated[
        float,
        Field(ge=TEMPERATURE_RANGE_C[0], le=TEMPERATURE_RANGE_C[1]),
        Why("an image sensor works from −40 °C (outdoor cameras' rating) to +105 °C (AEC-Q100 grade 2)"),
    ] = 40.0
    """Operating sensor temperature, °C (drives dark current), within `TEMPERATURE_RANGE_C`."""
    frame_rate_max_hz: PositiveFloat = 30.0
    """Highest frame rate at full resolution, Hz."""
    quantum_efficiency: QuantumEfficiency = QuantumEfficiency()
    noise: Noise = Noise()

    @property
    def pitch_y_um(self) -> float:
        return self.pixel_pitch_y_um if self.pixel_pitch_y_um is not None else self.pixel_pitch_um

    @property
    def width_mm(self) -> float:
        return self.width_px * self.pixel_pitch_um * 1e-3

    @property
    def height_mm(self) -> float:
        return self.height_px * self.pitch_y_um * 1e-3

    @property
    def white_level_dn(self) -> int:
        return 2**self.bit_depth - 1

    @model_validator(mode="after")
    def _check(self) -> Sensor:
        if self.black_level_dn >= self.white_level_dn:
            raise invalid(
                "black_level_dn",
                f"must be below the white level {self.white_level_dn} DN of a {self.bit_depth}-bit ADC, "
                f"got {self.black_level_dn:g}",
            )
        if self.noise.hot_pixel_fraction > 0 and self.noise.hot_pixel_dark_current_e_per_s == 0:
            raise invalid(
                "noise.hot_pixel_dark_current_e_per_s",
                "must be > 0 when noise.hot_pixel_fraction is set (a hot pixel needs a dark current)",
            )
        offset = self.principal_point_offset_px
        if abs(offset[0]) > self.width_px / 2 or abs(offset[1]) > self.height_px / 2:
            raise invalid(
                "principal_point_offset_px",
                f"must put the optical axis on the sensor, within ±{self.width_px / 2:g} px across and "
                f"±{self.height_px / 2:g} px down, got [{offset[0]:g}, {offset[1]:g}]",
            )
        if self.width_px * self.height_px > SENSOR_PIXELS_MAX:
            raise invalid(
                "width_px",
                f"× height_px must be ≤ {SENSOR_PIXELS_MAX / 1e6:g} MP (the largest area sensors sold have 151 MP), "
                f"got {self.width_px} × {self.height_px} = {self.width_px * self.height_px / 1e6:.4g} MP",
            )
        noise = self.noise
        if self.full_well_e < DYNAMIC_RANGE_MIN * noise.read_noise_e:
            raise invalid(
                "full_well_e",
                f"must be ≥ {DYNAMIC_RANGE_MIN:g} × noise.read_noise_e = {DYNAMIC_RANGE_MIN * noise.read_noise_e:g} e⁻ "
                f"(a dynamic range full well / read noise of at least {20 * math.log10(DYNAMIC_RANGE_MIN):g} dB, "
                f"EMVA 1288; real sensors have 55–80 dB), got {self.full_well_e:g}",
            )
        for key in ("dsnu_e", "row_fpn_e", "column_fpn_e"):
            if getattr(noise, key) > self.full_well_e:
                raise invalid(
                    f"noise.{key}",
                    f"must be ≤ full_well_e ({self.full_well_e:g} e⁻): a fixed-pattern offset larger than the "
                    f"well fills every pixel, got {getattr(noise, key):g}",
                )
        rise = 2.0 ** ((self.temperature_c - noise.dark_current_reference_c) / noise.dark_current_doubling_c)
        for key in ("dark_current_e_per_s", "hot_pixel_dark_current_e_per_s"):
            at_reference = getattr(noise, key)
            if at_reference * rise > DARK_CURRENT_MAX_E_PER_S:
                raise invalid(
                    f"noise.{key}",
                    f"is {at_reference * rise:.3g} e⁻/s at temperature_c ({self.temperature_c:g} °C: "
                    f"{at_reference:g} e⁻/s at {noise.dark_current_reference_c:g} °C, doubling every "
                    f"{noise.dark_current_doubling_c:g} °C), more than the {DARK_CURRENT_MAX_E_PER_S:g} e⁻/s "
                    "that would fill the deepest well in 0.1 s; check the temperatures and the doubling",
                )
        return self


class Distortion(Model):
    """Brown–Conrady coefficients in OpenCV order (undistorted → distorted, as cv2.projectPoints)."""

    k1: float = 0.0
    k2: float = 0.0
    p1: float = 0.0
    p2: float = 0.0
    k3: float = 0.0
    k4: float = 0.0
    k5: float = 0.0
    k6: float = 0.0

    def as_array(self) -> np.ndarray:
        return np.array([self.k1, self.k2, self.p1, self.p2, self.k3, self.k4, self.k5, self.k6])

    @property
    def is_zero(self) -> bool:
        return not np.any(self.as_array())


FocalLength = Annotated[
    float,
    Field(ge=FOCAL_LENGTH_RANGE_MM[0], le=FOCAL_LENGTH_RANGE_MM[1]),
    Why(
        f"real lenses span {FOCAL_LENGTH_RANGE_MM[0]:g}–{FOCAL_LENGTH_RANGE_MM[1]:g} mm, from the shortest "
        "rectilinear lenses to the longest long-range zooms"
    ),
]
"""A focal length, mm, within `FOCAL_LENGTH_RANGE_MM`."""


class ZoomPosition(Model):
    """Lens properties at one focal length; values between entries are interpolated linearly."""

    focal_length_mm: FocalLength
    f_number: Annotated[float, Field(ge=0.5, le=64)] | None = None
    """Aperture at this focal length (zoom lenses ramp, e.g. F1.6 wide → F4.4 tele)."""
    distortion: Distortion | None = None


class ChromaticAberration(Model):
    """Chromatic aberration relative to green.

    Lateral: the red (blue) image is the green one magnified by `lateral_scale_r` (`_b`) about the
    principal point, so a feature at radius r from it is displaced by (s − 1)·r. Axial: the red (blue)
    focus lies `axial_focus_shift_r_um` (`_b`) behind the green one on the sensor side, which blurs
    that channel by a disc of diameter |shift|/N.
    """

    lateral_scale_r: Annotated[float, Field(gt=0.9, lt=1.1)] = 1.0
    lateral_scale_b: Annotated[float, Field(gt=0.9, lt=1.1)] = 1.0
    axial_focus_shift_r_um: Annotated[float, Field(ge=-500, le=500)] = 0.0
    axial_focus_shift_b_um: Annotated[float, Field(ge=-500, le=500)] = 0.0


class Vignetting(Model):
    """Relative illumination across the frame (`camgen.optics.vignetting`).

    The optical part is RI(ρ) = 1 + a1·ρ² + a2·ρ⁴ + a3·ρ⁶ wide open, ρ the image radius over the
    corner radius: give either the datasheet's corner figure (then a1 = RI_corner − 1) or the
    polynomial, not both.
    """

    natural_cos4: bool = False
    """Apply the cos⁴ law of the chief-ray angle (most real lenses correct much of it)."""
    relative_illumination_corner: Annotated[float, Field(gt=0, le=1)] = 1.0
    """Optical relative illumination at the image corner, wide open (datasheet figure; 1 = none)."""
    polynomial: tuple[float, float, float] | None = None
    """[a1, a2, a3] of the relative-illumination polynomial, wide open; null uses the corner figure."""
    full_illumination_f_number: Annotated[float, Field(ge=0.5, le=64)] | None = None
    """f-number from which the optical vignetting has gone (it fades linearly in stops from wide
    open); null keeps it at every aperture."""

    @property
    def optical_polynomial(self) -> tuple[float, float, float]:
        if self.polynomial is not None:
            return self.polynomial
        return (self.relative_illumination_corner - 1.0, 0.0, 0.0)

    @model_validator(mode="after")
    def _check(self) -> Vignetting:
        if self.polynomial is not None and self.relative_illumination_corner != 1.0:
            raise invalid(
                "polynomial",
                "must not be given together with relative_illumination_corner (one source, not two); drop one of them",
            )
        if self.polynomial is not None:
            rho = np.linspace(0.0, 1.0, 1001)
            a1, a2, a3 = self.polynomial
            r2 = rho * rho
            ri = 1.0 + r2 * (a1 + r2 * (a2 + r2 * a3))
            if not (np.all(ri > 0.0) and np.all(ri <= 1.0 + 1e-9)):
                worst = rho[int(np.argmin(ri))] if ri.min() <= 0 else rho[int(np.argmax(ri))]
                value = 1.0 + worst**2 * (a1 + worst**2 * (a2 + worst**2 * a3))
                raise invalid(
                    "polynomial",
                    f"must give a relative illumination in (0, 1] from centre to corner, got {value:.4g} at "
                    f"ρ = {worst:.3g} for {list(self.polynomial)}",
                )
        return self


class Lens(Model):
    """The lens: focal length or zoom range, aperture, focus, distortion, CA and vignetting."""

    model: str = ""
    """Lens part number, for people."""
    focal_length_mm: FocalLength | None = None
    """Focal length of a fixed lens, mm. Give this or `focal_length_range_mm`, not both."""
    focal_length_range_mm: tuple[FocalLength, FocalLength] | None = None
    """[wide, tele] focal lengths of a zoom or varifocal lens, mm."""
    f_number: Annotated[float, Field(ge=0.5, le=64)]
    """Working f-number N = f/D at the wide end (seed paper eq. 3)."""
    focus_distance_m: PositiveFloat | None = None
    """Distance the lens is focused at, m; null focuses at the hyperfocal distance."""
    min_focus_distance_m: PositiveFloat = 0.3
    """Closest focus distance, m."""
    coc_um: PositiveFloat | None = None
    """Acceptable circle of confusion for depth-of-field figures, µm; null uses 2 pixel pitches."""
    distortion: Distortion = Distortion()
    zoom_table: list[ZoomPosition] = []
    """Per-focal-length f-number and distortion, ordered by focal length."""
    chromatic_aberration: ChromaticAberration = ChromaticAberration()
    vignetting: Vignetting = Vignetting()

    @property
    def focal_length_min_mm(self) -> float:
        return self.focal_length_range_mm[0] if self.focal_length_range_mm else self.focal_length_mm

    @property
    def focal_length_max_mm(self) -> float:
        return self.focal_length_range_mm[1] if self.focal_length_range_mm else self.focal_length_mm

    @property
    def zoom_max_x(self) -> float:
        return self.focal_length_max_mm / self.focal_length_min_mm

    def at_focal_length(self, focal_length_mm: float) -> tuple[float, Distortion]:
        """f-number and distortion at `focal_length_mm`, interpolated over the zoom table."""
        f_numbers = [(z.focal_length_mm, z.f_number) for z in self.zoom_table if z.f_number is not None]
        dists = [(z.focal_length_mm, z.distortion) for z in self.zoom_table if z.distortion is not None]
        f_number = self.f_number
        if f_numbers:
            xs, ys = zip(*f_numbers, strict=True)
            f_number = float(np.interp(focal_length_mm, xs, ys))
        distortion = self.distortion
        if dists:
            xs = [x for x, _ in dists]
            table = np.array([d.as_array() for _, d in dists])
            values = [float(np.interp(focal_length_mm, xs, table[:, i])) for i in range(table.shape[1])]
            distortion = Distortion(**dict(zip(Distortion.model_fields, values, strict=True)))
        return f_number, distortion

    @model_validator(mode="after")
    def _check(self) -> Lens:
        if (self.focal_length_mm is None) == (self.focal_length_range_mm is None):
            raise invalid(
                "focal_length_mm",
                "must be given for a fixed lens, or `focal_length_range_mm: [wide, tele]` for a zoom "
                "lens — exactly one of the two"
                + (", got both" if self.focal_length_mm is not None else ", got neither"),
            )
        if self.focal_length_range_mm and self.focal_length_range_mm[0] > self.focal_length_range_mm[1]:
            wide, tele = self.focal_length_range_mm
            raise invalid(
                "focal_length_range_mm",
                f"must be ordered [wide, tele] with wide ≤ tele, got [{wide:g}, {tele:g}]",
            )
        if self.focus_distance_m is not None and self.focus_distance_m < self.min_focus_distance_m:
            raise invalid(
                "focus_distance_m",
                f"must be ≥ min_focus_distance_m ({self.min_focus_distance_m:g} m), got {self.focus_distance_m:g}",
            )
        full = self.vignetting.full_illumination_f_number
        if full is not None and full <= self.f_number:
            raise invalid(
                "vignetting.full_illumination_f_number",
                f"must be above the wide-open f_number ({self.f_number:g}): the optical vignetting fades as "
                f"the aperture closes from there, got {full:g}",
            )
        if not self.distortion.is_zero and any(z.distortion for z in self.zoom_table):
            raise invalid(
                "distortion",
                "must be left out when zoom_table gives distortion per focal length (one source, "
                "not two); move these coefficients into the zoom_table entry for the wide end",
            )
        previous = -math.inf
        for i, position in enumerate(self.zoom_table):
            f = position.focal_length_mm
            if not self.focal_length_min_mm <= f <= self.focal_length_max_mm:
                raise invalid(
                    f"zoom_table[{i}].focal_length_mm",
                    f"must lie in the lens range [{self.focal_length_min_mm:g}, "
                    f"{self.focal_length_max_mm:g}] mm, got {f:g}",
                )
            if f <= previous:
                raise invalid(
                    f"zoom_table[{i}].focal_length_mm",
                    f"must increase along the table (previous {previous:g} mm), got {f:g}",
                )
            previous = f
        return self


class AutoExposure(Model):
    """Auto-exposure: meter a region, drive the mean towards a target, adapt at a limited speed."""

    target_level_frac: Annotated[float, Field(gt=0, lt=1)] = 0.18
    """Metered mean to aim for, as a fraction of the raw full scale above black."""
    metering_region_frac: tuple[Fraction, Fraction, Fraction, Fraction] = (0.0, 0.0, 1.0, 1.0)
    """[x0, y0, x1, y1] of the metering window as fractions of width and height."""
    speed_up_ev_per_s: PositiveFloat = 4.0
    """Fastest brightening, exposure values (stops) per second."""
    speed_down_ev_per_s: PositiveFloat = 8.0
    """Fastest darkening, stops per second (cameras react faster to over-exposure)."""

    @model_validator(mode="after")
    def _check(self) -> AutoExposure:
        x0, y0, x1, y1 = self.metering_region_frac
        if not (x0 < x1 and y0 < y1):
            raise invalid(
                "metering_region_frac",
                f"must be [x0, y0, x1, y1] with x0 < x1 and y0 < y1, got [{x0:g}, {y0:g}, {x1:g}, {y1:g}]",
            )
        return self


class Exposure(Model):
    """Exposure time and gain: fixed (manual) or driven by auto-exposure within limits."""

    mode: Literal["manual", "auto"] = "auto"
    exposure_time_s: Annotated[float, Field(ge=1e-6, le=10)] = 0.01
    """Manual exposure time, or the auto-exposure starting point, s."""
    exposure_time_min_s: Annotated[float, Field(ge=1e-6, le=10)] = 1e-5
    exposure_time_max_s: Annotated[float, Field(ge=1e-6, le=10)] = 1 / 30
    gain_db: Annotated[float, Field(ge=0, le=72)] = 0.0
    """Manual analog gain, or the auto-exposure starting point, dB."""
    auto: AutoExposure = AutoExposure()

    @model_validator(mode="after")
    def _check(self) -> Exposure:
        if self.exposure_time_min_s > self.exposure_time_max_s:
            raise invalid(
                "exposure_time_min_s",
                f"must be ≤ exposure_time_max_s ({self.exposure_time_max_s:g} s), got {self.exposure_time_min_s:g}",
            )
        if not self.exposure_time_min_s <= self.exposure_time_s <= self.exposure_time_max_s:
            raise invalid(
                "exposure_time_s",
                f"must lie in [exposure_time_min_s, exposure_time_max_s] = "
                f"[{self.exposure_time_min_s:g}, {self.exposure_time_max_s:g}] s, got {self.exposure_time_s:g}",
            )
        return self


WhiteBalanceGain = Annotated[
    float,
    Field(ge=0.05, le=20),
    Why("white balance multiplies a channel by 1–4 from daylight to tungsten light, so 0.05–20 at the most"),
]


class WhiteBalance(Model):
    mode: Literal["auto_grey_world", "fixed"] = "auto_grey_world"
    gains_rgb: tuple[WhiteBalanceGain, WhiteBalanceGain, WhiteBalanceGain] = (1.0, 1.0, 1.0)
    """Fixed white-balance gains (R, G, B), used when mode is fixed."""


class ContrastStretch(Model):
    """Contrast stretch (seed paper Fig. 7): map the [low, high] percentiles to the output range."""

    low_percentile: Annotated[float, Field(ge=0, lt=100)] = 0.5
    high_percentile: Annotated[float, Field(gt=0, le=100)] = 99.5
    adaptation_time_s: NonNegativeFloat = 0.5
    """Time constant of the limits' adaptation after a lighting change, s (0 = instant)."""
    max_gain: Annotated[float, Field(ge=1, le=1000)] = 8.0
    """Largest amplification of the stretch: a flat scene keeps its low contrast rather than having
    its noise stretched over the output range (an estimate; cameras rarely publish it)."""
    output_range_frac: tuple[Fraction, Fraction] = (0.0, 1.0)
    """[low, high] output levels (fractions of 255) the stretched range maps to after the tone
    curve: the lower and upper limit of the stretched histogram (a washed-out camera has e.g. [0.06, 0.92])."""

    @model_validator(mode="after")
    def _check(self) -> ContrastStretch:
        if self.low_percentile >= self.high_percentile:
            raise invalid(
                "low_percentile",
                f"must be below high_percentile ({self.high_percentile:g}), got {self.low_percentile:g}",
            )
        low, high = self.output_range_frac
        if low >= high:
            raise invalid("output_range_frac", f"must be [low, high] with low < high, got [{low:g}, {high:g}]")
        return self


class Isp(Model):
    """The camera's image signal processor, in the order it runs."""

    demosaic: Literal["bilinear", "edge_aware", "vng"] = "edge_aware"
    white_balance: WhiteBalance = WhiteBalance()
    ccm: tuple[Rgb, Rgb, Rgb] = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
    """Colour-correction matrix, camera RGB → linear sRGB, rows summing to 1 to keep white."""
    contrast_stretch: ContrastStretch | None = ContrastStretch()
    """null turns the stretch off."""
    tone_curve: Literal["srgb", "bt709", "gamma", "linear"] = "bt709"
    gamma: Annotated[float, Field(gt=0.1, le=5)] = 2.2
    """Display gamma, used when tone_curve is gamma."""
    false_colour_median_px: Literal[0, 3, 5, 7] = 0
    """False-colour suppression (`camgen.isp.enhance.suppress_false_colour`): the side of the median window
    over the colour-difference planes, px; 0 = off. Camera ISPs run one (Freeman 1988): without it a white
    line one or two pixels wide demosaics into a row of coloured dots. 3 and 5 px cost a few ms a 1080p frame,
    7 px about a quarter of a second (OpenCV's median changes method above 5 px)."""
    denoise_strength: Fraction = 0.0
    """Spatial/temporal denoise strength, 0 = off."""
    sharpen_amount: Annotated[float, Field(ge=0, le=5)] = 0.0
    """Unsharp-mask amount, 0 = off."""
    sharpen_radius_px: Annotated[
        float,
        Field(gt=0, le=20),
        Why("a camera sharpens detail a few pixels wide (unsharp-mask σ of 0.5–3 px), so at most 20 px"),
    ] = 1.0
    """σ of the unsharp mask's Gaussian, px."""

    @property
    def ccm_is_identity(self) -> bool:
        return bool(np.allclose(np.array(self.ccm), np.eye(3)))

    @model_validator(mode="after")
    def _check(self) -> Isp:
        sums = np.array(self.ccm).sum(axis=1)
        for i, total in enumerate(sums):
            if abs(total - 1.0) > 1e-3:
                raise invalid(
                    f"ccm[{i}]",
                    f"must sum to 1 so that a grey stays grey (the contrast stretch is measured before the "
                    f"CCM and applied after it), got {total:.4g}; scale the row or put the excess in white_balance",
                )
        return self


BITRATE_RANGE_KBPS = (32.0, 1_000_000.0)
"""Bitrates a camera stream may have, kbit/s. The floor is the lowest rate surveillance recorders and
cameras offer (32 kbit/s: Hikvision's rate lists start at "32K"). Lower targets are not met anyway:
x264 at 320×240 made 17 kbit/s when asked for 1 or 10, and below 1 kbit/s `io.video` hands FFmpeg
0 bit/s, which turns rate control off without a word (7 Mbit/s of noise frames). The ceiling (1 Gbit/s)
is above H.264 level 6.2's 800 Mbit/s."""


class Codec(Model):
    """How the camera encodes its stream."""

    name: Literal["h264", "h265", "mjpeg"] = "h264"
    bitrate_kbps: (
        Annotated[
            float,
            Field(ge=BITRATE_RANGE_KBPS[0], le=BITRATE_RANGE_KBPS[1]),
            Why(
                f"surveillance cameras and recorders offer {BITRATE_RANGE_KBPS[0]:g} kbit/s and up; under "
                "1 kbit/s the rate rounds to 0 bit/s and FFmpeg silently drops rate control"
            ),
        ]
        | None
    ) = 4096.0
    """Target bitrate, kbit/s (`BITRATE_RANGE_KBPS`); null uses constant quality (crf)."""
    crf: Annotated[int, Field(ge=0, le=51)] = 23
    gop_frames: Annotated[
        int,
        Field(ge=1, le=10_000),
        Why("cameras set a key frame every 1 to about a thousand frames, so 1–10000"),
    ] = 50
    """Frames between key frames (I-frame interval)."""
    preset: Literal["ultrafast", "superfast", "veryfast", "faster", "fast", "medium", "slow", "slower", "veryslow"] = (
        "veryfast"
    )
    """x264/x265 speed preset (ignored by MJPEG). Camera encoders are real-time hardware that trade
    compression efficiency for speed, nearer the fast presets than `medium` (an estimate)."""
    pixel_format: Literal["yuv420p", "yuv422p", "yuv444p"] = "yuv420p"


PanLimit = Annotated[float, Field(ge=-360, le=360), Why("a pan range's ends lie within one turn either way, ±360°")]
TiltLimit = Annotated[
    float, Field(ge=-180, le=180), Why("a tilt range's ends lie within ±180° (a head that flips over reaches 180°)")
]
ZoomSweepTime = Annotated[
    float,
    Field(gt=0, le=100),
    Why("a zoom crosses its range in 1–10 s on real cameras, so at most 100 s"),
]
"""Time for a full zoom sweep, s."""
CommandLatency = Annotated[
    float,
    Field(ge=0, le=5),
    Why("IP PTZ heads start moving 50–200 ms after a command; over 5 s is no working camera"),
]
"""Time from a PTZ command to its head moving, s."""
AutofocusTime = Annotated[
    float,
    Field(ge=0, le=10),
    Why(
        "contrast-detection autofocus of CCTV zoom cameras locks in 1–3 s (a time constant of about "
        "0.3–1 s), so at most 10 s; 0 focuses at once"
    ),
]
"""Time constant of the autofocus lag, s."""


class Ptz(Model):
    """Pan–tilt–zoom head limits. Pan and tilt are relative to the mount; tilt > 0 looks up."""

    pan_range_deg: tuple[PanLimit, PanLimit] = (-180.0, 180.0)
    pan_continuous: bool = True
    """Endless pan (slip ring): the range wraps around."""
    tilt_range_deg: tuple[TiltLimit, TiltLimit] = (-90.0, 20.0)
    pan_max_deg_s: PositiveFloat = 100.0
    """Fastest pan, degrees per second."""
    tilt_max_deg_s: PositiveFloat = 100.0
    pan_accel_deg_s2: PositiveFloat = 200.0
    tilt_accel_deg_s2: PositiveFloat = 200.0
    pan_step_deg: NonNegativeFloat = 0.0
    """Mechanical resolution of pan, degrees (0 = continuous)."""
    tilt_step_deg: NonNegativeFloat = 0.0
    zoom_wide_to_tele_s: ZoomSweepTime = 3.5
    """Time for a full zoom sweep from the optical wide end to the optical tele end, s: the figure
    datasheets give as "zoom speed, approx. N s (optical, wide–tele)". The zoom motor moves
    magnification at a constant rate in log scale (1×→2× takes as long as 10×→20×) and reaches that
    rate in `ZOOM_RAMP_S` (camgen.plan.ptz), so a commanded sweep arrives `ZOOM_RAMP_S` (0.2 s) after
    this time; the focus then settles with `autofocus_time_s`. 3.5 s lies between the PTZ listings
    profiles/ptz_2mp_30x.yaml cites ([S5]): 2.3 s for a 15× and 5.6 s for a 32× module (the time
    grows with the zoom ratio); an estimate for a head whose datasheet is not at hand: take the
    figure from the camera's own."""
    autofocus_time_s: AutofocusTime = 0.5
    """Time constant with which the focus follows the distance of the view after the head moves or
    zooms, s (first order in dioptres: 95 % of the way in 3 time constants); 0 focuses instantly.
    Autofocus lag blurs the first frames after a zoom. 0.5 s (95 % in 1.5 s) is an estimate from
    two sources, as no zoom-module datasheet found states an autofocus time: CCTV block cameras
    focus by contrast detection (Sony FCB-H11 technical manual, "Focus": the lens is set by "the high
    frequency content of the picture in a center measurement area"), and a PTZ module maker
    gives contrast-detection lock times of 1.0–3.0 s against 0.1–0.5 s for phase detection
    (Loyalty-Secu, "Can my PTZ focus algorithm maintain sub-second clarity after high-speed
    rotation?", 2026, a table of typical lock times, not a measurement of one camera). Set the
    measured time of a camera (frames from a zoom's end to the sharpest frame, divided by 3)."""
    command_latency_s: CommandLatency = 0.1
    """Time from a command reaching the camera to its head starting to move, s (`camgen.sim`). 0.1 s is
    an estimate, not a published figure: no PTZ datasheet found states a command latency. What is
    published bounds it from below: a Sony FCB block camera processes VISCA commands once per
    vertical cycle and acknowledges one within 16.7 ms (NTSC) / 20 ms (PAL) (FCB-IX11A technical manual, "Timing
    Chart"); an IP head adds receiving and parsing the ONVIF SOAP request and its motor controller's
    cycle. Hill et al., "Measuring Latency for Video Surveillance Systems" (DICTA 2009), define this
    "command latency" and a camera-agnostic way to measure it; measure a camera's own that way or as
    US 2016/0191858 A1 does (command time against the first frame whose pixels change), and set it."""

    @model_validator(mode="after")
    def _check(self) -> Ptz:
        for key in ("pan_range_deg", "tilt_range_deg"):
            low, high = getattr(self, key)
            if low >= high:
                raise invalid(key, f"must be ordered [min, max] with min < max, got [{low:g}, {high:g}]")
        if self.pan_continuous and self.pan_range_deg[1] - self.pan_range_deg[0] != 360:
            low, high = self.pan_range_deg
            raise invalid(
                "pan_range_deg",
                f"must span exactly 360° when pan_continuous is true, got [{low:g}, {high:g}]; "
                "set pan_continuous: false for a limited pan",
            )
        return self


def _validation_points_px(width_px: int, height_px: int, per_edge: int = 33) -> np.ndarray:
    """Where a lens must be invertible: a grid over the image including its outer pixel edges."""
    u, v = np.meshgrid(np.linspace(-0.5, width_px - 0.5, per_edge), np.linspace(-0.5, height_px - 0.5, per_edge))
    return np.stack([u.ravel(), v.ravel()], axis=-1)


class IrIlluminator(Model):
    """The camera's built-in infrared LEDs, on in night mode: a round beam from the lens, intensity
    I_e·cos-weighted like the renderer's spot (`camgen.world.night`), falling off as 1/d²."""

    wavelength_nm: Literal[850] = 850
    """The LEDs' peak wavelength, nm: camgen models 850 nm illuminators (the sensor's QE is given
    there, `Sensor.qe_850nm_rel`); 940 nm ones are not modelled."""
    radiant_intensity_mw_sr: Annotated[
        float,
        Field(gt=0, le=1e5),
        Why("camera IR illuminators give about 100–20 000 mW/sr (a few LEDs to a long-range array); at most 1e5"),
    ] = 2000.0
    """On-axis radiant intensity, mW/sr. 2000: about a bullet camera's "30 m IR" array of 2–4
    high-power 850 nm LEDs of 0.5–1 W/sr each (e.g. OSRAM Oslon Black SFH 4715AS class, ±45° lens);
    an estimate: take the figure from the illuminator's datasheet."""
    half_angle_deg: Annotated[float, Field(gt=1, lt=89), Why("a beam's half angle lies between 1° and 89°")] = 40.0
    """Where the beam ends (full intensity within 80 % of it): about the lens's widest half field of view."""


class NightMode(Model):
    """Day/night switching: below `switch_lux` the IR-cut filter comes out, the stream turns monochrome
    and the IR illuminator lights the scene (`camgen.world.night`)."""

    switch_lux: Annotated[
        float,
        Field(gt=0, le=1000),
        Why("cameras switch to night mode between about 0.1 and 50 lx; at most 1000 lx"),
    ] = 2.0
    """Scene illuminance below which the camera is in night mode, lux: the sky's horizontal illuminance
    (ambient plus sun) the camera's light sensor reads; lamps, which light only their pools, do not
    count. 2 lx: manufacturers' day/night thresholds lie at about 1–5 lx (deep dusk; civil dusk is 3 lx);
    an estimate."""
    ir_cut_filter: bool = True
    """Whether the camera has a switchable IR-cut filter (true: it is removed in night mode, and the
    850 nm light reaches the sensor; false: a camera without one never switches)."""
    ir_illuminator: IrIlluminator | None = IrIlluminator()
    """The built-in IR LEDs; null: none (the camera relies on the scene's light)."""


class Profile(Model):
    """A camera model as sold: everything that does not depend on where it is installed."""

    description: str = ""
    serial: Annotated[int, Field(ge=0)] = 0
    """Default serial seed of the fixed-pattern maps; a scene camera may give its own."""
    sensor: Sensor
    lens: Lens
    exposure: Exposure = Exposure()
    isp: Isp = Isp()
    codec: Codec = Codec()
    ptz: Ptz | None = None
    """The PTZ head, absent for a fixed camera."""
    night_mode: NightMode | None = None
    """Day/night switching with an IR illuminator; null: a day-only camera (always colour)."""

    @property
    def coc_mm(self) -> float:
        coc_um = self.lens.coc_um if self.lens.coc_um is not None else 2.0 * self.sensor.pixel_pitch_um
        return coc_um * 1e-3

    def camera_matrix_px(self, focal_length_mm: float) -> np.ndarray:
        s = self.sensor
        return camera_matrix_px(
            focal_length_mm, s.pixel_pitch_um, s.pitch_y_um, s.width_px, s.height_px, s.principal_point_offset_px
        )

    def corner_radius_normalized(self, focal_length_mm: float) -> float:
        """Normalised (distorted) radius of the farthest image corner at `focal_length_mm`."""
        s = self.sensor
        return corner_radius_normalized(self.camera_matrix_px(focal_length_mm), s.width_px, s.height_px)

    @model_validator(mode="after")
    def _check(self) -> Profile:
        lens, sensor = self.lens, self.sensor
        if self.exposure.gain_db > sensor.analog_gain_max_db:
            raise invalid(
                "exposure.gain_db",
                f"must be ≤ sensor.analog_gain_max_db ({sensor.analog_gain_max_db:g} dB), "
                f"got {self.exposure.gain_db:g}",
            )
        # The distortion model must stay monotone out to the image corners at every zoom position.
        table_has_distortion = any(z.distortion is not None for z in lens.zoom_table)
        checks = [] if table_has_distortion else [("lens.distortion", lens.focal_length_min_mm)]
        checks += [
            (f"lens.zoom_table[{i}].distortion", z.focal_length_mm)
            for i, z in enumerate(lens.zoom_table)
            if z.distortion is not None
        ]
        if table_has_distortion:
            checks += [
                ("lens.zoom_table", f) for f in np.geomspace(lens.focal_length_min_mm, lens.focal_length_max_mm, 17)
            ]
        for key, focal_length in checks:
            _, distortion = lens.at_focal_length(focal_length)
            if distortion.is_zero:
                continue
            corner = self.corner_radius_normalized(focal_length)
            K = self.camera_matrix_px(focal_length)
            reach = fold_inside(distortion.as_array(), corner)
            if reach is not None:
                raise invalid(
                    key,
                    f"folds over inside the image at {focal_length:.4g} mm: the radial mapping turns back "
                    f"at distorted radius {reach:.3f} but the image corner lies at {corner:.3f} "
                    "(normalised units); reduce |k1|/k2/k3 or check their signs",
                )
            try:
                undistort_points(_validation_points_px(sensor.width_px, sensor.height_px), K, distortion.as_array())
            except LensInversionError as error:
                raise invalid(
                    key,
                    f"cannot be inverted everywhere inside the image at {focal_length:.4g} mm ({error}); "
                    "the tangential terms p1/p2 or the rational terms k4–k6 are too large for this field of view",
                ) from None
        return self
