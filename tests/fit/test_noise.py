"""Sensor noise fit (`camgen.fit.noise`) against the sensor model it inverts and against `emva1288`.

Round trip: dark and flat stacks are simulated with `camgen.sensor.capture.SensorModel` from a profile
(256 × 256 px, RGGB and mono; read noise 2.5 e⁻, DSNU 1.5 e⁻, row and column FPN 0.6 e⁻, PRNU 1 %,
K = 0.35 DN/e⁻, full well 10 000 e⁻, dark current 20 e⁻/s at 25 °C doubling every 6.5 °C, hot pixels
1e-3 at 2000 e⁻/s, dead pixels 5e-4, blooming on), darks at 30, 40 and 50 °C (4 exposure times,
8 frames each), 37 flat groups at 40 °C up to 2.5× the saturating exposure. Measured with this
module's seed (error = fit/profile − 1, z = error/uncertainty; combined over channels; the dark
currents at the reference temperature 40 °C):

    figure                        mono               RGGB
    read_noise_e                  +0.32 % (z +1.3)   +0.22 % (z +0.9)
    dsnu_e (DSNU1288 pixel part)  −0.34 % (z −1.1)   −0.38 % (z −0.7)
    prnu_pct (PRNU1288 pixel)     −0.28 % (z −0.9)   −0.45 % (z −1.5)
    conversion gain K             −0.15 % (z −0.8)   −0.07 % (z −0.4)
    dark current                  +0.18 % (z +0.9)   +0.08 % (z +0.4)
    doubling temperature          +0.05 % (z +1.4)   +0.05 % (z +1.5)
    full well (plateau)           +0.15 % (z +0.8)   +0.07 % (z +0.4)
    hot-pixel dark current        +0.08 % (z +0.3)   +0.18 % (z +0.7)
    DSNU1288                      +0.61 % (z +0.8)   +0.47 % (z +0.7)
    row / column FPN              +1.1 / +5.9 %      +1.5 / +5.2 %   (z ≤ 1.6: 128–256 rows sample a σ to ±6–9 %)
    black level                   +0.02 % (z +1.5)   +0.02 % (z +1.5)
    hot / dead pixel fraction     +0.7 % / +0.7 %    +0.7 % / +0.7 %  (66 and 33 sites; maps exact)

Per RGGB channel the errors stay within 1.4 % (read noise ≤ 1.0 %, K ≤ 0.7 %, PRNU ≤ 1.2 %, DSNU ≤ 1.4 %,
dark current ≤ 0.8 %). Over 20 further seeds per CFA (measured when the pixel, row and column parts
had unbiased finite-sample factors; EMVA 4.0's, used now, differ by O(1/M)) every figure's error stayed
within 1.5 % (row and column FPN 11.5 %), and the reported uncertainties matched the scatter: z rms
0.7–1.25, max |z| 3.0. The K, dark-current and full-well errors are one K error divided out. A
vignetted PRNU flat (1 − 0.3·ρ²) gives PRNU1288 7.15 % by default (EMVA's definition: no shading
correction), while its pixel part stays at 1.00 %; the standard's high-pass filter gives 0.999 % (mono)
and 1.05 % (RGGB, whose 128 px planes keep more edge residue), the quadratic illumination surface
1.00 %. The linearity error, EMVA's LE = (max δ − min δ)/2, is 0.012 ± 0.007 % for mono; for RGGB it
is 3.7 % in B, whose response picks up the charge the saturating green neighbours bloom into it.

Agreement with the EMVA 1288 reference implementation `emva1288` 1.0.2 on a mono set arranged as a real
measurement (128 × 96 px; a dark and a bright pair at each of 50 exposure times under one light, and a
50-frame dark and a 50-frame bright stack at half saturation; QE 60 %, row and column PRNU 0.5 and
0.4 % besides the 1 % pixel PRNU), with the defaults, ours/reference − 1:

    quantity            truth     camgen    emva1288   camgen/emva1288 − 1
    K (DN/e⁻)           0.35      0.34742   0.34706    +0.10 %
    σ_d (e⁻)            3         3.0356    3.0387     −0.10 %
    σ_y.dark (DN)       1.0890    1.0934    1.0934     −0.002 %
    dark current, mean  99.0 e⁻/s 99.753    99.855     −0.10 %
    dark current, var.  99.0 e⁻/s 100.20    100.41     −0.21 %
    DSNU1288 (e⁻)       1.803     1.8418    1.8436     −0.10 %  (pixel 1.5037, row 0.8697, column 0.6122: −0.10 %)
    PRNU1288 (%)        1.187     1.2090    1.2090      0.000 % (pixel 0.9996, row 0.5693, column 0.3722: 0.000 %)
    QE η (%)            60        60.473    60.535     −0.10 %
    R (DN/p)            0.21      0.21009   0.21009    −0.000 %
    μ_e.sat (e⁻)        ≈ 10 000  9574.8    9584.7     −0.10 %
    μ_p.sat (p)         ≈ 16 667  15 833    15 833      0.000 %
    μ_p.min (p)         6.085     6.0965    6.0305     +1.10 %
    DR                  ≈ 2739    2597.1    2625.6     −1.08 %
    LE (%)              0         0.0307    0.0307     +0.03 %

The 0.1 % is all in K: our fit has the 50-frame bright stack as one more photon transfer point (and
the dark stack one more dark point). Given only the 2-frame pairs, our K, σ_d, both dark currents, R,
η, μ_p.sat and LE are the reference's to 1e-10. μ_p.min (and DR with it) differ by the formula:
EMVA 4.0's μ_e.min = sqrt(σ²_y.dark/K² + 1/4) + 1/2 solves SNR = 1 exactly, the reference keeps the
approximation σ_y.dark/K + 1/2, 1.1 % lower at σ_y.dark/K = 3.1 e⁻. Our μ_e.sat is (μ_y.sat −
μ_y.dark)/K, the reference's R·μ_p.sat/K; they coincide to 0.001 % on the pairs. From the pairs alone
(a 2-frame "stack", as the old default took) DSNU1288 reads 3 % high and its pixel part 4 %: half the
temporal variance, and with it any temporal row noise, stays in a 2-frame mean.

Review cases: flats that stop at half the full well give no saturation and no full well; darks whose
temperature dependence is not resolved give no doubling temperature; figures the profile would refuse
(a dark current < 0, a 20-bit ADC) are left out of the fragment; frames too small for the tiles are
refused. The module runs in about 40 s on 2 cores (the two reports, 13 s, most of it).
"""

