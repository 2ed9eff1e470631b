"""Fit a profile's noise to a camera's ordinary 8-bit output: the noise level function, matched.

For a camera whose raw frames are not available, the noise of its processed output is still visible:
the *noise level function* (NLF), the noise variance of the 8-bit output against its mean intensity,
per channel (Liu et al. 2006). `fit_match` measures it on the reference, then adjusts the profile's
noise parameters until camgen's own output, processed by the profile's ISP and measured by the *same*
estimator, shows the same NLF.

Where each part lives: `camgen.fit.match_statistics` reads the frames once, `camgen.fit.match_nlf`
estimates the NLF (method in its module docstring), `camgen.fit.match_tone` reads the output's clips,
`camgen.fit.match_simulation` renders camgen's output of the same content, `camgen.fit.match_report`
plots the result; this module fits the parameters.

Fitting (`fit_match`)
---------------------
Camgen's side is a simulation whose *content* is the reference's own, through the profile's sensor, ISP
and (when given) codec, measured by the same estimator with the same bins (`camgen.fit.match_simulation`).

The parameters, in log space relative to the start:

- ``sensor.full_well_e``, with ``sensor.conversion_gain_dn_per_e`` scaled by its inverse so that the
  raw DN of the content stay the same (only the electrons per output code, the shot-noise scale, move);
- ``sensor.noise.read_noise_e``;
- optionally ``isp.denoise_strength`` (``fit_denoise``), in [0, 1]; then the NLF of the frames averaged
  over 2 × 2 pixels joins the objective, as denoise trades against the full well in the NLF but also
  correlates the noise of neighbours;
- with grey-world white balance, the light's R/G and B/G: the output hides the light's colour, but the
  balance gains, and with them the noise of R and B against G, follow it (a warm light gives a noisier
  blue channel). A nuisance parameter of the scene, reported as `MatchFit.light_rgb`, not in the profile.

A first guess takes the start's misfit as if shot noise ruled (output variance ∝ 1/full well, and R, B
against G ∝ G/R, G/B of the light); `scipy.optimize.least_squares` (trust region, soft-L1 loss) then
minimises log(NLF_camgen / NLF_reference) over the channel-bins both measure, with forward differences
of 2 % steps. Every evaluation reuses one seed (common random numbers), so the objective is
deterministic and smooth at that scale. 35–55 simulations of 64 frames.

Limits: the analog gain the reference was taken at is invisible in its output, so the fit assumes
`gain_db` (default the profile's exposure gain, 0 dB for daylight), and a fitted full well is the
*effective* electrons per output range at that gain. Without `codec`, a codec's effect on the
reference's noise (its rounding through YUV adds, its quantisation removes) is folded into the fitted
parameters: an H.264 stream at crf 0 in 4:4:4 measured +9–16 % variance over its PNG frames, a nearly
constant 0.2 code² that no sensor parameter mimics. Read noise is determined only as far as it shows
against shot noise in the darkest bins (`MatchFit.uncertainties`; a warning when one is unconstrained).
With a contrast stretch, the content is undone through it as if its low limit were black, and nothing
in the output says otherwise (the stretch sends the scene's darkest point to its output low either way):
a scene whose darkest point is not black adds that point's shot noise, a constant variance in the
output that read noise gives as well. The NLF is then matched with the wrong parameters (darkest point
at 30 % of the peak: NLF within 4.4 %, full well −56 %, read noise ×5.4), so a fit whose read noise
makes most of the variance at its darkest compared bin warns that read noise and full well are not
separable from that footage: include true black (a shadow, a dark object) in the view. The contrast
stretch's output range is taken from where the output piles up at its extremes and its percentiles are
only bounded (`estimate_tone`); the tone curve stays the base profile's: in a single camera's output its
shape is confounded with the scene's own distribution of intensities. A colour cast strong enough to
clip one channel at the stretch's top shifts the simulated stretch by a few percent, which the full well
takes up. The spatial method, on a few images, gives a rough fit (bins scatter by ±10 %): prefer frames
of a static view.

What 8-bit footage can and cannot identify
------------------------------------------
The output shows noise variance against output level, per channel, after an unknown tone curve, an
adaptive stretch and a codec: NLF(c) ≈ (dc/de)² · (e(c) + σ_read²), with e(c) the electrons that map to
output code c and dc/de the codes per electron there (the tone curve's slope times 255 over the electrons
the stretch spans). From this:

- *identified*: the electrons per output code at the operating point (the shot-noise slope of the NLF),
  i.e. the effective full well at the assumed gain, to a few per cent on a static view with mid-tones;
  the codec's and ISP's temporal correlation and blockiness of the noise, compared after the fit;
- *not identified*: the analog gain (a 4× larger full well at +12 dB gives the same output as the base at
  0 dB), the absolute light (only its level relative to the stretch; the fit assumes the auto-exposure
  target for an auto base, a raw range spanning the output for a manual one), and so the exposure time;
  these set the operating point the matched profile pins rather than measures;
- *read noise against full well*: read noise shows only as the constant term of the NLF at its darkest
  bins. Where the NLF has only a shot-noise slope (no dark bins, or 8-bit rounding's 1/12 code² and a
  codec's rounding swamp the constant), read noise is unconstrained (`MatchFit.uncertainties`, a warning);
  where the stretch's low limit sits above black (no true black in view), that limit's shot noise is a
  constant too, so read noise and the stretch's black offset are confounded (the pedestal warning); an
  8-bit MPEG stream quantises small noise away (its NLF falls below the sensor's in flat areas and the
  codec's inter-frame prediction correlates it in time), so read noise and full well from such footage
  are effective values that reproduce it only through the same codec;
- *codecs camgen does not write*: camgen encodes H.264, H.265 and MJPEG, so footage from another codec
  (MPEG-4 part 2, as the footage of issue 24) is reproduced only as far as one of them shapes its noise
  alike. camgen's own 320 × 240 ramp through MPEG-4 part 2 at 400 kbit/s showed noise blockiness 2.92 and
  D_4/D_1 2.21 (1 and 1 for the sensor's noise), against 1.00 and 1.00 without a codec and 1.14 and 1.12
  through the bullet profile's H.265; the fits missed the NLF by 28 % and 122 % with a full well 20
  times the true one (at their bound, 50 times the start), and all three figures refuse them.

Operating point and verification
--------------------------------
The fit assumes an exposure: the base's exposure time and ``gain_db`` (default the base's gain), with the
content's light at the auto-exposure target (an auto base) or spanning the raw range (a manual one). The
matched profile pins it as a manual exposure (`OperatingPoint`): left to auto-exposure, a rendered scene
gets the camera's own split of exposure time and gain, whose electrons per code are not those the fit
found (issue 24 measured the matched profile's noise equal to the base's that way). Then the matched
profile films the reference's content once more under the same light, through its own exposure block,
with an independent seed and the codec, and its NLF, temporal noise spectrum and blockiness are compared
with the reference's (`camgen.fit.match_verify`); a miss beyond 15 % is refused with
`MatchNotReproducedError` unless ``accept_poor_fit``. The content model leaves a bias of its own at the
darkest bins, which the verification exposes: at 12 dB gain (0 dB alike) on a 160 × 120 ramp through the bullet
profile, the truth's own parameters simulated from the inverted content miss the darkest R bin by +28 %
and the mid-tones by +5 % (from the true light: +9 % and ±4 %, the seed's scatter). It comes from the
strong CCM's inversion with the adaptive stretch (identity CCM: +12 %; no stretch: +11 %); median- or
box-filtering the content does not remove it, and its cause is not pinned down. A fit absorbs it into
its parameters or not, depending on its start (the verification's worst bin measured 7.2, 11.9, 14.7 and
22 % from four starts), and is refused when not.

References
----------
C. Liu, W. T. Freeman, R. Szeliski and S. B. Kang, "Noise estimation from a single image", CVPR 2006;
C. Liu, R. Szeliski, S. B. Kang, C. L. Zitnick and W. T. Freeman, "Automatic estimation and removal of
noise from a single image", IEEE TPAMI 30(2), 299–314 (2008).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from scipy import optimize

from camgen.config.profile import Codec, Profile
from camgen.errors import ConfigError
from camgen.fit.match_nlf import (
    DEFAULT_BINS,
    MIN_COUNT,
    TEMPORAL_FRAMES_MIN,
    NoiseLevelFunction,
    _bin_edges,
    _check_method,
    _nlf,
)
from camgen.fit.match_simulation import (
    _capture,
    _codec_fps,
    _content,
    _exposure_at_light,
    _grey_world,
    _light,
    _simulate,
)
from camgen.fit.match_statistics import ReferenceContentError, _collect, _plane_image
from camgen.fit.match_tone import _tone_from_counts
from camgen.fit.match_verify import MatchNotReproducedError, MatchVerification, OperatingPoint, compare
from camgen.plan.compile import isp_steps
from camgen.sensor.auto_exposure import metering_window
from camgen.sensor.exposure import photons_per_cd_m2_s

SIGNIFICANT_DIGITS = 4
"""Fitted values are rounded to this many significant digits."""
SIMULATION_FRAMES = 64
"""Frames the simulation runs for the temporal method."""
SIMULATION_FRAMES_SPATIAL = 16
"""Frames the simulation runs for the spatial method (their blocks are pooled)."""
READ_NOISE_BOUNDS_E = (0.01, 500.0)
"""Range of the fitted read noise, e⁻."""
LIGHT_RATIO_MAX = 4.0
"""The fitted light's R/G and B/G lie within [1/4, 4]."""
DENOISE_START_MIN = 0.2
"""`fit_denoise` starts the strength at least here."""
WORST_BIN_WARNING = 0.1
"""A fit whose NLF misses a bin by more than this fraction gets a warning."""
FULL_WELL_SCALE_BOUNDS = (1 / 50, 50.0)
"""Range of the fitted full well relative to the start."""
FIT_COST_TOLERANCE = 1e-2
"""Relative decrease of the cost below which the fit stops."""
FIT_STEP_TOLERANCE = 1e-3
"""Relative step of the parameters below which the fit stops (a looser one stopped a fit whose trust
region had shrunk on the objective's jitter while the cost still fell by 4 % a step)."""
TEMPORAL_CORRELATION_RATIO_MIN = 0.85
"""A temporal reference whose successive-difference variance falls below this fraction of its plain
temporal variance gets a warning (noise correlated between frames). For frame-independent noise both
estimate σ² with ≥ 1000 degrees of freedom even at the fewest data the estimate accepts (200 pixels of
8 frames), so their ratio scatters by ≤ 6 % there (0.998 measured on 8 frames of 320 × 240 px): 0.85 is
2.5σ below 1 in the worst case and far more in practice, while noise correlated by ρ₁ = 0.6 between
frames gives 0.57 on 8 frames and 0.42 on 64. A drift of δ codes per frame over T frames lifts the plain
variance by δ²(T² − 1)/12 (0.85 code² at 0.1 code per frame over 32 frames), which lowers the ratio too."""
UNCONSTRAINED_SIGMA = 0.5
"""A fitted value whose 1σ uncertainty exceeds this fraction of it (denoise strength: this much in
absolute terms) is reported as unconstrained by the reference."""
PEDESTAL_READ_SHARE = 0.5
"""With a contrast stretch, a fit whose read noise makes more than this share of the variance at the
darkest compared bin gets a warning: that constant term is what a stretch low limit above black (a
scene without black) produces as well (module docstring)."""
VERIFY_SEED_KEY = 0x5EED
"""Mixed with the fit's seed into the verification's (`SeedSequence`), so the two are independent."""
DIFF_STEP = 0.02
"""Finite-difference step of the fit, in log parameter units (2 %; denoise strength: 0.02): far above
the jitter that 8-bit rounding gives the objective."""


