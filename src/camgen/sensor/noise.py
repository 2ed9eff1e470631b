"""Temporal sensor noise and the ADC: expected electrons → noisy electrons → raw DN.

DESIGN.md "Sensor model" (the seed paper's N_cap after Irie et al., quantities as in EMVA 1288):

    e  = min(Poisson(μ), full well) + offset + N(0, σ_read²)        μ = η·Φ·(1 + PRNU) + D(T)·t
    DN = clip(round(K·G·e + black), 0, 2^bits − 1)

Fast, and statistically the same (each choice is measured in `make bench`):

- Shot noise above `gaussian_above_e` expected electrons is drawn as N(μ, μ); below it, exactly
  (numpy's Poisson on those sites only). Above the threshold shot and read noise are independent
  Gaussians, so one draw N(0, μ + σ_read²) stands for both.
- Standard normals come from a 65 536-entry inverse-CDF table indexed by 16 random bits: 3× faster
  than numpy's ziggurat (the generator, not the arithmetic, bounds a noise model). The table holds the
  normal quantiles at bin centres rescaled to unit variance, so it is exact in mean and variance; its
  tails stop at ±4.3 σ (probability 1.5·10⁻⁵ beyond).
- Sites that could reach full well are redone in the physical order (shot noise, clip, blooming,
  then offset and read noise), so a saturated site carries read noise and no shot noise.
- The frame is processed in two row bands, each with its own generator; an executor given by the
  caller runs them in parallel, and the result does not depend on whether one is given.
"""

from __future__ import annotations

import itertools
import math
from concurrent.futures import Executor
from dataclasses import dataclass
from functools import lru_cache

import cv2
import numpy as np
from scipy.special import ndtri

BANDS = 2
"""Row bands of a frame; each draws from its own generator (fixed, so threading changes nothing)."""
FLOAT32_MAX = float(np.finfo(np.float32).max)
SATURATION_MARGIN_SIGMA = 6.0
"""Sites whose expected signal is within this many noise σ of full well are redone in full."""


@lru_cache(maxsize=1)
def _normal_table() -> np.ndarray:
    quantiles = ndtri((np.arange(65536, dtype=np.float64) + 0.5) / 65536.0)
    quantiles /= np.sqrt(np.mean(quantiles * quantiles))
    table = quantiles.astype(np.float32)
    table.flags.writeable = False
    return table


def standard_normal(shape, *, rng: np.random.Generator) -> np.ndarray:
    """float32 standard normals from 16 random bits each (see the module docstring).

    `cv2.LUT` does the table lookup (0.6 ms for 2 M samples against 2.4 ms for `np.take`).
    """
    shape = (shape,) if isinstance(shape, int) else tuple(shape)
    count = int(np.prod(shape))
    if count == 0:
        return np.zeros(shape, np.float32)
    index = np.frombuffer(rng.bytes(2 * count), dtype="<u2").reshape(count, 1)
    return cv2.LUT(index, _normal_table()).reshape(shape)


def _read_noise(count: int, sigma_e: float, tail_dof: float | None, rng: np.random.Generator) -> np.ndarray:
    """Read noise of `count` sites, e⁻: Gaussian, or Student-t of `tail_dof` degrees of freedom scaled
    to the same σ (heavy-tailed random-telegraph noise)."""
    if tail_dof is None:
        return standard_normal(count, rng=rng) * np.float32(sigma_e)
    scale = np.sqrt((tail_dof - 2.0) / tail_dof) * sigma_e
    return (rng.standard_t(tail_dof, count) * scale).astype(np.float32)


def _band_slices(height: int) -> list[slice]:
    edges = np.linspace(0, height, BANDS + 1).round().astype(int)
    return [slice(int(a), int(b)) for a, b in itertools.pairwise(edges)]


def _part(value, rows: slice):
    return value[rows] if isinstance(value, np.ndarray) else value


def _shot_electrons(mean_e: np.ndarray, scale, gaussian_above_e: float, rng: np.random.Generator) -> np.ndarray:
    """Photo- and dark-signal electrons with shot noise (no offset, no read noise), float32."""
    low = mean_e < gaussian_above_e
    out = mean_e + np.sqrt(mean_e) * standard_normal(mean_e.shape, rng=rng) * scale
    if low.any():
        mu = mean_e[low]
        s = scale[low] if isinstance(scale, np.ndarray) else scale
        out[low] = mu + (rng.poisson(mu).astype(np.float32) - mu) * s
    return out


