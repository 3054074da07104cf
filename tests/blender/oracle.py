"""What the Blender tests compare against, independent of tagsplat and of the add-on: PC2 and
OBJ written and read with struct and numpy, and Blender's own evaluated mesh."""

import os
import struct

import numpy as np

PC2_HEADER = struct.Struct("<12siiffi")

# Blender's reading of a Y-up file (its OBJ and glTF importers' and the add-on's documented
# one): file (x, y, z) is Blender (x, -z, y). A Z-up file is kept.
TO_BLENDER = {
    "Y": lambda p: np.stack([p[..., 0], -p[..., 2], p[..., 1]], axis=-1),
    "Z": lambda p: p,
}


def read_pc2(path):
    """The samples of a PC2 file as (T, V, 3) float32, checked against its header."""
    with open(path, "rb") as f:
        data = f.read()
    signature, version, points, _start, _rate, samples = PC2_HEADER.unpack_from(data)
    assert signature == b"POINTCACHE2\0" and version == 1, f"{path}: not a PC2 v1 file"
    body = np.frombuffer(data, dtype="<f4", offset=PC2_HEADER.size)
    assert body.size == samples * points * 3, f"{path}: {body.size} floats for {samples}×{points}"
    return body.reshape(samples, points, 3).astype(np.float32)


def write_pc2(path, positions):
    """``positions`` (T, V, 3) as a PC2 file: start frame 0, one sample per frame."""
    positions = np.ascontiguousarray(positions, dtype="<f4")
    with open(path, "wb") as f:
        f.write(PC2_HEADER.pack(b"POINTCACHE2\0", 1, positions.shape[1], 0.0, 1.0, len(positions)))
        f.write(positions.tobytes())


def write_obj(path, faces, positions):
    """A triangle OBJ; ``%.9g`` prints every float32 so that it reads back to the same value."""
    with open(path, "w") as f:
        f.writelines(f"v {x:.9g} {y:.9g} {z:.9g}\n" for x, y, z in positions)
        f.writelines(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in faces)


def deforming_grid(frames=6, nx=5, ny=4):
    """A small Y-up sheet bending over ``frames`` frames: faces (F, 3), positions (T, V, 3).
    No coordinate is symmetric under the axis turn, so a wrong turn cannot pass."""
    x, z = np.meshgrid(np.linspace(-1.0, 1.5, nx), np.linspace(-0.5, 2.0, ny))
    base = np.stack([x.ravel(), 0.3 + 0.1 * x.ravel(), z.ravel()], axis=1)
    t = np.arange(frames)[:, None]
    positions = np.repeat(base[None], frames, axis=0)
    positions[..., 1] += 0.2 * np.sin(0.7 * t + base[:, 0])
    positions[..., 0] += 0.05 * t
    positions[..., 2] -= 0.03 * t * base[:, 0]
    quads = [(j * nx + i, j * nx + i + 1, (j + 1) * nx + i + 1, (j + 1) * nx + i)
             for j in range(ny - 1) for i in range(nx - 1)]
    faces = np.array([tri for a, b, c, d in quads for tri in ((a, b, c), (a, c, d))], dtype=np.uint32)
    return faces, positions.astype(np.float32)


def write_obj_pc2(folder, name, faces, positions):
    """``folder/name.obj`` (frame 0) + ``folder/name.pc2``; returns the .pc2's path."""
    os.makedirs(folder, exist_ok=True)
    write_obj(os.path.join(folder, name + ".obj"), faces, positions[0])
    write_pc2(os.path.join(folder, name + ".pc2"), positions)
    return os.path.join(folder, name + ".pc2")


def write_obj_folder(folder, faces, positions):
    """One OBJ per frame, ``frame_000000.obj``, …, in ``folder``; returns the folder."""
    os.makedirs(folder, exist_ok=True)
    for t, frame in enumerate(positions):
        write_obj(os.path.join(folder, f"frame_{t:06d}.obj"), faces, frame)
    return folder


def evaluated_positions(bpy, obj, frame, subframe=0.0):
    """``obj``'s vertex positions (V, 3), object space, as Blender evaluates them (modifiers
    applied) at scene frame ``frame`` + ``subframe``."""
    bpy.context.scene.frame_set(frame, subframe=subframe)
    evaluated = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    mesh = evaluated.to_mesh()
    try:
        co = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
        mesh.vertices.foreach_get("co", co)
    finally:
        evaluated.to_mesh_clear()
    return co.reshape(-1, 3)


def evaluated_world(bpy, obj, frame):
    """``obj``'s evaluated vertex positions (V, 3) in world space at scene frame ``frame`` (a
    float: its whole part is the frame, the rest the subframe), float64."""
    whole = int(np.floor(frame + 1e-9))
    local = evaluated_positions(bpy, obj, whole, max(0.0, frame - whole)).astype(np.float64)
    world = np.array(obj.evaluated_get(bpy.context.evaluated_depsgraph_get()).matrix_world)
    return local @ world[:3, :3].T + world[:3, 3]


def export_fbx(bpy, path, all_actions):
    """Exports the armatures and meshes of the scene to ``path`` with Blender's FBX exporter,
    +Y up and -Z forward in centimetres (FBX_SCALE_NONE), every frame baked; each action as a
    stack of its own when ``all_actions``, else the active one only."""
    result = bpy.ops.export_scene.fbx(
        filepath=path, object_types={"ARMATURE", "MESH"}, axis_forward="-Z", axis_up="Y",
        apply_unit_scale=True, apply_scale_options="FBX_SCALE_NONE", bake_space_transform=False,
        add_leaf_bones=False, use_mesh_modifiers=False, bake_anim=True,
        bake_anim_use_all_bones=True, bake_anim_use_nla_strips=False,
        bake_anim_use_all_actions=all_actions, bake_anim_force_startend_keying=True,
        bake_anim_step=1.0, bake_anim_simplify_factor=0.0)
    assert result == {"FINISHED"}
    return path