from __future__ import annotations

import math
import shutil
import warnings
from dataclasses import replace
from types import SimpleNamespace

import cv2
import numpy as np
import pytest

from camgen.config.profile import Noise, Sensor
from camgen.errors import ConfigError
from camgen.fit.noise import fit_noise, photons_per_pixel
from camgen.fit.noise_report import DPI, noise_report_figure, write_noise_report
from camgen.fit.noise_spatial import HIGHPASS_PIXEL_VARIANCE_GAIN
from camgen.fit.noise_stack import FrameGroup, StackStatistics
from camgen.fit.noise_statistics import channel_phases
from camgen.sensor.capture import NOISE_TERMS, SensorModel
from camgen.sensor.characteristics import dark_current_e_per_s
from camgen.sensor.fixed_pattern import fixed_pattern

SERIAL = 1288
SEED = 20240607
NOISE = Noise(
    read_noise_e=2.5,
    prnu_pct=1.0,
    dsnu_e=1.5,
    row_fpn_e=0.6,
    column_fpn_e=0.6,
    dark_current_e_per_s=20.0,
    dark_current_reference_c=25.0,
    dark_current_doubling_c=6.5,
    hot_pixel_fraction=1e-3,
    hot_pixel_dark_current_e_per_s=2000.0,
    dead_pixel_fraction=5e-4,
    blooming=True,
)
TEMPERATURES_C = (30.0, 40.0, 50.0)
FLAT_TEMPERATURE_C = 40.0
DARK_EXPOSURES_S = (0.005, 0.05, 0.1, 0.2)
DARK_FRAMES = 8
ELECTRONS_PER_S = 50_000.0
"""η·Φ of the flat field in the green (and mono) channel: full well at 0.2 s."""


def sensor(cfa: str) -> Sensor:
    return Sensor(
        width_px=256,
        height_px=256,
        pixel_pitch_um=3.0,
        cfa=cfa,
        bit_depth=12,
        full_well_e=10_000,
        conversion_gain_dn_per_e=0.35,
        black_level_dn=128,
        temperature_c=FLAT_TEMPERATURE_C,
        noise=NOISE,
    )


def at_celsius(value_at_reference: float, temperature_c: float) -> float:
    """A profile dark current (at its reference temperature) at `temperature_c`."""
    return dark_current_e_per_s(
        value_at_reference, temperature_c, NOISE.dark_current_reference_c, NOISE.dark_current_doubling_c
    )


def stack(model: SensorModel, rate: np.ndarray, exposure_time_s: float, frames: int, rng) -> StackStatistics:
    stats = StackStatistics(rate.shape)
    for _ in range(frames):
        stats.add(model.capture(rate, exposure_time_s=exposure_time_s, rng=rng))
    return stats


def simulate(profile: Sensor) -> list[FrameGroup]:
    """Dark groups at three temperatures (same serial: the same fixed pattern) and flats at 40 °C."""
    rng = np.random.default_rng(SEED)
    shape = (profile.height_px, profile.width_px)
    groups = []
    for temperature_c in TEMPERATURES_C:
        model = SensorModel.build(profile.model_copy(update={"temperature_c": temperature_c}), SERIAL)
        for t in DARK_EXPOSURES_S:
            stats = stack(model, np.zeros(shape, np.float32), t, DARK_FRAMES, rng)
            groups.append(FrameGroup("dark", t, temperature_c, stats, f"dark t={t:g} s T={temperature_c:g} °C"))
    model = SensorModel.build(profile, SERIAL)
    qe = 1.0 if profile.cfa == "mono" else profile.quantum_efficiency.g
    rate = np.full(shape, ELECTRONS_PER_S / qe, np.float32)
    saturating_s = profile.full_well_e / ELECTRONS_PER_S
    exposures = [
        *np.geomspace(0.002, 0.85 * saturating_s, 14),
        *(saturating_s * np.arange(0.88, 1.45, 0.03)),  # across every channel's variance peak
        2.0 * saturating_s,
        2.5 * saturating_s,  # the clip plateau
    ]
    for t in exposures:
        stats = stack(model, rate, float(t), 2, rng)
        groups.append(FrameGroup("flat", float(t), FLAT_TEMPERATURE_C, stats, f"flat t={t:.4g} s"))
    stats = stack(model, rate, 0.5 * saturating_s, 16, rng)
    groups.append(FrameGroup("flat", 0.5 * saturating_s, FLAT_TEMPERATURE_C, stats, "flat PRNU stack"))
    return groups


@pytest.fixture(scope="module", params=["RGGB", "mono"])
def round_trip(request) -> SimpleNamespace:
    profile = sensor(request.param)
    groups = simulate(profile)
    return SimpleNamespace(profile=profile, groups=groups, fit=fit_noise(groups, cfa=profile.cfa, bit_depth=12))


def expected_figures(profile: Sensor) -> dict[str, float]:
    noise = profile.noise
    return {
        "read_noise_e": noise.read_noise_e,
        "dsnu_e": noise.dsnu_e,
        "prnu_pct": noise.prnu_pct,
        "gain_dn_per_e": profile.conversion_gain_dn_per_e,
        "dark_current_e_per_s": at_celsius(noise.dark_current_e_per_s, FLAT_TEMPERATURE_C),
    }


def check(estimate, expected: float, rel: float, sigmas: float = 4.0) -> None:
    """Within `rel` of `expected`, and the error within `sigmas` of the reported uncertainty."""
    assert estimate.value == pytest.approx(expected, rel=rel)
    assert abs(estimate.value - expected) <= sigmas * estimate.uncertainty, (estimate, expected)


def test_round_trip_recovers_the_profile(round_trip):
    fit, profile = round_trip.fit, round_trip.profile
    assert fit.dark_current_reference_c == pytest.approx(FLAT_TEMPERATURE_C)  # the median temperature
    expected = expected_figures(profile)
    for channel in (*fit.channels, fit.combined):
        for name, value in expected.items():
            check(getattr(channel, name), value, rel=0.03)
    check(fit.dark_current_doubling_c, NOISE.dark_current_doubling_c, rel=0.03)
    check(fit.combined.full_well_e, profile.full_well_e, rel=0.03)
    assert {c.full_well_source for c in fit.channels} == {"plateau"}
    check(fit.combined.black_level_dn, profile.black_level_dn, rel=0.001)
    check(fit.hot_pixel_dark_current_e_per_s, at_celsius(NOISE.hot_pixel_dark_current_e_per_s, 40.0), rel=0.03)
    # Brought back to the profile's own reference temperature with the fitted doubling.
    back_to_25c = fit.combined.dark_current_e_per_s.value * 2 ** (
        (NOISE.dark_current_reference_c - fit.dark_current_reference_c) / fit.dark_current_doubling_c.value
    )
    assert back_to_25c == pytest.approx(NOISE.dark_current_e_per_s, rel=0.03)


