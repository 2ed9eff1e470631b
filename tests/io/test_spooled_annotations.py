"""Annotations spooled to files frame by frame (`SequenceAnnotations(spool_dir=...)`, what a render
uses so that a long sequence takes no memory that grows with its frames) write the same bytes as those
kept in memory, and the spool files are gone once the sequence closes."""

from __future__ import annotations

import json
from pathlib import Path

from pycocotools.coco import COCO

from camgen.io.annotations import SequenceAnnotations
from camgen.plan.annotations import FrameAnnotations
from tests.io.test_crowd import HEIGHT_PX, WIDTH_PX, frame_annotations


def frames(count: int) -> list[FrameAnnotations]:
    one = frame_annotations()
    return [FrameAnnotations(frame=k, objects=one.objects, instance_id=one.instance_id) for k in range(count)]


def written(out: Path, spool_dir: Path | None) -> dict[str, bytes]:
    sequence = SequenceAnnotations(
        name="cam",
        fps=10,
        width_px=WIDTH_PX,
        height_px=HEIGHT_PX,
        frame_count=5,
        frame_suffix=".png",
        detections=True,
        spool_dir=spool_dir,
    )
    sequence.describe(1, name="p1", cls="person", attributes={"height_m": 1.7})
    for frame in frames(5):
        sequence.add(frame)
        sequence.add_detections(frame.frame, [(1.0, 2.0, 30.5, 60.25, 0.9)])
    files = [*sequence.write_mot(out), sequence.write_coco(out / "coco.json")]
    document = sequence.coco_document()
    sequence.close()
    assert json.loads((out / "coco.json").read_text()) == document
    return {str(path.relative_to(out)): path.read_bytes() for path in files}


def test_spooled_files_are_the_bytes_of_the_in_memory_ones(tmp_path: Path):
    in_memory = written(tmp_path / "memory", None)
    spool = tmp_path / "spooled" / ".spool"
    spooled = written(tmp_path / "spooled", spool)
    assert spooled == in_memory
    assert sorted(spooled) == ["coco.json", "det/det.txt", "gt/gt.txt", "seqinfo.ini"]
    assert in_memory["coco.json"] == json.dumps(json.loads(in_memory["coco.json"]), separators=(",", ":")).encode()
    assert list(spool.iterdir()) == []  # closed: every spool file deleted
    assert len(in_memory["gt/gt.txt"].decode().splitlines()) == 5 * 7
    coco = COCO(str(tmp_path / "spooled" / "coco.json"))
    assert len(coco.getImgIds()) == 5 and len(coco.getAnnIds(iscrowd=None)) == 5 * 5  # 4 people + 1 crowd


def test_an_empty_sequence_writes_empty_files(tmp_path: Path):
    sequence = SequenceAnnotations(
        name="cam", fps=10, width_px=8, height_px=8, frame_count=0, spool_dir=tmp_path / ".spool"
    )
    gt, _ = sequence.write_mot(tmp_path)
    coco = sequence.write_coco(tmp_path / "coco.json")
    sequence.close()
    assert gt.read_bytes() == b""
    document = json.loads(coco.read_text())
    assert document["images"] == [] and document["annotations"] == []
