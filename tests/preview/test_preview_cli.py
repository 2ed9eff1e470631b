"""camgen preview on a tiny render: the video decodes with every frame, the contact sheet has the documented
grid, the page holds the video, the plots and the card, and a real browser engine loads it without errors."""

from __future__ import annotations

import shutil
from pathlib import Path

import av
import cv2
import numpy as np
import pytest

from camgen.cli.main import main
from camgen.io.video import read_video_rgb8
from camgen.preview.draw import CONTACT_SHEET_GAP_PX, track_colour_rgb8
from tests.preview.conftest import FRAMES

CARD = "# Tiny dataset\n\n| class | tracks |\n| --- | --- |\n| person | 1 |\n\n![boxes](card/boxes.png)\n"


@pytest.fixture(scope="module")
def previewed(tiny_render, tmp_path_factory) -> Path:
    """The preview files of `tiny_render`, with a dataset card beside its job directory."""
    root = tmp_path_factory.mktemp("previewed") / "out"
    shutil.copytree(tiny_render, root)
    (root / "DATASET_CARD.md").write_text(CARD, encoding="utf-8")
    (root / "card").mkdir()
    cv2.imwrite(str(root / "card" / "boxes.png"), np.zeros((8, 8, 3), np.uint8))
    assert main(["preview", str(root), "--html"]) == 0
    return root / "preview"


def files(previewed: Path, suffix: str) -> Path:
    (path,) = previewed.glob(f"*-cam{suffix}")
    return path


def test_the_video_has_every_frame_annotated(previewed):
    path = files(previewed, ".webm")
    with av.open(str(path)) as container:
        assert container.streams.video[0].codec_context.name == "vp9"
    frames = list(read_video_rgb8(path))
    assert len(frames) == FRAMES and frames[0].shape == (240, 320, 3)
    for frame in frames:  # each track's tag and mask in its colour (within the codec's loss)
        for track_id in (1, 2):
            distance = np.abs(frame.astype(int) - track_colour_rgb8(track_id)).sum(axis=2)
            assert (distance < 80).sum() > 50
    assert not list(previewed.glob(".*partial*"))


def test_the_contact_sheet_has_one_tile_per_frame_four_to_a_row(previewed):
    sheet = cv2.imread(str(files(previewed, ".contact.png")))
    gap = CONTACT_SHEET_GAP_PX
    assert sheet.shape == (240 + 2 * gap, FRAMES * 320 + (FRAMES + 1) * gap, 3)


def test_the_page_holds_the_video_the_plots_and_the_card(previewed):
    page = files(previewed, ".html").read_text(encoding="utf-8")
    assert page.count('src="data:video/webm;base64,') == 1
    assert page.count("<svg") == 1
    for label in ("angle, deg", "zoom, x", "exposure, ms", "gain, dB"):
        assert f"<!-- {label} -->" in page
    assert "<h1>Tiny dataset</h1>" in page and "<td>person</td>" in page
    assert 'src="data:image/png;base64,' in page  # the card's picture, embedded


def test_a_camera_directory_with_frames_and_no_video(previewed, tiny_render, tmp_path, capsys):
    camera = tmp_path / "walk-00000000" / "cam"
    shutil.copytree(next(tiny_render.glob("*/cam")), camera)
    (camera / "frames").mkdir()
    for k, frame in enumerate(read_video_rgb8(camera / "video.mp4")):
        cv2.imwrite(str(camera / "frames" / f"{k:06d}.png"), cv2.cvtColor(frame, cv2.COLOR_RGB2BGR))
    (camera / "video.mp4").unlink()
    assert main(["preview", str(camera), "-o", str(tmp_path / "p")]) == 0
    assert len(list(read_video_rgb8(tmp_path / "p" / "walk-00000000-cam.webm"))) == FRAMES
    assert f"walk-00000000/cam: {FRAMES} frames" in capsys.readouterr().out


def chromium(playwright):
    """Playwright's own Chromium, else the system's (Debian's chromium package), else a skip."""
    errors = []
    system = [path for path in (shutil.which("chromium"), shutil.which("chromium-browser")) if path]
    for executable in (None, *system):
        try:
            return playwright.chromium.launch(executable_path=executable, args=["--no-sandbox"])
        except Exception as error:  # any failure to start a browser means: none here
            errors.append(str(error).splitlines()[0])
    pytest.skip(f"no Chromium for Playwright (python -m playwright install chromium): {'; '.join(errors)}")


def test_a_browser_plays_the_page_without_errors(previewed):
    sync_api = pytest.importorskip(
        "playwright.sync_api", reason="Playwright is not installed: pip install camgen[browser]"
    )
    with sync_api.sync_playwright() as playwright:
        browser = chromium(playwright)
        try:
            page = browser.new_page()
            problems = []
            page.on("console", lambda message: problems.append(message.text) if message.type == "error" else None)
            page.on("pageerror", lambda error: problems.append(str(error)))
            page.goto(files(previewed, ".html").resolve().as_uri())
            page.wait_for_function("document.getElementById('video').readyState >= 2", timeout=10_000)
            video = page.evaluate(
                "(() => { const v = document.getElementById('video'); "
                "return [v.error, v.videoWidth, v.videoHeight, v.duration]; })()"
            )
            assert video[:3] == [None, 320, 240] and video[3] == pytest.approx(FRAMES / 10, abs=0.05)
            plot = page.locator("#plots svg").bounding_box()
            assert plot["width"] > 300 and plot["height"] > 200
            page.evaluate(
                "document.getElementById('video').pause(); document.getElementById('video').currentTime = 0.2"
            )
            page.wait_for_function("document.getElementById('cursor').style.left !== ''")
            assert page.locator("#card h1").inner_text() == "Tiny dataset"
            assert page.evaluate("document.querySelector('#card img').naturalWidth") == 8
            assert problems == []
        finally:
            browser.close()
