"""Bad `environment.kerbs` input: each case gets its own error at the marked line (file:line:column, key path,
value, fix), as tests/config/test_bad_input.py checks every other key."""

from __future__ import annotations

from pathlib import Path

import pytest

from camgen.config import load_scene
from camgen.errors import ConfigError
from tests.conftest import SCENE, assert_located_problem, write


def with_kerb(line: str) -> str:
    """The test scene with one kerb (its line marked ``#<``) after the ground plane."""
    anchor = "      size_m: [20, 20]\n"
    assert anchor in SCENE
    return SCENE.replace(anchor, anchor + "  kerbs:\n    - " + line + " #<\n", 1)


# (id, the kerb, expected key path, expected message fragment)
CASES = [
    ("one_point", "{along_m: [[0, 0]]}", "environment.kerbs[0].along_m", "at least 2"),
    (
        "zero_length_segment",
        "{along_m: [[0, 0], [4, 0], [4, 0]]}",
        "environment.kerbs[0].along_m[2]",
        "repeats the point before it, [4.0, 0.0]; a kerb's points must be at least 1 mm apart",
    ),
    (
        "negative_width",
        "{along_m: [[0, 0], [4, 0]], width_m: -0.125}",
        "environment.kerbs[0].width_m",
        "must be ≥ 0.05",
    ),
    (
        "negative_upstand",
        "{along_m: [[0, 0], [4, 0]], upstand_m: -0.1}",
        "environment.kerbs[0].upstand_m",
        "must be > 0, got -0.1; a kerb stands 0–0.4 m over the road",
    ),
    (
        "negative_joint",
        "{along_m: [[0, 0], [4, 0]], joint_m: -0.003}",
        "environment.kerbs[0].joint_m",
        "must be ≥ 0",
    ),
    (
        "unit_too_short",
        "{along_m: [[0, 0], [4, 0]], unit_length_m: 0.01}",
        "environment.kerbs[0].unit_length_m",
        "kerb units are 0.1–5 m long (BS 7263: 0.914 m)",
    ),
    ("unknown_key", "{along_m: [[0, 0], [4, 0]], height_m: 0.1}", "environment.kerbs[0].height_m", "height_m"),
    ("road_side_unknown", "{along_m: [[0, 0], [4, 0]], road_side: north}", "environment.kerbs[0].road_side", "'north'"),
    (
        "batter_above_the_kerb",
        "{along_m: [[0, 0], [4, 0]], upstand_m: 0.05}",
        "environment.kerbs[0].batter_rise_m",
        "is 0.1 m, above the kerb's upstand_m (0.05 m); make it at most 0.05",
    ),
    (
        "batter_without_rise",
        "{along_m: [[0, 0], [4, 0]], batter_rise_m: 0}",
        "environment.kerbs[0].batter_setback_m",
        "needs the other of batter_setback_m and batter_rise_m above 0 too",
    ),
    (
        "no_top_left",
        "{along_m: [[0, 0], [4, 0]], width_m: 0.06}",
        "environment.kerbs[0].batter_setback_m",
        "leaves no top on a 0.06 m wide kerb",
    ),
    (
        "arris_below_the_road",
        "{along_m: [[0, 0], [4, 0]], upstand_m: 0.01, batter_setback_m: 0, batter_rise_m: 0}",
        "environment.kerbs[0].arris_radius_m",
        "is 0.015 m, whose rounding takes 15.0 mm of a 10.0 mm road face (upstand_m); make it at most 0.01 m",
    ),
    (
        "arris_past_the_batter",
        "{along_m: [[0, 0], [4, 0]], width_m: 0.2, batter_setback_m: 0.005, batter_rise_m: 0.005, "
        "arris_radius_m: 0.05}",
        "environment.kerbs[0].arris_radius_m",
        "whose rounding takes 20.7 mm of a 7.1 mm batter",
    ),
    (
        "hairpin",
        "{along_m: [[0, 0], [4, 0], [0, 0.5]]}",
        "environment.kerbs[0].along_m[1]",
        "turns the kerb by 173°, sharper than 135°",
    ),
    (
        "kerb_named_like_a_mesh",
        "{name: ground, along_m: [[0, 0], [4, 0]]}",
        "environment.kerbs[0].name",
        "is the instance 'ground', a name another mesh, prop, marking or kerb has already",
    ),
]


@pytest.mark.parametrize(("line", "key", "fragment"), [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_bad_kerb_is_located_and_explained(workspace: Path, line: str, key: str, fragment: str):
    assert_located_problem(workspace, with_kerb(line), key, fragment)


def test_unnamed_kerbs_take_their_default_names(workspace: Path):
    """A kerb named like another's default `kerb_<index>` is refused at the second of the two."""
    text = SCENE.replace(
        "      size_m: [20, 20]\n",
        "      size_m: [20, 20]\n  kerbs:\n"
        "    - {name: kerb_1, along_m: [[0, 0], [5, 0]]}\n"
        "    - {along_m: [[0, 1], [5, 1]]} #<\n",
        1,
    )
    path = write(workspace, "scenes/bad.yaml", text)
    with pytest.raises(ConfigError, match=r"environment\.kerbs\[1\] is the instance 'kerb_1'"):
        load_scene(path)


def test_good_kerb_loads_with_the_hb2_defaults(workspace: Path):
    path = write(workspace, "scenes/ok.yaml", with_kerb("{along_m: [[0, 0], [4, 0], [6, 2]]}").replace(" #<", ""))
    (kerb,) = load_scene(path).scene.environment.kerbs
    assert (kerb.width_m, kerb.upstand_m, kerb.unit_length_m, kerb.road_side) == (0.125, 0.125, 0.914, "right")