def test_row_and_column_noise_are_honest(round_trip):
    """128–256 rows per channel sample a row σ only to ±6–9 %, so these are checked against their own
    uncertainty (and loosely in value); DSNU1288 is the total of all three parts."""
    c = round_trip.fit.combined
    check(c.row_fpn_e, NOISE.row_fpn_e, rel=0.12)
    check(c.column_fpn_e, NOISE.column_fpn_e, rel=0.12)
    check(c.dsnu1288_e, math.hypot(NOISE.dsnu_e, NOISE.row_fpn_e, NOISE.column_fpn_e), rel=0.03)


def test_hot_and_dead_pixels_are_the_simulated_ones(round_trip):
    profile, fit = round_trip.profile, round_trip.fit
    pattern = fixed_pattern(profile.noise, profile.height_px, profile.width_px, SERIAL)
    hot = pattern.dark_current_e_per_s == np.float32(NOISE.hot_pixel_dark_current_e_per_s)
    dead = pattern.response == 0
    np.testing.assert_array_equal(fit.hot_pixel_map, hot)
    np.testing.assert_array_equal(fit.dead_pixel_map, dead)
    assert fit.hot_pixel_fraction.value == pytest.approx(NOISE.hot_pixel_fraction, rel=0.1)
    assert fit.dead_pixel_fraction.value == pytest.approx(NOISE.dead_pixel_fraction, rel=0.1)


def test_illumination_shading_is_kept_unless_a_correction_is_asked_for(round_trip):
    """The PRNU stack replaced by one under a vignetted light, 1 − 0.3·ρ² (ρ = 1 at the corners). By
    default (EMVA's PRNU1288, as `emva1288`) the shading swamps the 1 % PRNU in the total, and the notes
    say it was not corrected; a quadratic ρ² is a row function plus a column function, so the pixel part
    (what the profile takes) stays the sensor's (hot and dead pixels filled with their block's level, not
    the frame's: a global median put them 4 % higher). The standard's high-pass filter removes the shading
    (less the 0.6 % of a white σ the filter takes too), and so does the quadratic illumination surface."""
    profile = round_trip.profile
    height, width = profile.height_px, profile.width_px
    y, x = np.mgrid[0:height, 0:width]
    rho2 = ((x - (width - 1) / 2) ** 2 + (y - (height - 1) / 2) ** 2) / (
        ((width - 1) / 2) ** 2 + ((height - 1) / 2) ** 2
    )
    qe = 1.0 if profile.cfa == "mono" else profile.quantum_efficiency.g
    rate = (ELECTRONS_PER_S / qe * (1 - 0.3 * rho2)).astype(np.float32)
    exposure_s = 0.5 * profile.full_well_e / ELECTRONS_PER_S
    model = SensorModel.build(profile, SERIAL)
    stats = stack(model, rate, exposure_s, 16, np.random.default_rng(SEED + 1))
    vignetted = FrameGroup("flat", exposure_s, FLAT_TEMPERATURE_C, stats, "flat vignetted stack")
    groups = [g for g in round_trip.groups if g.label != "flat PRNU stack"] + [vignetted]
    kept = fit_noise(groups, cfa=profile.cfa, bit_depth=12)
    assert kept.shading_correction == "none"
    assert kept.combined.prnu_pct.value > 5 * NOISE.prnu_pct
    assert any("illumination shading not corrected" in note for note in kept.notes)
    assert any("flat vignetted stack (16 frames" in note for note in kept.notes)
    # The pixels' gain spread is relative to their own signal: over the frame it is rms/mean of the light.
    light = 1 - 0.3 * rho2
    check(kept.combined.prnu_pixel_pct, NOISE.prnu_pct * math.sqrt(np.mean(light**2)) / np.mean(light), rel=0.03)
    # Within the filter's reach of the mirrored edges a little of the 30 % vignetting stays: +5 % on the
    # 128 px planes of the Bayer channels, +0.5 % on the 256 px mono frames.
    highpass = fit_noise(groups, cfa=profile.cfa, bit_depth=12, shading_correction="highpass")
    filtered_prnu_pct = NOISE.prnu_pct * math.sqrt(HIGHPASS_PIXEL_VARIANCE_GAIN)
    assert highpass.combined.prnu_pct.value == pytest.approx(filtered_prnu_pct, rel=0.06)
    assert any("high-pass filter" in note for note in highpass.notes)
    polynomial = fit_noise(groups, cfa=profile.cfa, bit_depth=12, shading_correction="polynomial")
    check(polynomial.combined.prnu_pct, NOISE.prnu_pct, rel=0.03)
    with pytest.raises(ConfigError, match=r"shading_correction \(--shading-correction\) must be one of none"):
        fit_noise(groups, cfa=profile.cfa, bit_depth=12, shading_correction="flat")


