"""Photon transfer of a simulated sensor, measured by the EMVA 1288 reference implementation.

The reference is the `emva1288` package (1.0.2): frames go through its own descriptor parser, image
loader (`fload=np.load` on .npy frames), `Data1288` and `Results1288`, and the figures it reports are
checked against the profile the frames were simulated from.

The photon count is varied by the exposure time at a constant irradiance (EMVA 1288 allows either),
because the reference fits dark current only from three or more exposure times and, with several
exposure times, accepts exactly one bright point per exposure time (one dark pair each).
"""

from __future__ import annotations

import math
import shutil
import warnings
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.stats import norm

from camgen.config.profile import Noise, Sensor
from camgen.sensor.capture import NOISE_TERMS, SensorModel
from camgen.sensor.characteristics import dark_current_e_per_s, saturation_e

SENSOR = Sensor(
    width_px=512,
    height_px=512,
    pixel_pitch_um=3.0,
    cfa="mono",
    bit_depth=12,
    full_well_e=10_000,
    conversion_gain_dn_per_e=0.35,
    black_level_dn=100,
    temperature_c=40.0,
    noise=Noise(
        read_noise_e=2.5,
        prnu_pct=1.0,
        dsnu_e=1.5,
        row_fpn_e=0.5,
        column_fpn_e=0.5,
        dark_current_e_per_s=20.0,
        dark_current_reference_c=25.0,
        dark_current_doubling_c=6.5,
        blooming=True,
    ),
)
TERMS = frozenset(NOISE_TERMS) - {"hot_pixels", "dead_pixels"}
SERIAL = 1288
SEED = 20240601
QE = SENSOR.quantum_efficiency.g
"""A mono site takes QE-weighted photons (`SensorModel.capture`); the flat field is green light."""
ELECTRONS_PER_S = 25_000.0
"""η·Φ of the flat field: full well at 0.4 s."""
SATURATION_TIME_S = SENSOR.full_well_e / ELECTRONS_PER_S
EXPOSURES_S = np.concatenate(
    [
        np.geomspace(0.002, 0.85 * SATURATION_TIME_S, 18),  # 50 e⁻ … 85 % of full well
        SATURATION_TIME_S * np.linspace(0.90, 1.02, 13),  # 1 % steps across the variance maximum
        # One point deep in saturation only: the reference searches the variance maximum backwards
        # and stops at the first local maximum, so two points on the flat, read-noise-only plateau
        # would let a noise wiggle there pass for the saturation point.
        [1.5 * SATURATION_TIME_S],
    ]
)
SPATIAL_EXPOSURE_S = 0.5 * SATURATION_TIME_S
SPATIAL_FRAMES = 50

DARK_CURRENT_E_PER_S = dark_current_e_per_s(
    SENSOR.noise.dark_current_e_per_s,
    SENSOR.temperature_c,
    SENSOR.noise.dark_current_reference_c,
    SENSOR.noise.dark_current_doubling_c,
)
QUANTISATION_DN2 = 1.0 / 12.0


def photons(exposure_time_s: float) -> float:
    """Mean photons per pixel of the flat field (before QE), the reference's μ_p."""
    return ELECTRONS_PER_S / QE * exposure_time_s


def _simulate(directory) -> str:
    """Write dark and flat frames (.npy) and their EMVA 1288 descriptor; return the descriptor path."""
    model = SensorModel.build(SENSOR, SERIAL, terms=TERMS)
    rng = np.random.default_rng(SEED)
    shape = (SENSOR.height_px, SENSOR.width_px)
    flat = np.full(shape, ELECTRONS_PER_S, np.float32)
    dark = np.zeros(shape, np.float32)
    lines = [f"n {SENSOR.bit_depth} {SENSOR.width_px} {SENSOR.height_px}"]
    count = 0

    def series(header: str, rate: np.ndarray, exposure_time_s: float, frames: int) -> None:
        nonlocal count
        lines.append(header)
        for _ in range(frames):
            name = f"{count:04d}.npy"
            np.save(directory / name, model.capture(rate, exposure_time_s=exposure_time_s, rng=rng))
            lines.append(f"i {name}")
            count += 1

    for t in EXPOSURES_S:
        series(f"d {t * 1e9:.1f}", dark, t, 2)
        series(f"b {t * 1e9:.1f} {photons(t):.4f}", flat, t, 2)
    series(f"d {SPATIAL_EXPOSURE_S * 1e9:.1f}", dark, SPATIAL_EXPOSURE_S, SPATIAL_FRAMES)
    series(
        f"b {SPATIAL_EXPOSURE_S * 1e9:.1f} {photons(SPATIAL_EXPOSURE_S):.4f}", flat, SPATIAL_EXPOSURE_S, SPATIAL_FRAMES
    )
    descriptor = directory / "descriptor.txt"
    descriptor.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return str(descriptor)


