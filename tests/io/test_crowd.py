"""COCO crowd regions (`camgen.io.annotations.crowd_groups`): three or more people under 20 px tall whose
visible pixels touch become one ``iscrowd`` annotation, and pycocotools' COCOeval then ignores detections
in it instead of counting them as false positives; MOT's gt.txt keeps every person."""

from __future__ import annotations

import json

import numpy as np
import pytest
from pycocotools.coco import COCO
from pycocotools.cocoeval import COCOeval

from camgen.io.annotations import CROWD_MAX_HEIGHT_PX, SequenceAnnotations, crowd_groups
from camgen.plan.annotations import FrameAnnotations, ObjectAnnotation

WIDTH_PX, HEIGHT_PX = 200, 120
# Track id → (x0, y0, x1, y1) of a solid rectangle of its pixels. 1–3 touch in a chain (1|2 share an
# edge, 2 and 3 meet at a corner); 4 stands alone; 5 and 6 touch but are only two; 7 is tall.
PEOPLE = {
    1: (20, 30, 26, 46),
    2: (26, 32, 32, 48),
    3: (32, 48, 38, 64),
    4: (60, 30, 66, 46),
    5: (90, 30, 96, 46),
    6: (96, 30, 102, 46),
    7: (140, 10, 160, 70),
}


def frame_annotations() -> FrameAnnotations:
    ids = np.zeros((HEIGHT_PX, WIDTH_PX), np.uint32)
    objects = []
    for track_id, (x0, y0, x1, y1) in PEOPLE.items():
        ids[y0:y1, x0:x1] = track_id
        box = (float(x0), float(y0), float(x1), float(y1))
        objects.append(
            ObjectAnnotation(
                track_id=track_id,
                name=f"p{track_id}",
                cls="person",
                visible_box=box,
                amodal_box=box,
                unclipped_box=box,
                visible_pixels=(x1 - x0) * (y1 - y0),
                unoccluded_pixels=(x1 - x0) * (y1 - y0),
                visibility=1.0,
                truncation=0.0,
                box_3d_world_m=np.zeros((8, 3)),
                box_3d_cam_m=np.zeros((8, 3)),
            )
        )
    return FrameAnnotations(frame=0, objects=objects, instance_id=ids)


def test_touching_small_people_are_one_crowd_and_coco_eval_ignores_detections_there(tmp_path):
    frame = frame_annotations()
    assert all(PEOPLE[i][3] - PEOPLE[i][1] < CROWD_MAX_HEIGHT_PX for i in range(1, 7))
    assert crowd_groups(frame.objects, frame.instance_id) == [[1, 2, 3]]
    sequence = SequenceAnnotations(name="cam", fps=10, width_px=WIDTH_PX, height_px=HEIGHT_PX, frame_count=1)
    sequence.add(frame)
    document = sequence.coco_document()
    crowds = [a for a in document["annotations"] if a["iscrowd"]]
    assert len(crowds) == 1 and crowds[0]["crowd_track_ids"] == [1, 2, 3]
    assert crowds[0]["area"] == sum((x1 - x0) * (y1 - y0) for x0, y0, x1, y1 in (PEOPLE[i] for i in (1, 2, 3)))
    assert crowds[0]["bbox"] == [20, 30, 18, 34]
    singles = sorted(a["track_id"] for a in document["annotations"] if not a["iscrowd"])
    assert singles == [4, 5, 6, 7]
    assert len(sequence.mot) == 7  # every person stays in MOT's gt.txt

    # COCOeval: the four separate people detected exactly, plus two detections inside the crowd region:
    # ignored there, so AP is 1.0; without the crowd region they would be false positives.
    path = tmp_path / "coco.json"
    path.write_text(json.dumps(document))
    gt = COCO(str(path))
    detections = [
        {"image_id": 1, "category_id": 1, "bbox": list(map(float, a["bbox"])), "score": 0.9}
        for a in document["annotations"]
        if not a["iscrowd"]
    ]
    detections += [
        {"image_id": 1, "category_id": 1, "bbox": [20.0, 30.0, 6.0, 16.0], "score": 0.95},
        {"image_id": 1, "category_id": 1, "bbox": [32.0, 48.0, 6.0, 16.0], "score": 0.95},
    ]
    evaluation = COCOeval(gt, gt.loadRes(detections), "bbox")
    evaluation.params.catIds = [1]
    evaluation.evaluate()
    evaluation.accumulate()
    evaluation.summarize()
    assert evaluation.stats[1] == pytest.approx(1.0)  # AP at IoU 0.5

    document["annotations"] = [a for a in document["annotations"] if not a["iscrowd"]]
    path.write_text(json.dumps(document))
    gt = COCO(str(path))
    evaluation = COCOeval(gt, gt.loadRes(detections), "bbox")
    evaluation.params.catIds = [1]
    evaluation.evaluate()
    evaluation.accumulate()
    evaluation.summarize()
    assert evaluation.stats[1] < 1.0


def test_tall_people_are_never_a_crowd():
    import dataclasses

    frame = frame_annotations()
    tall = [  # the same chain, each person's visible box 20 px tall
        dataclasses.replace(obj, visible_box=(*obj.visible_box[:3], obj.visible_box[1] + CROWD_MAX_HEIGHT_PX))
        for obj in frame.objects
    ]
    assert crowd_groups(tall, frame.instance_id) == []