def test_one_exposure_time_without_temperatures(round_trip):
    """Darks at one exposure time and no recorded temperature: hot pixels are still found (from the
    excess of their mean), the black level and read noise are still fitted, the dark current is not."""
    profile, fit = round_trip.profile, round_trip.fit
    darks = [
        replace(g, temperature_c=None)
        for g in round_trip.groups
        if g.kind == "dark" and g.temperature_c == FLAT_TEMPERATURE_C and g.exposure_time_s == DARK_EXPOSURES_S[0]
    ]
    one = fit_noise(darks, cfa=profile.cfa, bit_depth=12, gain_dn_per_e=profile.conversion_gain_dn_per_e)
    np.testing.assert_array_equal(one.hot_pixel_map, fit.hot_pixel_map)
    assert one.combined.dark_current_e_per_s is None and one.dark_current_reference_c is None
    # Not extrapolated to t = 0: the dark signal of the one exposure stays in the black level.
    dark_signal_dn = (
        profile.conversion_gain_dn_per_e * expected_figures(profile)["dark_current_e_per_s"] * DARK_EXPOSURES_S[0]
    )
    check(one.combined.black_level_dn, profile.black_level_dn + dark_signal_dn, rel=0.001)
    # The read noise now carries the dark-current shot noise of the 5 ms exposure, D·t = 0.5 e⁻².
    dark_shot_e2 = expected_figures(profile)["dark_current_e_per_s"] * DARK_EXPOSURES_S[0]
    check(one.combined.read_noise_e, math.sqrt(NOISE.read_noise_e**2 + dark_shot_e2), rel=0.03)
    assert any("no temperature" in w for w in one.warnings)
    assert any("one exposure time" in w for w in one.warnings)
    assert "temperature_c" not in one.profile_fragment()["sensor"]
    # The hot pixels' dark current is their excess over the channel median, and the warning says so: the
    # normal dark current cannot be told from the black level with one exposure time.
    total_e_per_s = at_celsius(NOISE.hot_pixel_dark_current_e_per_s, FLAT_TEMPERATURE_C)
    excess_e_per_s = total_e_per_s - expected_figures(profile)["dark_current_e_per_s"]
    assert one.hot_pixel_dark_current_e_per_s.value == pytest.approx(excess_e_per_s, rel=0.03)
    assert any("only the excess over the channel median, not the total rate" in w for w in one.warnings)


def test_profile_fragment_loads_as_a_sensor(round_trip):
    fit, profile = round_trip.fit, round_trip.profile
    fragment = fit.profile_fragment()["sensor"]
    noise = fragment.pop("noise")
    assert set(noise) == {
        "read_noise_e",
        "prnu_pct",
        "dsnu_e",
        "row_fpn_e",
        "column_fpn_e",
        "dark_current_e_per_s",
        "dark_current_reference_c",
        "dark_current_doubling_c",
        "hot_pixel_fraction",
        "hot_pixel_dark_current_e_per_s",
        "dead_pixel_fraction",
    }
    assert all(type(v) is float for v in noise.values())
    assert type(fragment["bit_depth"]) is int
    fitted = Sensor(
        width_px=profile.width_px, height_px=profile.height_px, pixel_pitch_um=3.0, noise=Noise(**noise), **fragment
    )
    assert fitted.noise.read_noise_e == pytest.approx(NOISE.read_noise_e, rel=0.03)
    assert fitted.temperature_c == fitted.noise.dark_current_reference_c == FLAT_TEMPERATURE_C
    names = [row[0] for row in fit.summary_rows()]
    assert "system gain K" in names and "PRNU1288 (total)" in names and "PRNU1288 pixel" in names


def test_gain_from_the_argument_without_flats_and_flats_winning_over_it(round_trip):
    profile, groups = round_trip.profile, round_trip.groups
    darks = [g for g in groups if g.kind == "dark"]
    given = fit_noise(darks, cfa=profile.cfa, bit_depth=12, gain_dn_per_e=0.35)
    assert given.combined.gain_dn_per_e.value == 0.35
    assert given.combined.read_noise_e.value == pytest.approx(NOISE.read_noise_e, rel=0.03)
    assert given.dead_pixel_fraction is None and given.combined.prnu_pct is None
    assert any("no flats: K taken from gain_dn_per_e" in w for w in given.warnings)
    bare = fit_noise(darks, cfa=profile.cfa, bit_depth=12)
    assert bare.combined.read_noise_e is None and bare.combined.read_noise_dn is not None
    assert any("figures in electrons are not reported" in w for w in bare.warnings)
    assert "read_noise_e" not in bare.profile_fragment()["sensor"].get("noise", {})
    both = fit_noise(groups, cfa=profile.cfa, bit_depth=12, gain_dn_per_e=0.5)
    assert both.combined.gain_dn_per_e.value == pytest.approx(round_trip.fit.combined.gain_dn_per_e.value)
    assert any("instead of the given 0.5 DN/e⁻" in w for w in both.warnings)


def test_flats_that_never_reach_saturation_give_no_full_well(round_trip):
    """Flats up to half the full well: the variance still rises at the last flat, so it is no saturation
    point. No full well, μ_y.sat or μ_e.sat (the profile keeps its own), K from every point, PRNU from a
    flat at 30–70 % of the largest mean (43 % of it here)."""
    profile, fit = round_trip.profile, round_trip.fit
    half_s = 0.5 * profile.full_well_e / ELECTRONS_PER_S
    groups = [g for g in round_trip.groups if g.kind == "dark" or g.exposure_time_s <= half_s * (1 + 1e-9)]
    dim = fit_noise(groups, cfa=profile.cfa, bit_depth=12)
    for channel in (*dim.channels, dim.combined):
        assert channel.full_well_e is None and channel.saturation_dn is None, channel.channel
        assert channel.saturation_capacity_e is None and channel.full_well_source is None
        check(channel.gain_dn_per_e, profile.conversion_gain_dn_per_e, rel=0.03)
    check(dim.combined.prnu_pct, NOISE.prnu_pct, rel=0.05)
    np.testing.assert_array_equal(dim.dead_pixel_map, fit.dead_pixel_map)
    for curve in dim.photon_transfer:
        assert curve.saturation_index is None and curve.used_in_gain_fit.all()
    assert "full_well_e" not in dim.profile_fragment()["sensor"]
    assert any(
        "the flats do not reach saturation: no full well" in w and "add brighter flats" in w for w in dim.warnings
    )
    assert not any("full_well_e is EMVA's μ_e.sat" in w for w in dim.warnings)
    assert len(noise_report_figure(dim).axes) > 0


