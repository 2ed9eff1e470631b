"""COCO masks from an annotation's own box (`camgen.io.annotations.rle`, `ids_mask`): the same RLE string
as pycocotools' ``mask.encode`` of the whole frame's mask, in the files `SequenceAnnotations` writes too."""

from __future__ import annotations

import json

import numpy as np
from pycocotools import mask as mask_utils

from camgen.io.annotations import SequenceAnnotations, ids_mask, rle
from tests.io.test_crowd import HEIGHT_PX, WIDTH_PX, frame_annotations


def encoded(mask: np.ndarray) -> dict:
    """pycocotools' RLE of a whole image's mask: the reference."""
    result = mask_utils.encode(np.asfortranarray(mask.astype(np.uint8)))
    return {"size": [int(s) for s in result["size"]], "counts": result["counts"].decode("ascii")}


def test_a_mask_cut_anywhere_out_of_an_image_encodes_as_the_whole_image():
    rng = np.random.default_rng(11)
    for _ in range(300):
        height, width = int(rng.integers(1, 12)), int(rng.integers(1, 12))
        row0, col0 = int(rng.integers(0, height)), int(rng.integers(0, width))
        row1, col1 = int(rng.integers(row0 + 1, height + 1)), int(rng.integers(col0 + 1, width + 1))
        whole = np.zeros((height, width), bool)
        whole[row0:row1, col0:col1] = rng.random((row1 - row0, col1 - col0)) < rng.random()
        cut = whole[row0:row1, col0:col1]
        assert rle(cut, at_px=(col0, row0), image_shape=(height, width)) == encoded(whole)
        assert rle(whole) == encoded(whole)


def test_runs_that_go_on_from_the_foot_of_one_column_to_the_head_of_the_next_are_one_run():
    whole = np.zeros((4, 5), bool)
    whole[2:, 1] = whole[:, 2] = whole[:1, 3] = True  # one run over three columns
    whole[3, 4] = True  # the image's last pixel
    whole[0, 0] = True  # its first
    assert encoded(whole)["counts"] == rle(whole[:, :5], image_shape=(4, 5))["counts"]
    assert rle(whole[:, 1:4], at_px=(1, 0), image_shape=(4, 5)) != encoded(whole)  # the corners left out
    whole[0, 0] = whole[3, 4] = False
    assert rle(whole[:, 1:4], at_px=(1, 0), image_shape=(4, 5)) == encoded(whole)


def test_a_box_that_misses_some_of_the_pixels_falls_back_on_the_whole_image():
    instance = np.zeros((30, 40), np.uint32)
    instance[5:9, 10:14] = 3
    instance[25, 35] = 3  # far from the rest
    full = (4.0, 5.0, 36.0, 26.0)
    mask, at_px = ids_mask(instance, [3], full, 17)
    assert at_px == (4, 5) and mask.shape == (21, 32)
    short = (10.0, 5.0, 14.0, 9.0)  # the bulk's box: one pixel outside it
    mask, at_px = ids_mask(instance, [3], short, 17)
    assert at_px == (0, 0) and mask.shape == instance.shape
    for box in (full, short):
        mask, at_px = ids_mask(instance, [3], box, 17)
        assert rle(mask, at_px=at_px, image_shape=instance.shape) == encoded(instance == 3)


def test_the_files_hold_each_objects_and_each_crowds_whole_frame_mask():
    frame = frame_annotations()
    frame.instance_id[HEIGHT_PX - 1, WIDTH_PX - 1] = 9  # an id annotated nowhere stays out of every mask
    sequence = SequenceAnnotations(name="cam", fps=10, width_px=WIDTH_PX, height_px=HEIGHT_PX, frame_count=1)
    sequence.add(frame)
    annotations = [json.loads(line) for line in sequence.annotations]
    crowd = next(a for a in annotations if a["iscrowd"])
    assert crowd["segmentation"] == encoded(np.isin(frame.instance_id, crowd["crowd_track_ids"]))
    singles = [a for a in annotations if not a["iscrowd"]]
    assert len(singles) == 4
    for annotation in singles:
        assert annotation["segmentation"] == encoded(frame.instance_id == annotation["track_id"])
