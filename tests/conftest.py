"""Shared fixtures: small valid profiles and scenes written to a temporary directory."""

from __future__ import annotations

import os
import re
import textwrap
from pathlib import Path

import pytest

# One OpenBLAS thread per test process. Its threads busy-wait for work, and beside the other test process
# (`make test`: -n 2), OpenCV's thread pool and llvmpipe's on 2 cores they mostly wait: a (4 M × 3) @ (3 × 3)
# product after OpenCV had run took 0.65 s instead of 0.06 s (the 12 ChArUco views of tests/fit/boards.py:
# 35 s → 13 s wall, 13 s → 4.6 s CPU, the same images bit for bit). Read when numpy loads OpenBLAS: nothing
# imports numpy before this file; the processes the tests start inherit it.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

REPO = Path(__file__).resolve().parents[1]

FIXED_PROFILE = """\
description: test fixed camera
sensor:
  width_px: 640
  height_px: 480
  pixel_pitch_um: 3.0
  cfa: RGGB
  bit_depth: 12
  full_well_e: 10000
  conversion_gain_dn_per_e: 0.4
  black_level_dn: 64
  noise:
    read_noise_e: 2.0
lens:
  focal_length_mm: 4.0
  f_number: 2.0
  min_focus_distance_m: 0.3
"""

PTZ_PROFILE = """\
description: test ptz camera
sensor:
  width_px: 640
  height_px: 480
  pixel_pitch_um: 3.0
  full_well_e: 10000
  conversion_gain_dn_per_e: 0.4
lens:
  focal_length_range_mm: [4.0, 40.0]
  f_number: 1.6
ptz:
  pan_max_deg_s: 100
  tilt_range_deg: [-90, 10]
"""

SCENE = """\
duration_s: 1
fps: 10
seed: 1
environment:
  meshes:
    - type: plane
      name: ground
      size_m: [20, 20]
lights:
  - {type: ambient, illuminance_lux: 1000}
actors:
  - name: walker
    class: person
    path:
      waypoints_m: [[-3, 5], [3, 5]]
      speed_m_s: 1.4
cameras:
  - name: cam
    profile: fixed
    mount:
      position_m: [0, -5, 3]
      yaw_deg: 90
      pitch_deg: -20
"""


def write(directory: Path, name: str, text: str) -> Path:
    path = directory / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(textwrap.dedent(text), encoding="utf-8")
    return path


def assert_located_problem(workspace: Path, text: str, key: str, fragment: str) -> None:
    """Loading the scene `text` (written to `workspace`/scenes/bad.yaml) fails with one problem, located at the
    line marked ``#<`` (file:line:column), naming `key` and saying `fragment`."""
    from camgen.config import load_scene
    from camgen.errors import ConfigError

    path = write(workspace, "scenes/bad.yaml", text)
    with pytest.raises(ConfigError) as caught:
        load_scene(path)
    (problem,) = caught.value.problems
    message = str(problem)
    assert fragment in message, message
    assert f" {key} " in f" {message} ", message
    marked = next(i + 1 for i, row in enumerate(text.splitlines()) if "#<" in row)
    assert re.match(rf"^{re.escape(str(path))}:{marked}:\d+: ", message), message


@pytest.fixture
def workspace(tmp_path: Path) -> Path:
    """A directory with profiles/fixed.yaml, profiles/ptz.yaml and scenes/ for test scenes."""
    write(tmp_path, "profiles/fixed.yaml", FIXED_PROFILE)
    write(tmp_path, "profiles/ptz.yaml", PTZ_PROFILE)
    (tmp_path / "scenes").mkdir()
    return tmp_path


@pytest.fixture(scope="session")
def renderer():
    """One headless OpenGL context for every rendering test (creating EGL contexts is slow)."""
    from camgen.render.renderer import Renderer

    with Renderer() as instance:
        yield instance