@dataclass(frozen=True)
class MatchFit:
    """What `fit_match` found.

    Attributes
    ----------
    reference : NoiseLevelFunction
        The reference's NLF.
    fitted, base : NoiseLevelFunction
        Camgen's NLF on the same content, method and bins with the fitted and with the base profile
        (both under the fitted light).
    parameters : dict of str to float
        Fitted values by profile key path (``sensor.noise.read_noise_e``); a list entry carries its
        index (``isp.contrast_stretch.output_range_frac[0]``).
    relative_error_per_bin : (3, B) float64
        fitted.variance / reference.variance − 1; NaN where either is.
    worst_relative_error : float
        Largest |relative_error_per_bin| over the channel-bins the fit compared (NaN if none).
    profile : Profile
        The base profile with the fitted values.
    warnings : tuple of str
    tone : dict
        `estimate_tone` of the reference.
    light_rgb : (float, float, float)
        Colour of the light (R, G, B relative to G) the simulation found for the reference's scene: with
        grey-world white balance the output hides it, but the balance gains, and with them the noise of R
        and B against G, depend on it. (1, 1, 1) when not fitted.
    evaluations : int
        Simulations the optimiser ran.
    uncertainties : dict of str to float
        1σ uncertainty of each fitted noise value in `parameters` (same keys and units; the tone values
        adopted from the output's clips have none): cov ≈ (JᵀJ)⁻¹·s² of the optimiser's variables, J the
        Jacobian of the log-NLF residuals at the solution and s² their variance per degree of freedom,
        carried to the profile's values to first order. inf where the NLF does not respond to a value,
        NaN where there are no more residuals than variables.
    operating_point : OperatingPoint or None
        The exposure the fit assumed, which `profile` pins as a manual exposure (None only for a fit made
        without it).
    verification : MatchVerification or None
        `profile` rendered at the operating point with an independent seed, against the reference.
    """

    reference: NoiseLevelFunction
    fitted: NoiseLevelFunction
    base: NoiseLevelFunction
    parameters: dict[str, float]
    relative_error_per_bin: np.ndarray
    worst_relative_error: float
    profile: Profile
    warnings: tuple[str, ...]
    tone: dict
    light_rgb: tuple[float, float, float]
    evaluations: int
    uncertainties: dict[str, float] = field(default_factory=dict)
    operating_point: OperatingPoint | None = None
    verification: MatchVerification | None = None

    def profile_fragment(self) -> dict:
        """YAML-ready nested dict of only the fitted keys (plain floats and lists), and the pinned
        operating point (``exposure``: mode, exposure time, gain)."""
        dumped = self.profile.model_dump(mode="json")
        fragment: dict = {}
        keys = list(self.parameters)
        if self.operating_point is not None:
            keys += ["exposure.mode", "exposure.exposure_time_s", "exposure.gain_db"]
        for key in keys:
            path = key.split("[")[0].split(".")
            value = dumped
            for part in path:
                value = value[part]
            node = fragment
            for part in path[:-1]:
                node = node.setdefault(part, {})
            node[path[-1]] = list(value) if isinstance(value, list | tuple) else value
        return fragment


