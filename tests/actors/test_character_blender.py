"""A character made by Blender now (not the shipped file): camgen skins it as Blender does.

Blender's `bpy` pins numpy < 2, which camgen's own environment cannot take, so it lives in a venv of
its own: `make blender` makes `.venv-blender`, and this test runs when CAMGEN_BLENDER_PYTHON names
its interpreter (the Makefile's `test-blender` target sets it); otherwise it is skipped.
"""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

from camgen.io.gltf import load_character, pose_character

SCRIPT = Path(__file__).parent.parent / "data" / "characters" / "make_walker.py"
BLENDER_PYTHON = os.environ.get("CAMGEN_BLENDER_PYTHON")


@pytest.mark.skipif(
    not BLENDER_PYTHON, reason="Blender's bpy is not set up: run `make blender`, then `make test-blender`"
)
def test_a_fresh_blender_export_skins_as_blender_does(tmp_path):
    from scipy.spatial import cKDTree

    glb, reference_path = tmp_path / "walker.glb", tmp_path / "reference.npz"
    subprocess.run([BLENDER_PYTHON, str(SCRIPT), str(glb), str(reference_path)], check=True, capture_output=True)
    character = load_character(glb)
    reference = np.load(reference_path)
    blender_to_gltf = np.array([[1, 0, 0], [0, 0, 1], [0, -1, 0]], float)
    rest = np.concatenate([p for p, _ in pose_character(character, None, 0.0)])
    distance, match = cKDTree(reference["rest"] @ blender_to_gltf.T).query(rest)
    assert distance.max() < 1e-5
    for key in [k for k in reference.files if k not in ("rest", "fps")]:
        name, frame = key.rsplit("_", 1)
        time_s = int(frame) / float(reference["fps"])
        posed = np.concatenate([p for p, _ in pose_character(character, character.clip(name), time_s)])
        assert np.abs(posed - (reference[key] @ blender_to_gltf.T)[match]).max() < 1e-5, key
