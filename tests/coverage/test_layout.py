"""Layout optimisation: the greedy's (1 − 1/e) guarantee and the online bound against brute force, the
local search, and the CLI's scene fragment."""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import numpy as np
import yaml

from camgen.cli.main import main
from camgen.config.layout import LayoutCandidates
from camgen.config.scene import Scene
from camgen.coverage.layout import _gains, enumerate_options, evenly_spaced, greedy, objective_m2, swap_search
from tests.conftest import SCENE, write


def test_greedy_and_swaps_against_brute_force_on_random_coverage():
    rng = np.random.default_rng(5)
    for _ in range(20):
        meets = rng.random((9, 40)) < 0.25
        weight = rng.uniform(0.5, 2.0, 40)
        budget = 3
        best = max(objective_m2(meets, s, weight, 0.0) for s in itertools.combinations(range(9), budget))
        chosen = greedy(meets, budget, weight, 0.0)
        value = objective_m2(meets, chosen, weight, 0.0)
        assert value >= (1 - 1 / math.e) * best - 1e-9
        improved = swap_search(meets, chosen, weight, 0.0)
        assert objective_m2(meets, improved, weight, 0.0) >= value
        count = meets[chosen].sum(axis=0)
        bound = value + np.sort(_gains(meets, count, weight, 0.0))[::-1][:budget].sum()
        assert bound >= best - 1e-9


def test_handoff_weight_rewards_overlap():
    meets = np.array([[1, 1, 0, 0], [1, 1, 0, 0], [0, 0, 1, 0]], dtype=bool)
    weight = np.ones(4)
    assert sorted(greedy(meets, 2, weight, 0.0)) == [0, 2]  # coverage alone: spread out
    assert sorted(greedy(meets, 2, weight, 1.0)) == [0, 1]  # overlap worth as much: both on the same cells


CANDIDATES = """\
mounts:
  - {name: south, position_m: [0, -9, 4], yaw_deg_range: [60, 120], pitch_deg_range: [-30, -10]}
  - {name: east, kind: wall, position_m: [9, 0, 4], yaw_deg_range: [150, 210], pitch_deg_range: [-30, -10]}
profiles: [fixed]
yaw_step_deg: 30
pitch_step_deg: 20
"""
REGION = "regions:\n  - {name: gate, polygon_m: [[-2, -2], [2, -2], [2, 2], [-2, 2]], required_class: observe}\n"


def test_layout_cli_writes_a_scene_fragment_that_validates(workspace: Path, capsys):
    scene = write(workspace, "scenes/lot.yaml", SCENE + REGION)
    candidates = write(workspace, "candidates.yaml", CANDIDATES)
    out = workspace / "layout"
    assert (
        main(["layout", str(scene), "--candidates", str(candidates), "--budget", "2", "-o", str(out), "--cell-m", "1"])
        == 0
    )
    fragment = yaml.safe_load((out / "layout.yaml").read_text())
    assert len(fragment["cameras"]) == 2
    document = yaml.safe_load(scene.read_text()) | fragment
    assert len(Scene.model_validate(document).cameras) == 2
    assert (
        (out / "layout.json").exists() and (out / "site_layout.png").exists() and (out / "site_baseline.png").exists()
    )
    assert "baseline" in capsys.readouterr().out
    assert main(["layout", str(scene), "--candidates", str(candidates), "--budget", "0", "-o", str(out)]) == 2
    assert "--budget must be ≥ 1 camera, got 0" in capsys.readouterr().err


def test_the_baseline_turns_each_camera_towards_the_regions_within_its_heading_range():
    candidates = LayoutCandidates.model_validate(
        {
            "mounts": [
                {"name": "pole", "position_m": [10, 10, 5]},  # any heading: towards the origin, -135°
                # towards the origin is -16.7°, out of range: its nearer end, 260° (83° away; 100° is 117° away)
                {"name": "wall", "position_m": [-10, 3, 5], "yaw_deg_range": [100, 260]},
            ],
            "profiles": ["fixed"],
            "yaw_step_deg": 5,
        }
    )
    options = enumerate_options(candidates)
    chosen = [options[i] for i in evenly_spaced(options, candidates, 2, np.zeros(3))]
    assert [(o.mount, o.yaw_deg, o.pitch_deg) for o in chosen] == [("pole", -135.0, -25.0), ("wall", 260.0, -25.0)]


