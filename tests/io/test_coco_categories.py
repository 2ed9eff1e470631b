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


def test_a_merged_dataset_keeps_the_ids_and_moves_only_a_colliding_one():
    from types import SimpleNamespace

    from camgen.batch.dataset_files import _merged_categories

    camgen_file = SimpleNamespace(coco={"categories": [{"id": 1, "name": "person"}, {"id": 3, "name": "car"}]})
    older_file = SimpleNamespace(coco={"categories": [{"id": 3, "name": "bus"}, {"id": 1, "name": "person"}]})
    merged = _merged_categories([camgen_file, older_file])
    assert merged == [{"id": 1, "name": "person"}, {"id": 3, "name": "car"}, {"id": 4, "name": "bus"}]
    assert {c["name"]: c["id"] for c in _merged_categories([])} == COCO_CATEGORY_IDS
