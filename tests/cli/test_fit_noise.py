"""`camgen fit noise` end to end: frames simulated from a known profile, written as DNG (EXIF exposure
time and temperature) or as 16-bit linear TIFF (with a frames.csv side file), fitted back by the CLI.

The acceptance criterion: read noise, DSNU, PRNU, system gain K, dark current and its doubling within
3 % of the profile the frames were simulated from, hot-pixel density within 10 %, and the fitted
profile loads (it `extends:` the base profile). Bad input gives one clear error naming the files.
The flats' light, given as an irradiance and a wavelength (flags) or as photons per pixel (a
frames.csv column), gives the quantum efficiency; the output says where DSNU and PRNU come from and
whether illumination shading was corrected.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest
import tifffile
import yaml

from camgen.cli.fit import SHADING_CHOICES
from camgen.cli.main import main
from camgen.config import load_profile
from camgen.config.profile import Noise, Sensor
from camgen.fit.noise import PLANCK_J_S, SPEED_OF_LIGHT_M_PER_S
from camgen.fit.noise_spatial import SHADING_CORRECTIONS
from camgen.io.dng import write_dng
from camgen.sensor.capture import SensorModel
from camgen.sensor.characteristics import dark_current_e_per_s
from tests.conftest import FIXED_PROFILE

SENSOR = Sensor(
    width_px=256,
    height_px=256,
    pixel_pitch_um=3.0,
    cfa="RGGB",
    bit_depth=12,
    full_well_e=10_000,
    conversion_gain_dn_per_e=0.35,
    black_level_dn=100,
    temperature_c=40.0,
    noise=Noise(
        read_noise_e=2.5,
        prnu_pct=1.0,
        dsnu_e=1.5,
        row_fpn_e=0.4,
        column_fpn_e=0.4,
        dark_current_e_per_s=3.0,
        dark_current_reference_c=25.0,
        dark_current_doubling_c=6.5,
        hot_pixel_fraction=2e-3,
        hot_pixel_dark_current_e_per_s=200.0,
        blooming=False,
    ),
)
SERIAL = 77
TEMPERATURES_C = (30.0, 40.0, 50.0)
DARK_EXPOSURES_S = (0.001, 0.25, 0.5, 1.0)
DARK_FRAMES = 4
FLAT_ELECTRONS_PER_S = 25_000.0
"""Photo-electrons per second of the flat field: full well at 0.4 s."""
FLAT_EXPOSURES_S = tuple(np.geomspace(0.004, 0.34, 14)) + tuple(0.4 * np.array([0.95, 1.0, 1.05, 1.3]))
PRNU_EXPOSURE_S = 0.2
PRNU_FRAMES = 16


def simulate(directory: Path, write) -> None:
    """Dark stacks at three temperatures and a photon-transfer series of flats at 40 °C; each frame is
    handed to `write(path_without_suffix, raw_dn, exposure_time_s, temperature_c)`."""
    rng = np.random.default_rng(1288)
    shape = (SENSOR.height_px, SENSOR.width_px)
    flat = np.full(shape, FLAT_ELECTRONS_PER_S / SENSOR.quantum_efficiency.g, np.float32)
    for temperature_c in TEMPERATURES_C:
        model = SensorModel.build(SENSOR.model_copy(update={"temperature_c": temperature_c}), SERIAL)
        for t in DARK_EXPOSURES_S:
            for i in range(DARK_FRAMES):
                raw = model.capture(np.zeros(shape, np.float32), exposure_time_s=t, rng=rng)
                write(directory / "dark" / f"d_{temperature_c:.0f}C_{round(t * 1e6):07d}us_{i}", raw, t, temperature_c)
    # A Bayer sensor's flat: the same photo-electron rate at every site (QE taken out per colour).
    qe = SENSOR.quantum_efficiency
    model = SensorModel.build(SENSOR, SERIAL)
    rates = {"R": qe.g / qe.r, "G": 1.0, "B": qe.g / qe.b}
    for y in range(2):
        for x in range(2):
            flat[y::2, x::2] *= rates[SENSOR.cfa[2 * y + x]]
    for k, t in enumerate(FLAT_EXPOSURES_S):
        for i in range(2):
            raw = model.capture(flat, exposure_time_s=t, rng=rng)
            write(directory / "flat" / f"f_{k:02d}_{i}", raw, t, SENSOR.temperature_c)
    for i in range(PRNU_FRAMES):
        raw = model.capture(flat, exposure_time_s=PRNU_EXPOSURE_S, rng=rng)
        write(directory / "flat" / f"p_{i:02d}", raw, PRNU_EXPOSURE_S, SENSOR.temperature_c)


def write_dng_frame(path: Path, raw: np.ndarray, t: float, temperature_c: float) -> None:
    write_dng(
        path.with_suffix(".dng"),
        raw,
        cfa=SENSOR.cfa,
        black_level_dn=SENSOR.black_level_dn,
        white_level_dn=SENSOR.white_level_dn,
        bit_depth=SENSOR.bit_depth,
        exposure_time_s=t,
        temperature_c=temperature_c,
    )


class TiffWriter:
    """16-bit TIFF frames without metadata, and a frames.csv in each folder."""

    def __init__(self):
        self.rows: dict[Path, list] = {}

    def __call__(self, path: Path, raw: np.ndarray, t: float, temperature_c: float) -> None:
        path.parent.mkdir(parents=True, exist_ok=True)
        tifffile.imwrite(path.with_suffix(".tif"), raw)
        self.rows.setdefault(path.parent, []).append((path.with_suffix(".tif").name, t, temperature_c))

    def close(self) -> None:
        for folder, rows in self.rows.items():
            with (folder / "frames.csv").open("w", newline="") as handle:
                writer = csv.writer(handle)
                writer.writerow(["file", "exposure_time_s", "temperature_c"])
                writer.writerows(rows)


@pytest.fixture(scope="module")
def base_profile(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("base") / "base.yaml"
    path.write_text(FIXED_PROFILE.replace("width_px: 640", "width_px: 256").replace("height_px: 480", "height_px: 256"))
    return path


def run_fit(directory: Path, base: Path, extra: list[str]) -> tuple[dict, Path]:
    output = directory / "fitted.yaml"
    argv = ["fit", "noise", "--dark", str(directory / "dark"), "--flat", str(directory / "flat")]
    assert main([*argv, *extra, "--profile", str(base), "-o", str(output)]) == 0
    return yaml.safe_load(output.read_text()), output


@pytest.fixture(scope="module")
def dng_fit(tmp_path_factory, base_profile):
    directory = tmp_path_factory.mktemp("dng")
    simulate(directory, write_dng_frame)
    return run_fit(directory, base_profile, [])


@pytest.fixture(scope="module")
def tiff_fit(tmp_path_factory, base_profile):
    directory = tmp_path_factory.mktemp("tiff")
    writer = TiffWriter()
    simulate(directory, writer)
    writer.close()
    return run_fit(directory, base_profile, ["--cfa", SENSOR.cfa, "--bit-depth", str(SENSOR.bit_depth)])


def expected_dark_current(reference_c: float) -> float:
    noise = SENSOR.noise
    return dark_current_e_per_s(
        noise.dark_current_e_per_s, reference_c, noise.dark_current_reference_c, noise.dark_current_doubling_c
    )


@pytest.fixture(params=["dng", "tiff"])
def fitted(request):
    return request.getfixturevalue(f"{request.param}_fit")


def test_the_fitted_profile_loads_and_extends_the_base(fitted, base_profile):
    data, path = fitted
    assert data["extends"].startswith("../")  # relative to the output, so the pair can move together
    assert (path.parent / data["extends"]).resolve() == base_profile.resolve()
    profile = load_profile(path).profile
    assert profile.lens.focal_length_mm == 4.0  # from the base
    assert path.with_suffix(".png").stat().st_size > 10_000


@pytest.mark.parametrize(
    ("key", "truth"),
    [
        ("read_noise_e", SENSOR.noise.read_noise_e),
        ("dsnu_e", SENSOR.noise.dsnu_e),
        ("prnu_pct", SENSOR.noise.prnu_pct),
        ("dark_current_doubling_c", SENSOR.noise.dark_current_doubling_c),
    ],
)
def test_noise_terms_within_3_percent(fitted, key, truth):
    noise = fitted[0]["sensor"]["noise"]
    assert noise[key] == pytest.approx(truth, rel=0.03)


def test_gain_and_dark_current_within_3_percent(fitted):
    sensor = fitted[0]["sensor"]
    assert sensor["conversion_gain_dn_per_e"] == pytest.approx(SENSOR.conversion_gain_dn_per_e, rel=0.03)
    noise = sensor["noise"]
    reference_c = noise["dark_current_reference_c"]
    assert noise["dark_current_e_per_s"] == pytest.approx(expected_dark_current(reference_c), rel=0.03)
    assert sensor["black_level_dn"] == pytest.approx(SENSOR.black_level_dn, abs=0.5)


def test_hot_pixel_density_within_10_percent(fitted):
    noise = fitted[0]["sensor"]["noise"]
    assert noise["hot_pixel_fraction"] == pytest.approx(SENSOR.noise.hot_pixel_fraction, rel=0.10)
    reference_c = noise["dark_current_reference_c"]
    hot_truth = dark_current_e_per_s(
        SENSOR.noise.hot_pixel_dark_current_e_per_s,
        reference_c,
        SENSOR.noise.dark_current_reference_c,
        SENSOR.noise.dark_current_doubling_c,
    )
    assert noise["hot_pixel_dark_current_e_per_s"] == pytest.approx(hot_truth, rel=0.10)


def test_dng_and_tiff_give_the_same_figures(dng_fit, tiff_fit):
    """The same DN through two readers (rawpy, OpenImageIO) and two metadata routes (EXIF, frames.csv)."""
    assert dng_fit[0]["sensor"] == tiff_fit[0]["sensor"]


def test_an_irradiance_and_a_wavelength_give_the_quantum_efficiency(tiff_fit, base_profile, capsys):
    """The TIFF set again, with the flats' irradiance: the simulated flat gives every site 25 000 e⁻/s,
    so at the irradiance whose photon rate is 25 000/η_G every channel's η is η_G (as the light were
    filtered to match). The base profile gives the pixel area; the output names the stacks DSNU and PRNU
    come from and the shading correction asked for."""
    directory = tiff_fit[1].parent
    wavelength_nm, area_m2 = 550.0, (3e-6) ** 2  # the base profile's pitch, 3.0 µm
    photons_per_s = FLAT_ELECTRONS_PER_S / SENSOR.quantum_efficiency.g
    irradiance = photons_per_s * PLANCK_J_S * SPEED_OF_LIGHT_M_PER_S / (wavelength_nm * 1e-9 * area_m2)
    capsys.readouterr()
    output = directory / "lit.yaml"
    argv = ["fit", "noise", "--dark", str(directory / "dark"), "--flat", str(directory / "flat")]
    argv += ["--cfa", "RGGB", "--bit-depth", "12", "--shading-correction", "highpass"]
    argv += ["--irradiance-w-per-m2", f"{irradiance:.6g}", "--wavelength-nm", "550", "--profile", str(base_profile)]
    assert main([*argv, "-o", str(output)]) == 0
    printed = capsys.readouterr().out
    for channel in ("R", "Gr", "Gb", "B"):
        row = next(line for line in printed.splitlines() if f"quantum efficiency η ({channel})" in line)
        assert float(row.split("│")[2].split("±")[0]) == pytest.approx(100 * SENSOR.quantum_efficiency.g, rel=0.02)
    assert "DSNU1288 from dark t=0.001 s" in printed
    assert "PRNU1288 from flat t=0.2 s T=40.0 °C (16 frames" in printed
    assert "EMVA 1288 4.0's high-pass filter" in printed and "at 550 nm" in printed
    header = output.read_text()
    assert "--shading-correction highpass" in header and "quantum efficiency η (Gr)" in header


def test_photons_per_pixel_from_frames_csv_split_the_stacks(tmp_path, capsys):
    """Flats at one exposure time under two lights, told apart only by frames.csv's photons_per_pixel
    column: two stacks, and η from them. A negative count names the line."""
    sensor = SENSOR.model_copy(update={"width_px": 48, "height_px": 48, "cfa": "mono"})
    model = SensorModel.build(sensor, SERIAL)
    rng = np.random.default_rng(7)
    shape = (48, 48)
    efficiency, exposure_s = 0.5, 0.1
    rows = {"dark": [], "flat": []}
    for kind, t, photons in [("dark", 0.05, 0.0), ("dark", exposure_s, 0.0)] + [
        ("flat", exposure_s, p) for p in (2000.0, 4000.0, 8000.0)
    ]:
        folder = tmp_path / kind
        folder.mkdir(exist_ok=True)
        for i in range(2):
            raw = model.capture(np.full(shape, efficiency * photons / t, np.float32), exposure_time_s=t, rng=rng)
            name = f"{kind}_{t:g}_{photons:g}_{i}.tif"
            tifffile.imwrite(folder / name, raw)
            rows[kind].append((name, t, 40.0, photons))
    for kind, entries in rows.items():
        with (tmp_path / kind / "frames.csv").open("w", newline="") as handle:
            writer = csv.writer(handle)
            writer.writerow(["file", "exposure_time_s", "temperature_c", "photons_per_pixel"])
            writer.writerows(entries)
    output = tmp_path / "fit.yaml"
    argv = ["fit", "noise", "--dark", str(tmp_path / "dark"), "--flat", str(tmp_path / "flat"), "--bit-depth", "12"]
    assert main([*argv, "-o", str(output)]) == 0
    printed = capsys.readouterr().out
    assert "3 of 3 flat stacks" in printed
    row = next(line for line in printed.splitlines() if "quantum efficiency η" in line)
    assert float(row.split("│")[2].split("±")[0]) == pytest.approx(100 * efficiency, rel=0.03)
    with (tmp_path / "flat" / "frames.csv").open("a", newline="") as handle:
        csv.writer(handle).writerow(["extra.tif", exposure_s, 40.0, -5])
    assert main([*argv, "-o", str(tmp_path / "bad.yaml")]) == 2
    assert "frames.csv:8: photons_per_pixel must be ≥ 0, got -5" in capsys.readouterr().err


def test_an_irradiance_needs_a_wavelength_and_the_choices_match_the_library(tmp_path, capsys):
    argv = ["fit", "noise", "--dark", str(tmp_path / "dark"), "--irradiance-w-per-m2", "0.5"]
    assert main([*argv, "-o", str(tmp_path / "out.yaml")]) == 2
    assert "give --wavelength-nm" in capsys.readouterr().err
    assert main([*argv, "--wavelength-nm", "550", "-o", str(tmp_path / "out.yaml")]) == 2
    assert "give --pixel-pitch-um or --profile" in capsys.readouterr().err
    assert SHADING_CHOICES == SHADING_CORRECTIONS