def test_a_region_no_candidate_reaches_at_its_class_is_a_located_error(workspace: Path, capsys):
    far = "  - {name: far_corner, polygon_m: [[7, 7], [9, 7], [9, 9], [7, 9]], required_class: identify}\n"
    scene = write(workspace, "scenes/lot.yaml", SCENE + REGION + far)
    candidates = write(workspace, "candidates.yaml", CANDIDATES)
    args = ["layout", str(scene), "--candidates", str(candidates), "--budget", "2", "-o", str(workspace / "out")]
    assert main([*args, "--cell-m", "1"]) != 0
    err = capsys.readouterr().err
    line = len((SCENE + REGION).splitlines()) + 1
    assert f"{scene}:{line}:" in err
    assert (
        "regions[1].required_class is 'identify', which no candidate camera (mount, heading, pitch and profile)" in err
    )
    # the east wall faces away from it (headings 150–210°); the south pole sees it only from 18 m away
    assert "region 'far_corner': the best is 'observe'; lower the required class" in err
    assert "gate" not in err  # reachable at observe: no problem
    assert not (workspace / "out").exists()


def test_zoom_lenses_are_tried_at_focal_lengths_in_equal_ratios_and_the_fragment_sets_them(workspace: Path, capsys):
    from camgen.config import load_profile
    from camgen.coverage.layout import focal_lengths_mm

    ptz = load_profile(workspace / "profiles/ptz.yaml").profile  # 4–40 mm
    fixed = load_profile(workspace / "profiles/fixed.yaml").profile
    np.testing.assert_allclose(focal_lengths_mm(ptz, 3), [4.0, 4.0 * math.sqrt(10), 40.0])
    assert focal_lengths_mm(ptz, 1) == [4.0] and focal_lengths_mm(fixed, 3) == [None]
    # A far region at recognise: the wide ends (4 mm) reach it nowhere, so the layout zooms the PTZ in.
    far = "regions:\n  - {name: far, polygon_m: [[-1, 9], [1, 9], [1, 11], [-1, 11]], required_class: recognise}\n"
    scene = write(workspace, "scenes/lot.yaml", SCENE.replace("[20, 20]", "[30, 30]") + far)
    candidates = write(
        workspace,
        "candidates.yaml",
        "mounts:\n  - {name: south, position_m: [0, -9, 4], yaw_deg_range: [90, 90], pitch_deg_range: [-10, -10]}\n"
        "profiles: [ptz, fixed]\nfocal_length_steps: 3\n",
    )
    out = workspace / "layout"
    assert main(["layout", str(scene), "--candidates", str(candidates), "--budget", "1", "-o", str(out)]) == 0
    (camera,) = yaml.safe_load((out / "layout.yaml").read_text())["cameras"]
    assert camera["profile"] == "ptz" and camera["ptz"] == {"pan_deg": 0, "tilt_deg": 0, "zoom_x": 3.162}
    assert len(Scene.model_validate(yaml.safe_load(scene.read_text()) | {"cameras": [camera]}).cameras) == 1
    candidates.write_text(candidates.read_text().replace("focal_length_steps: 3", "focal_length_steps: 1"))
    assert main(["layout", str(scene), "--candidates", str(candidates), "--budget", "1", "-o", str(out) + "1"]) != 0
    assert "reaches on any point of region 'far'" in capsys.readouterr().err


def test_a_bad_focal_length_steps_is_located(workspace: Path, capsys):
    scene = write(workspace, "scenes/lot.yaml", SCENE + REGION)
    candidates = write(workspace, "candidates.yaml", CANDIDATES + "focal_length_steps: 0\n")
    assert main(["layout", str(scene), "--candidates", str(candidates), "--budget", "1"]) != 0
    line = len(CANDIDATES.splitlines()) + 1
    assert f"{candidates}:{line}:1: focal_length_steps must be ≥ 1, got 0; 1 tries the wide end only" in (
        capsys.readouterr().err
    )
