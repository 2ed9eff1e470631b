"""People: what a real-photo detector finds on camgen's frames, and what posing people costs.

- Detection (`camgen.bench.realism`): OpenCV's HOG people detector (INRIA Person: real photographs),
  YOLOv4-tiny's person class (MS COCO: real photographs) and, with the `detect` extra, YOLOv8 (COCO,
  fine-tuned on UAH FPDS: real photographs) on the same frames spread over every example scene with
  people, every camera; recall and precision of people ≥ 96 px tall and ≥ 70 % visible, per detector.
- Cost: the plaza with 50 procedural people drawn at 1080p (radiance, shadows on) with every person
  posed and skinned before each draw, against the same draw of people standing as they were; and
  each part alone: posing (gait, forward kinematics, keypoints), skinning (one sparse product for
  all), and uploading the vertex buffers.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from camgen.bench.harness import Case
from camgen.bench.realism import DetectionScore

PEOPLE = 50
FRAME_S = 1 / 25


def _crowd_graph(repo: Path):
    """The plaza with extra wanderers up to `PEOPLE` people, as a scene graph, and a 1080p view."""
    from camgen.config import load_scene
    from camgen.config.scene import Actor
    from camgen.motion.pose import T_world_from_cam
    from camgen.render.renderer import View
    from camgen.render.scene_graph import build_scene_graph

    loaded = load_scene(repo / "scenes/plaza.yaml")
    actors = list(loaded.scene.actors)
    for i in range(PEOPLE - sum(a.cls == "person" for a in actors)):
        actors.append(
            Actor.model_validate(
                {"name": f"extra_{i}", "class": "person",
                 "random_walk": {"region_m": [[-12, -8], [12, 8]], "speed_m_s": 1.3, "seed": i}}
            )
        )  # fmt: skip
    scene = loaded.scene.model_copy(update={"actors": actors})
    graph = build_scene_graph(scene)
    # A 1080p camera on the station's facade looking down over the plaza.
    eye = np.array([0.0, 15.5, 6.0])
    forward = np.array([0.0, -1.0, -0.35])
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    down = np.cross(forward, right)
    T = T_world_from_cam(tuple(eye), np.column_stack([right, down, forward]))
    K = np.array([[1100.0, 0.0, 959.5], [0.0, 1100.0, 539.5], [0.0, 0.0, 1.0]])
    return graph, View(K, T, 1920, 1080)


DETECTION_CASE = "person detection (HOG, YOLOv4-tiny, YOLOv8-FPDS) over the example scenes"


def people_cases(
    repo: Path, scores: list[DetectionScore], counts: dict[str, int], samples: dict | None = None
) -> list[Case]:
    from camgen.bench.realism import person_detection_scores
    from camgen.bench.render_cases import _renderer

    state: dict = {}

    def setup() -> None:
        if "graph" not in state:
            state["graph"], state["view"] = _crowd_graph(repo)
            state["renderer"] = _renderer()
            state["time_s"] = 1.0
            counts["people"] = sum(rig is not None for rig in state["graph"].people)
            counts["vertices"] = int(sum(len(rig.model.vertices_m) for rig in state["graph"].people if rig))

    def draw(moving: bool):
        def run() -> None:
            graph = state["graph"]
            if moving:
                state["time_s"] += FRAME_S
                graph.place_actors(state["time_s"])
            state["renderer"].draw(graph, state["view"], ("radiance",))

        return run

    def pose() -> None:
        state["time_s"] += FRAME_S
        state["M"] = np.concatenate([rig.pose_skeleton(state["time_s"]) for rig in state["graph"].crowd.rigs])

    def skin_all() -> None:
        from camgen.actors.skeleton import skin

        crowd = state["graph"].crowd
        if "M" not in state:
            pose()
        skin(crowd._rest_vertices, crowd._rest_normals, crowd._weights, state["M"])

    def upload() -> None:
        from camgen.render.renderer import _upload_deformed

        graph = state["graph"]
        people = zip(graph.actor_nodes, graph.people, strict=True)
        graph.deformed.update(node.mesh.primitives[0] for node, rig in people if rig is not None)
        state["renderer"]._make_current()
        _upload_deformed(graph)

    def detect() -> None:
        scores.clear()
        if samples is not None:
            samples.clear()
        scores.extend(person_detection_scores(repo, samples=samples))

    name = f"{PEOPLE} people"
    return [
        Case(f"draw 1080p, {name} standing still", draw(False), setup=setup, repeats=7),
        Case(
            f"draw 1080p, {name} posed each frame",
            draw(True),
            setup=setup,
            repeats=7,
            baseline=f"draw 1080p, {name} standing still",
        ),
        Case(f"pose {name} (gait, kinematics, keypoints)", pose, setup=setup, repeats=7),
        Case(f"skin {name}", skin_all, setup=setup, repeats=7),
        Case(f"upload {name} to the GPU", upload, setup=setup, repeats=7),
        Case(DETECTION_CASE, detect, repeats=1, warmup=0),
    ]


def _ratio(numerator: int, denominator: int) -> str:
    return "—" if denominator == 0 else f"{numerator / denominator:.2f} ({numerator}/{denominator})"


def detection_table(scores: list[DetectionScore], counted: str = "people ≥ 96 px, ≥ 70 % visible") -> str:
    """One row per scene and camera; recall and precision (with their counts) for each detector;
    `counted` heads the column of the objects that count (`DetectionScore.people`)."""
    detectors = list(dict.fromkeys(s.detector for s in scores))
    rows: dict[tuple[str, str], dict[str, DetectionScore]] = {}
    for s in scores:
        rows.setdefault((s.scene, s.camera), {})[s.detector] = s
    header = f"| scene | camera | {counted} |" + "".join(f" {d} recall | {d} precision |" for d in detectors)
    lines = [header, "|---|---|---:|" + "---:|---:|" * len(detectors)]
    for (scene, camera), by in rows.items():
        cells = []
        for d in detectors:
            s = by[d]
            cells += [_ratio(s.hits, s.people), _ratio(s.hits, s.hits + s.false_alarms)]
        people = next(iter(by.values())).people
        lines.append(f"| {scene} | {camera} | {people} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def total(scores: list[DetectionScore], detector: str = "HOG") -> DetectionScore:
    """One detector's sums over every scene and camera."""
    mine = [s for s in scores if s.detector == detector]
    return dataclasses.replace(
        mine[0],
        scene="all",
        camera="all",
        people=sum(s.people for s in mine),
        hits=sum(s.hits for s in mine),
        detections=sum(s.detections for s in mine),
        false_alarms=sum(s.false_alarms for s in mine),
    )


