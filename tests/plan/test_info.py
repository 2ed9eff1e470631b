"""`camgen info` figures against hand calculation."""

from __future__ import annotations

import math

import pytest

from camgen.cli.main import main
from camgen.config import load_profile
from camgen.plan.info import profile_info
from tests.conftest import write

# The seed paper's Fig. 4: 25 mm → 48.1°, 40 mm → 31.2° horizontal. Those figures imply a sensor
# 2·25·tan(24.05°) = 22.3 mm wide (APS-C); we use 4460 px × 5.0 µm = 22.30 mm.
PAPER_PROFILE = """\
sensor:
  width_px: 4460
  height_px: 2973
  pixel_pitch_um: 5.0
  full_well_e: 10000
  conversion_gain_dn_per_e: 0.4
  black_level_dn: 0
  temperature_c: 25
  noise: {read_noise_e: 2.0, dark_current_e_per_s: 0.0}
lens:
  focal_length_range_mm: [25, 40]
  f_number: 2.0
exposure: {exposure_time_max_s: 0.01, exposure_time_s: 0.01}
"""


def test_afov_matches_the_seed_paper(tmp_path):
    info = profile_info(load_profile(write(tmp_path, "paper.yaml", PAPER_PROFILE)).profile)
    assert info.sensor_width_mm == pytest.approx(22.30)
    wide, tele = info.zoom_steps[0], info.zoom_steps[-1]
    assert wide.focal_length_mm == 25 and tele.focal_length_mm == pytest.approx(40)
    assert round(wide.hfov_deg, 1) == 48.1
    assert round(tele.hfov_deg, 1) == 31.2
    assert wide.fx_px == pytest.approx(25 / 0.005)


def test_sensor_figures_by_hand(tmp_path):
    info = profile_info(load_profile(write(tmp_path, "paper.yaml", PAPER_PROFILE)).profile)
    # Saturation: ADC reaches 4095 DN at 10237 e⁻ > full well, so the full well limits.
    assert info.saturation_e == 10000 and info.saturation_limit == "full well"
    # σ_d² = 2² + 0 (no dark current) + (1/0.4)²/12 quantisation.
    sigma = math.sqrt(4 + 2.5**2 / 12)
    assert info.dark_noise_e == pytest.approx(sigma)
    assert info.dynamic_range_db == pytest.approx(20 * math.log10(10000 / sigma))
    assert info.pixel_area_um2 == pytest.approx(25.0)
    # Hyperfocal H = f²/(N·c) + f with c = 2 pixel pitches = 10 µm.
    assert info.zoom_steps[0].hyperfocal_m == pytest.approx((25**2 / (2.0 * 0.010) + 25) / 1000)


def test_adc_can_limit_saturation(tmp_path):
    text = PAPER_PROFILE.replace("conversion_gain_dn_per_e: 0.4", "conversion_gain_dn_per_e: 1.0")
    info = profile_info(load_profile(write(tmp_path, "p.yaml", text)).profile)
    assert info.saturation_limit == "ADC" and info.saturation_e == 4095


def test_dark_current_doubles_per_doubling_temperature(tmp_path):
    text = PAPER_PROFILE.replace("dark_current_e_per_s: 0.0", "dark_current_e_per_s: 2.0").replace(
        "temperature_c: 25", "temperature_c: 38"
    )
    info = profile_info(load_profile(write(tmp_path, "p.yaml", text)).profile)
    assert info.dark_current_e_per_s == pytest.approx(8.0)  # 13 °C = two doublings of 6.5 °C


def test_info_cli_prints_the_figures(tmp_path, capsys):
    assert main(["info", str(write(tmp_path, "paper.yaml", PAPER_PROFILE))]) == 0
    out = capsys.readouterr().out
    assert "48.07" in out and "31.15" in out and "dynamic range" in out
