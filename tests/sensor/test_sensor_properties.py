"""Statistical and structural properties of the sensor model (DESIGN.md "Sensor model", "Randomness").

Temporal noise is white in time and space; fixed patterns belong to the serial; raw frames are a
function of the seed alone; saturation, dynamic range, hot and dead pixels, the shot-noise statistics on
both sides of the Gaussian threshold, and blooming follow their closed forms.
"""

from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

from camgen.config.profile import Exposure, Lens, Noise, Profile, Sensor
from camgen.plan.info import profile_info
from camgen.sensor.capture import NOISE_TERMS, SensorModel
from camgen.sensor.characteristics import dark_current_e_per_s, saturation_e
from camgen.sensor.noise import sample_electrons

ALL_TERMS = frozenset(NOISE_TERMS)
FULL_WELL_E = 10_000.0


def mono_sensor(
    height_px: int = 128,
    width_px: int = 128,
    *,
    conversion_gain_dn_per_e: float = 0.35,
    black_level_dn: float = 100.0,
    **noise,
) -> Sensor:
    """A 12-bit mono sensor with realistic noise; `noise` overrides fields of `Noise`."""
    fields = {
        "read_noise_e": 2.5,
        "prnu_pct": 1.0,
        "dsnu_e": 1.5,
        "row_fpn_e": 0.5,
        "column_fpn_e": 0.5,
        "dark_current_e_per_s": 20.0,
    }
    fields.update(noise)
    return Sensor(
        width_px=width_px,
        height_px=height_px,
        pixel_pitch_um=3.0,
        cfa="mono",
        bit_depth=12,
        full_well_e=FULL_WELL_E,
        conversion_gain_dn_per_e=conversion_gain_dn_per_e,
        black_level_dn=black_level_dn,
        temperature_c=40.0,
        noise=Noise(**fields),
    )


def dark_current_at_temperature(sensor: Sensor) -> float:
    noise = sensor.noise
    return dark_current_e_per_s(
        noise.dark_current_e_per_s, sensor.temperature_c, noise.dark_current_reference_c, noise.dark_current_doubling_c
    )


def frames(model: SensorModel, photon_rate, count: int, exposure_time_s: float, seed: int) -> np.ndarray:
    """`count` raw frames of one exposure, (count, H, W) float64 DN."""
    rng = np.random.default_rng(seed)
    rate = np.broadcast_to(np.asarray(photon_rate, np.float32), (model.sensor.height_px, model.sensor.width_px))
    return np.stack([model.capture(rate, exposure_time_s=exposure_time_s, rng=rng) for _ in range(count)]).astype(float)


def correlation(a: np.ndarray, b: np.ndarray) -> float:
    """Pearson correlation of two zero-mean samples, pooled over all their elements."""
    return float(np.sum(a * b) / math.sqrt(np.sum(a * a) * np.sum(b * b)))


# Temporal noise -----------------------------------------------------------------------------------


def test_temporal_noise_is_white_in_time_and_space():
    sensor = mono_sensor()
    model = SensorModel.build(sensor, serial=11)
    t = 0.01
    # 0 … 2000 e⁻ across the columns: exact Poisson below 20 e⁻, the Gaussian draw above.
    rate = np.linspace(0.0, 2000.0 / t, sensor.width_px, dtype=np.float32)[None, :]
    stack = frames(model, rate, 256, t, seed=5)
    temporal = stack - stack.mean(axis=0)
    # Subtracting the mean of n frames correlates their residuals by −1/(n − 1) = −0.004.
    assert abs(correlation(temporal[:-1], temporal[1:])) < 0.01
    assert abs(correlation(temporal[:, :, :-1], temporal[:, :, 1:])) < 0.01
    assert abs(correlation(temporal[:, :-1, :], temporal[:, 1:, :])) < 0.01
    # The frame is drawn in two row bands from two generators: they must not repeat each other.
    half = sensor.height_px // 2
    assert abs(correlation(temporal[:, :half], temporal[:, half : 2 * half])) < 0.01


# Fixed patterns -----------------------------------------------------------------------------------

