"""`camgen fit match` judged by what it renders (issue 24): the operating point the matched profile pins,
the verification at that point, its spectrum and blockiness figures against closed forms, and the refusal
of a reference that camgen's camera cannot reproduce.

The reference is camgen's own camera at a *manual* 0.01 s and 12 dB (a dim scene: the mean raw level at
the auto-exposure target only thanks to the gain), while the base profile leaves exposure to auto-exposure,
which at that light would choose the frame interval and almost no gain (0.033 s, 1.8 dB): the electrons
per output code, and so the noise, differ by 3.3×. Small frames (160 × 120, 48 frames) keep the file
under 15 s.
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
import pytest
import yaml

from camgen.cli.main import main
from camgen.config.loader import load_profile
from camgen.config.profile import Profile
from camgen.fit.match import MatchFit, fit_match
from camgen.fit.match_nlf import nlf_from_frames
from camgen.fit.match_statistics import _collect
from camgen.fit.match_verify import TOLERANCE, MatchNotReproducedError, blockiness, temporal_structure
from camgen.io.frames import write_frame
from camgen.isp.pipeline import CameraIsp
from camgen.isp.tone import tone_curve
from camgen.sensor.auto_exposure import ExposureLimits, metering_window, split_exposure
from camgen.sensor.capture import SensorModel
from camgen.sensor.cfa import mosaic
from camgen.sensor.exposure import gain_linear, photons_per_cd_m2_s
from tests.conftest import REPO
from tests.fit.test_match import ISP_STEPS, with_noise

WIDTH_PX, HEIGHT_PX = 160, 120
FRAMES = 48
BINS = 16
GAIN_DB = 12.0
EXPOSURE_TIME_S = 0.01
COUNT_MIN = 500
"""Reference pixels a bin needs for the independent render's check (a bin of 16 codes holds ~1100)."""
TNR_WEIGHT = 0.5
"""Recursive temporal noise reduction y_t = w·y_{t−1} + (1 − w)·x_t: noise correlated by ρ = w between
frames, which camgen's sensor cannot make."""


def ramp_cd_m2(peak_cd_m2: float) -> np.ndarray:
    """(H, W, 3) radiance whose bt709 level rises evenly left to right, every other 20-px band mirrored."""
    grid = np.linspace(0.0, 1.0, 4096)
    linear = np.interp(np.linspace(0.0, 1.0, WIDTH_PX), tone_curve(grid, "bt709"), grid)
    radiance = np.repeat(linear[None, :], HEIGHT_PX, axis=0)
    for top in range(20, HEIGHT_PX, 40):
        radiance[top : top + 20] = radiance[top : top + 20, ::-1]
    return (radiance[..., None] * peak_cd_m2 * np.array([1.0, 1.0, 0.9])).astype(np.float32)


def electrons_per_cd_m2_s(profile: Profile) -> tuple[SensorModel, np.ndarray]:
    sensor = profile.sensor.model_copy(update={"width_px": WIDTH_PX, "height_px": HEIGHT_PX})
    model = SensorModel.build(sensor, profile.serial)
    factor = photons_per_cd_m2_s(sensor.pixel_pitch_um**2, profile.lens.f_number)
    return model, model.electrons_per_photon * np.float32(factor)


def exposure_of(profile: Profile, radiance_cd_m2: np.ndarray) -> tuple[float, float]:
    """What camgen's camera sets for this light: the manual setting, or auto-exposure's settled one (the
    mean expected raw level at the target; exposure time first, up to the frame interval, then gain)."""
    exposure, sensor = profile.exposure, profile.sensor
    if exposure.mode == "manual":
        return exposure.exposure_time_s, exposure.gain_db
    _, per_site = electrons_per_cd_m2_s(profile)
    rate = (mosaic(radiance_cd_m2, sensor.cfa) * per_site)[metering_window(HEIGHT_PX, WIDTH_PX, (0, 0, 1, 1))]
    level_per_s = (
        float(np.mean(rate)) * sensor.conversion_gain_dn_per_e / (sensor.white_level_dn - sensor.black_level_dn)
    )
    longest = min(exposure.exposure_time_max_s, 1.0 / sensor.frame_rate_max_hz)
    limits = ExposureLimits(exposure.exposure_time_min_s, longest, sensor.analog_gain_max_db)
    setting = split_exposure(exposure.auto.target_level_frac / level_per_s, limits)
    return setting.exposure_time_s, setting.gain_db