def test_a_dark_current_without_measurable_temperature_dependence_has_no_doubling(round_trip):
    """Temperatures that do not resolve a rise of the dark current give no doubling temperature (none
    written, the profile keeps its own) and no temperature scaling: the 30 and 50 °C labels swapped (the
    current falls with T, ln 2/b ≈ −6.5 °C), and two independent 40 °C stacks labelled 40 and 43 °C (b
    0.0003 ± 0.0002 /°C, which ln 2/b would make a doubling of 2200 °C)."""
    profile, groups = round_trip.profile, round_trip.groups
    swap = {30.0: 50.0, 50.0: 30.0}
    swapped = [replace(g, temperature_c=swap.get(g.temperature_c, g.temperature_c)) for g in groups]
    falling = fit_noise(swapped, cfa=profile.cfa, bit_depth=12)
    rng = np.random.default_rng(SEED + 2)
    model = SensorModel.build(profile, SERIAL)
    dark = np.zeros((profile.height_px, profile.width_px), np.float32)
    flat_line = [
        FrameGroup("dark", t, temperature_c, stack(model, dark, t, 4, rng), f"dark t={t:g} s T={temperature_c:g} °C")
        for temperature_c in (40.0, 43.0)
        for t in DARK_EXPOSURES_S[::3]
    ]
    level = fit_noise(flat_line, cfa=profile.cfa, bit_depth=12, gain_dn_per_e=profile.conversion_gain_dn_per_e)
    for fit in (falling, level):
        assert fit.dark_current_doubling_c is None
        assert all(c.dark_current_doubling_c is None for c in fit.channels)
        assert "dark_current_doubling_c" not in fit.profile_fragment()["sensor"]["noise"]
        assert any("temperature dependence was not measurable" in w for w in fit.warnings)
    # Unscaled: the hot pixels at the 40 °C reference as measured there; the dark current of equal
    # temperatures their mean.
    check(falling.hot_pixel_dark_current_e_per_s, at_celsius(NOISE.hot_pixel_dark_current_e_per_s, 40.0), rel=0.03)
    assert level.combined.dark_current_e_per_s.value == pytest.approx(
        at_celsius(NOISE.dark_current_e_per_s, 40.0), rel=0.01
    )


def test_the_profile_fragment_leaves_out_what_the_profile_would_refuse(round_trip):
    """Darks whose exposure times are given in reverse (the dark signal falls with t: a dark current
    < 0) and a 20-bit ADC (the profile allows 8–16 bits): neither is written, each with a warning, and the
    fragment loads."""
    profile = round_trip.profile
    darks = [g for g in round_trip.groups if g.kind == "dark" and g.temperature_c == FLAT_TEMPERATURE_C]
    times = [g.exposure_time_s for g in darks]
    reversed_darks = [replace(g, exposure_time_s=t) for g, t in zip(darks, times[::-1], strict=True)]
    fit = fit_noise(reversed_darks, cfa=profile.cfa, bit_depth=20, gain_dn_per_e=profile.conversion_gain_dn_per_e)
    assert fit.combined.dark_current_e_per_s.value < 0
    sensor_fragment = fit.profile_fragment()["sensor"]
    noise = sensor_fragment.pop("noise")
    assert "bit_depth" not in sensor_fragment and "dark_current_e_per_s" not in noise
    assert "dark_current_reference_c" not in noise
    assert any(w.startswith("sensor.bit_depth = 20 is not written") and "≤ 16" in w for w in fit.warnings)
    assert any(w.startswith("sensor.noise.dark_current_e_per_s = -") and "≥ 0" in w for w in fit.warnings)
    Sensor(width_px=256, height_px=256, pixel_pitch_um=3.0, full_well_e=1e4, noise=Noise(**noise), **sensor_fragment)


def test_channel_phases_follow_the_cfa():
    assert channel_phases("RGGB") == (("R", (0, 0)), ("Gr", (0, 1)), ("Gb", (1, 0)), ("B", (1, 1)))
    assert channel_phases("GRBG") == (("R", (0, 1)), ("Gr", (0, 0)), ("Gb", (1, 1)), ("B", (1, 0)))
    assert channel_phases("BGGR") == (("R", (1, 1)), ("Gr", (1, 0)), ("Gb", (0, 1)), ("B", (0, 0)))
    assert channel_phases("mono") == (("mono", None),)


@pytest.mark.parametrize("dtype", [np.uint16, np.float32])
def test_stack_statistics_match_numpy_and_emva_frame_difference(dtype):
    rng = np.random.default_rng(3)
    frames = (rng.normal(1000, 5, (5, 7, 9)) + np.arange(5)[:, None, None]).astype(dtype)
    stats = StackStatistics((7, 9))
    for frame in frames:
        stats.add(frame)
    np.testing.assert_allclose(stats.mean_dn, frames.mean(axis=0, dtype=np.float64), rtol=0, atol=1e-9)
    np.testing.assert_allclose(stats.temporal_variance_dn2, frames.astype(np.float64).var(axis=0, ddof=1), atol=1e-9)
    pair = StackStatistics((7, 9))
    a, b = frames[0].astype(np.float64), frames[4].astype(np.float64)
    pair.add(frames[0])
    pair.add(frames[4])
    emva = np.mean((a - b - (a.mean() - b.mean())) ** 2) / 2  # EMVA 1288's frame-difference variance
    ours = pair.temporal_variance_dn2.mean() - pair.frame_mean_variance_dn2(None)
    assert ours == pytest.approx(emva, rel=1e-12)


# --- agreement with the EMVA 1288 reference implementation ------------------------------------------

EMVA_SENSOR = Sensor(
    width_px=128,
    height_px=96,
    pixel_pitch_um=3.45,
    cfa="mono",
    bit_depth=12,
    full_well_e=10_000,
    conversion_gain_dn_per_e=0.35,
    black_level_dn=100,
    temperature_c=40.0,
    noise=Noise(read_noise_e=3.0, prnu_pct=1.0, dsnu_e=1.5, row_fpn_e=0.8, column_fpn_e=0.6, dark_current_e_per_s=20.0),
)
EMVA_QE = 0.6
EMVA_ROW_PRNU_PCT, EMVA_COLUMN_PRNU_PCT = 0.5, 0.4
"""Gain spreads of whole rows and columns, multiplied into the sensor's (pixel) PRNU: PRNU1288's parts."""
EMVA_RATE_E_PER_S = 25_000.0
EMVA_PHOTONS_PER_S = EMVA_RATE_E_PER_S / EMVA_QE
EMVA_SATURATION_S = EMVA_SENSOR.full_well_e / EMVA_RATE_E_PER_S
EMVA_EXPOSURES_S = np.concatenate(
    [
        np.geomspace(0.002, 0.95 * EMVA_SATURATION_S, 44),
        EMVA_SATURATION_S * np.array([0.98, 1.0, 1.02, 1.04, 1.08]),
        # One point deep in saturation only: the reference searches the variance peak backwards and
        # stops at the first local maximum (tests/sensor/test_photon_transfer.py).
        [1.5 * EMVA_SATURATION_S],
    ]
)
"""50 exposure times, each with a dark and a bright pair, as a real EMVA 1288 measurement."""
EMVA_SPATIAL_S = 0.5 * EMVA_SATURATION_S
EMVA_SPATIAL_FRAMES = 50