PATTERN_NOISE = {"hot_pixel_fraction": 0.01, "hot_pixel_dark_current_e_per_s": 500.0, "dead_pixel_fraction": 0.01}


def test_fixed_patterns_are_the_same_in_every_frame():
    """Without temporal noise (no shot, no read noise) the frame is the fixed pattern alone."""
    sensor = mono_sensor(**PATTERN_NOISE)
    still = ALL_TERMS - {"shot", "read"}
    rate = np.full((sensor.height_px, sensor.width_px), 50_000.0, np.float32)
    model = SensorModel.build(sensor, serial=3, terms=still)
    first = model.capture(rate, exposure_time_s=0.05, rng=np.random.default_rng(1))
    again = model.capture(rate, exposure_time_s=0.05, rng=np.random.default_rng(2))
    rebuilt = SensorModel.build(sensor, serial=3, terms=still).capture(
        rate, exposure_time_s=0.05, rng=np.random.default_rng(3)
    )
    other = SensorModel.build(sensor, serial=4, terms=still).capture(
        rate, exposure_time_s=0.05, rng=np.random.default_rng(1)
    )
    assert np.array_equal(first, again)
    assert np.array_equal(first, rebuilt)
    assert np.mean(first != other) > 0.9


def _maps(model: SensorModel) -> dict[str, np.ndarray | None]:
    pattern = model.pattern
    return {"response": pattern.response, "offset_e": pattern.offset_e, "dark": pattern.dark_current_e_per_s}


def test_fixed_patterns_follow_the_serial():
    sensor = mono_sensor(**PATTERN_NOISE)
    first, same = _maps(SensorModel.build(sensor, serial=7)), _maps(SensorModel.build(sensor, serial=7))
    other = _maps(SensorModel.build(sensor, serial=8))
    for name, values in first.items():
        assert np.array_equal(values, same[name]), name
        assert not np.array_equal(values, other[name]), name
    centred = [maps["offset_e"] - maps["offset_e"].mean() for maps in (first, other)]
    assert abs(correlation(*centred)) < 0.1
    assert np.sum((first["dark"] > 100) & (other["dark"] > 100)) < 0.1 * np.sum(first["dark"] > 100)


def _row_plus_column(offset: np.ndarray) -> np.ndarray:
    """What is left of `offset` after taking out a per-row and a per-column term (exactly 0 if additive)."""
    return offset - offset[:, :1] - offset[:1, :] + offset[0, 0]


@pytest.mark.parametrize("term", ["prnu", "dsnu", "row_fpn", "column_fpn", "hot_pixels", "dead_pixels"])
def test_switching_one_term_off_leaves_the_other_patterns(term):
    sensor = mono_sensor(**PATTERN_NOISE)
    full = SensorModel.build(sensor, serial=21)
    part = SensorModel.build(sensor, serial=21, terms=ALL_TERMS - {term})
    dead = full.pattern.response == 0
    assert full.pattern.dead_pixels == round(0.01 * sensor.height_px * sensor.width_px)
    response = part.pattern.response
    if term == "prnu":
        assert np.array_equal(response, np.where(dead, 0.0, 1.0).astype(np.float32))
    elif term == "dead_pixels":
        assert np.array_equal(response[~dead], full.pattern.response[~dead])
        assert np.all(response[dead] > 0)
    else:
        assert np.array_equal(response, full.pattern.response)
    if term == "hot_pixels":
        assert part.pattern.dark_current_e_per_s is None
    else:
        assert np.array_equal(part.pattern.dark_current_e_per_s, full.pattern.dark_current_e_per_s)
    removed = full.pattern.offset_e - part.pattern.offset_e
    tolerance = {"atol": 1e-5}
    if term == "dsnu":
        np.testing.assert_allclose(_row_plus_column(part.pattern.offset_e), 0.0, **tolerance)
        assert np.std(removed) == pytest.approx(sensor.noise.dsnu_e, rel=0.05)
    elif term == "row_fpn":
        np.testing.assert_allclose(removed, np.broadcast_to(removed[:, :1], removed.shape), **tolerance)
        assert np.std(removed[:, 0]) == pytest.approx(sensor.noise.row_fpn_e, rel=0.25)
    elif term == "column_fpn":
        np.testing.assert_allclose(removed, np.broadcast_to(removed[:1, :], removed.shape), **tolerance)
        assert np.std(removed[0]) == pytest.approx(sensor.noise.column_fpn_e, rel=0.25)
    else:
        assert np.array_equal(removed, np.zeros_like(removed))


