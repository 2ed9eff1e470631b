"""Per-frame annotations of one camera: the rendered actor meshes and passes, through its lens.

For every actor in view at a frame:

- the visible box and mask from the instance pass after the lens (`LensStages.apply`: the same
  nearest-pixel remap as the pixels);
- the amodal box from the actor's rendered mesh (its vertices and edges, posed as drawn) projected
  through the frame's camera matrix and distortion (`camgen.annotate.boxes.amodal_box`), kept as it
  is and clipped to the image;
- visibility = visible pixels / pixels of the actor drawn alone (an unoccluded instance draw through
  the same lens), and truncation from the amodal box;
- the 3D box of the actor's local bounds in world and camera frames.

Track ids are the global instance ids (`camgen.render.scene_graph.instance_table`): the same in every
camera of a scene and over the whole sequence.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from camgen.annotate.boxes import Box, amodal_box, clip_box, mask_boxes, points_box, truncation, unique_edges
from camgen.annotate.keypoints import keypoint_visibility
from camgen.annotate.plates import plate_annotation
from camgen.job import CameraState
from camgen.plan.lens_stages import LensStages
from camgen.plan.visibility import box_corners
from camgen.render.renderer import Passes
from camgen.render.sequence import CameraRenderer, render_view


@dataclass(frozen=True)
class ObjectAnnotation:
    track_id: int
    name: str
    cls: str
    visible_box: Box | None
    """Tight box of the visible pixels (pixel edges); None when fully occluded."""
    amodal_box: Box | None
    """The whole object's projection, clipped to the image (pixel edges)."""
    unclipped_box: Box
    """The whole object's projection as it is, reaching outside the image where the object does (pixel
    edges; MOT17's boxes are so)."""
    visible_pixels: int
    unoccluded_pixels: int
    visibility: float
    truncation: float
    box_3d_world_m: np.ndarray
    """(8, 3) corners of the actor's local bounding box in the world (a person's: in its heading's
    frame, around its posed mesh)."""
    box_3d_cam_m: np.ndarray
    keypoints: np.ndarray | None = None
    """(17, 3) COCO keypoints of a person: x, y in COCO's pixel-edge coordinates (an OpenCV position
    p at p + ½) and visibility v (0 outside the image or behind the camera, 1 hidden, 2 visible);
    None for an actor without a skeleton."""
    keypoints_world_m: np.ndarray | None = None
    """(17, 3) the same keypoints in the world, m."""
    plates: tuple[dict, ...] = ()
    """A procedural vehicle's licence plates in the image (`camgen.annotate.plates.plate_annotation`, with
    ``side`` front or rear and the plate's ``text``), those imaged inside the image."""
    rides: str | None = None
    """For a rider, the name of the bicycle or motorcycle it rides (`camgen.config.scene.Actor.rides`)."""


@dataclass
class FrameAnnotations:
    frame: int
    objects: list[ObjectAnnotation] = field(default_factory=list)
    instance_id: np.ndarray | None = None
    """(H, W) uint32 ids of the frame after the lens (for masks)."""


def _mesh_geometry(node) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (V, 3) in the node's frame and unique edges (E, 2) of a pyrender mesh."""
    vertices, faces, offset = [], [], 0
    for primitive in node.mesh.primitives:
        positions = np.asarray(primitive.positions, dtype=np.float64)
        # Flat-shaded meshes are drawn unindexed: consecutive vertex triplets are the triangles.
        indices = (
            np.arange(len(positions)).reshape(-1, 3)
            if primitive.indices is None
            else np.asarray(primitive.indices).reshape(-1, 3)
        )
        vertices.append(positions)
        faces.append(indices + offset)
        offset += len(positions)
    return np.concatenate(vertices), unique_edges(np.concatenate(faces))