def emva_truth() -> dict[str, float]:
    """The figures the simulated sensor has by construction (μ_p.min and DR at EMVA 4.0's μ_e.min)."""
    noise, gain = EMVA_SENSOR.noise, EMVA_SENSOR.conversion_gain_dn_per_e
    sigma_y_dark = math.sqrt(gain**2 * noise.read_noise_e**2 + 1 / 12)
    threshold_e = math.sqrt((sigma_y_dark / gain) ** 2 + 0.25) + 0.5
    dark_current = dark_current_e_per_s(
        noise.dark_current_e_per_s,
        EMVA_SENSOR.temperature_c,
        noise.dark_current_reference_c,
        noise.dark_current_doubling_c,
    )
    return {
        "K": gain,
        "sigma_d": noise.read_noise_e,
        "sigma_y_dark": sigma_y_dark,
        "u_I_mean": dark_current,
        "u_I_var": dark_current,
        "DSNU1288": math.hypot(noise.dsnu_e, noise.row_fpn_e, noise.column_fpn_e),
        "DSNU1288_pixel": noise.dsnu_e,
        "DSNU1288_row": noise.row_fpn_e,
        "DSNU1288_col": noise.column_fpn_e,
        "PRNU1288": math.hypot(noise.prnu_pct, EMVA_ROW_PRNU_PCT, EMVA_COLUMN_PRNU_PCT),
        "PRNU1288_pixel": noise.prnu_pct,
        "PRNU1288_row": EMVA_ROW_PRNU_PCT,
        "PRNU1288_col": EMVA_COLUMN_PRNU_PCT,
        "QE": 100 * EMVA_QE,
        "R": EMVA_QE * gain,
        "u_e_sat": EMVA_SENSOR.full_well_e,
        "u_p_sat": EMVA_SENSOR.full_well_e / EMVA_QE,
        "u_p_min": threshold_e / EMVA_QE,
        "DR": EMVA_SENSOR.full_well_e / threshold_e,
        "LE": 0.0,
    }


@pytest.fixture(scope="module")
def emva(tmp_path_factory) -> SimpleNamespace:
    """A set arranged as a real EMVA 1288 measurement through `emva1288` (descriptor, .npy loader,
    Data1288, Results1288) and through `fit_noise`: a dark and a bright pair at each of 50 exposure
    times under one irradiance, and a 50-frame dark and a 50-frame bright stack at half saturation."""
    from emva1288.process import Data1288, LoadImageData, ParseEmvaDescriptorFile, Results1288

    directory = tmp_path_factory.mktemp("emva1288")
    model = SensorModel.build(EMVA_SENSOR, SERIAL, terms=frozenset(NOISE_TERMS) - {"hot_pixels", "dead_pixels"})
    rng = np.random.default_rng(SEED)
    shape = (EMVA_SENSOR.height_px, EMVA_SENSOR.width_px)
    lines = [f"n {EMVA_SENSOR.bit_depth} {shape[1]} {shape[0]}"]
    pattern = np.random.default_rng(SEED + 3)
    rows = 1 + EMVA_ROW_PRNU_PCT / 100 * pattern.standard_normal((shape[0], 1))
    columns = 1 + EMVA_COLUMN_PRNU_PCT / 100 * pattern.standard_normal((1, shape[1]))
    response = (model.electrons_per_photon * rows * columns).astype(np.float32)
    light = np.full(shape, EMVA_RATE_E_PER_S, np.float32)
    groups = []

    def series(kind: str, exposure_time_s: float, frames: int) -> None:
        photons = round(EMVA_PHOTONS_PER_S * exposure_time_s, 4) if kind == "flat" else 0.0
        lines.append(
            f"{'b' if kind == 'flat' else 'd'} {exposure_time_s * 1e9:.1f}" + (f" {photons:.4f}" if photons else "")
        )
        stats = StackStatistics(shape)
        rate = light if kind == "flat" else np.zeros(shape, np.float32)
        for _ in range(frames):
            frame = model.capture(rate, exposure_time_s=exposure_time_s, rng=rng, electrons_per_photon=response)
            name = f"{len(lines):04d}.npy"
            np.save(directory / name, frame)
            lines.append(f"i {name}")
            stats.add(frame)
        label = f"{kind} {exposure_time_s:.4g} s"
        groups.append(FrameGroup(kind, float(exposure_time_s), 40.0, stats, label, photons if kind == "flat" else None))

    for t in EMVA_EXPOSURES_S:
        series("dark", t, 2)
        series("flat", t, 2)
    series("dark", EMVA_SPATIAL_S, EMVA_SPATIAL_FRAMES)
    series("flat", EMVA_SPATIAL_S, EMVA_SPATIAL_FRAMES)
    descriptor = directory / "descriptor.txt"
    descriptor.write_text("\n".join(lines) + "\n", encoding="utf-8")
    with pytest.MonkeyPatch.context() as patch:
        # emva1288 1.0.2 calls np.asfarray, which numpy 2 removed.
        patch.setattr(np, "asfarray", lambda a, dtype=float: np.asarray(a, dtype=dtype), raising=False)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ResourceWarning)  # the parser never closes the descriptor
            parser = ParseEmvaDescriptorFile(str(descriptor))
        data = Data1288(LoadImageData(parser.images, fload=np.load).data)
        results = Results1288(data.data, pixel_area=EMVA_SENSOR.pixel_pitch_um**2)
        reference = {
            name: float(getattr(results, name))
            for name in (
                "K",
                "sigma_d",
                "sigma_y_dark",
                "u_I_mean",
                "u_I_var",
                "DSNU1288",
                "DSNU1288_pixel",
                "DSNU1288_row",
                "DSNU1288_col",
                "PRNU1288",
                "PRNU1288_pixel",
                "PRNU1288_row",
                "PRNU1288_col",
                "QE",
                "R",
                "u_e_sat",
                "u_p_sat",
                "u_p_min",
                "DR",
            )
        }
        reference["LE"] = float((results.LE_max - results.LE_min) / 2)
    shutil.rmtree(directory)
    fit = fit_noise(groups, cfa="mono", bit_depth=12)
    pairs = [g for g in groups if g.stats.count == 2]
    return SimpleNamespace(reference=reference, fit=fit, pairs_fit=fit_noise(pairs, cfa="mono", bit_depth=12))


