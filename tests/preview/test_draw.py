"""The drawing functions against arrays whose every pixel is known."""

from __future__ import annotations

import numpy as np
import pytest
from pycocotools import mask as mask_utils

from camgen.preview.draw import (
    CONTACT_SHEET_BACKGROUND_RGB8,
    CONTACT_SHEET_GAP_PX,
    DrawnObject,
    annotate_frame,
    blend_mask,
    camera_state_lines,
    contact_sheet,
    draw_box,
    draw_skeleton,
    draw_tail,
    track_colour_rgb8,
)

RED = (255, 0, 0)


def coco_bbox(mask: np.ndarray) -> list[float]:
    """[x, y, w, h] as camgen's COCO writer computes it from a mask (tests/cli/test_annotation_formats.py)."""
    rows, cols = np.nonzero(mask)
    return [
        float(cols.min()),
        float(rows.min()),
        float(cols.max() + 1 - cols.min()),
        float(rows.max() + 1 - rows.min()),
    ]


def test_a_box_is_drawn_on_the_outermost_pixels_of_its_object():
    mask = np.zeros((24, 32), bool)
    mask[5:15, 7:20] = True
    image = np.zeros((24, 32, 3), np.uint8)
    drawn = draw_box(image, coco_bbox(mask), RED)
    outline = mask & ~np.pad(mask[1:-1, 1:-1] & mask[:-2, 1:-1] & mask[2:, 1:-1] & mask[1:-1, :-2] & mask[1:-1, 2:], 1)
    np.testing.assert_array_equal((drawn == RED).all(axis=2), outline)
    assert not drawn[~outline].any() and not image.any()  # nothing else drawn, input untouched


def test_a_fractional_box_rounds_to_the_nearest_pixels():
    drawn = draw_box(np.zeros((10, 10, 3), np.uint8), [1.6, 2.4, 4.8, 3.2], RED)
    rows, cols = np.nonzero(drawn[..., 0])
    assert (cols.min(), rows.min(), cols.max(), rows.max()) == (2, 2, 5, 5)


def test_a_track_keeps_its_colour_in_every_frame_and_camera():
    assert track_colour_rgb8(7) == track_colour_rgb8(np.int64(7))
    colours = {track_colour_rgb8(k) for k in range(1, 41)}
    assert len(colours) == 40  # distinct ids, distinct colours
    box = (4.0, 4.0, 10.0, 8.0)
    frames = [np.full((24, 32, 3), level, np.uint8) for level in (0, 90, 200)]  # three cameras, or frames
    for image in frames:
        drawn = annotate_frame(image, [DrawnObject(track_id=7, label="", bbox_xywh=box)])
        assert tuple(drawn[4, 8]) == track_colour_rgb8(7)  # on the box's top edge


def test_a_mask_is_blended_only_inside_its_rle():
    rng = np.random.default_rng(0)
    image = rng.integers(0, 256, (30, 40, 3), dtype=np.uint8)
    mask = np.zeros((30, 40), np.uint8)
    mask[3:20, 5:9] = 1
    mask[10:25, 20:35] = 1
    rle = mask_utils.encode(np.asfortranarray(mask))
    inside = mask_utils.decode(rle).astype(bool)
    blended = blend_mask(image, inside, RED, alpha=0.25)
    np.testing.assert_array_equal(blended[~inside], image[~inside])
    expected = np.rint(0.75 * image[inside].astype(np.float64) + 0.25 * np.array(RED)).astype(np.uint8)
    np.testing.assert_array_equal(blended[inside], expected)


def test_a_skeleton_joins_labelled_points_only():
    image = np.zeros((40, 40, 3), np.uint8)
    keypoints = [5, 5, 2, 30, 5, 2, 30, 35, 0]  # the third is not labelled
    drawn = draw_skeleton(image, keypoints, [[1, 2], [2, 3]], RED)
    limb = drawn[5, 10:26].astype(int)  # from point 1 to point 2, antialiased
    assert (limb[:, 0] > 200).all() and (limb[:, 1:] < 60).all()
    assert not drawn[12:, :].any()  # nothing towards point 3
    hidden = draw_skeleton(image, [5, 5, 2, 30, 5, 1], [[1, 2]], RED)
    assert 0 < hidden[5, 30, 0] < 255  # a hidden point is dimmed


def test_a_tail_breaks_where_it_was_not_imaged():
    image = np.zeros((20, 40, 3), np.uint8)
    drawn = draw_tail(image, np.array([[2, 10], [12, 10], [np.nan, np.nan], [25, 10], [37, 10]]), RED)
    assert drawn[10, 5:10, 0].all() and drawn[10, 28:35, 0].all()
    assert not drawn[10, 15:22].any()


def test_camera_state_lines_leave_out_what_a_record_lacks():
    lines = camera_state_lines(
        {
            "frame": 3,
            "time_s": 0.3,
            "pan_deg": 12.5,
            "tilt_deg": -4.0,
            "zoom_x": 2.0,
            "exposure_time_s": 0.004,
            "gain_db": 6.0,
            "ptz_mode": "follow",
            "follow_target": "walker",
        }
    )
    assert lines == [
        "frame 3  t 0.30 s",
        "pan 12.5 deg  tilt -4.0 deg  zoom 2.00x",
        "exposure 4 ms  gain 6.0 dB",
        "ptz follow -> walker",
    ]
    assert camera_state_lines({"frame": 0, "pan_deg": None, "exposure_time_s": 0.01}) == ["frame 0", "exposure 10 ms"]


@pytest.mark.parametrize(("count", "shape_tiles"), [(1, (1, 1)), (4, (1, 4)), (5, (2, 4)), (9, (3, 4))])
def test_the_contact_sheet_grid(count, shape_tiles):
    tiles = [np.full((240, 320, 3), 10 * k, np.uint8) for k in range(count)]
    sheet = contact_sheet(tiles, [f"frame {k}" for k in range(count)])
    rows, cols = shape_tiles
    gap = CONTACT_SHEET_GAP_PX
    assert sheet.shape == (rows * 240 + (rows + 1) * gap, cols * 320 + (cols + 1) * gap, 3)
    assert tuple(sheet[0, 0]) == CONTACT_SHEET_BACKGROUND_RGB8
    last_row, last_col = divmod(count - 1, cols)
    y, x = gap + last_row * (240 + gap), gap + last_col * (320 + gap)
    assert (sheet[y + 5, x + 300] == 10 * (count - 1)).all()  # the last tile, away from its caption


def test_wide_frames_are_scaled_into_contact_sheet_tiles():
    sheet = contact_sheet([np.zeros((1080, 1920, 3), np.uint8)] * 2, ["a", "b"])
    assert sheet.shape == (180 + 2 * CONTACT_SHEET_GAP_PX, 2 * 320 + 3 * CONTACT_SHEET_GAP_PX, 3)