def _round(value: float) -> float:
    if value == 0 or not math.isfinite(value):
        return value
    return float(round(value, SIGNIFICANT_DIGITS - 1 - math.floor(math.log10(abs(value)))))


def _with_values(profile: Profile, values: dict[str, float]) -> Profile:
    """`profile` with the values set by key path (an index as ``key[i]``), validated."""
    dumped = profile.model_dump()
    for key, value in values.items():
        path, _, index = key.partition("[")
        parts = path.split(".")
        node = dumped
        for part in parts[:-1]:
            node = node[part]
        if index:
            items = list(node[parts[-1]])
            items[int(index.rstrip("]"))] = value
            node[parts[-1]] = items
        else:
            node[parts[-1]] = value
    return Profile.model_validate(dumped)


def _tone_values(tone: dict, base: Profile) -> tuple[dict[str, float], list[str]]:
    """Stretch settings `estimate_tone` contradicts in the base profile, and notes on what it cannot see.

    An output range seen at a clip is adopted; a percentile only where the base's lies beyond the bound
    the output sets (it would clip more than the camera does).
    """
    stretch = base.isp.contrast_stretch
    if stretch is None:
        inside = [
            code
            for code, extreme in ((tone["output_low_code"], 0), (tone["output_high_code"], 255))
            if code not in (None, extreme)
        ]
        if inside:
            return {}, [
                f"the reference clips at code(s) {', '.join(map(str, inside))}, an output range the base profile "
                "cannot set without a contrast stretch; not fitted"
            ]
        return {}, []
    values: dict[str, float] = {}
    notes = []
    output_range = list(stretch.output_range_frac)
    for end, index in (("low", 0), ("high", 1)):
        code = tone[f"output_{end}_code"]
        if code is None:
            dark = "dark" if end == "low" else "bright"
            notes.append(
                f"the reference shows no clip at its {dark} end (the scene stays inside the stretch, or denoise or "
                f"a codec smears the clip); kept the base {end}_percentile and output range {end}"
            )
        elif code != round(255 * output_range[index]):
            output_range[index] = _round(code / 255.0)
    if output_range[0] < output_range[1]:
        for index in (0, 1):
            if output_range[index] != stretch.output_range_frac[index]:
                values[f"isp.contrast_stretch.output_range_frac[{index}]"] = output_range[index]
    low_max, high_min = tone["low_percentile_max"], tone["high_percentile_min"]
    if low_max is not None and stretch.low_percentile > low_max:
        values["isp.contrast_stretch.low_percentile"] = _round(low_max)
    if (
        high_min is not None
        and stretch.high_percentile < high_min
        and high_min > values.get("isp.contrast_stretch.low_percentile", stretch.low_percentile)
    ):
        values["isp.contrast_stretch.high_percentile"] = _round(high_min)
    return values, notes


