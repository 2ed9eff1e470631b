"""A procedural person: the MakeHuman body shaped by an `Appearance`, dressed, rigged and skinned.

The body is MakeHuman's hm08 mesh morphed by its macro targets (`camgen.actors.makehuman`) and scaled
to the drawn stature. Clothing is built from MakeHuman's own fitting helpers, which share the body's
skinning: the "tights" helper (a closed shell over torso, arms, legs and feet) cut at the sleeve,
waist and trouser lengths and pushed out along its normals by the garment's thickness, the "skirt"
helper for skirts and coat tails, the "hair" helper for long hair. Body faces under a garment are not
drawn (they could only poke through it). Hair, hat, backpack and handbag complete the silhouette.

Everything is one triangle mesh with per-vertex colour (linear albedo), skinned to 22 joints with up to
four weights per vertex (`camgen.actors.skeleton`). Keypoints are the COCO 17 (Lin et al. 2014):
shoulders, elbows, wrists, hips, knees and ankles at the rig's joints, nose, eyes and ears at marker
points of the head.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import lru_cache

import fast_simplification
import numpy as np
import trimesh
from scipy.spatial import cKDTree

from camgen.actors import makehuman as mh
from camgen.actors.appearance import CLOTH_RGB, HAIR_RGB, Appearance
from camgen.actors.skeleton import INDEX, JOINTS
from camgen.annotate.keypoints import COCO_KEYPOINTS

_KEYPOINT_JOINTS = {
    "left_shoulder": "upperarm_l",
    "right_shoulder": "upperarm_r",
    "left_elbow": "lowerarm_l",
    "right_elbow": "lowerarm_r",
    "left_wrist": "hand_l",
    "right_wrist": "hand_r",
    "left_hip": "thigh_l",
    "right_hip": "thigh_r",
    "left_knee": "calf_l",
    "right_knee": "calf_r",
    "left_ankle": "foot_l",
    "right_ankle": "foot_r",
}
KEYPOINT_JOINT_ROWS = [INDEX[_KEYPOINT_JOINTS[name]] for name in COCO_KEYPOINTS[5:]]
"""Rows of the skeleton's joints that are the other twelve COCO keypoints, in COCO's order."""

# Which game-engine bones our joints absorb (fingers move with the hand).
_BONE_TO_JOINT = {"Root": "pelvis"} | {
    f"{finger}_{k:02d}_{side}": f"hand_{side}"
    for finger in ("thumb", "index", "middle", "ring", "pinky")
    for k in (1, 2, 3)
    for side in ("l", "r")
}
# Garment thickness: how far each garment stands off the tights helper, m.
TOP_OFFSET_M = {"tshirt": 0.004, "shirt": 0.008, "jacket": 0.022, "coat": 0.028}
TROUSERS_OFFSET_M = 0.010
WAISTBAND_UNDER_TOP_M = 0.05
"""How far trousers and skirts' briefs reach up under a top's hem, m (more than the tallest helper
face there, about 4 cm), standing off the body half as far as the top does."""
TROUSERS_HEM_EASE_M = 0.025
"""How much further trousers stand off the leg at the ankle than at the knee, m: a straight trouser leg
hangs from the knee, its hem about 42–46 cm round (the 21–23 cm leg opening laid flat of trousers' size
charts) about an ankle some 22–25 cm round (ANSUR II's ankle circumference, Gordon et al. 2014),
i.e. about 3 cm out all round; following the leg's taper like tights, trousers read as leggings."""
SKIRT_OFFSET_M = 0.02
SKIRT_LEG_FOLLOW = 0.5
SHOE_OFFSET_M = 0.012
SHORT_HAIR_OFFSET_M = 0.008
HAT_OFFSET_M = 0.015
INFLUENCES = 4
SOLE_LIFT_M = 0.002
FABRIC_SPAWN_KEY = 0x6661_6272  # "fabr"
FABRIC_WAVES = 6
FABRIC_VARIATION = 0.12
LONG_HAIR_BELOW_NECK_FRACTION = 0.12
"""Long hair ends this fraction of the stature below the neck joint (at the shoulder blades)."""
VERTEX_FRACTION = 0.3
"""The dressed mesh is decimated to this fraction of its vertices (quadric error metrics; Garland &
Heckbert 1997): about 4 000 vertices, whose edges stay under 3 cm, a pixel or two on a person filling
a 1080p frame, at a third of the skinning cost."""


@dataclass(frozen=True)
class PersonModel:
    """A person's rest mesh, rig and keypoint markers, in the actor frame (x forward, z up, m)."""

    appearance: Appearance
    vertices_m: np.ndarray
    """(V, 3) float32 rest vertices; the shoe soles stand on the ground (`SOLE_LIFT_M` above z = 0)."""
    normals: np.ndarray
    """(V, 3) float32 rest normals."""
    faces: np.ndarray
    """(F, 3) int32 triangles."""
    colours: np.ndarray
    """(V, 4) float32 linear albedo and alpha 1."""
    joint_index: np.ndarray
    """(V, 4) int64 joints each vertex follows."""
    joint_weight: np.ndarray
    """(V, 4) float32 their weights (rows sum to 1)."""
    joints_m: np.ndarray
    """(J, 3) rest joint positions (`camgen.actors.skeleton.JOINTS`)."""
    head_markers_m: np.ndarray
    """(5, 3) rest nose, left/right eye, left/right ear."""


def phenotype_of(appearance: Appearance, height: float = 0.5) -> mh.Phenotype:
    """MakeHuman macro parameters for an appearance (stature is matched afterwards)."""
    return mh.Phenotype(
        gender=0.0 if appearance.sex == "female" else 1.0,
        age=mh.age_parameter(appearance.age_years),
        muscle=appearance.muscle,
        weight=appearance.build,
        height=height,
        proportions=0.5,
    )


def _stature_m(vertices_m: np.ndarray) -> float:
    body = vertices_m[np.unique(mh.base_mesh().faces_by_group["body"])]
    return float(body[:, 2].max() - body[:, 2].min())


def shaped_vertices(appearance: Appearance) -> np.ndarray:
    """hm08 vertices for an appearance, at its stature with the bare soles on z = 0.

    MakeHuman's height parameter moves stature nearly linearly; it is set by a secant step between
    its neutral and maximal or minimal value (so limbs and trunk keep MakeHuman's height-dependent
    proportions), and a uniform scale then takes the stature exactly to the drawn value.
    """
    neutral = mh.morphed_vertices(phenotype_of(appearance, 0.5))
    h0 = _stature_m(neutral)
    end = 1.0 if appearance.stature_m > h0 else 0.0
    h1 = _stature_m(mh.morphed_vertices(phenotype_of(appearance, end)))
    param = 0.5 if h1 == h0 else 0.5 + (end - 0.5) * np.clip((appearance.stature_m - h0) / (h1 - h0), 0.0, 1.0)
    vertices = mh.morphed_vertices(phenotype_of(appearance, float(param)))
    vertices *= appearance.stature_m / _stature_m(vertices)
    body = vertices[np.unique(mh.base_mesh().faces_by_group["body"])]
    vertices[:, 2] -= body[:, 2].min()
    return vertices


@lru_cache(maxsize=1)
def _skin_weights() -> tuple[np.ndarray, np.ndarray]:
    """(V, 4) joint indices and weights of every hm08 vertex in our 22-joint rig."""
    bones, weights = mh.game_engine_rig()
    count = len(mh.base_mesh().vertices_m)
    dense = np.zeros((count, len(JOINTS)), dtype=np.float64)
    for bone in bones:
        joint = _BONE_TO_JOINT.get(bone.name, bone.name)
        if joint not in INDEX:
            continue
        pairs = np.array(weights.get(bone.name, []), dtype=np.float64).reshape(-1, 2)
        np.add.at(dense[:, INDEX[joint]], pairs[:, 0].astype(np.int64), pairs[:, 1])
    order = np.argsort(-dense, axis=1, kind="stable")[:, :INFLUENCES]
    top = np.take_along_axis(dense, order, axis=1)
    unweighted = top.sum(axis=1) <= 0
    order[unweighted, 0], top[unweighted, 0] = INDEX["pelvis"], 1.0
    return order, top / top.sum(axis=1, keepdims=True)


def rest_joints(vertices_m: np.ndarray) -> np.ndarray:
    """(J, 3) joint positions of shaped hm08 vertices (the means of MakeHuman's joint cubes)."""
    bones = {bone.name: bone for bone in mh.game_engine_rig()[0]}
    return np.array([mh.joint_position(vertices_m, bones[name]) for name in JOINTS])


def _head_markers(vertices_m: np.ndarray, joints_m: np.ndarray) -> np.ndarray:
    """Nose tip, eye centres and ear points (where COCO annotators click: the ear's middle)."""
    cubes = mh.base_mesh().joint_cubes
    left_eye = vertices_m[cubes["joint-l-eye"]].mean(axis=0)
    right_eye = vertices_m[cubes["joint-r-eye"]].mean(axis=0)
    body = vertices_m[np.unique(mh.base_mesh().faces_by_group["body"])]
    eye_z = (left_eye[2] + right_eye[2]) / 2
    near_mid = body[(np.abs(body[:, 1]) < 0.01) & (body[:, 2] < eye_z) & (body[:, 2] > eye_z - 0.07)]
    nose = near_mid[np.argmax(near_mid[:, 0])]
    head_x = joints_m[INDEX["head"], 0]
    band = body[(np.abs(body[:, 2] - (eye_z - 0.015)) < 0.02) & (np.abs(body[:, 0] - head_x) < 0.04)]
    left_ear = band[np.argmax(band[:, 1])]
    right_ear = band[np.argmin(band[:, 1])]
    return np.array([nose, left_eye, right_eye, left_ear, right_ear])


def _regions(points_m: np.ndarray, joint: np.ndarray, joints_m: np.ndarray, look: Appearance) -> dict[str, np.ndarray]:
    """Boolean masks of which points a garment covers: "top", "bottom", "shoes" (by the joint each
    point mostly follows and where it lies along its limb)."""
    J = INDEX
    j_of = np.array(JOINTS)[joint]
    z = points_m[:, 2]
    waist_z = joints_m[J["spine_01"], 2]
    hip_z = joints_m[J["thigh_l"], 2]
    knee_z = joints_m[J["calf_l"], 2]
    ankle_z = joints_m[J["foot_l"], 2]
    torso = np.isin(j_of, ("pelvis", "spine_01", "spine_02", "spine_03", "clavicle_l", "clavicle_r"))
    neck = np.isin(j_of, ("neck_01", "head"))
    upper_arm = np.isin(j_of, ("upperarm_l", "upperarm_r"))
    lower_arm = np.isin(j_of, ("lowerarm_l", "lowerarm_r"))
    legs = np.isin(j_of, ("thigh_l", "thigh_r", "calf_l", "calf_r"))
    feet = np.isin(j_of, ("foot_l", "foot_r", "ball_l", "ball_r"))
    # Along the arm: 0 at the shoulder, 1 at the elbow, 2 at the wrist (from |y| in the A-pose).
    shoulder_y, elbow_y, wrist_y = (abs(joints_m[J[n], 1]) for n in ("upperarm_l", "lowerarm_l", "hand_l"))
    y = np.abs(points_m[:, 1])
    along_arm = np.where(
        y < elbow_y, (y - shoulder_y) / (elbow_y - shoulder_y), 1 + (y - elbow_y) / (wrist_y - elbow_y)
    )
    sleeve = 1.85 if look.long_sleeves else 0.45
    # A top's hem is a level line around the body (a garment's hemline is cut level to the floor): it
    # covers the tops of the thighs where they reach above it, and never runs down between the legs.
    # (By the vertices' dominant joint alone, the pelvis's vertices reach the crotch while the outer hip
    # follows the thighs, and the hem would dip to the crotch like a leotard's.)
    hem_z = hip_z - (0.10 if look.top in ("jacket", "coat") else 0.04)
    top = (((torso | legs) | (neck & (z < joints_m[J["neck_01"], 2] + 0.01))) & (z >= hem_z)) | (
        (upper_arm | lower_arm) & (along_arm <= sleeve)
    )
    if look.bottom == "trousers":
        leg_end_z = ankle_z + 0.02
    elif look.bottom == "shorts":
        leg_end_z = knee_z + 0.35 * (hip_z - knee_z)
    else:  # a skirt: the tights only as far as the skirt's own helper reaches
        leg_end_z = hip_z - 0.02
    # The trousers (or briefs) reach `WAISTBAND_UNDER_TOP_M` up under the top's hem: ending where the
    # top begins, the ring of helper faces between the two would belong to neither, a slit through the
    # body (the skin under both is not drawn) that showed the ground through the waist.
    under_top = z < hem_z + WAISTBAND_UNDER_TOP_M
    bottom = (~top | under_top) & (((torso & (z < waist_z + 0.02)) | legs) & (z >= leg_end_z))
    if look.bottom == "skirt":  # briefs under the skirt, in its colour
        bottom |= (~top | under_top) & (torso | legs) & (z < waist_z + 0.02) & (z >= hip_z - 0.12)
    shoes = feet | (legs & (z < ankle_z + 0.01))
    return {"top": top, "bottom": bottom, "shoes": shoes}


@dataclass(frozen=True)
class _Piece:
    """One part of the dressed mesh, before the parts are joined."""

    points_m: np.ndarray
    faces: np.ndarray
    colours: np.ndarray
    joint_index: np.ndarray
    joint_weight: np.ndarray


def _surface(vertices_m, faces, keep_vertex, colour, offset_m=0.0) -> _Piece | None:
    """The faces of an hm08 surface all of whose vertices are kept, pushed out by `offset_m` along their
    normals (a garment's thickness: one value, or (V,) per hm08 vertex), with the skinning of the
    vertices they use. `colour`: one (3,) albedo, or (V, 3) per hm08 vertex."""
    keep_face = keep_vertex[faces].all(axis=1)
    sub = faces[keep_face]
    if len(sub) == 0:
        return None
    used = np.unique(sub)
    remap = np.full(len(vertices_m), -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    local_faces = remap[sub]
    points = vertices_m[used]
    offset_m = np.asarray(offset_m, dtype=np.float64)
    if offset_m.ndim:
        offset_m = offset_m[used, None]
    if np.any(offset_m):
        points = points + offset_m * trimesh.Trimesh(points, local_faces, process=False).vertex_normals
    colour = np.asarray(colour, dtype=np.float64)
    rgb = colour[used] if colour.ndim == 2 else np.broadcast_to(colour, (len(used), 3))
    joint_index, joint_weight = _skin_weights()
    return _Piece(points, local_faces, rgb, joint_index[used], joint_weight[used])


def _swinging_hem(piece: _Piece, joints_m: np.ndarray, hem_z: float) -> _Piece:
    """A skirt or coat tail skinned to hang from the pelvis and swing partly with the thighs: rigid at
    the waist, following its side's thigh by up to `SKIRT_LEG_FOLLOW` at the hem. (The helper's own
    weights follow the legs wholly, which tears the cloth open between them at every stride.)"""
    hip_z = joints_m[INDEX["thigh_l"], 2]
    points = piece.points_m
    follow = SKIRT_LEG_FOLLOW * np.clip((hip_z - points[:, 2]) / max(hip_z - hem_z, 1e-3), 0.0, 1.0)
    left = 0.5 + 0.5 * np.tanh(points[:, 1] / 0.05)
    index = np.zeros((len(points), INFLUENCES), dtype=np.int64)
    weight = np.zeros((len(points), INFLUENCES))
    index[:, :3] = (INDEX["pelvis"], INDEX["thigh_l"], INDEX["thigh_r"])
    weight[:, 0], weight[:, 1], weight[:, 2] = 1.0 - follow, follow * left, follow * (1.0 - left)
    return replace(piece, joint_index=index, joint_weight=weight)


def _rigid_box(extents_m, centre_m, colour, joint: str) -> _Piece:
    """A box (a bag) that moves rigidly with one joint."""
    box = trimesh.creation.box(extents=extents_m).subdivide()
    points = box.vertices + np.asarray(centre_m)
    count = len(points)
    index = np.zeros((count, INFLUENCES), dtype=np.int64)
    index[:, 0] = INDEX[joint]
    weight = np.zeros((count, INFLUENCES))
    weight[:, 0] = 1.0
    return _Piece(points, np.asarray(box.faces), np.broadcast_to(np.asarray(colour), (count, 3)), index, weight)


def decimate(points, faces, colours, joint_index, joint_weight, fraction: float):
    """The mesh reduced to `fraction` of its vertices by quadric edge collapses; each kept vertex takes
    the colour and skinning of the nearest of the vertices merged into it (a chain of collapses can
    merge vertices far apart, so their mean would be wrong)."""
    points64, faces64 = points.astype(np.float64), faces.astype(np.int64)
    _, _, collapses = fast_simplification.simplify(
        points64, faces64, target_reduction=1.0 - fraction, return_collapses=True
    )
    new_points, new_faces, mapping = fast_simplification.replay_simplification(points64, faces64, collapses)
    distance = np.linalg.norm(points64 - new_points[mapping], axis=1)
    order = np.lexsort((distance, mapping))  # by group, nearest first
    first = np.ones(len(order), dtype=bool)
    first[1:] = mapping[order][1:] != mapping[order][:-1]
    source = np.empty(len(new_points), dtype=np.int64)
    source[mapping[order][first]] = order[first]
    return (
        np.asarray(new_points, dtype=np.float64),
        np.asarray(new_faces, dtype=np.int32),
        np.asarray(colours, dtype=np.float64)[source],
        joint_index[source].astype(np.int64),
        joint_weight[source].astype(np.float32),
    )


def _fabric_variation(points_m: np.ndarray, *, rng: np.random.Generator) -> np.ndarray:
    """(V,) albedo factors around 1: a smooth random field over the body (a few random plane waves of
    10–30 cm wavelength, ±`FABRIC_VARIATION` together), the uneven shade that folds, wear and
    fading give real cloth and skin, so that no surface is one flat colour."""
    field = np.zeros(len(points_m))
    for _ in range(FABRIC_WAVES):
        direction = rng.normal(size=3)
        direction /= np.linalg.norm(direction)
        wavelength_m = rng.uniform(0.10, 0.30)
        field += np.sin(2 * np.pi * points_m @ direction / wavelength_m + rng.uniform(0, 2 * np.pi))
    return 1.0 + FABRIC_VARIATION * field / np.sqrt(FABRIC_WAVES / 2)


def _hairline(vertices_m, joints_m, markers_m, on_head) -> np.ndarray:
    """Head vertices under the hair: above the brow in front, down to the nape behind."""
    eye_z = markers_m[1, 2]
    front_x = joints_m[INDEX["head"], 0] + 0.045
    x, z = vertices_m[:, 0], vertices_m[:, 2]
    forehead = (x > front_x) & (z > eye_z + 0.045)
    crown_and_nape = (x <= front_x) & (z > eye_z - 0.02 - 0.6 * (front_x - x))
    return on_head & (forehead | crown_and_nape)


def _trousers_offset_m(vertices_m: np.ndarray, joints_m: np.ndarray) -> np.ndarray:
    """(V,) how far trousers stand off each hm08 vertex: `TROUSERS_OFFSET_M` down to the knee, then
    `TROUSERS_HEM_EASE_M` more, linearly, by the ankle (a straight leg hanging from the knee)."""
    knee_z, ankle_z = joints_m[INDEX["calf_l"], 2], joints_m[INDEX["foot_l"], 2]
    below_knee = np.clip((knee_z - vertices_m[:, 2]) / (knee_z - ankle_z), 0.0, 1.0)
    return TROUSERS_OFFSET_M + TROUSERS_HEM_EASE_M * below_knee


def _skin_and_garments(look: Appearance, vertices_m, joints_m, markers_m) -> list[_Piece | None]:
    """The body (the faces a garment leaves bare), the garments on the tights and skirt helpers, hair."""
    base = mh.base_mesh()
    dominant = np.array(JOINTS)[_skin_weights()[0][:, 0]]
    cover = _regions(vertices_m, _skin_weights()[0][:, 0], joints_m, look)
    skin, hair = np.array(look.skin_rgb), np.array(HAIR_RGB[look.hair_colour])
    on_head = dominant == "head"
    hairline = _hairline(vertices_m, joints_m, markers_m, on_head)
    body_rgb = np.tile(skin, (len(vertices_m), 1))
    if look.hair_style != "bald":
        body_rgb[hairline] = hair
    x, z, eye_z = vertices_m[:, 0], vertices_m[:, 2], markers_m[1, 2]
    head_x = joints_m[INDEX["head"], 0]
    brows = on_head & (x > head_x + 0.06) & (np.abs(z - (eye_z + 0.025)) < 0.006) & (np.abs(vertices_m[:, 1]) > 0.01)
    body_rgb[brows] = 0.6 * hair + 0.12 * skin
    # A body vertex is under a garment when the nearest vertex of the tights helper is (one rule for
    # both surfaces, so no gap opens between a garment's edge and the skin it hides); body faces all of
    # whose vertices are covered are not drawn.
    tights = base.faces_by_group["helper-tights"]
    tights_ids = np.unique(tights)
    distance, nearest = cKDTree(vertices_m[tights_ids]).query(vertices_m)
    garment = cover["top"] | cover["bottom"] | cover["shoes"]
    covered = garment[tights_ids[nearest]] & (distance < 0.05)
    body_faces = base.faces_by_group["body"]
    shown = body_faces[(~covered)[body_faces].any(axis=1)]
    everything = np.ones(len(vertices_m), bool)
    top_rgb = CLOTH_RGB[look.top_colour]
    trousers_offset_m = np.where(
        cover["top"],
        np.minimum(_trousers_offset_m(vertices_m, joints_m), TOP_OFFSET_M[look.top] / 2),
        _trousers_offset_m(vertices_m, joints_m),
    )
    pieces = [
        _surface(vertices_m, shown, everything, body_rgb),
        _surface(vertices_m, tights, cover["top"], top_rgb, TOP_OFFSET_M[look.top]),
        _surface(vertices_m, tights, cover["bottom"], CLOTH_RGB[look.bottom_colour], trousers_offset_m),
        _surface(vertices_m, tights, cover["shoes"], CLOTH_RGB[look.shoe_colour], SHOE_OFFSET_M),
    ]
    if look.bottom == "skirt" or look.top == "coat":  # the skirt helper, its hem raised to the length
        skirt = vertices_m.copy()
        ids = np.unique(base.faces_by_group["helper-skirt"])
        top_z, bottom_z = skirt[ids, 2].max(), skirt[ids, 2].min()
        knee_z = joints_m[INDEX["calf_l"], 2]
        hem_z = knee_z + (0.02 if look.top == "coat" else 0.10) * look.stature_m
        skirt[ids, 2] = top_z - (top_z - skirt[ids, 2]) * (top_z - hem_z) / (top_z - bottom_z)
        colour = top_rgb if look.top == "coat" else CLOTH_RGB[look.bottom_colour]
        piece = _surface(skirt, base.faces_by_group["helper-skirt"], everything, colour, SKIRT_OFFSET_M)
        pieces.append(_swinging_hem(piece, joints_m, hem_z))
    if look.hair_style == "long":
        # The helper drapes strands over the chest too, and it is not shaped by the macro targets for
        # small bodies: keep the hair behind the shoulders, down to the shoulder blades.
        neck_z = joints_m[INDEX["neck_01"], 2]
        behind = (vertices_m[:, 0] < head_x + 0.02) | (vertices_m[:, 2] > neck_z + 0.05)
        long_hair = behind & (vertices_m[:, 2] > neck_z - LONG_HAIR_BELOW_NECK_FRACTION * look.stature_m)
        pieces.append(_surface(vertices_m, base.faces_by_group["helper-hair"], long_hair, hair, 0.002))
    if look.hat:
        hat_rgb = CLOTH_RGB["black" if look.top_colour != "black" else "gray"]
        pieces.append(_surface(vertices_m, body_faces, on_head & (z > eye_z + 0.035), hat_rgb, HAT_OFFSET_M))
    elif look.hair_style != "bald":
        pieces.append(_surface(vertices_m, body_faces, hairline, hair, SHORT_HAIR_OFFSET_M))
    return pieces


def _carried(look: Appearance, vertices_m, joints_m) -> list[_Piece]:
    """A backpack on the upper back or a handbag at the hip."""
    if look.bag == "backpack":
        chest = joints_m[INDEX["spine_03"]]
        near_spine = (np.abs(vertices_m[:, 2] - chest[2]) < 0.05) & (np.abs(vertices_m[:, 1]) < 0.05)
        back_x = float(vertices_m[near_spine, 0].min())
        depth, width, height = 0.15, 0.30, 0.40
        centre = (back_x - TOP_OFFSET_M[look.top] - depth / 2 - 0.005, 0.0, chest[2] - 0.10)
        colour = CLOTH_RGB["black" if look.top_colour != "black" else "blue"]
        return [_rigid_box((depth, width, height), centre, colour, "spine_03")]
    if look.bag == "handbag":
        # Beside the hip, outside the trunk and thigh: the arms are left out, since in the rest A-pose
        # the hands hang at hip height a forearm's length out from it (the bag would float there).
        hip_z = joints_m[INDEX["thigh_l"], 2]
        dominant = np.array(JOINTS)[_skin_weights()[0][:, 0]]
        trunk = np.isin(dominant, ("pelvis", "spine_01", "thigh_l", "thigh_r"))
        side_y = float(vertices_m[trunk & (np.abs(vertices_m[:, 2] - hip_z) < 0.04), 1].max()) + 0.05
        return [_rigid_box((0.26, 0.08, 0.22), (0.0, side_y, hip_z - 0.02), CLOTH_RGB["brown"], "pelvis")]
    return []


def build_person(appearance: Appearance) -> PersonModel:
    """The rest mesh, colours, skinning and markers of a person (pure; about a second)."""
    vertices_m = shaped_vertices(appearance)
    joints_m = rest_joints(vertices_m)
    markers_m = _head_markers(vertices_m, joints_m)
    pieces = [p for p in _skin_and_garments(appearance, vertices_m, joints_m, markers_m) if p is not None]
    pieces += _carried(appearance, vertices_m, joints_m)
    rng = np.random.default_rng(np.random.SeedSequence(appearance.identity_seed, spawn_key=(FABRIC_SPAWN_KEY,)))
    pieces = [replace(p, colours=p.colours * _fabric_variation(p.points_m, rng=rng)[:, None]) for p in pieces]
    offsets = np.cumsum([0] + [len(p.points_m) for p in pieces[:-1]])
    points_m, faces, colours, joint_index, joint_weight = decimate(
        np.concatenate([p.points_m for p in pieces]),
        np.concatenate([p.faces + o for p, o in zip(pieces, offsets, strict=True)]),
        np.concatenate([p.colours for p in pieces]),
        np.concatenate([p.joint_index for p in pieces]),
        np.concatenate([p.joint_weight for p in pieces]),
        VERTEX_FRACTION,
    )
    # The shoe soles stand SOLE_LIFT_M above z = 0: flush with the ground they would tie with it in
    # depth and flicker in and out of the instance pass.
    ground = np.array([0.0, 0.0, points_m[:, 2].min() - SOLE_LIFT_M])
    points_m -= ground
    normals = trimesh.Trimesh(points_m, faces, process=False).vertex_normals
    return PersonModel(
        appearance=appearance,
        vertices_m=points_m.astype(np.float32),
        normals=np.asarray(normals, dtype=np.float32),
        faces=faces,
        colours=np.concatenate([colours, np.ones((len(points_m), 1))], axis=1).astype(np.float32),
        joint_index=joint_index,
        joint_weight=joint_weight,
        joints_m=joints_m - ground,
        head_markers_m=markers_m - ground,
    )
