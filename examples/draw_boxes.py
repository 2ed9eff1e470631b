"""Draw one frame of a rendered camera with its annotations: visible boxes (green, from coco.json),
amodal boxes (yellow, dashed where they differ) and track ids.

    python examples/draw_boxes.py OUT/<scene>-<hash>/<camera> --frame 30 -o docs/parking_lot_boxes.png
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import av
import cv2
import numpy as np


def video_frame(path: Path, index: int) -> np.ndarray:
    """Frame `index` of a video as (H, W, 3) BGR uint8."""
    with av.open(str(path)) as container:
        for i, frame in enumerate(container.decode(video=0)):
            if i == index:
                return frame.to_ndarray(format="bgr24")
    raise SystemExit(f"{path} has no frame {index}")


def draw(image: np.ndarray, annotations: list[dict], names: dict[int, str]) -> np.ndarray:
    out = image.copy()
    for a in annotations:
        ax, ay, aw, ah = a["amodal_bbox"]
        cv2.rectangle(out, (round(ax), round(ay)), (round(ax + aw) - 1, round(ay + ah) - 1), (0, 215, 255), 1)
        x, y, w, h = a["bbox"]
        cv2.rectangle(out, (round(x), round(y)), (round(x + w) - 1, round(y + h) - 1), (0, 220, 0), 2)
        label = f"{a['track_id']} {names[a['category_id']]} vis {a['visibility']:.2f}"
        cv2.putText(
            out, label, (round(x), max(12, round(y) - 4)), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (0, 220, 0), 1, cv2.LINE_AA
        )
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("camera_dir", type=Path, help="a rendered camera directory (video.mp4 and coco.json)")
    parser.add_argument("--frame", type=int, default=0)
    parser.add_argument("-o", "--output", type=Path, required=True, help="PNG to write")
    parser.add_argument("--width", type=int, default=960, help="width of the written image, px")
    args = parser.parse_args(argv)
    for required in ("video.mp4", "coco.json"):
        if not (args.camera_dir / required).exists():
            print(
                f"{args.camera_dir} has no {required}: render a scene with video and coco annotations", file=sys.stderr
            )
            return 2
    coco = json.loads((args.camera_dir / "coco.json").read_text())
    image_id = next(i["id"] for i in coco["images"] if i["frame_index"] == args.frame)
    names = {c["id"]: c["name"] for c in coco["categories"]}
    annotations = [a for a in coco["annotations"] if a["image_id"] == image_id]
    drawn = draw(video_frame(args.camera_dir / "video.mp4", args.frame), annotations, names)
    height = round(drawn.shape[0] * args.width / drawn.shape[1])
    args.output.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(args.output), cv2.resize(drawn, (args.width, height), interpolation=cv2.INTER_AREA))
    print(f"frame {args.frame}: {len(annotations)} objects → {args.output}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