def false_colour_warning(profile: Profile) -> str | None:
    """Why the fit's noise is uncertain for a profile that suppresses false colour (`isp.false_colour`), or
    None. The median of the colour differences takes most of the colour noise out of R, G and B, by an amount
    that depends on the picture (flat regions lose more of it than edges), and the simulation's picture is the
    reference's, downscaled: measured on `tests/fit/test_match.py`'s round trip with the bullet's 5 px median
    in both the reference and the simulation, the fitted read noise came out 4.2 e⁻ for 6.0 and the NLF missed
    the reference by 8 % in its worst bin (≤ 5 % without the median)."""
    if "isp.false_colour" not in isp_steps(profile.isp, profile.sensor):
        return None
    return (
        f"the profile suppresses false colour (isp.false_colour_median_px: {profile.isp.false_colour_median_px}): "
        "its median filters most of the colour noise the NLF measures, by an amount that depends on the picture, "
        "so the fitted noise can be off by a third (read noise 4.2 e⁻ for 6.0 in camgen's own round trip); fit "
        "footage of a camera with its false-colour (or chroma) filter off where it has the setting, with "
        "false_colour_median_px: 0 in the profile"
    )


def fit_match(
    reference_frames_rgb8: Iterable[np.ndarray],
    base: Profile,
    *,
    seed: int | np.random.Generator = 0,
    method: Literal["auto", "temporal", "spatial"] = "auto",
    bins: int | Sequence[float] = DEFAULT_BINS,
    min_count: int | None = None,
    gain_db: float | None = None,
    fit_tone: bool = True,
    fit_denoise: bool = False,
    codec: Codec | None = None,
    codec_fps: float | None = None,
    simulation_max_px: int = 320 * 240,
    max_evaluations: int = 60,
    accept_poor_fit: bool = False,
) -> MatchFit:
    """Fit the base profile's noise so that camgen's output reproduces the reference's noise level function.

    Parameters
    ----------
    reference_frames_rgb8 : iterable of (H, W, 3) uint8
        The camera's output, 8-bit R, G, B: frames of a static view (temporal NLF) or images (spatial).
    base : Profile
        The profile to start from; everything not fitted is kept.
    seed : int or numpy.random.Generator
        Seed of the simulation (a Generator gives one); every evaluation reuses it.
    method, bins, min_count
        As `nlf_from_frames`; the simulation is measured with the method chosen for the reference.
    gain_db : float, optional
        Analog gain the reference was taken at, dB (invisible in its output); default the base profile's
        ``exposure.gain_db``.
    fit_tone : bool
        Adopt the contrast stretch's output range where the reference shows its clips, and move a stretch
        percentile that the reference's clipping contradicts onto its bound (`estimate_tone`).
    fit_denoise : bool
        Also fit ``isp.denoise_strength``; the NLF of the frames averaged over 2 × 2 pixels joins the
        objective (temporal references), since denoise also correlates the noise between neighbours.
    codec : Codec, optional
        The codec the reference went through, when known: the simulated frames are encoded with it
        (bitrate scaled by the pixel count) and decoded before their NLF is measured. None compares
        with the ISP's output, and the fitted parameters take up the codec's effect on the noise.
    codec_fps : float, optional
        Frame rate the simulated frames are encoded at, Hz: the reference stream's (average) rate, which
        sets a rate-controlled codec's bits per frame; default the sensor's ``frame_rate_max_hz``.
    simulation_max_px : int
        Most pixels of the simulated frames (the reference's picture is downscaled to fit).
    max_evaluations : int
        Most evaluations of the objective the optimiser may make; each of its iterations also runs one
        simulation per fitted parameter for the finite differences.
    accept_poor_fit : bool
        Return a match that the verification doubts (its doubts become warnings) instead of raising.

    Returns
    -------
    MatchFit

    Raises
    ------
    ConfigError
        For a reference `nlf_from_frames` refuses, a simulation that shares no usable bin with it, or a
        `gain_db` above the base sensor's ``analog_gain_max_db``.
    MatchNotReproducedError
        (a ConfigError) Unless `accept_poor_fit`: the matched profile, rendered at its operating point,
        misses the reference by more than 15 % in an NLF bin with enough samples, in the temporal noise
        spectrum or in blockiness (`camgen.fit.match_verify`); its ``fit`` holds the refused MatchFit.

    Notes
    -----
    Method and its limits in the module docstring. At 320 × 240 px a simulation of 64 frames with its
    NLF costs about 0.15 s on 2 cores (0.35 s through a lossless H.264 round trip); a fit runs 35–55
    of them: 5–9 s, 15–20 s with a codec.
    """
    _check_method(method)
    edges = _bin_edges(bins)
    if gain_db is not None and not 0 <= gain_db <= base.sensor.analog_gain_max_db:
        raise ConfigError(
            f"gain_db must lie in [0, sensor.analog_gain_max_db] = [0, {base.sensor.analog_gain_max_db:g}] dB of "
            f"the base profile, got {gain_db:g}: the matched profile pins the exposure at this gain"
        )
    statistics = _collect(
        reference_frames_rgb8,
        temporal=method != "spatial",
        spatial=method != "temporal",
        histogram=True,
        half_scale=fit_denoise,
        spectrum=True,
    )
    reference = _nlf(statistics, method, edges, min_count)
    if not np.any(reference.variance[reference.usable] > 0):
        low, high = int(statistics.first.min()), int(statistics.first.max())
        flat = f"its first frame is one flat level ({low} in every pixel) and " if low == high else ""
        raise ReferenceContentError(
            f"the reference shows no noise: {flat}its {reference.method} variance is 0 in every intensity bin it "
            "fills, so it holds no noise-level information to fit; give the camera's own output with its noise "
            "(several frames of a static view, or images with flat but noisy regions), not a synthetic, uniform "
            "or fully denoised picture"
        )
    warnings: list[str] = []
    if method == "auto" and reference.method == "spatial" and statistics.frames >= TEMPORAL_FRAMES_MIN:
        if statistics.sizes_differ:
            why = "they differ in size"
        elif statistics.pairs == 0:
            why = "every pair of successive frames changes over most of the picture"
        else:
            why = f"only {statistics.static_fraction:.0%} of the picture is static"
        warnings.append(f"used the spatial noise estimate on {statistics.frames} frames: {why}")
    if reference.difference_to_plain_ratio < TEMPORAL_CORRELATION_RATIO_MIN:
        warnings.append(
            f"the reference's noise correlates between frames: successive differences show "
            f"{reference.difference_to_plain_ratio:.2f} of its plain temporal variance (1 for independent "
            "frames), as temporal noise reduction in the camera or a codec's inter-frame prediction make it; the "
            "temporal NLF is biased low by about that factor, and so is the fitted noise (or a slow drift or "
            "flicker of the light lifts the plain variance: check the footage)"
        )
    false_colour = false_colour_warning(base)
    if false_colour is not None:
        warnings.append(false_colour)
    tone = _tone_from_counts(statistics.counts)
    values: dict[str, float] = {}
    if fit_tone:
        values, notes = _tone_values(tone, base)
        warnings += notes
    start = _with_values(base, values) if values else base
    gain = start.exposure.gain_db if gain_db is None else gain_db
    simulation_seed = (
        int(np.random.default_rng(seed).integers(2**63)) if isinstance(seed, np.random.Generator) else int(seed)
    )
    picture = statistics.total / statistics.frames if reference.method == "temporal" else _plane_image(statistics.first)
    content = _content(
        picture,
        start,
        max_px=simulation_max_px,
        gain_db=gain,
        codec=codec,
        shows_fixed_pattern=reference.method == "temporal",
        codec_fps=codec_fps,
    )
    frames = SIMULATION_FRAMES if reference.method == "temporal" else SIMULATION_FRAMES_SPATIAL
    count = min_count if min_count is not None else MIN_COUNT[reference.method]

    # Denoise trades against the full well in the NLF (strength 0.19 with 24 % more electrons matched a
    # 0.5 reference within 4 %) but not in that of 2 × 2-averaged frames (−5 % there): fit both.
    half_scale = fit_denoise and reference.method == "temporal"
    reference_half = (
        _nlf(statistics.half, "temporal", edges, max(1, count // 4), refuse_empty=False) if half_scale else None
    )
    if half_scale and not reference_half.usable.any():
        half_scale, reference_half = False, None
        warnings.append(
            "the reference averaged over 2 × 2 pixels has no usable intensity bin; fitted the denoise strength "
            "from the full-resolution NLF alone, where it trades against the full well"
        )

    def measure_both(
        profile: Profile, light_rgb: tuple[float, float, float]
    ) -> tuple[NoiseLevelFunction, NoiseLevelFunction | None]:
        output = _simulate(profile, content, light_rgb, frames=frames, seed=simulation_seed)
        temporal = reference.method == "temporal"
        simulated = _collect(output, temporal=temporal, spatial=not temporal, histogram=False, half_scale=half_scale)
        # A simulation may lose bins (an extreme trial clips them); the objective penalises those.
        nlf = _nlf(simulated, reference.method, edges, count, refuse_empty=False)
        if not half_scale:
            return nlf, None
        return nlf, _nlf(simulated.half, "temporal", edges, max(1, count // 4), refuse_empty=False)

    def measure(profile: Profile, light_rgb: tuple[float, float, float]) -> NoiseLevelFunction:
        return measure_both(profile, light_rgb)[0]

    sensor = start.sensor
    read0 = max(sensor.noise.read_noise_e, 0.1)
    fit_light = _grey_world(start)
    # x: log full-well scale, log read noise over its start, [denoise strength], [log light R/G, log B/G].
    lower = [math.log(FULL_WELL_SCALE_BOUNDS[0]), math.log(READ_NOISE_BOUNDS_E[0] / read0)]
    upper = [math.log(FULL_WELL_SCALE_BOUNDS[1]), math.log(READ_NOISE_BOUNDS_E[1] / read0)]
    x0 = [0.0, 0.0]
    if fit_denoise:
        lower.append(0.0)
        upper.append(1.0)
        # At strength 0 the bilateral's range σ is far below the noise, so its slope there is flat: start
        # where a step changes the output.
        x0.append(max(start.isp.denoise_strength, DENOISE_START_MIN))
    if fit_light:
        lower += [-math.log(LIGHT_RATIO_MAX)] * 2
        upper += [math.log(LIGHT_RATIO_MAX)] * 2
        x0 += [0.0, 0.0]
    x0 = np.clip(x0, lower, upper)

    def profile_at(x: np.ndarray) -> Profile:
        scale = math.exp(x[0])
        noise = sensor.noise.model_copy(update={"read_noise_e": read0 * math.exp(x[1])})
        fitted_sensor = sensor.model_copy(
            update={
                "full_well_e": sensor.full_well_e * scale,
                "conversion_gain_dn_per_e": sensor.conversion_gain_dn_per_e / scale,
                "noise": noise,
            }
        )
        update = {"sensor": fitted_sensor}
        if fit_denoise:
            update["isp"] = start.isp.model_copy(update={"denoise_strength": float(np.clip(x[2], 0.0, 1.0))})
        return start.model_copy(update=update)

    def light_at(x: np.ndarray) -> tuple[float, float, float]:
        return (math.exp(x[-2]), 1.0, math.exp(x[-1])) if fit_light else (1.0, 1.0, 1.0)

    start_nlf, start_half = measure_both(start, light_at(x0))
    mask = reference.usable & start_nlf.usable & (reference.variance > 0) & (start_nlf.variance > 0)
    if not mask.any():
        raise ConfigError(
            "camgen's simulation of the reference shares no usable intensity bin with it; the base profile's "
            "tone settings may map the content far from the reference's levels"
        )
    log_reference = np.log(reference.variance[mask])
    if half_scale:
        mask_half = (
            reference_half.usable & start_half.usable & (reference_half.variance > 0) & (start_half.variance > 0)
        )
        log_reference = np.concatenate([log_reference, np.log(reference_half.variance[mask_half])])
    # A first guess from the start's misfit, as if shot noise ruled: its variance in the output goes as
    # 1/full well, and that of R (B) against G as G/R (G/B) of the light (through the balance gains).
    with np.errstate(invalid="ignore", divide="ignore"):
        log_ratio = np.where(mask, np.log(start_nlf.variance / reference.variance), np.nan)
    x0[0] = float(np.nanmean(log_ratio))
    if fit_light:
        channel = np.nanmean(log_ratio, axis=1)
        x0[-2:] = np.nan_to_num(channel[[0, 2]] - channel[1])
    x0 = np.clip(x0, lower, upper)
    evaluated: dict[tuple[float, ...], np.ndarray] = {}

    def residuals(x: np.ndarray) -> np.ndarray:
        key = tuple(float(v) for v in x)
        if key not in evaluated:
            nlf, half = measure_both(profile_at(x), light_at(x))
            variance = (
                nlf.variance[mask] if half is None else np.concatenate([nlf.variance[mask], half.variance[mask_half]])
            )
            # A bin the simulation lost (too few samples) counts as a 50 % miss, so the optimiser leaves it.
            lost = ~(variance > 0)
            residual = np.log(np.where(lost, 1.0, variance)) - log_reference
            residual[lost] = math.log(1.5)
            evaluated[key] = residual
        return evaluated[key]

    def jacobian(x: np.ndarray) -> np.ndarray:
        # Forward differences of a fixed step (scipy's relative step vanishes at x = 0), away from a bound.
        here = residuals(x)
        columns = []
        for i in range(x.size):
            step = DIFF_STEP if x[i] + DIFF_STEP <= upper[i] else -DIFF_STEP
            moved = x.copy()
            moved[i] += step
            columns.append((residuals(moved) - here) / step)
        return np.column_stack(columns)

    solution = optimize.least_squares(
        residuals,
        x0,
        jac=jacobian,
        bounds=(lower, upper),
        loss="soft_l1",
        f_scale=0.05,
        max_nfev=max_evaluations,
        ftol=FIT_COST_TOLERANCE,
        xtol=FIT_STEP_TOLERANCE,
    )
    noise_keys = ("sensor.full_well_e", "sensor.noise.read_noise_e")
    for name, value, low, high in zip(noise_keys, solution.x[:2], lower[:2], upper[:2], strict=True):
        if min(value - low, high - value) < 1e-3:
            warnings.append(f"the fitted {name} sits at its bound; the NLF may need a parameter this fit lacks")
    if not solution.success:
        warnings.append(f"the optimiser stopped early: {solution.message}")

    sigma_x = _sigma(jacobian(solution.x), residuals(solution.x))
    pedestal_share = 0.0
    if start.isp.contrast_stretch is not None:
        # d log(variance)/d log(read noise) = 2 × read noise's share of the variance; the first compared
        # bin of each channel is its darkest (the residuals run channel by channel, bins ascending).
        read_column = jacobian(solution.x)[: int(mask.sum()), 1]
        channel_rows = np.argwhere(mask)[:, 0]
        darkest = [int(np.flatnonzero(channel_rows == c)[0]) for c in np.unique(channel_rows)]
        pedestal_share = float(np.max(read_column[darkest])) / 2.0
    if pedestal_share > PEDESTAL_READ_SHARE:
        warnings.append(
            "the fit attributes most of the noise variance at the darkest levels it compared to read noise; with a "
            "contrast stretch, a scene whose darkest point is not black (the stretch's low limit above 0) adds "
            "the same constant variance, so read noise and full well are not separable from this "
            "footage: include true black in the view (a shadow, a dark object) and fit again"
        )

    fitted_raw = profile_at(solution.x)
    scale = fitted_raw.sensor.full_well_e / sensor.full_well_e
    values["sensor.full_well_e"] = _round(fitted_raw.sensor.full_well_e)
    values["sensor.conversion_gain_dn_per_e"] = _round(sensor.conversion_gain_dn_per_e / scale)
    values["sensor.noise.read_noise_e"] = _round(fitted_raw.sensor.noise.read_noise_e)
    if fit_denoise:
        values["isp.denoise_strength"] = _round(fitted_raw.isp.denoise_strength)
    # First order: a value exp(x)·v₀ has σ = value·σ_x; the denoise strength is x itself.
    log_sigma = {
        "sensor.full_well_e": sigma_x[0],
        "sensor.conversion_gain_dn_per_e": sigma_x[0],
        "sensor.noise.read_noise_e": sigma_x[1],
    }
    uncertainties = {key: _round(values[key] * sigma) for key, sigma in log_sigma.items()}
    if fit_denoise:
        uncertainties["isp.denoise_strength"] = _round(sigma_x[2])
    for key in ("sensor.full_well_e", "sensor.noise.read_noise_e", "isp.denoise_strength"):
        if key not in uncertainties:
            continue
        spread = uncertainties[key] if key == "isp.denoise_strength" else log_sigma[key]
        if spread > UNCONSTRAINED_SIGMA:
            shown = f"±{spread:.2g}" if key == "isp.denoise_strength" else f"±{spread:.0%}"
            why = " (swamped by shot noise: it shows only in the darkest bins)" if "read_noise" in key else ""
            warnings.append(
                f"{key} is hardly constrained by this reference (1σ {shown}){why}; the fitted value is not a "
                "measurement"
            )
    unpinned = _with_values(base, values)
    light = light_at(solution.x)
    fitted = measure(unpinned, light)
    base_nlf = measure(base, light)
    with np.errstate(invalid="ignore", divide="ignore"):
        relative = fitted.variance / reference.variance - 1.0
    worst = float(np.nanmax(np.abs(relative[mask]))) if np.isfinite(relative[mask]).any() else math.nan
    if not worst <= WORST_BIN_WARNING:
        warnings.append(f"the fitted NLF misses the reference by up to {worst:.0%} in a bin")

    # The operating point: the light that gave the fit its output levels, and the exposure it was taken
    # at, pinned as the matched profile's manual exposure (what auto-exposure would choose for a
    # rendered scene is not what the fit assumed).
    scene = _light(unpinned, content, light)
    operating_point = _operating_point(unpinned, scene.photons_per_s, scene.exposure_time_s, scene.gain_db)
    profile = unpinned.model_copy(
        update={
            "exposure": unpinned.exposure.model_copy(
                update={"mode": "manual", "exposure_time_s": scene.exposure_time_s, "gain_db": scene.gain_db}
            )
        }
    )
    verification = _verify(
        profile,
        content,
        scene.photons_per_s,
        reference,
        statistics,
        edges=edges,
        count=count,
        frames=frames,
        seed=simulation_seed,
    )
    result = MatchFit(
        reference=reference,
        fitted=fitted,
        base=base_nlf,
        parameters=values,
        relative_error_per_bin=relative,
        worst_relative_error=worst,
        profile=profile,
        warnings=tuple(warnings + list(verification.doubts)),
        tone=tone,
        light_rgb=light,
        evaluations=len(evaluated),
        uncertainties=uncertainties,
        operating_point=operating_point,
        verification=verification,
    )
    if verification.doubts and not accept_poor_fit:
        raise MatchNotReproducedError(
            "the matched profile does not reproduce the reference: "
            + "; ".join(verification.doubts)
            + f". {REFUSAL_ADVICE}",
            fit=result,
        )
    return result


REFUSAL_ADVICE = (
    "What to try: the temporal method on frames of a static view (--method temporal) with more frames "
    "(--max-frames), the reference's own codec in the base profile (or --no-codec when the footage is "
    "lossless), --fit-denoise where the camera smooths its noise, and the gain the footage was taken at "
    "(--gain-db); or pass --accept-poor-fit to write the profile anyway, with these doubts in its header"
)
"""The end of `MatchNotReproducedError`'s message."""


def _operating_point(
    profile: Profile, photons_per_s: np.ndarray, exposure_time_s: float, gain_db: float
) -> OperatingPoint:
    """The exposure the fit assumed and the mean scene luminance (metering window) of its light."""
    sensor = profile.sensor
    window = metering_window(*photons_per_s.shape, profile.exposure.auto.metering_region_frac)
    per_cd_m2_s = photons_per_cd_m2_s(sensor.pixel_pitch_um * sensor.pitch_y_um, profile.lens.f_number)
    return OperatingPoint(
        exposure_time_s=exposure_time_s,
        gain_db=gain_db,
        f_number=profile.lens.f_number,
        mean_luminance_cd_m2=float(np.mean(photons_per_s[window], dtype=np.float64)) / per_cd_m2_s,
        was_auto=profile.exposure.mode == "auto",
    )


def _verify(
    profile: Profile,
    content,
    photons_per_s: np.ndarray,
    reference: NoiseLevelFunction,
    reference_statistics,
    *,
    edges: np.ndarray,
    count: int,
    frames: int,
    seed: int,
) -> MatchVerification:
    """The matched profile films the content's light through its own exposure block, with a seed
    independent of the fit's, through the codec; its output against the reference (`camgen.fit.match_verify`)."""
    exposure_time_s, gain = _exposure_at_light(profile, photons_per_s, fps=_codec_fps(profile, content))
    verify_seed = int(np.random.SeedSequence([seed % 2**63, VERIFY_SEED_KEY]).generate_state(1, np.uint64)[0] >> 1)
    output = _capture(
        profile, content, photons_per_s, exposure_time_s=exposure_time_s, gain_db=gain, frames=frames, seed=verify_seed
    )
    temporal = reference.method == "temporal"
    simulated = _collect(output, temporal=temporal, spatial=not temporal, histogram=False, spectrum=temporal)
    nlf = _nlf(simulated, reference.method, edges, count, refuse_empty=False)
    return compare(
        reference,
        reference_statistics,
        nlf,
        simulated if temporal else None,
        exposure_time_s=exposure_time_s,
        gain_db=gain,
        seed=verify_seed,
    )


def _sigma(jacobian: np.ndarray, residuals: np.ndarray) -> np.ndarray:
    """1σ of the least-squares variables: sqrt(diag((JᵀJ)⁻¹)·s²), s² = Σr²/(m − n); inf for a variable
    the residuals do not respond to, NaN without spare residuals."""
    m, n = jacobian.shape
    if m <= n:
        return np.full(n, math.nan)
    s2 = float(np.sum(residuals**2)) / (m - n)
    information = jacobian.T @ jacobian
    sigma = np.full(n, math.inf)
    responds = np.any(jacobian != 0, axis=0)
    if responds.any():
        sub = information[np.ix_(responds, responds)]
        try:
            covariance = np.linalg.inv(sub) * s2
        except np.linalg.LinAlgError:
            return sigma
        sigma[responds] = np.sqrt(np.clip(np.diag(covariance), 0.0, None))
    return sigma