class Annotator:
    """Annotates frames of one camera (the graph's actors must be placed at the frame time)."""

    def __init__(self, drawer: CameraRenderer, lens: LensStages):
        self.drawer, self.lens = drawer, lens
        self.camera, self.graph, self.renderer = drawer.camera, drawer.graph, drawer.renderer
        graph = self.graph
        self._geometry = [
            None if graph.rig(index) else _mesh_geometry(node) for index, node in enumerate(graph.actor_nodes)
        ]
        self._ids = [graph.instance_ids[node] for node in graph.actor_nodes]
        self._alone_kept: dict[int, tuple[tuple, tuple[int, np.ndarray | None, tuple[int, int]]]] = {}
        """Per actor (index): its last draw alone in its window (`_alone_in_window`), by what it depends on."""

    def annotate(self, state: CameraState, passes: Passes, *, post=None) -> FrameAnnotations:
        """`passes`: the frame's passes after the lens (output size). The graph's actors must stand
        where they were drawn for the frame's instance pass (at the frame time). `post` maps an
        instance image after the lens onto the stream (the virtual PTZ's crop and scale), applied to
        the unoccluded draws too; the stream's camera matrix is then the state's `output_K_px`."""
        camera, graph = self.camera, self.graph
        # The stream is the lens's output (no virtual PTZ): each actor is drawn alone in its own window.
        direct = post is None and state.window_px is None
        post = post or (lambda ids: ids)
        W, H = camera.output_size_px or (camera.width_px, camera.height_px)
        K = np.array(state.K_px if state.output_K_px is None else state.output_K_px)
        T = np.array(state.T_world_from_cam)
        T_cam_from_world = np.linalg.inv(T)
        distortion = np.array(state.distortion)
        instance = passes.instance_id
        visible = mask_boxes(instance, self._ids)
        result = FrameAnnotations(state.frame, instance_id=instance)
        view = render_view(state, camera.render)
        clip = None
        for index, (actor, node) in enumerate(zip(graph.actors, graph.actor_nodes, strict=True)):
            pose = graph.scene.get_pose(node)
            rig = graph.rig(index)
            if rig is None:
                vertices, edges = self._geometry[index]
                world = vertices @ pose[:3, :3].T + pose[:3, 3]
                box = amodal_box(world, edges, T, K, distortion)
            else:  # a dense posed mesh (edges of a few cm): its vertices bound its projection
                box = points_box(getattr(rig, "box_vertices_m", rig.vertices_m), T, K, distortion)
            clipped = None if box is None else clip_box(box, W, H)
            if clipped is None:
                continue
            track_id = self._ids[index]
            if clip is None:
                clip = self.drawer.clip_range_m(view)
            # Drawn alone through the same lens: how much of it shows unoccluded (and, for a person,
            # how near its own surface is at each pixel, which hides keypoints on its far side).
            skeleton = rig is not None and rig.keypoints_m is not None
            alone_passes = ("depth_m", "instance_id") if skeleton else ("instance_id",)
            if direct:
                unoccluded_pixels, own_depth, own_depth_at = self._alone_kept_or_drawn(
                    index, state, view, node, alone_passes, clip, clipped
                )
            else:
                alone = self.renderer.draw(graph, view, alone_passes, nodes=[node], clip_range_m=clip)
                lensed = self.lens.apply(state, Passes(depth_m=alone.depth_m, instance_id=alone.instance_id))
                unoccluded_pixels = int(np.count_nonzero(post(lensed.instance_id) == track_id))
                own_depth = None if not skeleton else post(np.where(lensed.depth_m > 0, lensed.depth_m, np.inf))
                own_depth_at = (0, 0)
            seen = visible.get(track_id)
            pixels = 0 if seen is None else seen.pixels
            keypoints = keypoints_world = None
            if rig is None:
                corners_world = box_corners(vertices.min(axis=0), vertices.max(axis=0), pose)
            else:
                corners_world = box_corners(*rig.heading_box())
            if skeleton:
                keypoints_world = rig.keypoints_m
                keypoints = keypoint_visibility(
                    keypoints_world,
                    T,
                    K,
                    distortion,
                    instance,
                    track_id,
                    W,
                    H,
                    own_depth_m=own_depth,
                    own_depth_at_px=own_depth_at,
                )
            plates = []
            for side, corners in (rig.plate_corners_world() if hasattr(rig, "plate_corners_world") else {}).items():
                plate = plate_annotation(corners, T, K, distortion, instance, track_id)
                if plate is not None:
                    plates.append({"side": side, "text": rig.look.plate_text, **plate})
            result.objects.append(
                ObjectAnnotation(
                    track_id=track_id,
                    name=actor.name,
                    cls=actor.cls,
                    visible_box=None if seen is None else seen.box,
                    amodal_box=clipped,
                    unclipped_box=box,
                    visible_pixels=pixels,
                    unoccluded_pixels=unoccluded_pixels,
                    visibility=0.0 if unoccluded_pixels == 0 else min(1.0, pixels / unoccluded_pixels),
                    truncation=truncation(box, W, H),
                    box_3d_world_m=corners_world,
                    box_3d_cam_m=corners_world @ T_cam_from_world[:3, :3].T + T_cam_from_world[:3, 3],
                    keypoints=keypoints,
                    keypoints_world_m=keypoints_world,
                    plates=tuple(plates),
                    rides=actor.rides,
                )
            )
        return result

    def _alone_kept_or_drawn(self, index: int, state: CameraState, view, node, passes, clip, box) -> tuple:
        """`_alone_in_window` of actor `index`, or its last answer when the actor's look (`SceneGraph.look_versions`:
        a parked vehicle's never changes), the view, the lens, the passes, the clip range and the box are those
        it was drawn with: the same draw, so the same answer. A held camera's parked vehicles are drawn alone
        once, not at every frame."""
        versions = self.graph.look_versions
        key = (
            versions[index] if index < len(versions) else None,
            view.key(),
            self.lens.geometry(state),
            passes,
            clip,
            tuple(box),
        )
        kept = self._alone_kept.get(index)
        if key[0] is not None and kept is not None and kept[0] == key:
            return kept[1]
        answer = self._alone_in_window(state, view, node, passes, clip, box)
        if answer[1] is not None:
            answer[1].setflags(write=False)
        self._alone_kept[index] = (key, answer)
        return answer

    def _alone_in_window(self, state: CameraState, view, node, passes: tuple[str, ...], clip, box) -> tuple:
        """An actor drawn alone, only where it can show: the output pixels of its amodal `box` (pixel edges,
        clipped to the image) grown by `WINDOW_PAD_PX`, drawn as the crop of the render that those pixels
        take their ids and depth from (`LensStages.source_pixels`; `Renderer.draw`'s crop gives the whole
        draw's pixels bit for bit). The number of its unoccluded pixels, and (with depth) its camera z at every
        output pixel of the window (+inf where it is not; it is nowhere outside) with the window's top-left
        pixel (column, row): what a whole-frame draw through the lens gives, at a cost that follows the
        actor's size instead of the frame's."""
        W, H = self.camera.output_size_px or (self.camera.width_px, self.camera.height_px)
        x0, y0 = max(0, int(np.floor(box[0])) - WINDOW_PAD_PX), max(0, int(np.floor(box[1])) - WINDOW_PAD_PX)
        x1, y1 = min(W, int(np.ceil(box[2])) + WINDOW_PAD_PX), min(H, int(np.ceil(box[3])) + WINDOW_PAD_PX)
        rows, cols = self.lens.source_pixels(state, (x0, y0, x1, y1))
        top, left = int(rows.min()), int(cols.min())
        crop = (left, top, int(cols.max()) + 1, int(rows.max()) + 1)
        alone = self.renderer.draw(self.graph, view, passes, nodes=[node], clip_range_m=clip, crop_px=crop)
        rows, cols = rows - top, cols - left
        track_id = self.graph.instance_ids[node]
        pixels = int(np.count_nonzero(alone.instance_id[rows, cols] == track_id))
        if alone.depth_m is None:
            return pixels, None, (x0, y0)
        depth = alone.depth_m[rows, cols]
        return pixels, np.where(depth > 0, depth, np.float32(np.inf)), (x0, y0)


WINDOW_PAD_PX = 2
"""Pixels added around an actor's amodal box for its unoccluded draw: the box bounds its vertices' (and
a rigid mesh's edges') projection; rasterisation and the nearest-pixel lens lookup reach at most a pixel
past it, one more is spare."""