def film(profile: Profile, radiance_cd_m2: np.ndarray, frames: int, seed: int) -> list[np.ndarray]:
    """The profile's camera watching a static scene at the exposure it sets itself (`exposure_of`)."""
    exposure_time_s, gain_db = exposure_of(profile, radiance_cd_m2)
    model, per_site = electrons_per_cd_m2_s(profile)
    sensor = model.sensor
    isp = CameraIsp(profile.isp, sensor, frame_interval_s=1 / 25, steps=ISP_STEPS)
    light = mosaic(radiance_cd_m2, sensor.cfa).astype(np.float32)
    rng = np.random.default_rng(seed)
    return [
        isp.process(
            model.capture(
                light, exposure_time_s=exposure_time_s, gain_db=gain_db, rng=rng, electrons_per_photon=per_site
            ),
            gain_db,
        )
        for _ in range(frames)
    ]


def temporally_filtered(frames: list[np.ndarray], weight: float = TNR_WEIGHT) -> list[np.ndarray]:
    """The frames through recursive temporal noise reduction (`TNR_WEIGHT`), rounded to 8 bits."""
    state = frames[0].astype(np.float64)
    out = []
    for frame in frames:
        state = weight * state + (1 - weight) * frame
        out.append(np.clip(np.rint(state), 0, 255).astype(np.uint8))
    return out


@pytest.fixture(scope="module")
def bullet() -> Profile:
    """The bullet profile with its false-colour suppression off: the fit does not model the median's effect on
    the colour noise it measures (`camgen.fit.match.false_colour_warning`; with it on, this module's round trips
    fitted half the truth's noise variance)."""
    profile = load_profile(REPO / "profiles/bullet_4mp_2p8mm.yaml").profile
    return profile.model_copy(update={"isp": profile.isp.model_copy(update={"false_colour_median_px": 0})})


@pytest.fixture(scope="module")
def truth(bullet: Profile) -> Profile:
    """The bullet camera (read noise 6 e⁻) held at a manual 0.01 s and 12 dB."""
    manual = bullet.exposure.model_copy(
        update={"mode": "manual", "exposure_time_s": EXPOSURE_TIME_S, "gain_db": GAIN_DB}
    )
    return with_noise(bullet, read_noise_e=6.0).model_copy(update={"exposure": manual})


@pytest.fixture(scope="module")
def radiance(truth: Profile) -> np.ndarray:
    """The ramp scaled so that at 0.01 s and 12 dB the mean expected raw level is the auto-exposure target
    (the level the fit assumes for an auto-exposed base: 8-bit output does not show the absolute light)."""
    _, per_site = electrons_per_cd_m2_s(truth)
    sensor = truth.sensor
    unit = mosaic(ramp_cd_m2(1.0), sensor.cfa) * per_site * EXPOSURE_TIME_S
    level = float(np.mean(unit)) * sensor.conversion_gain_dn_per_e * gain_linear(GAIN_DB)
    peak = truth.exposure.auto.target_level_frac * (sensor.white_level_dn - sensor.black_level_dn) / level
    return ramp_cd_m2(peak)


@pytest.fixture(scope="module")
def reference(truth: Profile, radiance: np.ndarray) -> list[np.ndarray]:
    return film(truth, radiance, FRAMES, seed=1)


@pytest.fixture(scope="module")
def base(truth: Profile, bullet: Profile) -> Profile:
    """The truth's noise with the bullet's auto-exposure: the operating point is under test here, the
    optimiser's travel is `tests/fit/test_match.py`'s round trips'. (From full well ×0.4 and read noise ×3
    the verification measured 11.9 % in its worst bin, from ×0.6 and ×2 22 %: `fit_match` refuses that fit.)"""
    return truth.model_copy(update={"exposure": bullet.exposure})


@pytest.fixture(scope="module")
def matched(reference: list[np.ndarray], base: Profile) -> MatchFit:
    return fit_match(reference, base, seed=3, bins=BINS, gain_db=GAIN_DB)


