"""Bad `environment.markings` input: each case gets its own error at the marked line (file:line:column, key
path, value, fix), as tests/config/test_bad_input.py checks every other key."""

from __future__ import annotations

from pathlib import Path

import pytest

from camgen.config import load_scene
from camgen.errors import ConfigError
from tests.conftest import SCENE, assert_located_problem, write


def with_marking(line: str) -> str:
    """The test scene with one marking (its line marked ``#<``) after the ground plane."""
    anchor = "      size_m: [20, 20]\n"
    assert anchor in SCENE
    return SCENE.replace(anchor, anchor + "  markings:\n    - " + line + " #<\n", 1)


# (id, the marking, expected key path, expected message fragment)
CASES = [
    (
        "dash_without_gap",
        "{type: line, along_m: [[0, 0], [5, 0]], dash_m: 3}",
        "environment.markings[0].dash_m",
        "needs gap_m as well (a dashed line has both; a solid one neither)",
    ),
    (
        "repeated_point",
        "{type: line, along_m: [[0, 0], [0, 0], [5, 0]]}",
        "environment.markings[0].along_m[1]",
        "repeats the point before it, [0.0, 0.0]; a line's points must be at least 1 mm apart",
    ),
    (
        "one_point",
        "{type: line, along_m: [[0, 0]]}",
        "environment.markings[0].along_m",
        "at least 2",
    ),
    (
        "line_too_wide",
        "{type: line, along_m: [[0, 0], [5, 0]], width_m: 2}",
        "environment.markings[0].width_m",
        "must be ≤ 1, got 2; road lines are 0.05–1 m wide",
    ),
    (
        "unknown_type",
        "{type: arrow, along_m: [[0, 0], [5, 0]]}",
        "environment.markings[0].type",
        "got 'arrow'",
    ),
    (
        "red_paint",
        "{type: line, along_m: [[0, 0], [5, 0]], colour: red}",
        "environment.markings[0].colour",
        "got 'red'",
    ),
    (
        "worn_away",
        "{type: crossing, from_m: [0, -4], to_m: [0, 4], wear: 0.95}",
        "environment.markings[0].wear",
        "at most 90 % of a marking can be worn away",
    ),
    (
        "crossing_gap_over_mutcd",
        "{type: crossing, from_m: [0, -4], to_m: [0, 4], stripe_m: 0.3, gap_m: 1.0}",
        "environment.markings[0].gap_m",
        "is 1 m, over 2.5 × stripe_m (0.3 m; MUTCD §3B.18); make it at most 0.75",
    ),
    (
        "crossing_kerbs_together",
        "{type: crossing, from_m: [0, 0], to_m: [0, 0.2]}",
        "environment.markings[0].to_m",
        "is 0.2 m from from_m, narrower than one bar (0.6 m)",
    ),
    (
        "bays_without_count",
        "{type: bays, first_centre_m: [0, 0]}",
        "environment.markings[0].count",
        "is required",
    ),
    (
        "bay_lines_too_wide_for_the_bays",
        "{type: bays, first_centre_m: [0, 0], count: 2, width_m: 1.5, length_m: 3, line_width_m: 0.3}",
        "environment.markings[0].line_width_m",
        "is 0.3 m, too wide for 1.5 m wide bays (the lines take at most a fifth of a bay's width); make it 0.1",
    ),
    (
        "bay_layout_unknown",
        "{type: bays, first_centre_m: [0, 0], count: 2, layout: echelon}",
        "environment.markings[0].layout",
        "got 'echelon'",
    ),
    (
        "marking_named_like_a_mesh",
        "{type: line, name: ground, along_m: [[0, 0], [5, 0]]}",
        "environment.markings[0].name",
        "is the instance 'ground', a name another mesh, prop or marking has already",
    ),
]


@pytest.mark.parametrize(("line", "key", "fragment"), [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_bad_marking_is_located_and_explained(workspace: Path, line: str, key: str, fragment: str):
    assert_located_problem(workspace, with_marking(line), key, fragment)


def test_unnamed_markings_after_a_named_one_of_their_default_name(workspace: Path):
    """A marking named like another's default `<type>_<index>` is refused at the second of the two."""
    text = SCENE.replace(
        "      size_m: [20, 20]\n",
        "      size_m: [20, 20]\n  markings:\n"
        "    - {type: line, name: line_1, along_m: [[0, 0], [5, 0]]}\n"
        "    - {type: line, along_m: [[0, 1], [5, 1]]} #<\n",
        1,
    )
    path = write(workspace, "scenes/bad.yaml", text)
    with pytest.raises(ConfigError, match=r"environment\.markings\[1\] is the instance 'line_1'"):
        load_scene(path)


def test_good_markings_load_with_their_defaults(workspace: Path):
    path = write(
        workspace,
        "scenes/ok.yaml",
        with_marking("{type: bays, first_centre_m: [0, 0], count: 3, layout: parallel}").replace(" #<", ""),
    )
    (bays,) = load_scene(path).scene.environment.markings
    assert bays.bay_size_m == (2.0, 6.0) and bays.line_width_m == 0.1 and bays.colour == "white"
