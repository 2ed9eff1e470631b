"""The label files of one camera's annotated sequence: MOTChallenge, COCO and YOLO.

MOTChallenge, laid out as MOT17/MOT20 ship a sequence (Milan et al. 2016, "MOT16: A Benchmark for
Multi-Object Tracking", arXiv:1603.00831; the MOTChallenge devkit): ``img1/000001.jpg`` … (the
delivered 8-bit frames, named by frame number counted from 1, JPEG at `SEQUENCE_JPEG_QUALITY` or PNG),
``seqinfo.ini`` (``[Sequence]`` name, imDir=img1, frameRate, seqLength, imWidth, imHeight, imExt) and
``gt/gt.txt``, one line per object and frame: ``frame, id, bb_left, bb_top, bb_width, bb_height, conf,
class, visibility`` with frames counted from 1 and boxes in MOT's 1-based pixel coordinates (bb_left =
x0 + 1 for camgen's pixel-edge x0). The box is the whole object's projection, occluded parts included,
and not clipped: as in MOT17 it reaches outside the image where the object does; conf is 1 (consider)
when some of the object is visible, else 0; visibility, as MOT17 counts it, includes cropping by the
image border: (visible / unoccluded pixels) × (1 − truncation), truncation being the share of the
amodal box outside the image. Classes follow MOT17's table (`MOT_CLASSES`; a rider is class 2, person
on vehicle: `mot_class`). Optional ``det/det.txt``
holds public detections as MOT17's do: ``frame, -1, bb_left, bb_top, bb_width, bb_height, conf, -1,
-1, -1`` with conf the detector's score.

COCO (`coco.json`, one file per sequence, with the video/track extension used by TAO and
YouTube-VIS-style datasets): ``videos``, ``images`` (one per frame, with ``video_id`` and
``frame_index``), ``annotations`` (one per visible object and frame: ``bbox`` [x, y, w, h] of the
visible pixels, ``segmentation`` as compressed RLE of the visible mask, ``area`` in pixels,
``track_id``, ``amodal_bbox`` (clipped to the image), ``visibility``, ``truncation``,
``bbox_3d_world_m`` and ``bbox_3d_cam_m`` (8 corners each); for people also COCO ``keypoints``,
``num_keypoints`` and ``keypoints_world_m``; for procedural vehicles ``plates``, each plate imaged:
``side``, ``text``, ``quad`` (its 4 corners as one reads it), ``bbox``, ``visible`` and
``visible_share``: `camgen.annotate.plates`), ``categories`` (camgen's actor classes; ``person`` with
COCO's 17 keypoint names and skeleton) and ``tracks`` (one per actor, TAO-style, with a person's
attribute labels, or a procedural vehicle's body type, colour, plate text and dimensions; a rider's
``rides_track_id``, the track of its bicycle or motorcycle). People too
small to separate, three or more under `CROWD_MAX_HEIGHT_PX` whose visible pixels touch, are one crowd
annotation instead (``iscrowd`` 1, the union's mask and box, ``crowd_track_ids``; `crowd_groups`), which
COCO's evaluation ignores; MOT's gt.txt, YOLO and ``tracks`` keep every person.

YOLO, as Ultralytics reads a detection data set (docs.ultralytics.com/datasets/detect): ``images/``
(the delivered frames, named by frame index counted from 0 as camgen's other per-frame files),
``labels/`` (one text file per image, the same stem, one line per visible object: ``class x_center
y_center width height`` of the visible box, normalised by the image's width and height to [0, 1];
class ids index `YOLO_CLASSES` from 0; an image with nothing visible has an empty file) and
``data.yaml`` (``train`` and ``val`` both naming ``images``, the one sequence; ``names``: class id →
name).
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path

import cv2
import numpy as np
from pycocotools import mask as mask_utils

from camgen.annotate.keypoints import COCO_KEYPOINTS, COCO_SKELETON
from camgen.io.files import atomic_path, write_text_atomic
from camgen.io.frames import write_frame

MOT_CLASSES = {"person": 1, "car": 3, "truck": 3, "bus": 3, "bicycle": 4, "motorcycle": 5, "other": 6}
"""MOT17 class ids: 1 pedestrian, 3 car (all motor vehicles of four or more wheels), 4 bicycle,
5 motorbike, 6 non-motorised vehicle (camgen's 'other')."""
MOT_PERSON_ON_VEHICLE = 2
"""MOT17's class of a person riding a bicycle or motorcycle (`Actor.rides`), which its evaluation
ignores (Milan et al. 2016, Table 2); in COCO and YOLO a rider is a person, as COCO labels riders."""


def mot_class(obj) -> int:
    """The MOT17 class id of an annotated object (a `camgen.plan.annotations.ObjectAnnotation`)."""
    return MOT_PERSON_ON_VEHICLE if getattr(obj, "rides", None) is not None else MOT_CLASSES[obj.cls]


COCO_CATEGORY_IDS = {"person": 1, "bicycle": 2, "car": 3, "motorcycle": 4, "bus": 6, "truck": 8, "other": 1000}
"""Each class's category id in coco.json: COCO 2017's own (Lin et al. 2014, the ``categories`` of
``instances_val2017.json``), so that a model trained on COCO is scored against camgen's ground truth by
pycocotools without a mapping. `other` has no COCO category and takes an id above COCO's 1–90."""
COCO_CATEGORIES = tuple(COCO_CATEGORY_IDS)
"""camgen's classes in the order coco.json lists them (by id)."""
YOLO_CLASSES = ("person", "car", "truck", "bus", "bicycle", "motorcycle", "other")
"""YOLO class names by class id (from 0, contiguous as YOLO wants them; not COCO's ids)."""
ANNOTATIONS_OF_DELIVERED_FRAMES = ("mot", "reid", "yolo")
"""Annotation formats written with (or cut from) the delivered 8-bit frames."""
IMAGE_SUFFIXES = {"jpg": ".jpg", "png": ".png"}
"""File suffix of the MOT and YOLO images by `Outputs.annotation_images`."""
SEQUENCE_JPEG_QUALITY = 95
"""libjpeg quality (0–100) of the MOT and YOLO images, stored without chroma subsampling (4:4:4). On
the test scene's 640×480 frames this errs by 1.7 DN RMS (8-bit), under the simulated camera's own
temporal noise there (2.2 DN), at a fifth of the PNG's size; the usual 4:2:0 subsampling erred by
3.6 DN RMS and up to 129 DN at coloured edges, and quality 100 quadruples the file for 0.8 DN."""


class LineSpool:
    """Text lines kept in order: in memory, or (given a path) appended to a file as they come, so that a
    long sequence's annotations take no memory that grows with its frames (issue 23)."""

    def __init__(self, path: Path | None = None):
        self.path = path
        self._lines: list[str] | None = [] if path is None else None
        self._handle = None
        self._count = 0

    def append(self, line: str) -> None:
        if self._lines is not None:
            self._lines.append(line)
        else:
            if self._handle is None:
                self.path.parent.mkdir(parents=True, exist_ok=True)
                self._handle = open(self.path, "w", encoding="utf-8")  # open until `close`
            self._handle.write(line + "\n")
        self._count += 1

    def __len__(self) -> int:
        return self._count

    def __iter__(self) -> Iterator[str]:
        if self._lines is not None:
            yield from self._lines
            return
        if self._handle is None:
            return
        self._handle.flush()
        with open(self.path, encoding="utf-8") as lines:
            for line in lines:
                yield line[:-1]

    def write(self, path: Path) -> Path:
        """Write the lines to `path` (atomically), each ended by a newline (an empty file for none)."""
        with atomic_path(path) as tmp, open(tmp, "w", encoding="utf-8") as out:
            for line in self:
                out.write(line + "\n")
        return path

    def write_into(self, out, *, separator: str) -> None:
        for i, line in enumerate(self):
            out.write(line if i == 0 else separator + line)

    def mark(self) -> tuple[int, int]:
        """(lines, bytes) of the spool file now, its lines flushed to it: what `resume` cuts it back to
        after an interrupted render (`camgen.plan.execute`'s checkpoints). Only for a spool with a file."""
        if self.path is None:
            raise ValueError("a spool kept in memory has no file to mark; give LineSpool a path")
        if self._handle is None:
            return self._count, 0
        self._handle.flush()
        return self._count, self._handle.tell()

    def resume(self, lines: int, size_bytes: int) -> None:
        """Continue the spool file left by an interrupted render from a `mark`: cut it back to its first
        `size_bytes` bytes, which must hold exactly `lines` lines, and append after them.

        Raises
        ------
        ValueError
            When the file is shorter than the mark, or its first `size_bytes` bytes do not hold `lines`
            whole lines: it is not the file the mark was taken of.
        """
        if self.path is None:
            raise ValueError("a spool kept in memory has no file to resume; give LineSpool a path")
        if self._handle is not None or self._count:
            raise ValueError(f"{self.path}: resume a spool before appending to it")
        if lines < 0 or size_bytes < 0:
            raise ValueError(f"{self.path}: a mark of {lines} lines in {size_bytes} bytes")
        if size_bytes == 0:
            if lines:
                raise ValueError(f"{self.path}: a mark of {lines} lines in 0 bytes")
            self.path.unlink(missing_ok=True)
            return
        size = self.path.stat().st_size if self.path.is_file() else None
        if size is None or size < size_bytes:
            held = "missing" if size is None else f"{size} bytes"
            raise ValueError(f"{self.path}: {held}, shorter than the {size_bytes} bytes of its checkpoint")
        newlines, last = 0, b""
        with open(self.path, "rb") as handle:
            remaining = size_bytes
            while remaining:
                chunk = handle.read(min(remaining, 1 << 20))
                if not chunk:
                    break  # the file shrank while read: the count below tells
                newlines += chunk.count(b"\n")
                remaining -= len(chunk)
                last = chunk[-1:]
        if newlines != lines or last != b"\n":
            raise ValueError(
                f"{self.path}: its first {size_bytes} bytes hold {newlines} lines, its checkpoint says {lines}"
            )
        with open(self.path, "r+b") as handle:
            handle.truncate(size_bytes)
        self._handle = open(self.path, "a", encoding="utf-8")  # open until `close`
        self._count = lines

    def close(self, *, keep: bool = False) -> None:
        """Close and delete the spool file (after the outputs were written from it); keep=True leaves the
        file for a render that resumes (`mark`, `resume`)."""
        if self._handle is not None:
            self._handle.close()
            self._handle = None
        if self.path is not None and not keep:
            self.path.unlink(missing_ok=True)


class SequenceAnnotations:
    """Collects a camera's annotations frame by frame (masks become RLE at once, so no frame's
    instance image is kept; each frame's lines go to memory or, with `spool_dir`, to files) and writes
    the MOTChallenge and COCO files at the end."""

    def __init__(
        self,
        *,
        name: str,
        fps: float,
        width_px: int,
        height_px: int,
        frame_count: int,
        frame_suffix: str | None = None,
        image_suffix: str = ".jpg",
        detections: bool = False,
        spool_dir: Path | None = None,
    ):
        """`frame_suffix`: the extension of the frame files written beside (frames/NNNNNN.ext, frames
        counted from 0), or None when only the video holds the frames (its frame `frame_index`).
        `image_suffix`: the extension of the MOT and YOLO images (`IMAGE_SUFFIXES`). `detections`:
        whether det/det.txt is written (`add_detections` fills it). `spool_dir`: a folder to append
        each frame's lines to as they come (deleted by `close`), instead of memory: a long sequence's
        annotations then take no memory that grows with its frames; the files written are the same bytes."""
        self.name, self.fps, self.width_px, self.height_px = name, fps, width_px, height_px
        self.frame_count, self.frame_suffix, self.image_suffix = frame_count, frame_suffix, image_suffix

        def spool(name: str) -> LineSpool:
            return LineSpool(None if spool_dir is None else spool_dir / f"{name}.lines")

        self.mot = spool("mot")
        """MOT gt.txt lines."""
        self.detections: LineSpool | None = spool("det") if detections else None
        """MOT det.txt lines, or None when no detections are written."""
        self.images = spool("images")
        """COCO's images, a compact JSON object per line."""
        self.annotations = spool("annotations")
        """COCO's annotations, a compact JSON object per line."""
        self.tracks: dict[int, dict] = {}
        """Track id → the TAO-style track record, with the identity's attribute labels for people."""
        self.keypoint_lines = spool("keypoints")
        """One JSON line per frame with people: their keypoints in the image and in the world."""

    def describe(
        self, track_id: int, *, name: str, cls: str, attributes: dict | None = None, rides: int | None = None
    ) -> None:
        """Record a track (once per actor): its class, for a person its attributes, and for a rider the
        track id of the bicycle or motorcycle it rides (``rides_track_id``)."""
        record = {"id": track_id, "video_id": 1, "category_id": COCO_CATEGORY_IDS[cls], "name": name}
        if attributes is not None:
            record["attributes"] = attributes
        if rides is not None:
            record["rides_track_id"] = rides
        self.tracks[track_id] = record

    def add(self, frame) -> None:
        """One `camgen.plan.annotations.FrameAnnotations`. Each object's mask is read inside its visible box,
        which must be the tight box of its `visible_pixels` pixels in the frame's instance image (as the
        annotator gives them; `ids_mask` reads the whole image when the box misses some)."""
        image_id = frame.frame + 1
        image = {
            "id": image_id,
            "video_id": 1,
            "frame_index": frame.frame,
            "width": self.width_px,
            "height": self.height_px,
        }
        if self.frame_suffix is not None:  # relative to coco.json
            image["file_name"] = f"frames/{frame.frame:06d}{self.frame_suffix}"
        self.images.append(_compact(image))
        world_points = {
            obj.track_id: _world_points(obj.keypoints_world_m) for obj in frame.objects if obj.keypoints is not None
        }
        people = [
            {
                "track_id": obj.track_id,
                "keypoints": np.round(obj.keypoints, 3).tolist(),
                "keypoints_world_m": world_points[obj.track_id],
            }
            for obj in frame.objects
            if obj.keypoints is not None
        ]
        if people:
            self.keypoint_lines.append(_compact({"frame": frame.frame + 1, "people": people}))
        crowds = crowd_groups(frame.objects, frame.instance_id)
        crowded = {track_id for group in crowds for track_id in group}
        for group in crowds:
            self._add_crowd(image_id, frame.instance_id, [obj for obj in frame.objects if obj.track_id in group])
        for obj in frame.objects:
            u0, v0, u1, v1 = (round(v, 4) for v in obj.unclipped_box)  # the same digits on every machine
            self.mot.append(
                f"{frame.frame + 1},{obj.track_id},{u0 + 1:.3f},{v0 + 1:.3f},{u1 - u0:.3f},{v1 - v0:.3f},"
                f"{1 if obj.visible_pixels > 0 else 0},{mot_class(obj)},"
                f"{obj.visibility * (1.0 - obj.truncation):.4f}"
            )
            x0, y0, x1, y1 = (round(v, 4) for v in obj.amodal_box)
            if obj.visible_box is None or obj.track_id in crowded:
                continue
            vx0, vy0, vx1, vy1 = obj.visible_box
            mask, at_px = ids_mask(frame.instance_id, [obj.track_id], obj.visible_box, obj.visible_pixels)
            self.annotations.append(
                _compact(
                    {
                        "id": len(self.annotations) + 1,
                        "image_id": image_id,
                        "video_id": 1,
                        "category_id": COCO_CATEGORY_IDS[obj.cls],
                        "track_id": obj.track_id,
                        "instance_name": obj.name,
                        "bbox": [vx0, vy0, vx1 - vx0, vy1 - vy0],
                        "area": obj.visible_pixels,
                        "segmentation": rle(mask, at_px=at_px, image_shape=frame.instance_id.shape),
                        "iscrowd": 0,
                        "amodal_bbox": [x0, y0, round(x1 - x0, 4), round(y1 - y0, 4)],
                        "visibility": round(obj.visibility, 6),
                        "truncation": round(obj.truncation, 6),
                        "bbox_3d_world_m": np.round(obj.box_3d_world_m, 6).tolist(),
                        "bbox_3d_cam_m": np.round(obj.box_3d_cam_m, 6).tolist(),
                        **_keypoint_fields(obj, world_points.get(obj.track_id)),
                        **({"plates": list(obj.plates)} if getattr(obj, "plates", ()) else {}),
                    }
                )
            )

    def _add_crowd(self, image_id: int, instance_id: np.ndarray, members: list) -> None:
        """One COCO crowd annotation (iscrowd 1) over the union of a group's visible pixels (`members`:
        their annotated objects); its members stay in MOT's gt.txt and in `tracks`, and are listed in
        ``crowd_track_ids``."""
        track_ids = [obj.track_id for obj in members]
        boxes = np.array([obj.visible_box for obj in members])
        union = (*boxes[:, :2].min(axis=0), *boxes[:, 2:].max(axis=0))
        mask, (col0, row0) = ids_mask(instance_id, track_ids, union, sum(obj.visible_pixels for obj in members))
        rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
        x0, x1, y0, y1 = col0 + int(cols[0]), col0 + int(cols[-1]) + 1, row0 + int(rows[0]), row0 + int(rows[-1]) + 1
        self.annotations.append(
            _compact(
                {
                    "id": len(self.annotations) + 1,
                    "image_id": image_id,
                    "video_id": 1,
                    "category_id": COCO_CATEGORY_IDS["person"],
                    "bbox": [x0, y0, x1 - x0, y1 - y0],
                    "area": int(np.count_nonzero(mask)),
                    "segmentation": rle(mask, at_px=(col0, row0), image_shape=instance_id.shape),
                    "iscrowd": 1,
                    "crowd_track_ids": sorted(track_ids),
                }
            )
        )

    def add_detections(self, frame_index: int, boxes) -> None:
        """A frame's detections, (x0, y0, x1, y1, score) in pixel edges
        (`camgen.annotate.detection.detect_people`), as MOT det.txt lines."""
        for x0, y0, x1, y1, score in boxes:
            x0, y0, x1, y1 = (round(float(v), 4) for v in (x0, y0, x1, y1))
            self.detections.append(
                f"{frame_index + 1},-1,{x0 + 1:.3f},{y0 + 1:.3f},{x1 - x0:.3f},{y1 - y0:.3f},{score:.4f},-1,-1,-1"
            )

    def write_mot_image(self, directory: Path, frame_index: int, rgb8: np.ndarray) -> Path:
        """One delivered frame as MOT's ``img1/<frame number from 1>.jpg|png``."""
        path = directory / "img1" / f"{frame_index + 1:06d}{self.image_suffix}"
        write_image(path, rgb8)
        return path

    def write_yolo_frame(self, directory: Path, frame, rgb8: np.ndarray) -> list[Path]:
        """One delivered frame as ``images/<frame index>.jpg|png`` and its YOLO labels
        ``labels/<frame index>.txt`` (a `camgen.plan.annotations.FrameAnnotations`)."""
        image = directory / "images" / f"{frame.frame:06d}{self.image_suffix}"
        write_image(image, rgb8)
        labels = directory / "labels" / f"{frame.frame:06d}.txt"
        lines = [
            yolo_label(YOLO_CLASSES.index(obj.cls), obj.visible_box, self.width_px, self.height_px)
            for obj in frame.objects
            if obj.visible_box is not None
        ]
        write_text_atomic(labels, "".join(line + "\n" for line in lines))
        return [image, labels]

    def write_yolo_data(self, directory: Path) -> Path:
        """``data.yaml`` of the sequence's YOLO data set. It has no ``path`` key: Ultralytics then takes
        the folder holding data.yaml as the root (an absolute path would tie the file to one output
        folder and break byte-identical renders)."""
        path = directory / "data.yaml"
        names = "".join(f"  {i}: {name}\n" for i, name in enumerate(YOLO_CLASSES))
        write_text_atomic(
            path,
            f"# camgen sequence {self.name}: an Ultralytics YOLO detection data set\n"
            "# (docs.ultralytics.com/datasets/detect); the root is this file's folder\n"
            "train: images\nval: images\nnames:\n" + names,
        )
        return path

    def _coco_parts(self) -> tuple[dict, dict]:
        """The COCO document's keys before its images and annotations, and after them."""
        head = {
            "info": {"description": f"camgen sequence {self.name}"},
            "videos": [{"id": 1, "name": self.name, "width": self.width_px, "height": self.height_px}],
        }
        tail = {
            "categories": [_category(category_id, name) for name, category_id in COCO_CATEGORY_IDS.items()],
            "tracks": [self.tracks[key] for key in sorted(self.tracks)],
        }
        return head, tail

    def coco_document(self) -> dict:
        """The whole COCO document in memory (what `write_coco` writes)."""
        head, tail = self._coco_parts()
        images = [json.loads(line) for line in self.images]
        annotations = [json.loads(line) for line in self.annotations]
        return {**head, "images": images, "annotations": annotations, **tail}

    def write_mot(self, directory: Path) -> list[Path]:
        """`gt/gt.txt` and `seqinfo.ini` under `directory` (img1/ is written frame by frame,
        `write_mot_image`), `det/det.txt` when detections were asked for, and `gt/keypoints.jsonl` when
        people were annotated: per frame (counted from 1, as gt.txt) each person's track id, its COCO
        keypoints (x, y, v) and its 3-D keypoints in the world, m."""
        gt = self.mot.write(directory / "gt" / "gt.txt")
        seqinfo = directory / "seqinfo.ini"
        write_text_atomic(
            seqinfo,
            "[Sequence]\n"
            f"name={self.name}\nimDir=img1\nframeRate={self.fps:g}\nseqLength={self.frame_count}\n"
            f"imWidth={self.width_px}\nimHeight={self.height_px}\nimExt={self.image_suffix}\n",
        )
        written = [gt, seqinfo]
        if self.detections is not None:
            written.append(self.detections.write(directory / "det" / "det.txt"))
        if len(self.keypoint_lines):
            written.append(self.keypoint_lines.write(directory / "gt" / "keypoints.jsonl"))
        return written

    def write_coco(self, path: Path) -> Path:
        """coco.json, compact: streamed from the images' and annotations' lines, the same bytes as
        `json.dumps(self.coco_document(), separators=(",", ":"))`."""
        head, tail = self._coco_parts()
        with atomic_path(path) as tmp, open(tmp, "w", encoding="utf-8") as out:
            out.write(_compact(head)[:-1] + ',"images":[')
            self.images.write_into(out, separator=",")
            out.write('],"annotations":[')
            self.annotations.write_into(out, separator=",")
            out.write("]," + _compact(tail)[1:])
        return path

    def spools(self) -> dict[str, LineSpool]:
        """The sequence's line spools by name (``mot``, ``det``, ``images``, ``annotations``,
        ``keypoints``): what a checkpoint marks and a resumed render cuts back (`LineSpool.mark`)."""
        named = {
            "mot": self.mot,
            "det": self.detections,
            "images": self.images,
            "annotations": self.annotations,
            "keypoints": self.keypoint_lines,
        }
        return {name: lines for name, lines in named.items() if lines is not None}

    def close(self) -> None:
        """Delete the spool files (`spool_dir`), once the outputs are written or abandoned (a render that
        resumes closes `spools` itself and keeps them)."""
        for lines in self.spools().values():
            lines.close()


def _compact(value) -> str:
    return json.dumps(value, separators=(",", ":"))


REID_SIZE_PX = (64, 128)
"""Width and height of a re-identification crop: Market-1501's."""
REID_MIN_HEIGHT_PX = 32
REID_MIN_VISIBILITY = 0.5
REID_JPEG_QUALITY = 95


def write_reid_crops(directory: Path, frame, rgb8: np.ndarray, *, camera_number: int) -> list[Path]:
    """Crops of the people in one delivered frame, as Market-1501 ships them (Zheng et al. 2015): the
    person's amodal box, clipped to the image, resized to 64×128 and saved as JPEG under
    ``{track id:04d}_c{camera number}s1_{frame number:06d}_00.jpg`` (camera numbers and frames counted
    from 1). People under `REID_MIN_HEIGHT_PX` tall or less than `REID_MIN_VISIBILITY` visible are left
    out, as a detector-cropped data set would lack them. Returns the files written."""
    written = []
    for obj in frame.objects:
        if obj.keypoints is None or obj.visibility < REID_MIN_VISIBILITY or obj.visible_box is None:
            continue
        x0, y0, x1, y1 = obj.amodal_box
        c0, r0, c1, r1 = int(np.floor(x0)), int(np.floor(y0)), int(np.ceil(x1)), int(np.ceil(y1))
        if r1 - r0 < REID_MIN_HEIGHT_PX or c1 <= c0:
            continue
        crop = cv2.resize(rgb8[r0:r1, c0:c1], REID_SIZE_PX, interpolation=cv2.INTER_AREA)
        ok, data = cv2.imencode(".jpg", crop[..., ::-1], [cv2.IMWRITE_JPEG_QUALITY, REID_JPEG_QUALITY])
        if not ok:
            raise OSError(f"could not encode the re-identification crop of track {obj.track_id}")
        path = directory / "reid" / f"{obj.track_id:04d}_c{camera_number}s1_{frame.frame + 1:06d}_00.jpg"
        path.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(path) as tmp:
            tmp.write_bytes(data.tobytes())
        written.append(path)
    return written


def yolo_label(class_id: int, box, width_px: int, height_px: int) -> str:
    """``class x_center y_center width height`` of a pixel-edge box (x0, y0, x1, y1) inside a
    `width_px` × `height_px` image, normalised to [0, 1] (Ultralytics YOLO), 6 decimals."""
    x0, y0, x1, y1 = box
    return (
        f"{class_id} {(x0 + x1) / 2 / width_px:.6f} {(y0 + y1) / 2 / height_px:.6f} "
        f"{(x1 - x0) / width_px:.6f} {(y1 - y0) / height_px:.6f}"
    )


def write_image(path: Path, rgb8: np.ndarray) -> None:
    """An 8-bit (H, W, 3) RGB frame as JPEG (`SEQUENCE_JPEG_QUALITY`, 4:4:4) or PNG, by `path`'s suffix."""
    if path.suffix == ".png":
        write_frame(path, rgb8, format="png")
        return
    quality = [cv2.IMWRITE_JPEG_QUALITY, SEQUENCE_JPEG_QUALITY]
    full_chroma = [cv2.IMWRITE_JPEG_SAMPLING_FACTOR, cv2.IMWRITE_JPEG_SAMPLING_FACTOR_444]
    ok, data = cv2.imencode(".jpg", rgb8[..., ::-1], quality + full_chroma)
    if not ok:
        raise OSError(f"could not encode {path} as JPEG")
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        tmp.write_bytes(data.tobytes())


def _category(category_id: int, name: str) -> dict:
    category = {"id": category_id, "name": name}
    if name == "person":  # COCO's person keypoints and skeleton
        category["keypoints"] = list(COCO_KEYPOINTS)
        category["skeleton"] = [list(pair) for pair in COCO_SKELETON]
    return category


CROWD_MAX_HEIGHT_PX = 20
"""A person whose visible box is shorter than this, px, may be part of a crowd. At under 20 px a person
is some 6 × 20 px, below the smallest anchors of COCO-trained detectors (Faster R-CNN's 32 px, YOLO's
stride-8 cells), which cannot split touching figures that small."""
CROWD_MIN_MEMBERS = 3
"""Fewest small people whose visible pixels touch (8-connected) that COCO gets as one crowd region."""


def crowd_groups(objects, instance_id: np.ndarray | None) -> list[list[int]]:
    """Groups (track ids) of at least `CROWD_MIN_MEMBERS` people, each visible but under
    `CROWD_MAX_HEIGHT_PX` tall, whose visible pixels touch one another (a chain of 8-neighbours): the
    groups too small to separate, which COCO marks ``iscrowd`` (evaluation then ignores detections in
    them instead of counting each unmatched one as a false positive)."""
    if instance_id is None:
        return []
    small = [
        obj
        for obj in objects
        if obj.cls == "person"
        and obj.visible_box is not None
        and obj.visible_box[3] - obj.visible_box[1] < CROWD_MAX_HEIGHT_PX
    ]
    if len(small) < CROWD_MIN_MEMBERS:
        return []
    import cv2

    parent = list(range(len(small)))

    def root(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    height, width = instance_id.shape
    kernel = np.ones((3, 3), np.uint8)
    for i, a in enumerate(small):
        ax0, ay0, ax1, ay1 = a.visible_box
        for j in range(i + 1, len(small)):
            bx0, by0, bx1, by1 = small[j].visible_box
            if bx0 > ax1 + 1 or ax0 > bx1 + 1 or by0 > ay1 + 1 or ay0 > by1 + 1:
                continue  # boxes more than a pixel apart: the masks cannot touch
            c0, r0 = max(int(min(ax0, bx0)) - 1, 0), max(int(min(ay0, by0)) - 1, 0)
            c1, r1 = min(int(max(ax1, bx1)) + 2, width), min(int(max(ay1, by1)) + 2, height)
            window = instance_id[r0:r1, c0:c1]
            grown = cv2.dilate((window == a.track_id).astype(np.uint8), kernel)
            if np.any(grown.astype(bool) & (window == small[j].track_id)):
                parent[root(i)] = root(j)
    groups: dict[int, list[int]] = {}
    for i, obj in enumerate(small):
        groups.setdefault(root(i), []).append(obj.track_id)
    return [sorted(group) for group in groups.values() if len(group) >= CROWD_MIN_MEMBERS]


def _world_points(points_m: np.ndarray) -> list:
    """[[x, y, z], …] in m, 5 decimals; null for a keypoint the person's rig has no joint for (a glTF
    character's rig may lack some of COCO's 17, `camgen.actors.character.coco_joint_nodes`)."""
    points = np.asarray(points_m, dtype=np.float64)
    finite = np.isfinite(points).all(axis=1).tolist()
    return [[round(v, 5) for v in point] if ok else None for point, ok in zip(points.tolist(), finite, strict=True)]


def _keypoint_fields(obj, world_points: list | None = None) -> dict:
    """COCO `keypoints` (x, y, v triplets, x and y 0 where v = 0), `num_keypoints` (labelled ones,
    v > 0) and the 3-D keypoints in the world (`world_points`: `_world_points` of them when already
    made), for an annotated person."""
    if obj.keypoints is None:
        return {}
    keypoints = np.array(obj.keypoints, dtype=np.float64)
    keypoints[keypoints[:, 2] == 0, :2] = 0.0
    return {
        "keypoints": [round(v, 3) if i % 3 != 2 else int(v) for i, v in enumerate(keypoints.ravel().tolist())],
        "num_keypoints": int(np.count_nonzero(keypoints[:, 2] > 0)),
        "keypoints_world_m": _world_points(obj.keypoints_world_m) if world_points is None else world_points,
    }


def rle(mask: np.ndarray, *, at_px: tuple[int, int] = (0, 0), image_shape: tuple[int, int] | None = None) -> dict:
    """COCO compressed RLE, JSON-ready, of a boolean (h, w) `mask` whose top-left pixel lies at column, row
    `at_px` of an (H, W) image `image_shape` that is empty elsewhere (default: the mask is the image).
    The same string as pycocotools' ``mask.encode`` of the whole image's mask, at a cost that follows the
    mask's size instead of the image's.

    COCO's runs go down each column of the image in turn, starting with a run of zeros (empty when the
    first pixel is set); a run of ones that ends on the image's last row continues at the top of the next
    column."""
    height, width = mask.shape if image_shape is None else image_shape
    col0, row0 = at_px
    padded = np.zeros((mask.shape[1], mask.shape[0] + 2), np.int8)  # each column of the mask, a 0 at both ends
    padded[:, 1:-1] = mask.T
    col, row = np.nonzero(np.diff(padded, axis=1))  # where a run starts or ends, column by column
    changes = (col0 + col).astype(np.int64) * height + row0 + row  # column-major index in the image, ascending
    # A run that ends at the foot of one column and goes on at the head of the next is one run.
    joined = np.flatnonzero(changes[1:] == changes[:-1])
    changes = np.delete(changes, np.concatenate([joined, joined + 1]))
    bounds = np.concatenate([[0], changes[changes < height * width], [height * width]])
    encoded = mask_utils.frPyObjects({"size": [height, width], "counts": np.diff(bounds).tolist()}, height, width)
    return {"size": [int(height), int(width)], "counts": encoded["counts"].decode("ascii")}


def ids_mask(instance_id: np.ndarray, ids: list[int], box, pixels: int) -> tuple[np.ndarray, tuple[int, int]]:
    """The mask of the pixels whose id is in `ids`, cut to `box` (x0, y0, x1, y1, pixel edges; grown to
    whole pixels and clipped to the image) when that holds `pixels` of them (their count in the whole
    image: then it holds them all), else the whole image's mask; with its top-left pixel (column, row).
    What `rle` needs of an annotation's mask, at a cost that follows its box instead of the frame."""
    height, width = instance_id.shape
    x0, y0 = max(int(np.floor(box[0])), 0), max(int(np.floor(box[1])), 0)
    x1, y1 = min(int(np.ceil(box[2])), width), min(int(np.ceil(box[3])), height)
    window = instance_id[y0:y1, x0:x1]
    mask = window == ids[0] if len(ids) == 1 else np.isin(window, ids)
    if int(np.count_nonzero(mask)) == pixels:
        return mask, (x0, y0)
    return (instance_id == ids[0] if len(ids) == 1 else np.isin(instance_id, ids)), (0, 0)
