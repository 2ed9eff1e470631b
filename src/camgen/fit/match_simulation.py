"""Camgen's side of `camgen.fit.match.fit_match`: the reference's picture through a profile's sensor, ISP
and codec, whose output is measured by the same noise level function estimator (Liu et al. 2006) as the
reference.

Camgen's side is a simulation whose *content* is the reference's own: the temporal-mean frame (spatial:
the first frame with each 8 × 8 block replaced by its fitted plane, which removes the noise) is
downscaled to at most `simulation_max_px` pixels (INTER_AREA keeps its histogram, so the adaptive
contrast stretch sees what the camera saw) and inverted through the profile's output range, tone curve
and CCM to linear camera RGB. Per CFA site the sensor collects electrons ∝ that RGB × the colour of the
light × the QE of the site's colour (with fixed white-balance gains: ∝ RGB / gains), scaled so that
auto-exposure has converged (the metered mean at `exposure.auto.target_level_frac`, as
`CameraPipeline.converge_exposure` does) or, for a manual profile, so that the output range spans the
raw range; a colour the camera clipped after white balance is put beyond the clip (`_site_levels`).
`SensorModel.capture` and `CameraIsp.process` (the stages the plan would keep) run frame by frame with
one seed, without the fixed patterns when the content is a temporal mean (it already shows them), then
through the reference's codec when one is given, and the same estimator with the same bins measures
the NLF.

References
----------
C. Liu, W. T. Freeman, R. Szeliski and S. B. Kang, "Noise estimation from a single image", CVPR 2006;
C. Liu, R. Szeliski, S. B. Kang, C. L. Zitnick and W. T. Freeman, "Automatic estimation and removal of
noise from a single image", IEEE TPAMI 30(2), 299–314 (2008).
"""

from __future__ import annotations

import math
import tempfile
from dataclasses import dataclass

import av
import cv2
import numpy as np

from camgen.config.profile import Codec, Isp, Profile
from camgen.errors import ConfigError
from camgen.io.video import VideoWriter, decoded_rgb8
from camgen.isp.pipeline import CameraIsp
from camgen.isp.tone import tone_curve
from camgen.plan.compile import isp_steps
from camgen.sensor.auto_exposure import ExposureLimits, metering_window, settled_exposure, split_exposure
from camgen.sensor.capture import NOISE_TERMS, SensorModel
from camgen.sensor.cfa import cfa_site_values, mosaic
from camgen.sensor.characteristics import saturation_e
from camgen.sensor.exposure import gain_linear

CLIP_KNEE = 0.98
"""Content within this fraction of the white-balance clip counts as clipped (`_site_levels`)."""
CLIP_OVERSHOOT = 1.25
"""Clipped content is placed this far beyond the clip, well beyond its noise."""
TEMPORAL_NOISE_TERMS = frozenset({"shot", "dark_current", "read", "blooming"})
"""The sensor model's terms that vary from frame to frame (or act on the signal in a frame)."""


@dataclass(frozen=True)
class _Content:
    """The simulation's static scene, before light colour and exposure."""

    linear_rgb: np.ndarray
    """(H, W, 3) float32: the output's linear signal (after CCM, relative to the stretch range)."""
    gain_db: float
    codec: Codec | None
    """The codec the simulated frames pass through (encoded and decoded), or None."""
    codec_fps: float | None
    """Frame rate the codec encodes at, Hz; None: the sensor's ``frame_rate_max_hz``."""
    shows_fixed_pattern: bool
    """The content is the reference's temporal mean, which already shows the camera's fixed patterns
    (PRNU, DSNU, row and column offsets, hot and dead pixels): the simulation leaves them out rather than
    apply them twice (they change the temporal noise only through edge-aware demosaicing and denoise,
    which see them as texture: +4…+16 % green variance with `edge_aware` when doubled)."""