def overall_scores(scores: list[DetectionScore]) -> str:
    """Each detector's recall and precision over every scene and camera, as one line of text."""
    parts = []
    for detector in dict.fromkeys(s.detector for s in scores):
        everything = total(scores, detector)
        counted = everything.hits + everything.false_alarms
        precision = f"{everything.precision:.2f}" if counted else "— (no detection)"
        recall = f"**{everything.recall:.2f}**" if everything.people else "—"
        parts.append(f"{detector}: recall {recall} ({everything.hits} of {everything.people}), precision {precision}")
    return "; ".join(parts)


def write_contact_sheet(path: Path, samples: dict) -> None:
    """`contact_sheet(samples)` as a JPEG (quality 85) at `path`, its folder made if missing."""
    import cv2

    path.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(path), contact_sheet(samples), [cv2.IMWRITE_JPEG_QUALITY, 85])


def contact_sheet(samples: dict, tile_width_px: int = 480, columns: int = 3) -> np.ndarray:
    """The sample frames (by (scene, camera)), each scaled to `tile_width_px` wide and labelled, in a
    grid `columns` wide (8-bit BGR)."""
    import cv2

    tiles = []
    for (scene, camera), frame in samples.items():
        height_px = round(frame.shape[0] * tile_width_px / frame.shape[1])
        tile = cv2.resize(frame, (tile_width_px, height_px), interpolation=cv2.INTER_AREA)
        cv2.putText(tile, f"{scene} / {camera}", (6, 18), 0, 0.5, (0, 0, 0), 3)
        cv2.putText(tile, f"{scene} / {camera}", (6, 18), 0, 0.5, (255, 255, 255), 1)
        tiles.append(tile)
    row_height_px = max(t.shape[0] for t in tiles)
    tiles = [cv2.copyMakeBorder(t, 0, row_height_px - t.shape[0], 0, 0, cv2.BORDER_CONSTANT) for t in tiles]
    tiles += [np.zeros_like(tiles[0])] * (-len(tiles) % columns)
    return np.vstack([np.hstack(tiles[i : i + columns]) for i in range(0, len(tiles), columns)])