# Seeds ----------------------------------------------------------------------------------------------


def test_raw_frames_are_a_function_of_the_seed():
    # An odd height splits into unequal row bands; spots above full well take the saturation path
    # (with blooming), dim sites the exact Poisson path.
    sensor = mono_sensor(101, 96, **PATTERN_NOISE)
    model = SensorModel.build(sensor, serial=5)
    t = 0.02
    rate = np.random.default_rng(0).uniform(0.0, 3000.0 / t, (101, 96)).astype(np.float32)
    rate[::9, ::7] = 3 * FULL_WELL_E / t

    def raw(seed, executor=None):
        return model.capture(rate, exposure_time_s=t, rng=np.random.default_rng(seed), executor=executor)

    first = raw(42)
    assert raw(42).tobytes() == first.tobytes()
    assert np.mean(raw(43) != first) > 0.9
    with ThreadPoolExecutor(2) as executor:
        assert raw(42, executor).tobytes() == first.tobytes()


# Saturation and dynamic range -------------------------------------------------------------------

FULL_WELL_LIMITED = {"conversion_gain_dn_per_e": 0.35, "black_level_dn": 100.0}
"""K·full well + black = 3600 DN < 4095."""
ADC_LIMITED = {"conversion_gain_dn_per_e": 0.5, "black_level_dn": 64.0}
"""(4095 − 64)/0.5 = 8062 e⁻ < full well."""


@pytest.mark.parametrize(
    ("adc", "gain_db", "limit"),
    [(FULL_WELL_LIMITED, 0.0, "full well"), (ADC_LIMITED, 0.0, "ADC"), (FULL_WELL_LIMITED, 6.0, "ADC")],
)
def test_saturated_sites_clip_where_the_profile_says(adc, gain_db, limit):
    sensor = mono_sensor(**adc)
    K, black, white = adc["conversion_gain_dn_per_e"] * 10 ** (gain_db / 20), adc["black_level_dn"], 4095
    assert saturation_e(FULL_WELL_E, adc["conversion_gain_dn_per_e"], black, 12, gain_db)[1] == limit
    rate = np.full((sensor.height_px, sensor.width_px), 3 * FULL_WELL_E / 0.01, np.float32)

    def raw(terms):
        model = SensorModel.build(sensor, serial=9, terms=terms)
        return model, model.capture(rate, exposure_time_s=0.01, gain_db=gain_db, rng=np.random.default_rng(4))

    model, noisy = raw(ALL_TERMS)
    if limit == "ADC":
        assert np.all(noisy == white)
        return
    # Exact without read noise and offsets: every site holds the full well.
    _, clean = raw(ALL_TERMS - {"read", "dsnu", "row_fpn", "column_fpn"})
    assert np.all(clean == round(K * FULL_WELL_E + black))
    # With them, each site lies within the read-noise tails (±4.3 σ) of K·(full well + offset) + black.
    ideal = K * (FULL_WELL_E + model.pattern.offset_e) + black
    assert np.max(np.abs(noisy - ideal)) <= K * 4.5 * sensor.noise.read_noise_e + 0.5
    assert noisy.mean() == pytest.approx(K * FULL_WELL_E + black, abs=0.05)


