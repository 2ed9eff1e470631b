"""Make walker.glb with Blender: a low-poly, skinned, textured figure with 'Walk' and 'Idle' clips.

Run with a Python that has Blender's `bpy` (it pins numpy < 2, so not camgen's own environment):

    python3 -m venv .venv-blender && .venv-blender/bin/pip install bpy
    .venv-blender/bin/python tests/data/characters/make_walker.py OUT.glb [REFERENCE.npz]

With REFERENCE.npz it also writes what Blender itself computes for the skinned mesh (its evaluated
vertices, Blender's world axes: z up, −y front) at a few frames of each clip, which
tests/actors/test_character_blender.py compares with camgen's glTF skinning. The shipped walker.glb
was made by Blender 5.0.1 with this script; it and this script are CC0 (camgen's own).
"""

import math
import sys

import bpy

args = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else sys.argv[1:]
out = args[0]
reference = args[1] if len(args) > 1 else None
bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
scene.render.fps = 24


def part(kind, name, loc, scale):
    if kind == "cyl":
        bpy.ops.mesh.primitive_cylinder_add(vertices=12, radius=1, depth=1, location=loc)
    else:
        bpy.ops.mesh.primitive_uv_sphere_add(segments=16, ring_count=8, radius=1, location=loc)
    ob = bpy.context.active_object
    ob.name = name
    ob.scale = scale
    return ob


parts = [
    part("cyl", "torso", (0, 0, 1.25), (0.17, 0.11, 0.55)),
    part("sph", "head", (0, 0, 1.65), (0.10, 0.11, 0.12)),
    part("cyl", "thigh_l", (0.09, 0, 0.72), (0.07, 0.07, 0.42)),
    part("cyl", "shin_l", (0.09, 0, 0.27), (0.055, 0.055, 0.48)),
    part("cyl", "thigh_r", (-0.09, 0, 0.72), (0.07, 0.07, 0.42)),
    part("cyl", "shin_r", (-0.09, 0, 0.27), (0.055, 0.055, 0.48)),
    part("cyl", "arm_l", (0.22, 0, 1.22), (0.045, 0.045, 0.55)),
    part("cyl", "arm_r", (-0.22, 0, 1.22), (0.045, 0.045, 0.55)),
]
bpy.ops.object.select_all(action="DESELECT")
for ob in parts:
    ob.select_set(True)
bpy.context.view_layer.objects.active = parts[0]
bpy.ops.object.transform_apply(location=False, rotation=False, scale=True)
bpy.ops.object.join()
body = bpy.context.active_object
body.name = "Walker"
# UVs from a smart projection, and a generated texture as base colour.
bpy.ops.object.mode_set(mode="EDIT")
bpy.ops.mesh.select_all(action="SELECT")
bpy.ops.uv.smart_project()
bpy.ops.object.mode_set(mode="OBJECT")
image = bpy.data.images.new("cloth", 64, 64)
pixels = []
for y in range(64):
    stripe = (y // 8) % 2
    pixels += ([0.6, 0.15, 0.1, 1.0] if stripe else [0.1, 0.2, 0.55, 1.0]) * 64
image.pixels = pixels
image.pack()
material = bpy.data.materials.new("cloth")
material.use_nodes = True
bsdf = material.node_tree.nodes["Principled BSDF"]
tex = material.node_tree.nodes.new("ShaderNodeTexImage")
tex.image = image
material.node_tree.links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])
bsdf.inputs["Roughness"].default_value = 0.8
body.data.materials.append(material)

# The armature: bones along the limbs.
bpy.ops.object.armature_add(location=(0, 0, 0))
rig = bpy.context.active_object
rig.name = "Armature"
bpy.ops.object.mode_set(mode="EDIT")
bones = rig.data.edit_bones
root = bones[0]
root.name = "hips"
root.head, root.tail = (0, 0, 0.95), (0, 0, 1.1)


def bone(name, head, tail, parent):
    b = bones.new(name)
    b.head, b.tail, b.parent = head, tail, bones[parent]
    return b