def test_matched_profile_pins_the_operating_point(matched: MatchFit, truth: Profile, radiance: np.ndarray) -> None:
    exposure = matched.profile.exposure
    assert (exposure.mode, exposure.exposure_time_s, exposure.gain_db) == ("manual", EXPOSURE_TIME_S, GAIN_DB)
    assert matched.profile_fragment()["exposure"] == {
        "mode": "manual",
        "exposure_time_s": EXPOSURE_TIME_S,
        "gain_db": GAIN_DB,
    }
    point = matched.operating_point
    assert point.was_auto and "replaces the base profile's auto-exposure" in point.describe()
    # The light it names is the reference's (measured +3 %): what 8-bit output leaves of it, the level at
    # the auto-exposure target, was the reference's true level here.
    window = metering_window(HEIGHT_PX, WIDTH_PX, (0, 0, 1, 1))
    true_mean_cd_m2 = float(np.mean(mosaic(radiance, truth.sensor.cfa)[window]))
    assert point.mean_luminance_cd_m2 == pytest.approx(true_mean_cd_m2, rel=0.05)


def test_matched_profile_renders_the_reference_noise_at_the_same_light(
    matched: MatchFit, reference: list[np.ndarray], radiance: np.ndarray, base: Profile
) -> None:
    verification = matched.verification
    assert verification.reproduces and verification.doubts == ()
    # Measured: worst bin 7.2 % of 41, D_k/D_1 within 0.2 %, blockiness −4.2 %.
    assert verification.checked.sum() >= 36
    assert verification.worst_relative_error <= TOLERANCE
    assert np.nanmax(np.abs(verification.structure_error)) < 0.05
    assert (verification.exposure_time_s, verification.gain_db) == (EXPOSURE_TIME_S, GAIN_DB)
    # Independently: the matched profile films the reference's scene as camgen's camera would, at the
    # exposure its own profile sets (measured: −9.6 % … +4.5 % in 41 bins).
    reference_nlf = nlf_from_frames(reference, bins=BINS)
    checked = (reference_nlf.count >= COUNT_MIN) & reference_nlf.usable
    rendered = nlf_from_frames(film(matched.profile, radiance, FRAMES, seed=9), bins=BINS)
    error = rendered.variance[checked] / reference_nlf.variance[checked] - 1
    assert checked.sum() >= 36 and np.all(np.abs(error) <= TOLERANCE), f"worst {np.nanmax(np.abs(error)):.1%}"
    # The same fitted noise left to the base's auto-exposure (as fit match wrote it before): 0.033 s at
    # 1.8 dB, 3.3× the electrons per code, the noise variance 69–84 % low.
    unpinned = matched.profile.model_copy(update={"exposure": base.exposure})
    assert exposure_of(unpinned, radiance)[1] < 2.0
    auto = nlf_from_frames(film(unpinned, radiance, FRAMES, seed=9), bins=BINS)
    assert np.all(auto.variance[checked] / reference_nlf.variance[checked] - 1 < -0.5)


def test_temporally_filtered_reference_is_refused(reference: list[np.ndarray], base: Profile) -> None:
    """Recursive temporal noise reduction: the NLF (from successive differences) can be matched by more
    electrons, but the noise is correlated between frames, which camgen's sensor cannot make. (Accepted
    with the override: the command's test below.)"""
    filtered = temporally_filtered(reference)
    with pytest.raises(MatchNotReproducedError, match="temporal noise spectrum differs") as refused:
        fit_match(filtered, base, seed=3, bins=BINS, gain_db=GAIN_DB, max_evaluations=1)
    assert "--accept-poor-fit" in str(refused.value)
    verification = refused.value.fit.verification
    assert not verification.reproduces
    # AR(1) with ρ = 0.5: D_k/D_1 = (1 − ρ^k)/(1 − ρ) = 1.5, 1.75, 1.875 at lags 2–4; camgen's stays 1.
    assert verification.reference_structure[1:] == pytest.approx([1.5, 1.75, 1.875], rel=0.1)
    assert verification.structure[1:] == pytest.approx([1.0, 1.0, 1.0], abs=0.05)


# --- The figures against closed forms ---------------------------------------------------------------


