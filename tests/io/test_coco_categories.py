"""coco.json's category ids are COCO 2017's own, so a model trained on COCO is scored against camgen's ground
truth without a mapping; YOLO's class ids stay contiguous from 0."""

from __future__ import annotations

from camgen.io.annotations import COCO_CATEGORY_IDS, YOLO_CLASSES, SequenceAnnotations

COCO_2017_IDS = {"person": 1, "bicycle": 2, "car": 3, "motorcycle": 4, "bus": 6, "truck": 8}
"""From the ``categories`` of COCO 2017's ``instances_val2017.json`` (Lin et al. 2014)."""


def test_every_coco_class_has_its_coco_2017_id():
    assert {name: COCO_CATEGORY_IDS[name] for name in COCO_2017_IDS} == COCO_2017_IDS
    assert COCO_CATEGORY_IDS["other"] > 90  # outside COCO's 1-90: no COCO model predicts it
    assert len(set(COCO_CATEGORY_IDS.values())) == len(COCO_CATEGORY_IDS)


def test_the_written_file_lists_those_ids_and_yolo_counts_from_zero():
    sequence = SequenceAnnotations(name="cam", fps=10.0, width_px=64, height_px=48, frame_count=1)
    categories = {c["name"]: c["id"] for c in sequence.coco_document()["categories"]}
    assert categories == COCO_CATEGORY_IDS
    assert sorted(YOLO_CLASSES) == sorted(COCO_CATEGORY_IDS)  # the same classes, ids 0 … 6


def test_a_merged_dataset_gives_camgens_classes_coco_ids_and_moves_only_a_colliding_other_name():
    from types import SimpleNamespace

    from camgen.batch.dataset_files import _merged_categories

    camgen_file = SimpleNamespace(coco={"categories": [{"id": 1, "name": "person"}, {"id": 3, "name": "car"}]})
    other_file = SimpleNamespace(coco={"categories": [{"id": 3, "name": "scooter"}, {"id": 1, "name": "person"}]})
    merged = _merged_categories([camgen_file, other_file])
    assert merged == [{"id": 1, "name": "person"}, {"id": 3, "name": "car"}, {"id": 4, "name": "scooter"}]
    assert {c["name"]: c["id"] for c in _merged_categories([])} == COCO_CATEGORY_IDS


OLDER_IDS = {"person": 1, "car": 2, "truck": 3, "bus": 4, "bicycle": 5, "motorcycle": 6, "other": 7}
"""coco.json's ids before COCO 2017's: camgen's class list order. A batch run again after an update reuses its
finished jobs (the job hash holds camgen's version, 0.1.0 before and after the change), so one merge can see
files of both."""


def _sequence(job: str, ids: dict[str, int], cls: str):
    from camgen.batch.dataset_files import CameraSequence

    coco = {
        "images": [{"id": 1, "frame_index": 0, "width": 64, "height": 48}],
        "annotations": [{"id": 1, "image_id": 1, "category_id": ids[cls], "track_id": 1, "bbox": [1, 2, 3, 4]}],
        "categories": [{"id": category_id, "name": name} for name, category_id in ids.items()],
        "tracks": [{"id": 1, "video_id": 1, "category_id": ids[cls], "name": cls}],
    }
    return CameraSequence(job=job, directory=job, camera="cam", coco=coco, fps=10.0)


def test_a_merge_that_starts_with_an_older_file_still_has_cocos_ids():
    from camgen.batch.dataset_files import merge_coco

    merged = merge_coco([_sequence("old", OLDER_IDS, "car"), _sequence("new", COCO_CATEGORY_IDS, "truck")])
    assert {c["name"]: c["id"] for c in merged["categories"]} == COCO_CATEGORY_IDS
    names = {c["id"]: c["name"] for c in merged["categories"]}
    assert [names[a["category_id"]] for a in merged["annotations"]] == ["car", "truck"]
    assert [names[t["category_id"]] for t in merged["tracks"]] == ["car", "truck"]