@pytest.mark.parametrize("adc", [FULL_WELL_LIMITED, ADC_LIMITED], ids=["full well", "ADC"])
def test_dynamic_range_measured_from_frames_matches_the_profile(adc):
    """EMVA 1288: DR = μ_e.sat / σ_d, σ_d from dark frames at the longest exposure (quantisation included)."""
    exposure_s = 0.25
    sensor = mono_sensor(256, 256, **adc)
    profile = Profile(
        sensor=sensor,
        lens=Lens(focal_length_mm=4.0, f_number=2.0),
        exposure=Exposure(exposure_time_max_s=exposure_s),
    )
    model = SensorModel.build(sensor, serial=13)
    dark = frames(model, 0.0, 8, exposure_s, seed=1)
    temporal_dark_dn2 = np.mean((dark[0::2] - dark[1::2]) ** 2) / 2
    sat_e = saturation_e(sensor.full_well_e, sensor.conversion_gain_dn_per_e, sensor.black_level_dn, 12)[0]
    mid = frames(model, 0.4 * sat_e / exposure_s, 8, exposure_s, seed=2)
    temporal_mid_dn2 = np.mean((mid[0::2] - mid[1::2]) ** 2) / 2
    K = (temporal_mid_dn2 - temporal_dark_dn2) / (mid.mean() - dark.mean())
    saturated = frames(model, 3 * FULL_WELL_E / exposure_s, 2, exposure_s, seed=3)
    measured_db = 20 * math.log10((saturated.mean() - dark.mean()) / K / (math.sqrt(temporal_dark_dn2) / K))
    info = profile_info(profile)
    assert info.dynamic_range_exposure_s == exposure_s
    assert measured_db == pytest.approx(info.dynamic_range_db, abs=0.5)


# Defects ------------------------------------------------------------------------------------------


def test_hot_pixels_are_counted_and_dead_pixels_stay_dark():
    hot_e_per_s, fractions = 2000.0, {"hot_pixel_fraction": 0.001, "dead_pixel_fraction": 0.002}
    sensor = mono_sensor(256, 256, hot_pixel_dark_current_e_per_s=hot_e_per_s, **fractions)
    model = SensorModel.build(sensor, serial=17)
    t, pixels = 0.1, sensor.height_px * sensor.width_px
    K, black = sensor.conversion_gain_dn_per_e, sensor.black_level_dn
    temperature_factor = dark_current_at_temperature(sensor) / sensor.noise.dark_current_e_per_s
    dark = frames(model, 0.0, 8, t, seed=1).mean(axis=0)
    hot_signal_dn = K * hot_e_per_s * temperature_factor * t
    hot = dark > black + hot_signal_dn / 2
    assert hot.sum() == round(fractions["hot_pixel_fraction"] * pixels) == model.pattern.hot_pixels
    assert np.array_equal(hot, model.pattern.dark_current_e_per_s == hot_e_per_s)

    lit = frames(model, 5000.0 / t, 8, t, seed=2).mean(axis=0)
    dead = lit - dark < K * 5000.0 / 2
    assert dead.sum() == round(fractions["dead_pixel_fraction"] * pixels) == model.pattern.dead_pixels
    # Mean of 8 frames: read and dark-current shot noise ≈ 1 DN per frame, so 3 DN is > 8 σ.
    assert np.max(np.abs(lit[dead] - dark[dead])) < 3.0


# Shot noise across the Gaussian threshold ---------------------------------------------------------

SAMPLES = (2048, 2048)


@pytest.mark.parametrize("gaussian_above_e", [20.0, math.inf], ids=["gaussian above 20", "poisson"])
@pytest.mark.parametrize("read_noise_e", [0.0, 2.0])
@pytest.mark.parametrize("mean_e", [0.5, 2.0, 10.0, 19.0, 21.0, 50.0, 500.0, 5000.0])
def test_electrons_are_poisson_plus_read_noise(mean_e, read_noise_e, gaussian_above_e):
    electrons = sample_electrons(
        np.full(SAMPLES, mean_e, np.float32),
        read_noise_e=read_noise_e,
        gaussian_above_e=gaussian_above_e,
        rng=np.random.default_rng([int(mean_e * 10), int(read_noise_e), math.isinf(gaussian_above_e)]),
    ).astype(np.float64)
    n = electrons.size
    variance = mean_e + read_noise_e**2
    # Standard errors of the sample mean and variance (Poisson's fourth cumulant is μ): ≤ 0.25 %, so
    # the 1 % tolerance is at least 4 of them.
    assert math.sqrt(variance / n) / mean_e < 0.0025
    assert math.sqrt((mean_e + 2 * variance**2) / n) / variance < 0.0025
    assert electrons.mean() == pytest.approx(mean_e, rel=0.01)
    assert electrons.var(ddof=1) == pytest.approx(variance, rel=0.01)