@dataclass(frozen=True)
class TemporalNoise:
    """What `sample_electrons` and `sample_raw` draw (see `sample_electrons` for each field)."""

    read_noise_e: float
    noise_scale: np.ndarray | float = 1.0
    shot_noise: bool = True
    gaussian_above_e: float = 20.0
    read_noise_tail_dof: float | None = None
    full_well_e: float = np.inf
    blooming: bool = False


@dataclass(frozen=True)
class Adc:
    """The ADC: DN = clip(round(gain·e + black), 0, 2^bits − 1) (`digitize`)."""

    gain_dn_per_e: float
    black_level_dn: float
    bit_depth: int


@dataclass
class _Band:
    rows: slice
    mean: np.ndarray
    electrons: np.ndarray
    dn: np.ndarray | None


def _expected(band: _Band, rate, per_unit, exposure_time_s, dark_e_per_s) -> None:
    """μ = rate · per_unit · t + dark · t into `band.mean` (one pass each, no temporaries)."""
    t = float(exposure_time_s)
    if isinstance(per_unit, np.ndarray):
        cv2.multiply(rate, per_unit, dst=band.mean, scale=t)
    else:
        cv2.multiply(rate, float(per_unit) * t, dst=band.mean)
    if isinstance(dark_e_per_s, np.ndarray):
        cv2.scaleAdd(dark_e_per_s, t, band.mean, dst=band.mean)
    elif dark_e_per_s:
        band.mean += np.float32(dark_e_per_s * t)
    _clamp_expected(band.mean, band.mean, "the light at the sensor (rate · per_unit · t + dark · t)")


def _clamp_expected(mean: np.ndarray, out: np.ndarray, what: str) -> None:
    """Expected electrons clamped to [0, float32 max] into `out`; ValueError on NaN.

    FFT convolutions (large blur discs) leave round-off such as −3e-12 where the light is zero, taken
    as 0. Light beyond float32 (an infinite rate, or rate · t overflowing) is held at the largest
    float32, which every full well clips: inf would turn into NaN in the noise (inf − inf) and read as
    0 DN. NaN is no light level at all; one pass (a sum, NaN iff any site is NaN) finds it.
    """
    np.clip(mean, 0.0, FLOAT32_MAX, out=out)
    with np.errstate(over="ignore"):  # a sum past float32 is inf, still not NaN
        total = float(np.sum(out))
    if math.isnan(total):
        raise ValueError(f"{what} contains NaN; fix the render (or the radiance passed in) before the sensor")


def _temporal(band: _Band, offset_e, scale, noise: TemporalNoise, rng: np.random.Generator) -> None:
    """Shot and read noise of one band (and its offsets), into `band.electrons`."""
    mean, out = band.mean, band.electrons
    read, tail = noise.read_noise_e, noise.read_noise_tail_dof
    if not noise.shot_noise:
        np.add(mean, _read_noise(mean.size, read, tail, rng).reshape(mean.shape) * scale, out=out)
    elif tail is not None:
        out[...] = _shot_electrons(mean, scale, noise.gaussian_above_e, rng)
        out += _read_noise(mean.size, read, tail, rng).reshape(mean.shape) * scale
    else:
        z = standard_normal(mean.shape, rng=rng)
        sigma = np.add(mean, np.float32(read * read))
        cv2.sqrt(sigma, dst=sigma)
        if isinstance(scale, np.ndarray) or scale != 1.0:
            sigma *= scale
        cv2.multiply(sigma, z, dst=out)
        out += mean
        low = mean < noise.gaussian_above_e
        if low.any():
            mu = mean[low]
            s = scale[low] if isinstance(scale, np.ndarray) else np.float32(scale)
            out[low] = mu + (rng.poisson(mu).astype(np.float32) - mu + z[low] * np.float32(read)) * s
    if offset_e is not None:
        out += offset_e