bone("spine", (0, 0, 1.1), (0, 0, 1.5), "hips")
bone("head", (0, 0, 1.5), (0, 0, 1.78), "spine")
bone("thigh_l", (0.09, 0, 0.93), (0.09, 0, 0.51), "hips")
bone("shin_l", (0.09, 0, 0.51), (0.09, 0, 0.03), "thigh_l")
bone("thigh_r", (-0.09, 0, 0.93), (-0.09, 0, 0.51), "hips")
bone("shin_r", (-0.09, 0, 0.51), (-0.09, 0, 0.03), "thigh_r")
bone("arm_l", (0.22, 0, 1.48), (0.22, 0, 0.95), "spine")
bone("arm_r", (-0.22, 0, 1.48), (-0.22, 0, 0.95), "spine")
bpy.ops.object.mode_set(mode="OBJECT")
bpy.ops.object.select_all(action="DESELECT")
body.select_set(True)
rig.select_set(True)
bpy.context.view_layer.objects.active = rig
bpy.ops.object.parent_set(type="ARMATURE_AUTO")


# Clips: a 1 s walk in place (a scene gives the speed it was made for, clip_speed_m_s) facing −Y,
# Blender's front, and a 2 s idle sway.
def action(name, frames, keys):
    rig.animation_data_create()
    act = bpy.data.actions.new(name)
    rig.animation_data.action = act
    bpy.ops.object.mode_set(mode="POSE")
    for frame, pose in keys:
        for bname, (rot_x, loc_y) in pose.items():
            pb = rig.pose.bones[bname]
            pb.rotation_mode = "XYZ"
            pb.rotation_euler = (rot_x, 0, 0)
            pb.keyframe_insert("rotation_euler", frame=frame)
            if loc_y is not None:
                pb.location = (0, loc_y, 0)  # the hips bone's local y is the world's up; z its forward
                pb.keyframe_insert("location", frame=frame)
    bpy.ops.object.mode_set(mode="OBJECT")
    track = rig.animation_data.nla_tracks.new()
    track.name = name
    track.strips.new(name, int(keys[0][0]), act)
    rig.animation_data.action = None
    return act


swing = math.radians(28)
walk_keys = []
for frame in range(1, 26, 3):
    phase = 2 * math.pi * (frame - 1) / 24
    s = math.sin(phase)
    walk_keys.append(
        (
            frame,
            {
                "thigh_l": (swing * s, None),
                "thigh_r": (-swing * s, None),
                "shin_l": (max(0.0, -1.1 * math.cos(phase)) * 0.6, None),
                "shin_r": (max(0.0, 1.1 * math.cos(phase)) * 0.6, None),
                "arm_l": (-0.6 * swing * s, None),
                "arm_r": (0.6 * swing * s, None),
                "hips": (0.0, None),
            },
        )
    )
walk = action("Walk", 24, walk_keys)
idle_keys = [(f, {"spine": (0.04 * math.sin(2 * math.pi * (f - 1) / 48), None)}) for f in range(1, 50, 6)]
idle = action("Idle", 48, idle_keys)

bpy.ops.export_scene.gltf(
    filepath=out,
    export_format="GLB",
    export_animations=True,
    export_animation_mode="NLA_TRACKS",
    export_skins=True,
    export_image_format="AUTO",
    export_yup=True,
)
print("wrote", out)

if reference:
    import numpy as np

    # The NLA tracks would mix both clips: evaluate each action alone.
    for track in rig.animation_data.nla_tracks:
        track.mute = True
    arrays = {}
    for act, frames in ((walk, (4, 10, 16, 22)), (idle, (13, 31))):
        for bone in rig.pose.bones:  # a bone the action does not key keeps its last pose otherwise
            bone.location, bone.rotation_euler, bone.scale = (0, 0, 0), (0, 0, 0), (1, 1, 1)
            bone.rotation_quaternion = (1, 0, 0, 0)
        rig.animation_data.action = act
        for frame in frames:
            scene.frame_set(frame)
            depsgraph = bpy.context.evaluated_depsgraph_get()
            evaluated = body.evaluated_get(depsgraph)
            mesh = evaluated.to_mesh()
            matrix = np.array(evaluated.matrix_world)
            points = np.array([tuple(v.co) for v in mesh.vertices])
            arrays[f"{act.name}_{frame}"] = (points @ matrix[:3, :3].T + matrix[:3, 3]).astype(np.float32)
            evaluated.to_mesh_clear()
    rig.animation_data.action = None
    rest = np.array([tuple(v.co) for v in body.data.vertices])
    arrays["rest"] = rest @ np.array(body.matrix_world)[:3, :3].T + np.array(body.matrix_world)[:3, 3]
    arrays["fps"] = np.array(scene.render.fps)
    np.savez_compressed(reference, **arrays)
    print("wrote", reference)
