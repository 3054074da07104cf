"""Writes the small Blender-made fixtures of tests/formats/data/blender/ and Blender's own numbers for
them, once (their output is committed):

    blender -b --factory-startup --python-exit-code 1 --python tests/blender/make_fixtures.py

The scene: ``Strip``, a 10-vertex strip of two quads and a hexagon, moved and turned, skinned
to a two-bone armature (the second bone bends) with a shape key ``Bulge`` whose value rises;
and ``Prop``, an unskinned triangle whose object moves. Frames 1-5 at 24 fps.

- ``strip.fbx``: Blender's FBX exporter, +Y up, -Z forward, FBX_SCALE_NONE (centimetres),
  the animation baked at every frame, one stack.
- ``strip.mdd`` + ``strip.obj``: the strip by io_shape_mdd (with its "Rest Frame": one extra
  first frame) and its base mesh by Blender's OBJ exporter, both in Blender's axes.
- ``strip.json``: Blender's evaluated world-space vertices of each object at frames 1-5, in
  each file's axes and units, the polygons of each mesh, and the times.
"""

import json
import os

import addon_utils
import bpy
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.path.join(HERE, "..", "formats", "data", "blender")
FRAMES = range(1, 6)
FPS = 24


def strip_mesh():
    """The strip: vertices 0-4 along the bottom, 5-9 along the top; two quads, one hexagon."""
    mesh = bpy.data.meshes.new("Strip")
    verts = [(x, 0.0, 0.0) for x in range(5)] + [(x, 0.0, 1.0) for x in range(5)]
    faces = [(0, 1, 6, 5), (1, 2, 7, 6), (2, 3, 4, 9, 8, 7)]
    mesh.from_pydata([(x * 0.5, y, z * 0.6) for x, y, z in verts], [], faces)
    return mesh


def build_scene():
    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = FRAMES[0], FRAMES[-1]
    scene.render.fps, scene.render.fps_base = FPS, 1.0
    armature_data = bpy.data.armatures.new("Rig")
    rig = bpy.data.objects.new("Rig", armature_data)
    scene.collection.objects.link(rig)
    rig.location = (0.2, -0.1, 0.3)
    bpy.context.view_layer.objects.active = rig
    bpy.ops.object.mode_set(mode="EDIT")
    root = armature_data.edit_bones.new("Root")
    root.head, root.tail = (0.0, 0.0, 0.3), (1.0, 0.0, 0.3)
    tip = armature_data.edit_bones.new("Tip")
    tip.head, tip.tail, tip.parent = (1.0, 0.0, 0.3), (2.0, 0.0, 0.3), root
    bpy.ops.object.mode_set(mode="OBJECT")

    strip = bpy.data.objects.new("Strip", strip_mesh())
    scene.collection.objects.link(strip)
    strip.parent = rig
    strip.location, strip.rotation_euler = (0.1, 0.2, 0.0), (0.0, 0.0, 0.3)
    for bone in ("Root", "Tip"):
        group = strip.vertex_groups.new(name=bone)
        for v in strip.data.vertices:
            # Local x runs 0-2: Root's weight falls from 1 to 0 over it, Tip's rises.
            w = min(max(v.co.x / 2.0, 0.0), 1.0)
            group.add([v.index], w if bone == "Tip" else 1.0 - w, "REPLACE")
    strip.modifiers.new("Armature", "ARMATURE").object = rig
    strip.shape_key_add(name="Basis")
    bulge = strip.shape_key_add(name="Bulge")
    for i in (1, 2, 3, 6, 7, 8):
        bulge.data[i].co.y += 0.25 + 0.05 * i
    for frame, value in ((1, 0.0), (5, 1.0)):
        bulge.value = value
        bulge.keyframe_insert("value", frame=frame)

    tip_pose = rig.pose.bones["Tip"]
    tip_pose.rotation_mode = "XYZ"
    for frame, angle in ((1, 0.0), (3, 0.4), (5, 0.9)):
        tip_pose.rotation_euler = (0.0, angle, 0.2 * angle)
        tip_pose.keyframe_insert("rotation_euler", frame=frame)

    prop_mesh = bpy.data.meshes.new("Prop")
    prop_mesh.from_pydata([(0.0, 0.0, 0.0), (0.3, 0.0, 0.0), (0.0, 0.4, 0.1)], [], [(0, 1, 2)])
    prop = bpy.data.objects.new("Prop", prop_mesh)
    scene.collection.objects.link(prop)
    for frame, x in ((1, -1.0), (5, -0.5)):
        prop.location = (x, 0.5, 0.25 * frame)
        prop.rotation_euler = (0.1 * frame, 0.0, 0.0)
        prop.keyframe_insert("location", frame=frame)
        prop.keyframe_insert("rotation_euler", frame=frame)
    return strip, prop