def _run_bands(height: int, width: int, work, rng: np.random.Generator, executor: Executor | None, adc: Adc | None):
    """Split the frame into `BANDS` row bands, run `work(band, rng)` on each, return the bands and the
    generator left for the saturated sites."""
    streams = rng.spawn(BANDS + 1)
    mean = np.empty((height, width), np.float32)
    electrons = np.empty((height, width), np.float32)
    dn = None if adc is None else np.empty((height, width), np.uint16)
    # A sensor of one row has an empty band: it is skipped (OpenCV refuses empty arrays), and each
    # band keeps its own stream, so the draws of the other do not change.
    bands = [
        (_Band(rows, mean[rows], electrons[rows], None if dn is None else dn[rows]), stream)
        for rows, stream in zip(_band_slices(height), streams, strict=False)
        if rows.stop > rows.start
    ]
    if executor is None:
        for band, stream in bands:
            work(band, stream)
    else:
        for future in [executor.submit(work, band, stream) for band, stream in bands]:
            future.result()
    return _Band(slice(0, height), mean, electrons, dn), streams[-1]


def sample_electrons(
    mean_e: np.ndarray,
    *,
    read_noise_e: float,
    offset_e: np.ndarray | None = None,
    noise_scale: np.ndarray | float = 1.0,
    shot_noise: bool = True,
    gaussian_above_e: float = 20.0,
    read_noise_tail_dof: float | None = None,
    full_well_e: float = np.inf,
    blooming: bool = False,
    rng: np.random.Generator,
    executor: Executor | None = None,
) -> np.ndarray:
    """Electrons read from each site: shot noise, full well (blooming), offsets and read noise.

    Parameters
    ----------
    mean_e : (H, W) float32
        Expected collected electrons μ (photo-electrons plus dark-current electrons); round-off below
        0 is taken as 0, values beyond float32 (inf) as the largest float32. NaN raises ValueError.
    read_noise_e : float
        Temporal read noise σ_read, electrons rms.
    offset_e : (H, W) float32, optional
        Fixed dark offset (DSNU, row and column FPN), electrons.
    noise_scale : float or (H, W) float32
        Multiplier on the temporal noise (shot and read), per site (the seed paper's Fig. 5).
    shot_noise : bool
        False: no Poisson noise (μ is collected exactly).
    gaussian_above_e : float
        Expected electrons above which shot noise is drawn as a Gaussian; ``inf`` draws Poisson everywhere.
    read_noise_tail_dof : float, optional
        Degrees of freedom of a Student-t read noise (heavy tail) with the same σ.
    full_well_e : float
        Saturation capacity, electrons; signal above it is clipped (or spills, with `blooming`).
    blooming : bool
        Charge above full well spills equally into the four neighbours (once; what they cannot hold
        is drained), as a CMOS pixel's overflow does.
    rng : numpy.random.Generator
        Two band generators and one for saturated sites are spawned from it.
    executor : concurrent.futures.Executor, optional
        Runs the two bands in parallel (numpy releases the GIL); the output is the same without it.

    Returns
    -------
    (H, W) float32
        Electrons, including offsets and read noise (may be negative).
    """
    mean_e = np.asarray(mean_e, dtype=np.float32)
    if mean_e.ndim != 2:
        raise ValueError(f"mean_e must be an (H, W) array, got shape {mean_e.shape}")
    noise = TemporalNoise(
        read_noise_e=read_noise_e,
        noise_scale=noise_scale if isinstance(noise_scale, np.ndarray) else float(noise_scale),
        shot_noise=shot_noise,
        gaussian_above_e=gaussian_above_e,
        read_noise_tail_dof=read_noise_tail_dof,
        full_well_e=full_well_e,
        blooming=blooming,
    )

    def work(band: _Band, stream: np.random.Generator) -> None:
        _clamp_expected(mean_e[band.rows], band.mean, "mean_e")
        _temporal(band, _part(offset_e, band.rows), _part(noise.noise_scale, band.rows), noise, stream)

    frame, rest = _run_bands(*mean_e.shape, work, rng, executor, None)
    _saturate(frame, offset_e, noise, rest, None)
    return frame.electrons