def emva_figures(fit) -> dict[str, float]:
    """`fit_noise`'s figures under the reference's names (and units: DN, e⁻, %, photons, ratio)."""
    c = fit.combined
    figures = {
        "K": c.gain_dn_per_e,
        "sigma_d": c.read_noise_e,
        "sigma_y_dark": c.temporal_dark_noise_dn,
        "u_I_mean": c.dark_current_e_per_s,
        "u_I_var": c.dark_current_from_variance_e_per_s,
        "DSNU1288": c.dsnu1288_e,
        "DSNU1288_pixel": c.dsnu_e,
        "DSNU1288_row": c.row_fpn_e,
        "DSNU1288_col": c.column_fpn_e,
        "PRNU1288": c.prnu_pct,
        "PRNU1288_pixel": c.prnu_pixel_pct,
        "PRNU1288_row": c.prnu_row_pct,
        "PRNU1288_col": c.prnu_column_pct,
        "QE": c.quantum_efficiency_pct,
        "R": c.responsivity_dn_per_photon,
        "u_e_sat": c.saturation_capacity_e,
        "u_p_sat": c.saturation_photons,
        "u_p_min": c.sensitivity_threshold_photons,
        "DR": c.dynamic_range,
        "LE": c.linearity_error_pct,
    }
    return {name: estimate.value for name, estimate in figures.items()}


def test_agrees_with_the_emva1288_reference_implementation(emva):
    """Every figure within 2 % of `emva1288` on the same frames, with the defaults (DSNU and PRNU from
    the 50-frame stacks, illumination shading kept, as the reference)."""
    ours = emva_figures(emva.fit)
    for name, value in emva.reference.items():
        if name == "LE":
            assert abs(ours[name] - value) < 0.02, name  # percentage points of a ~0.1 % error
        else:
            assert ours[name] == pytest.approx(value, rel=0.02), name
    assert not emva.fit.hot_pixel_map.any() and not emva.fit.dead_pixel_map.any()
    assert emva.fit.notes[0] == f"DSNU1288 from dark {EMVA_SPATIAL_S:.4g} s ({EMVA_SPATIAL_FRAMES} frames)"


def test_recovers_the_simulated_sensor(emva):
    """And close to what the simulated sensor has: the temporal figures within 1 %, the spatial ones
    within their sampling error (96 rows and 128 columns sample a row or column σ to ±7 %)."""
    ours, truth = emva_figures(emva.fit), emva_truth()
    for name in ("K", "sigma_d", "sigma_y_dark", "QE", "R", "DSNU1288_pixel", "PRNU1288_pixel"):
        assert ours[name] == pytest.approx(truth[name], rel=0.015), name
    for name in ("u_I_mean", "u_I_var", "DSNU1288", "PRNU1288"):
        assert ours[name] == pytest.approx(truth[name], rel=0.05), name
    for name in ("DSNU1288_row", "DSNU1288_col", "PRNU1288_row", "PRNU1288_col"):
        assert ours[name] == pytest.approx(truth[name], rel=0.2), name
    # μ_e.sat is the variance peak, a little below the full well; μ_p.sat and DR with it.
    for name in ("u_e_sat", "u_p_sat", "DR"):
        assert 0.9 < ours[name] / truth[name] <= 1.0, name
    assert ours["u_p_min"] == pytest.approx(truth["u_p_min"], rel=0.02)


def test_on_the_frame_pairs_alone_the_estimators_are_the_reference_s(emva):
    """Given only the 2-frame series the reference's temporal figures come from, K, σ_d, the dark
    currents, R, η, μ_p.sat and LE are the reference's own numbers (to its least-squares solver's
    tolerance): the same points, the same frame-difference variance, the same fits. μ_p.min differs by
    the reference's approximation σ_y.dark/K + 1/2 of EMVA 4.0's sqrt(σ²_y.dark/K² + 1/4) + 1/2."""
    c, ref = emva.pairs_fit.combined, emva.reference
    assert c.gain_dn_per_e.value == pytest.approx(ref["K"], rel=1e-6)
    assert c.read_noise_e.value == pytest.approx(ref["sigma_d"], rel=1e-6)
    assert c.dark_current_e_per_s.value == pytest.approx(ref["u_I_mean"], rel=1e-6)
    assert c.dark_current_from_variance_e_per_s.value == pytest.approx(ref["u_I_var"], rel=1e-6)
    assert c.responsivity_dn_per_photon.value == pytest.approx(ref["R"], rel=1e-6)
    assert c.quantum_efficiency_pct.value == pytest.approx(ref["QE"], rel=1e-6)
    assert c.saturation_photons.value == pytest.approx(ref["u_p_sat"], rel=1e-9)
    assert c.linearity_error_pct.value == pytest.approx(ref["LE"], rel=1e-6)
    approximate_threshold_e = c.temporal_dark_noise_dn.value / c.gain_dn_per_e.value + 0.5
    assert approximate_threshold_e / (c.quantum_efficiency_pct.value / 100) == pytest.approx(ref["u_p_min"], rel=1e-6)


def test_spectrograms_hold_the_non_uniformity_they_show(emva):
    """EMVA 1288 4.0's spectrograms, normalised so that the mean power over frequency is the variance:
    along a row, the pixel part, the column part (column offsets change from pixel to pixel along a
    row) and the temporal noise left in the 50-frame mean; the row part lies at frequency 0 alone."""
    c = emva.fit.combined
    dsnu = next(s for s in emva.fit.spectrograms if s.kind == "DSNU")
    expected_dn2 = c.dsnu_dn.value**2 + c.column_fpn_dn.value**2 + dsnu.temporal**2 / EMVA_SPATIAL_FRAMES
    assert np.mean(dsnu.horizontal[1:] ** 2) == pytest.approx(expected_dn2, rel=0.1)
    assert dsnu.horizontal_frequency_per_px[-1] == 0.5 and dsnu.horizontal.size == EMVA_SENSOR.width_px // 2 + 1
    assert dsnu.vertical.size == EMVA_SENSOR.height_px // 2 + 1
    prnu = next(s for s in emva.fit.spectrograms if s.kind == "PRNU")
    assert prnu.unit == "%" and prnu.nonuniformity == c.prnu_pct.value


