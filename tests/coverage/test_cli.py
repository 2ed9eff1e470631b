"""camgen coverage writes its report, arrays and plots; bad settings and regions get located errors."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from camgen.cli.main import main
from tests.conftest import SCENE, write

REGIONS = """\
regions:
  - {name: gate, polygon_m: [[-2, 2], [2, 2], [2, 6], [-2, 6]], required_class: observe}
"""


def test_coverage_writes_report_arrays_and_plots(workspace: Path, capsys):
    scene = write(workspace, "scenes/lot.yaml", SCENE + REGIONS)
    out = workspace / "cov"
    assert main(["coverage", str(scene), "-o", str(out), "--cell-m", "1", "--height-m", "0", "--height-m", "1.6"]) == 0
    report = json.loads((out / "coverage.json").read_text())
    assert [p["height_m"] for p in report["planes"]] == [0.0, 1.6]
    assert report["dori"]["thresholds_px_m"]["identify"] == 250.0
    (gate,) = report["planes"][0]["regions"]
    assert gate["name"] == "gate" and gate["area_m2"] == 16.0 and gate["share_meeting_required"] > 0.5
    with np.load(out / "coverage.npz") as arrays:  # plain arrays: no pickle needed
        assert arrays["plane0_dori"].shape == (1, 20, 20)
        assert arrays["camera_names"].tolist() == ["cam"]
    pngs = sorted(p.name for p in out.glob("*.png"))
    assert pngs == ["image_cam_0m.png", "image_cam_1.6m.png", "site_0m.png", "site_1.6m.png"]
    assert not list(out.glob(".*partial*"))
    assert "region gate: needs observe" in capsys.readouterr().out


def test_bad_cell_size_and_a_region_off_the_ground_are_reported(workspace: Path, capsys):
    scene = write(workspace, "scenes/lot.yaml", SCENE + REGIONS)
    assert main(["coverage", str(scene), "-o", str(workspace / "c"), "--cell-m", "0"]) == 2
    assert "--cell-m must be > 0 m, got 0" in capsys.readouterr().err
    off = REGIONS.replace("[2, 6], [-2, 6]", "[2, 6], [-2, 60]")
    scene = write(workspace, "scenes/off.yaml", SCENE + off)
    assert main(["coverage", str(scene), "-o", str(workspace / "c"), "--no-plots"]) == 2
    err = capsys.readouterr().err
    assert f"{scene}:25:55:" in err and "regions[0].polygon_m[3] puts a corner of region 'gate' at [-2, 60]" in err
    assert "Traceback" not in err