def sample_raw(
    rate: np.ndarray,
    *,
    per_unit: np.ndarray | float,
    exposure_time_s: float,
    dark_e_per_s: np.ndarray | float,
    offset_e: np.ndarray | None,
    noise: TemporalNoise,
    adc: Adc,
    rng: np.random.Generator,
    executor: Executor | None = None,
) -> np.ndarray:
    """Raw DN of one exposure, fused: μ = rate·per_unit·t + dark·t, then `sample_electrons`'s noise,
    then `digitize`, band by band (each band's pass over memory does all three).

    Parameters
    ----------
    rate : (H, W) float32
        Light at each site in any linear unit that `per_unit` turns into electrons per second.
    per_unit : (H, W) float32 or float
        Electrons per second per unit of `rate` (QE, PRNU, the camera equation, vignetting).
    exposure_time_s : float
    dark_e_per_s : (H, W) float32 or float
        Dark current of each site at the operating temperature, e⁻/s.
    offset_e, noise, adc, rng, executor
        As in `sample_electrons` and `digitize`.

    Returns
    -------
    (H, W) uint16
        Raw DN. The same draws as `digitize(sample_electrons(μ, …))`.
    """
    rate = np.asarray(rate, dtype=np.float32)
    if rate.ndim != 2:
        raise ValueError(f"rate must be an (H, W) array, got shape {rate.shape}")

    def work(band: _Band, stream: np.random.Generator) -> None:
        rows = band.rows
        _expected(band, rate[rows], _part(per_unit, rows), exposure_time_s, _part(dark_e_per_s, rows))
        _temporal(band, _part(offset_e, rows), _part(noise.noise_scale, rows), noise, stream)
        band.dn[...] = digitize(band.electrons, **vars(adc))

    frame, rest = _run_bands(*rate.shape, work, rng, executor, adc)
    _saturate(frame, offset_e, noise, rest, adc)
    return frame.dn


def _saturate(frame: _Band, offset_e, noise: TemporalNoise, rng: np.random.Generator, adc: Adc | None) -> None:
    """Redo the sites that may reach full well in the physical order: shot noise, clip, spill, read."""
    full_well_e = noise.full_well_e
    if not np.isfinite(full_well_e):
        return
    mean_e, out, scale = frame.mean, frame.electrons, noise.noise_scale
    scale_max = float(np.max(scale)) if isinstance(scale, np.ndarray) else scale
    margin = SATURATION_MARGIN_SIGMA * scale_max * np.sqrt(full_well_e) if noise.shot_noise else 0.0
    near = mean_e > np.float32(full_well_e - margin)
    if not near.any():
        return
    if noise.blooming:
        near = cv2.dilate(near.view(np.uint8), np.ones((3, 3), np.uint8)).view(bool)
    index = np.flatnonzero(near)
    mu = mean_e.ravel()[index]
    s = scale.ravel()[index] if isinstance(scale, np.ndarray) else np.float32(scale)
    signal = _shot_electrons(mu, s, noise.gaussian_above_e, rng) if noise.shot_noise else mu.copy()
    if noise.blooming:
        excess = np.zeros(mean_e.shape, np.float32)
        excess.ravel()[index] = np.maximum(signal - np.float32(full_well_e), 0.0)
        spill = cv2.filter2D(
            excess,
            -1,
            np.array([[0, 0.25, 0], [0.25, 0, 0.25], [0, 0.25, 0]], np.float32),
            borderType=cv2.BORDER_CONSTANT,
        )
        with np.errstate(over="ignore"):  # spill from light beyond float32 is inf, clipped next
            signal += spill.ravel()[index]
    np.minimum(signal, np.float32(full_well_e), out=signal)
    signal += _read_noise(index.size, noise.read_noise_e, noise.read_noise_tail_dof, rng) * s
    if offset_e is not None:
        signal += offset_e.ravel()[index]
    out.ravel()[index] = signal
    if adc is not None:
        frame.dn.ravel()[index] = digitize(signal, **vars(adc))


def digitize(electrons: np.ndarray, *, gain_dn_per_e: float, black_level_dn: float, bit_depth: int) -> np.ndarray:
    """The ADC: DN = clip(round(G·e + black), 0, 2^bits − 1) as uint16 (rounding half up).

    `gain_dn_per_e` is the system gain K times the analog gain. Quantisation adds 1/12 DN² of
    variance (EMVA 1288 eq. 6).
    """
    white = float(2**bit_depth - 1)
    with np.errstate(over="ignore"):  # electrons near float32's largest may give inf DN: clipped to white
        scaled = electrons * np.float32(gain_dn_per_e)
        scaled += np.float32(black_level_dn + 0.5)
    np.clip(scaled, 0.0, white, out=scaled)
    return scaled.astype(np.uint16)