# Blooming -----------------------------------------------------------------------------------------

CELL = 8
SPOTS = 20


def _spot_field(background_e: float, spot_e: float) -> np.ndarray:
    """Expected electrons: a 3×3 spot in the middle of each 8×8 cell of a 20×20 grid of cells."""
    mean = np.full((CELL * SPOTS, CELL * SPOTS), background_e, np.float32)
    for dy in range(3):
        for dx in range(3):
            mean[3 + dy :: CELL, 3 + dx :: CELL] = spot_e
    return mean


def _cell_sites(offsets) -> tuple[np.ndarray, np.ndarray]:
    """Indices of the sites at (dy, dx) from each cell's corner, all cells."""
    ys, xs = [], []
    for dy, dx in offsets:
        grid_y, grid_x = np.meshgrid(np.arange(SPOTS) * CELL + dy, np.arange(SPOTS) * CELL + dx, indexing="ij")
        ys.append(grid_y.ravel())
        xs.append(grid_x.ravel())
    return np.concatenate(ys), np.concatenate(xs)


SPOT = _cell_sites([(3 + dy, 3 + dx) for dy in range(3) for dx in range(3)])
RING = _cell_sites([(2, 3), (2, 4), (2, 5), (6, 3), (6, 4), (6, 5), (3, 2), (4, 2), (5, 2), (3, 6), (4, 6), (5, 6)])
"""The 12 sites outside a spot that share an edge with it (each with exactly one spot site)."""
DIAGONAL = _cell_sites([(2, 2), (2, 6), (6, 2), (6, 6)])
WINDOW = _cell_sites([(y, x) for y in range(2, 7) for x in range(2, 7)])


def _bloom(background_e: float, blooming: bool, seed: int = 8) -> np.ndarray:
    return sample_electrons(
        _spot_field(background_e, 3 * FULL_WELL_E),
        read_noise_e=2.0,
        full_well_e=FULL_WELL_E,
        blooming=blooming,
        rng=np.random.default_rng(seed),
    )


def test_blooming_spills_a_quarter_of_the_excess_into_each_neighbour():
    background = 1000.0
    electrons = _bloom(background, blooming=True)
    excess = 3 * FULL_WELL_E - FULL_WELL_E
    assert electrons[SPOT].mean() == pytest.approx(FULL_WELL_E, abs=1.0)
    assert electrons[RING].mean() - background == pytest.approx(excess / 4, rel=0.01)
    assert electrons[DIAGONAL].mean() == pytest.approx(background, rel=0.01)
    # Charge: the spot keeps 9 full wells, 12 edges × ¼ of the excess leave it, and the rest spilled
    # into spot sites that were already full (24 of its 36 quarter-shares) is drained.
    cells = SPOTS * SPOTS
    collected = 9 * 3 * FULL_WELL_E + 16 * background
    drained = 24 * excess / 4
    assert electrons[WINDOW].sum() / cells == pytest.approx(collected - drained, rel=0.005)


def test_blooming_drains_what_the_neighbours_cannot_hold():
    background = 0.8 * FULL_WELL_E
    electrons = _bloom(background, blooming=True)
    excess = 3 * FULL_WELL_E - FULL_WELL_E
    assert electrons[RING].mean() == pytest.approx(FULL_WELL_E, abs=1.0)
    cells = SPOTS * SPOTS
    collected = 9 * 3 * FULL_WELL_E + 16 * background
    drained = 24 * excess / 4 + 12 * (background + excess / 4 - FULL_WELL_E)
    assert electrons[WINDOW].sum() / cells == pytest.approx(collected - drained, rel=0.005)


def test_without_blooming_the_neighbours_are_unaffected():
    background = 1000.0
    electrons = _bloom(background, blooming=False)
    assert electrons[SPOT].mean() == pytest.approx(FULL_WELL_E, abs=1.0)
    assert electrons[RING].mean() == pytest.approx(background, rel=0.005)
    assert electrons[DIAGONAL].mean() == pytest.approx(background, rel=0.005)