def noise_frames(rng: np.random.Generator, *, rho: float = 0.0, white_code: float = 2.0, block_code: float = 0.0):
    """A static ramp (40…210 codes) plus AR(1) noise of σ = `white_code` correlated by `rho` between frames,
    plus (per frame) a constant offset of σ = `block_code` per 8 × 8 block, rounded."""
    clean = np.tile(np.linspace(40.0, 210.0, WIDTH_PX)[None, :, None], (HEIGHT_PX, 1, 3))
    noise = white_code * rng.standard_normal(clean.shape)
    for _ in range(32):
        noise = rho * noise + np.sqrt(1 - rho**2) * white_code * rng.standard_normal(clean.shape)
        blocks = block_code * rng.standard_normal((HEIGHT_PX // 8, WIDTH_PX // 8, 3))
        frame = clean + noise + np.repeat(np.repeat(blocks, 8, axis=0), 8, axis=1)
        yield np.clip(np.rint(frame), 0, 255).astype(np.uint8)


def test_temporal_structure_of_ar1_noise() -> None:
    rng = np.random.default_rng(21)
    white = _collect(noise_frames(rng), temporal=True, spatial=False, histogram=False, spectrum=True)
    assert temporal_structure(white) == pytest.approx(np.ones(4), abs=0.02)
    rho = 0.6
    correlated = _collect(noise_frames(rng, rho=rho), temporal=True, spatial=False, histogram=False, spectrum=True)
    expected = [(1 - rho**k) / (1 - rho) for k in range(1, 5)]
    assert temporal_structure(correlated) == pytest.approx(expected, rel=0.03)
    # A slow drift of 0.05 code per frame hardly moves it (δ²k²/2 ≤ 0.02 code² against D_1 ≈ 4 code²).
    drifting = (
        np.clip(f.astype(np.float64) + 0.05 * t, 0, 255).astype(np.uint8) for t, f in enumerate(noise_frames(rng))
    )
    assert temporal_structure(_collect(drifting, temporal=True, spatial=False, histogram=False, spectrum=True)) == (
        pytest.approx(np.ones(4), abs=0.03)
    )


def test_blockiness_of_block_quantised_noise() -> None:
    """Noise with a per-block offset: a step inside a block sees the white part (4σ_w² in the frame
    difference), one across a block edge that plus 4σ_b², so blockiness = 1 + σ_b²/σ_w² (σ_w² including
    8-bit rounding's 1/12)."""
    rng = np.random.default_rng(22)
    plain = _collect(noise_frames(rng), temporal=True, spatial=False, histogram=False, spectrum=True)
    assert blockiness(plain) == pytest.approx(1.0, abs=0.02)
    blocky = _collect(noise_frames(rng, block_code=1.0), temporal=True, spatial=False, histogram=False, spectrum=True)
    assert blockiness(blocky) == pytest.approx(1 + 1 / (4 + 1 / 12), rel=0.03)


# --- The command -----------------------------------------------------------------------------------------


def test_camgen_fit_match_refuses_naming_the_reference_and_accepts_with_the_flag(
    reference: list[np.ndarray], base: Profile, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys
) -> None:
    import camgen.fit.match

    # The wiring is under test, not the optimiser's travel: one iteration from the truth's noise, with
    # simulations of 32 frames.
    monkeypatch.setattr(camgen.fit.match, "fit_match", functools.partial(fit_match, max_evaluations=1))
    monkeypatch.setattr(camgen.fit.match, "SIMULATION_FRAMES", 32)
    frames = tmp_path / "tnr_camera"
    frames.mkdir()
    for index, frame in enumerate(temporally_filtered(reference)):
        write_frame(frames / f"{index:03d}.png", frame, format="png")
    base_path = tmp_path / "base.yaml"
    base_path.write_text(yaml.safe_dump(base.model_dump(mode="json")), encoding="utf-8")
    output = tmp_path / "matched.yaml"
    argv = ["fit", "match", "--reference", str(frames), "--profile", str(base_path), "-o", str(output)]
    argv += ["--gain-db", "12", "--bins", str(BINS), "--seed", "3"]
    assert main(argv) == 2
    message = capsys.readouterr().err
    assert f"--reference {frames}: the matched profile does not reproduce the reference" in message
    assert "temporal noise spectrum differs" in message and "--accept-poor-fit" in message
    assert not output.exists() and output.with_suffix(".png").stat().st_size > 30_000
    assert main([*argv, "--accept-poor-fit"]) == 0
    text = output.read_text(encoding="utf-8")
    assert "# warning: the temporal noise spectrum differs" in text
    assert "# operating point pinned: manual exposure 0.01 s at 12 dB" in text
    fitted = load_profile(output).profile
    assert (fitted.exposure.mode, fitted.exposure.gain_db) == ("manual", GAIN_DB)