def shared_directory(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory, name: str) -> Path:
    """A directory every test process of this run sees: under pytest-xdist, one beside the workers' own
    base directories, named by the run's id (so no earlier run's files are reused); otherwise a fresh one."""
    workerinput = getattr(request.config, "workerinput", None)
    if workerinput is None:
        return tmp_path_factory.mktemp(name)
    directory = tmp_path_factory.getbasetemp().parent / f"{name}-{workerinput['testrunuid']}"
    directory.mkdir(exist_ok=True)
    return directory


@pytest.fixture(scope="session")
def board_views(request, renderer, tmp_path_factory):
    """name → (directory, job, 8-bit grey views) of the board scene through a `tests.fit.boards.DISTORTIONS`
    lens, rendered once per test run: tests/fit/test_lens.py fits them as a person would (the PNGs in
    directory/images), tests/render/test_lens_calibration.py calibrates them with OpenCV alone.

    The two files usually run in different test processes (`make test`'s --dist loadfile): the first to
    ask renders the views under a file lock, the other waits for them and reads the PNGs back (8-bit,
    lossless: the same arrays) and plans the same scene file again. That saves two of the suite's
    costliest renders (12 views at 1920 × 1080, supersampled)."""
    import cv2
    from filelock import FileLock

    from camgen.config import load_scene
    from camgen.fit.checkerboard import gray8_from_radiance
    from camgen.plan import PlanSettings, compile_scene
    from tests.fit.boards import (
        CALIBRATION_VIEWS,
        DISTORTIONS,
        SUPERSAMPLING,
        lens_output,
        lens_profile,
        write_board_scene,
    )

    root = shared_directory(request, tmp_path_factory, "boards")
    cache = {}

    def views(name: str):
        if name not in cache:
            directory = root / f"board_{name}"
            done = directory / "rendered"
            with FileLock(str(root / f"board_{name}.lock")):
                if done.exists():
                    scene = directory / f"scenes/board_{name}.yaml"
                    job = compile_scene(load_scene(scene), PlanSettings(supersampling=SUPERSAMPLING))
                    paths = [directory / "images" / f"{camera.name}.png" for camera in job.cameras]
                    grays = [cv2.imread(str(path), cv2.IMREAD_GRAYSCALE) for path in paths]
                else:
                    directory.mkdir()
                    profile = lens_profile(distortion=DISTORTIONS[name])
                    job = write_board_scene(directory, name, profile, CALIBRATION_VIEWS)
                    (directory / "images").mkdir()
                    grays = []
                    for camera, radiance in lens_output(renderer, job):
                        grays.append(gray8_from_radiance(radiance))
                        cv2.imwrite(str(directory / "images" / f"{camera.name}.png"), grays[-1])
                    done.touch()
            cache[name] = directory, job, grays
        return cache[name]

    return views


@pytest.fixture(scope="session")
def board_detections(board_views):
    """(name, board spec) → `camgen.fit.lens.detect_in_folder` of `board_views(name)`'s PNGs (a `BoardImages`),
    detected once per test run: tests/fit/test_lens.py fits them as `camgen fit lens` would, and
    tests/render/test_lens_calibration.py calibrates their corners with OpenCV. Shared across test processes
    as `board_views` is: the first to ask detects under a file lock and pickles the result beside the views,
    the other reads it back. Detecting the 12 views at 1920 × 1080 costs about 12 s (1 s a view)."""
    import pickle

    from filelock import FileLock

    from camgen.fit.lens import detect_in_folder

    cache = {}

    def detections(name: str, spec):
        if name not in cache:
            directory, _, _ = board_views(name)
            saved = directory / "detections.pickle"
            with FileLock(str(directory.parent / f"board_{name}_detections.lock")):
                if saved.exists():
                    saved_spec, found = pickle.loads(saved.read_bytes())
                    assert saved_spec == spec, f"board_{name} was detected as {saved_spec}, not {spec}"
                else:
                    found = detect_in_folder(directory / "images", spec)
                    saved.write_bytes(pickle.dumps((spec, found)))
            cache[name] = found
        return cache[name]

    return detections