def evaluated(obj, frame):
    """``obj``'s evaluated vertices at ``frame``, world space, float64 (V, 3)."""
    bpy.context.scene.frame_set(frame)
    ev = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    mesh = ev.to_mesh()
    co = np.empty(len(mesh.vertices) * 3)
    mesh.vertices.foreach_get("co", co)
    ev.to_mesh_clear()
    world = np.array(obj.matrix_world)
    return co.reshape(-1, 3) @ world[:3, :3].T + world[:3, 3]


def fbx_axes(p):
    """Blender world -> the FBX file's +Y-up centimetres."""
    return 100.0 * np.stack([p[..., 0], p[..., 2], -p[..., 1]], axis=-1)


def main():
    strip, prop = build_scene()
    os.makedirs(DATA, exist_ok=True)
    fbx = os.path.join(DATA, "strip.fbx")
    assert bpy.ops.export_scene.fbx(
        filepath=fbx, object_types={"ARMATURE", "MESH"}, axis_forward="-Z", axis_up="Y",
        apply_unit_scale=True, apply_scale_options="FBX_SCALE_NONE", bake_space_transform=False,
        add_leaf_bones=False, use_mesh_modifiers=False, bake_anim=True,
        bake_anim_use_all_bones=True, bake_anim_use_nla_strips=False,
        bake_anim_use_all_actions=False, bake_anim_force_startend_keying=True,
        bake_anim_step=1.0, bake_anim_simplify_factor=0.0, use_metadata=False,
    ) == {"FINISHED"}

    addon_utils.enable("io_shape_mdd", default_set=True, handle_error=None)
    bpy.ops.object.select_all(action="DESELECT")
    strip.select_set(True)
    bpy.context.view_layer.objects.active = strip
    bpy.context.scene.frame_set(FRAMES[0])
    assert bpy.ops.wm.obj_export(
        filepath=os.path.join(DATA, "strip.obj"), forward_axis="Y", up_axis="Z",
        apply_modifiers=True, export_selected_objects=True, export_uv=False,
        export_normals=False, export_materials=False, export_triangulated_mesh=False,
    ) == {"FINISHED"}
    assert bpy.ops.export_shape.mdd(
        filepath=os.path.join(DATA, "strip.mdd"), fps=FPS, frame_start=FRAMES[0],
        frame_end=FRAMES[-1], use_rest_frame=True,
    ) == {"FINISHED"}

    blender = {o.name: np.stack([evaluated(o, f) for f in FRAMES]) for o in (strip, prop)}
    polygons = lambda o: [list(p.vertices) for p in o.data.polygons]
    numbers = {
        "made_by": "tests/blender/make_fixtures.py, Blender " + bpy.app.version_string,
        "times": [f / FPS for f in FRAMES],
        "fbx": {
            "up": "+y",
            "meters_per_unit": 0.01,
            "meshes": {
                name: {"polygons": polygons(bpy.data.objects[name]),
                       "frames": fbx_axes(frames).tolist()}
                for name, frames in blender.items()
            },
        },
        "mdd": {
            "note": "io_shape_mdd with Rest Frame: frame 0 repeats frame 1 (Blender frame 1)",
            "times": [k / FPS for k in range(len(FRAMES) + 1)],
            "frames": np.concatenate([blender["Strip"][:1], blender["Strip"]]).tolist(),
        },
    }
    with open(os.path.join(DATA, "strip.json"), "w") as f:
        json.dump(numbers, f, indent=1)
        f.write("\n")
    for name in ("strip.fbx", "strip.mdd", "strip.obj", "strip.json"):
        print(name, os.path.getsize(os.path.join(DATA, name)), "bytes")


main()