@pytest.fixture(scope="module")
def emva(tmp_path_factory) -> SimpleNamespace:
    """The reference's figures for the simulated camera (exposure times in ns, as it expects)."""
    from emva1288.process import Data1288, LoadImageData, ParseEmvaDescriptorFile, Results1288

    directory = tmp_path_factory.mktemp("emva1288")
    descriptor = _simulate(directory)
    with pytest.MonkeyPatch.context() as patch:
        # emva1288 1.0.2 calls np.asfarray, which numpy 2 removed.
        patch.setattr(np, "asfarray", lambda a, dtype=float: np.asarray(a, dtype=dtype), raising=False)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ResourceWarning)  # the parser never closes the descriptor
            parser = ParseEmvaDescriptorFile(descriptor)
        images = LoadImageData(parser.images, fload=np.load).data
        shutil.rmtree(directory)  # 120 MB of frames, reduced to sums by the loader
        data = Data1288(images)
        results = Results1288(data.data, pixel_area=SENSOR.pixel_pitch_um**2)
        return SimpleNamespace(
            K=results.K,
            QE=results.QE,
            sigma_y_dark=results.sigma_y_dark,
            sigma_d=results.sigma_d,
            u_I_mean=results.u_I_mean,
            u_I_var=results.u_I_var,
            DSNU1288=results.DSNU1288,
            PRNU1288=results.PRNU1288,
            u_e_sat=results.u_e_sat,
            temporal=data.data["temporal"],
        )


def test_system_gain(emva):
    assert emva.K == pytest.approx(SENSOR.conversion_gain_dn_per_e, rel=0.02)


def test_quantum_efficiency(emva):
    assert emva.QE == pytest.approx(100.0 * QE, rel=0.02)


def test_temporal_dark_noise(emva):
    """σ_d in electrons without quantisation noise (the reference subtracts 1/12 DN²).

    With more than two exposure times the reference takes σ²_y.dark as the intercept at t = 0 of a
    line through σ²_y.dark(t), so its σ_d is the read noise alone; its per-exposure dark variances
    carry the dark-current shot noise D(T)·t as well.
    """
    K = SENSOR.conversion_gain_dn_per_e
    read_noise_e = SENSOR.noise.read_noise_e
    assert emva.sigma_d == pytest.approx(read_noise_e, rel=0.02)
    assert emva.sigma_y_dark == pytest.approx(math.sqrt((K * read_noise_e) ** 2 + QUANTISATION_DN2), rel=0.02)
    measured_e = np.sqrt(emva.temporal["s2_ydark"] - QUANTISATION_DN2) / emva.K
    expected_e = np.sqrt(read_noise_e**2 + DARK_CURRENT_E_PER_S * EXPOSURES_S)
    np.testing.assert_allclose(measured_e, expected_e, rtol=0.02)


def test_dark_current(emva):
    assert emva.u_I_mean == pytest.approx(DARK_CURRENT_E_PER_S, rel=0.05)
    assert emva.u_I_var == pytest.approx(DARK_CURRENT_E_PER_S, rel=0.05)


def test_dsnu(emva):
    noise = SENSOR.noise
    assert emva.DSNU1288 == pytest.approx(math.hypot(noise.dsnu_e, noise.row_fpn_e, noise.column_fpn_e), rel=0.02)


def test_prnu(emva):
    assert emva.PRNU1288 == pytest.approx(SENSOR.noise.prnu_pct, rel=0.02)


def _temporal_variance_e2(photo_e: np.ndarray) -> np.ndarray:
    """Pixel-averaged temporal variance of the clipped signal, e⁻², at mean photo-electrons `photo_e`.

    Shot noise on photo- and dark-current electrons is Gaussian here (μ ≫ 20 e⁻), clipped at full well;
    PRNU spreads the pixels' means (Gauss–Hermite over N(1, prnu²)). Read and quantisation noise add a
    constant and do not move the maximum.
    """
    node, weight = np.polynomial.hermite_e.hermegauss(64)
    weight = weight / weight.sum()
    photo = np.asarray(photo_e, float)[..., None]
    mean = photo * (1.0 + SENSOR.noise.prnu_pct / 100.0 * node) + DARK_CURRENT_E_PER_S * photo / ELECTRONS_PER_S
    sigma = np.sqrt(mean)
    well = SENSOR.full_well_e
    a = (well - mean) / sigma
    below, density = norm.cdf(a), norm.pdf(a)
    first = mean * below - sigma * density + well * (1.0 - below)
    second = (mean**2 + sigma**2) * below - sigma * (mean + well) * density + well**2 * (1.0 - below)
    return np.sum(weight * (second - first**2), axis=-1)


def test_saturation(emva):
    """μ_e.sat is where the photon transfer curve peaks (EMVA 1288), not the clip at full well.

    Shot noise (√10 000 = 100 e⁻) and PRNU (1 % = 100 e⁻) make the pixels clip one by one, and the
    temporal variance turns down some 4 % below full well. The reference's μ_e.sat therefore matches
    the peak this model predicts, and the plateau of the fully saturated frames sits at the profile's
    saturation (full well here).
    """
    photo_e = np.arange(0.8, 1.1, 1e-4) * SENSOR.full_well_e
    predicted_peak_e = photo_e[np.argmax(_temporal_variance_e2(photo_e))]
    assert emva.u_e_sat == pytest.approx(predicted_peak_e, rel=0.02)
    assert emva.u_e_sat < SENSOR.full_well_e
    sat_e, limit = saturation_e(
        SENSOR.full_well_e, SENSOR.conversion_gain_dn_per_e, SENSOR.black_level_dn, SENSOR.bit_depth
    )
    assert limit == "full well"
    plateau_dn = emva.temporal["u_y"][-1]
    assert (plateau_dn - SENSOR.black_level_dn) / emva.K == pytest.approx(sat_e, rel=0.02)