def _inverse_tone(encoded: np.ndarray, isp: Isp) -> np.ndarray:
    """Linear signal (relative to the stretch range) of encoded output fractions, by table inversion."""
    grid = np.linspace(0.0, 1.0, 65536)
    forward = np.maximum.accumulate(tone_curve(grid, isp.tone_curve, isp.gamma))
    return np.interp(encoded, forward, grid)


def _grey_world(profile: Profile) -> bool:
    """Whether the profile balances colour by grey world (then the light's colour is not in its output)."""
    steps = isp_steps(profile.isp, profile.sensor)
    return "isp.white_balance" in steps and profile.isp.white_balance.mode == "auto_grey_world"


def _simulation_size(height: int, width: int, max_px: int) -> tuple[int, int]:
    scale = min(1.0, math.sqrt(max_px / (height * width)))
    return max(16, int(height * scale) // 2 * 2), max(16, int(width * scale) // 2 * 2)


def _output_range(isp: Isp) -> tuple[float, float]:
    return isp.contrast_stretch.output_range_frac if isp.contrast_stretch is not None else (0.0, 1.0)


def _content(
    picture_rgb8: np.ndarray,
    profile: Profile,
    *,
    max_px: int,
    gain_db: float,
    codec: Codec | None,
    shows_fixed_pattern: bool,
    codec_fps: float | None = None,
) -> _Content:
    """The reference's picture, downscaled, through the inverse output range and tone curve. A codec's
    bitrate is scaled with the pixel count (the bits per pixel stay the reference's)."""
    height, width = _simulation_size(*picture_rgb8.shape[:2], max_px)
    image = cv2.resize(picture_rgb8.astype(np.float32), (width, height), interpolation=cv2.INTER_AREA)
    low, high = _output_range(profile.isp)
    linear = _inverse_tone(np.clip((image / 255.0 - low) / (high - low), 0.0, 1.0), profile.isp)
    if codec_fps is not None and not (math.isfinite(codec_fps) and codec_fps > 0):
        raise ConfigError(f"codec_fps must be a finite frame rate > 0 Hz, got {codec_fps}")
    if codec is not None and codec.bitrate_kbps is not None:
        ratio = height * width / (picture_rgb8.shape[0] * picture_rgb8.shape[1])
        codec = codec.model_copy(update={"bitrate_kbps": codec.bitrate_kbps * ratio})
    return _Content(
        linear_rgb=linear.astype(np.float32),
        gain_db=gain_db,
        codec=codec,
        shows_fixed_pattern=shows_fixed_pattern,
        codec_fps=codec_fps,
    )


def _site_levels(content: _Content, profile: Profile, light_rgb: tuple[float, float, float]) -> np.ndarray:
    """(H, W) float32: electrons each site collects, as a fraction of saturation (module docstring).

    Camera RGB is the linear content through the inverse CCM; with grey world it is multiplied by the
    light's colour and the QE of each colour relative to the largest (what grey world then divides out),
    with fixed gains it is divided by them. Auto-exposure scales the result until the metered mean is
    at its target; a manual profile keeps it (the output range spans the raw range).

    A colour that the camera clipped after white balance comes back from the output exactly at the clip,
    where the simulation's noise would dither it in and out (and through the CCM into the other
    colours), while the camera's light went on beyond it: such values (≥ `CLIP_KNEE` of the clip) are
    set to `CLIP_OVERSHOOT` times the clip.
    """
    sensor, isp = profile.sensor, profile.isp
    steps = isp_steps(isp, sensor)
    if sensor.cfa == "mono":
        camera = content.linear_rgb.mean(axis=2, keepdims=True)
        colour = np.ones(1)
        balanced = 1.0
    else:
        ccm = np.array(isp.ccm, np.float64) if "isp.ccm" in steps else np.eye(3)
        camera = np.clip(content.linear_rgb @ np.linalg.inv(ccm).T.astype(np.float32), 0.0, None)
        if _grey_world(profile):
            qe = sensor.quantum_efficiency
            colour = np.array([qe.r, qe.g, qe.b]) / max(qe.r, qe.g, qe.b) * np.asarray(light_rgb)
            # Grey world's gains, smallest 1, bring each colour to the largest colour's level.
            balanced = float(np.max(colour))
        elif "isp.white_balance" in steps:
            gains = np.array(isp.white_balance.gains_rgb)
            colour = np.min(gains) / gains
            balanced = 1.0
        else:
            colour = np.ones(3)
            balanced = 1.0

    def sites(camera: np.ndarray) -> np.ndarray:
        weighted = (camera * colour.astype(np.float32)).astype(np.float32)
        return weighted[..., 0] if sensor.cfa == "mono" else mosaic(weighted, sensor.cfa)

    site = sites(camera)
    scale = _exposure_scale(site, profile, content.gain_db)
    # After white balance a colour reaches the clip at camera · scale · balanced = 1.
    clip = 1.0 / (scale * balanced)
    clipped = camera >= CLIP_KNEE * clip
    if clipped.any():
        camera = np.where(clipped, np.float32(CLIP_OVERSHOOT * clip), camera)
        site = sites(camera)
        scale = _exposure_scale(site, profile, content.gain_db)
    return site * np.float32(scale)


def _exposure_scale(site: np.ndarray, profile: Profile, gain_db: float) -> float:
    """The factor on the site levels at which auto-exposure has converged (the metered mean at its
    target, as `CameraPipeline.converge_exposure`), or 1 for a manual profile."""
    sensor, exposure = profile.sensor, profile.exposure
    if exposure.mode != "auto":
        return 1.0
    saturation, _ = saturation_e(
        sensor.full_well_e, sensor.conversion_gain_dn_per_e, sensor.black_level_dn, sensor.bit_depth, gain_db
    )
    level_per_frac = (
        saturation
        * sensor.conversion_gain_dn_per_e
        * gain_linear(gain_db)
        / (sensor.white_level_dn - sensor.black_level_dn)
    )
    metered = site[metering_window(*site.shape, exposure.auto.metering_region_frac)]
    scale = 1.0
    # Clipping at saturation makes it a few multiplicative steps.
    for _ in range(30):
        level = float(np.mean(np.minimum(metered * scale, 1.0))) * level_per_frac
        if level <= 0:
            break
        step = exposure.auto.target_level_frac / level
        scale *= step
        if abs(step - 1.0) < 1e-6:
            break
    return scale


@dataclass(frozen=True)
class _Light:
    """The simulated scene's light at the sensor and the exposure that gave the fit's output levels."""

    photons_per_s: np.ndarray
    """(H, W) float32: photons per second arriving at each site (before its QE)."""
    exposure_time_s: float
    gain_db: float


def _light(profile: Profile, content: _Content, light_rgb: tuple[float, float, float]) -> _Light:
    """The photons per second that give the site levels of `_site_levels` at the profile's exposure time
    and the content's gain, once the sensor model applies each colour's QE."""
    sensor = profile.sensor
    height, width = content.linear_rgb.shape[:2]
    saturation, _ = saturation_e(
        sensor.full_well_e, sensor.conversion_gain_dn_per_e, sensor.black_level_dn, sensor.bit_depth, content.gain_db
    )
    exposure_time_s = profile.exposure.exposure_time_s
    qe = sensor.quantum_efficiency
    per_photon = 1.0 if sensor.cfa == "mono" else cfa_site_values((qe.r, qe.g, qe.b), sensor.cfa, height, width)
    rate = _site_levels(content, profile, light_rgb) * np.float32(saturation / exposure_time_s) / per_photon
    return _Light(photons_per_s=rate.astype(np.float32), exposure_time_s=exposure_time_s, gain_db=content.gain_db)


def _exposure_at_light(profile: Profile, photons_per_s: np.ndarray, *, fps: float) -> tuple[float, float]:
    """(exposure time s, gain dB) that the profile's own exposure block sets for this light: the manual
    setting, or where auto-exposure settles as `camgen.plan.camera_pipeline.CameraPipeline.converge_exposure`
    finds it (the noise-free metered level at the target, exposure time first up to the frame interval,
    then analog gain up to ``sensor.analog_gain_max_db``)."""
    sensor, exposure = profile.sensor, profile.exposure
    if exposure.mode != "auto":
        return exposure.exposure_time_s, exposure.gain_db
    longest = min(exposure.exposure_time_max_s, 1.0 / fps)
    limits = ExposureLimits(min(exposure.exposure_time_min_s, longest), longest, sensor.analog_gain_max_db)
    height, width = photons_per_s.shape
    qe = sensor.quantum_efficiency
    per_photon = 1.0 if sensor.cfa == "mono" else cfa_site_values((qe.r, qe.g, qe.b), sensor.cfa, height, width)
    window = metering_window(height, width, exposure.auto.metering_region_frac)
    rate_e_per_s = (photons_per_s * per_photon)[window].astype(np.float64)
    start = split_exposure(exposure.exposure_time_s * gain_linear(exposure.gain_db), limits)
    setting = settled_exposure(
        rate_e_per_s, start, sensor=sensor, target_frac=exposure.auto.target_level_frac, limits=limits
    )
    return setting.exposure_time_s, setting.gain_db


def _simulate(
    profile: Profile, content: _Content, light_rgb: tuple[float, float, float], *, frames: int, seed: int
) -> list[np.ndarray]:
    """Camgen's 8-bit output of the static content through the profile's sensor and ISP."""
    light = _light(profile, content, light_rgb)
    return _capture(
        profile,
        content,
        light.photons_per_s,
        exposure_time_s=light.exposure_time_s,
        gain_db=light.gain_db,
        frames=frames,
        seed=seed,
    )


def _capture(
    profile: Profile,
    content: _Content,
    photons_per_s: np.ndarray,
    *,
    exposure_time_s: float,
    gain_db: float,
    frames: int,
    seed: int,
) -> list[np.ndarray]:
    """Frames of a static light (photons per second per site) through the profile's sensor at an exposure,
    its ISP and the content's codec."""
    height, width = photons_per_s.shape
    sensor = profile.sensor.model_copy(update={"width_px": width, "height_px": height})
    terms = TEMPORAL_NOISE_TERMS if content.shows_fixed_pattern else NOISE_TERMS
    model = SensorModel.build(sensor, profile.serial, terms=terms)
    isp = CameraIsp(
        profile.isp, sensor, frame_interval_s=1.0 / sensor.frame_rate_max_hz, steps=isp_steps(profile.isp, sensor)
    )
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(frames):
        raw = model.capture(photons_per_s, exposure_time_s=exposure_time_s, gain_db=gain_db, rng=rng)
        out.append(isp.process(raw, gain_db))
    if content.codec is not None:
        out = _through_codec(out, content.codec, fps=_codec_fps(profile, content))
    return out


def _codec_fps(profile: Profile, content: _Content) -> float:
    """Frame rate the simulated frames are encoded (and auto-exposure's frame interval set) at, Hz."""
    return content.codec_fps if content.codec_fps is not None else profile.sensor.frame_rate_max_hz


def _through_codec(frames_rgb8: list[np.ndarray], codec: Codec, *, fps: float) -> list[np.ndarray]:
    """The frames encoded by `camgen.io.video.VideoWriter` (into a temporary file) and decoded by PyAV
    with the colour matrix and range the stream is tagged with."""
    height, width = frames_rgb8[0].shape[:2]
    with tempfile.TemporaryDirectory(prefix="camgen-match-") as directory:
        path = f"{directory}/simulation.mp4"
        with VideoWriter(path, width_px=width, height_px=height, fps=fps, codec=codec, preset=codec.preset) as writer:
            for frame in frames_rgb8:
                writer.write(frame)
        with av.open(path) as container:
            return [decoded_rgb8(frame) for frame in container.decode(video=0)]