def test_photons_per_pixel_is_the_energy_over_the_photon_energy():
    from scipy.constants import c as speed_of_light
    from scipy.constants import h as planck

    energy_j = 0.8 * (3.45e-6) ** 2 * 0.002  # 0.8 W/m² on a 3.45 µm pixel for 2 ms
    assert photons_per_pixel(0.8, 0.002, 525.0, 3.45**2) == pytest.approx(
        energy_j / (planck * speed_of_light / 525e-9), rel=1e-12
    )


# --- bad input ----------------------------------------------------------------------------------------


def small_group(kind: str, label: str, *, frames: int = 2, value: float = 100.0, shape=(16, 16), temperature=None):
    rng = np.random.default_rng(1)
    stats = StackStatistics(shape)
    for _ in range(frames):
        stats.add(np.clip(rng.normal(value, 2.0, shape), 0, 4095).round().astype(np.uint16))
    return FrameGroup(kind, 0.01, temperature, stats, label)


def test_no_dark_group_is_refused():
    with pytest.raises(ConfigError, match=r"no dark group \(groups given: flats/a\).*--dark"):
        fit_noise([small_group("flat", "flats/a", value=2000)], cfa="mono", bit_depth=12)


def test_a_single_frame_stack_is_refused():
    groups = [small_group("dark", "darks/ok"), small_group("dark", "darks/lonely", frames=1)]
    with pytest.raises(ConfigError, match=r"darks/lonely: 1 frame.*at least 2 frames"):
        fit_noise(groups, cfa="mono", bit_depth=12)


def test_a_saturated_dark_group_is_refused():
    groups = [small_group("dark", "darks/ok"), small_group("dark", "darks/lit", value=4095)]
    with pytest.raises(ConfigError, match="darks/lit: a saturated dark group"):
        fit_noise(groups, cfa="mono", bit_depth=12)


def test_groups_of_different_shapes_are_refused():
    groups = [small_group("dark", "darks/a"), small_group("flat", "flats/wide", value=2000, shape=(16, 24))]
    with pytest.raises(ConfigError, match="flats/wide: frames of 24×16 px differ from darks/a's 16×16 px"):
        fit_noise(groups, cfa="mono", bit_depth=12)


def test_other_bad_input_names_the_fix():
    with pytest.raises(ConfigError, match=r"darks/hot: values reach 5000 DN.*--bit-depth"):
        stats = StackStatistics((4, 4))
        stats.add(np.full((4, 4), 5000, np.uint16))
        stats.add(np.full((4, 4), 5000, np.uint16))
        fit_noise([FrameGroup("dark", 0.01, None, stats, "darks/hot")], cfa="mono", bit_depth=12)
    with pytest.raises(ConfigError, match="darks/b: no temperature"):
        fit_noise(
            [small_group("dark", "darks/a", temperature=20.0), small_group("dark", "darks/b")], cfa="mono", bit_depth=12
        )
    with pytest.raises(ConfigError, match="cannot join a stack"):
        StackStatistics((4, 4)).add(np.zeros((4, 5), np.uint16))
    with pytest.raises(ConfigError, match="NaN"):
        StackStatistics((2, 2)).add(np.array([[0.0, np.nan], [1.0, 2.0]]))


def test_frames_too_small_for_the_tiles_are_refused():
    """A channel plane needs 3 px a side for each of the tiles along it (EMVA's split into pixel, row and
    column variances has no solution for 2 rows and 2 columns): 2×2 px RGGB frames (1×1 px planes) used
    to end in a ValueError from round(NaN); 12×12 px mono frames are the smallest for 4×4 tiles."""
    tiny = [
        small_group("dark", "darks/tiny", shape=(2, 2)),
        small_group("flat", "flats/tiny", value=2000, shape=(2, 2)),
    ]
    with pytest.raises(ConfigError, match=r"darks/tiny: frames of 2×2 px give RGGB channel planes of 1×1 px.*24×24 px"):
        fit_noise(tiny, cfa="RGGB", bit_depth=12)
    with pytest.raises(
        ConfigError, match=r"frames of 11×12 px give mono channel planes of 11×12 px.*at least 12×12 px"
    ):
        fit_noise([small_group("dark", "darks/narrow", shape=(12, 11))], cfa="mono", bit_depth=12)
    with pytest.raises(ConfigError, match=r"at least 6×6 px per channel plane.*frames of at least 12×12 px"):
        fit_noise([small_group("dark", "darks/a", shape=(10, 10))], cfa="GRBG", bit_depth=12, tiles=2)
    smallest = fit_noise([small_group("dark", "darks/12", shape=(12, 12))], cfa="mono", bit_depth=12)
    assert math.isfinite(smallest.combined.black_level_dn.uncertainty)
    assert math.isfinite(smallest.combined.dsnu_dn.uncertainty)
    with pytest.raises(ConfigError, match=r"tiles must be a whole number ≥ 2"):
        fit_noise([small_group("dark", "darks/a")], cfa="mono", bit_depth=12, tiles=1)
    with pytest.raises(ConfigError, match=r"gain_dn_per_e \(--gain-dn-per-e\) must be a system gain > 0"):
        fit_noise([small_group("dark", "darks/a")], cfa="mono", bit_depth=12, gain_dn_per_e=-0.3)


# --- report ---------------------------------------------------------------------------------------------


def test_report_is_a_real_png(round_trip, tmp_path):
    path = tmp_path / "out" / "noise.png"
    write_noise_report(round_trip.fit, path)
    image = cv2.imread(str(path), cv2.IMREAD_COLOR)
    width_in, height_in = noise_report_figure(round_trip.fit).get_size_inches()
    assert image.shape == (round(height_in * DPI), round(width_in * DPI), 3)
    colours = np.unique(image.reshape(-1, 3), axis=0)
    assert len(colours) > 100 and image.std() > 20
    assert [p.name for p in path.parent.iterdir()] == ["noise.png"]


def test_a_failed_report_leaves_nothing(round_trip, tmp_path, monkeypatch):
    from matplotlib.figure import Figure

    def fail(self, target, **kwargs):
        target.write_bytes(b"\x89PNG partial")
        raise OSError("disk full")

    monkeypatch.setattr(Figure, "savefig", fail)
    with pytest.raises(OSError, match="disk full"):
        write_noise_report(round_trip.fit, tmp_path / "noise.png")
    assert list(tmp_path.iterdir()) == []
