"""A person's keypoints as `SequenceAnnotations` writes them: in coco.json (COCO's x, y, v triplets, x and y
0 where v = 0) and in gt/keypoints.jsonl, with the world keypoints at 5 decimals and null for a joint the
rig lacks, the same in both."""

from __future__ import annotations

import dataclasses
import json

import numpy as np

from camgen.io.annotations import SequenceAnnotations
from tests.io.test_crowd import HEIGHT_PX, WIDTH_PX, frame_annotations


def test_keypoints_in_coco_and_in_the_keypoint_lines():
    rng = np.random.default_rng(2)
    keypoints = np.c_[rng.uniform(0, 100, (17, 2)), rng.integers(0, 3, 17)]
    world = rng.normal(0.0, 3.0, (17, 3))
    world[[4, 9], 1] = np.nan  # joints the rig lacks
    world[11, 2] = np.inf
    frame = frame_annotations()
    person = dataclasses.replace(frame.objects[6], keypoints=keypoints, keypoints_world_m=world)
    frame.objects[6] = person
    sequence = SequenceAnnotations(name="cam", fps=10, width_px=WIDTH_PX, height_px=HEIGHT_PX, frame_count=1)
    sequence.add(frame)

    expected_world = [None if k in (4, 9, 11) else [round(float(v), 5) for v in world[k]] for k in range(17)]
    (line,) = [json.loads(text) for text in sequence.keypoint_lines]
    (entry,) = line["people"]
    assert entry["track_id"] == person.track_id and entry["keypoints_world_m"] == expected_world
    (annotation,) = [a for a in map(json.loads, sequence.annotations) if a.get("track_id") == person.track_id]
    assert annotation["keypoints_world_m"] == expected_world
    expected = []
    for x, y, v in keypoints:
        expected += [0.0, 0.0, 0] if v == 0 else [round(float(x), 3), round(float(y), 3), int(v)]
    assert annotation["keypoints"] == expected
    assert annotation["num_keypoints"] == int(np.count_nonzero(keypoints[:, 2]))
