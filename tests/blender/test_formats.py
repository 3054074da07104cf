"""The Khronos Fox's Run as Blender exports it, in each format Blender writes (skinned glTF,
FBX with a baked animation, MDD and OBJ + PC2 with their base OBJ, an OBJ sequence), read
back by ``tagsplat track``: every frame-0 vertex, tracked through every frame, must stay within
1e-5 of the figure's size (its frame-0 bounding-box diagonal) of Blender's own evaluated vertex.

Each exporter is given explicit axis options, and the test knows where each puts Blender's
world: glTF and FBX are +Y up (Blender's (x, y, z) is the file's (x, z, -y)), FBX in
centimetres (Blender's FBX_SCALE_NONE writes metres x 100); MDD, PC2 and OBJ keep Blender's
+Z-up axes and its units. The scene runs frames 0-27 at 24 fps, so every format's frame k is
Blender's frame k at k / 24 s.
"""

import csv
import os
import subprocess

import addon_utils
import bpy
import numpy as np

import oracle

HERE = os.path.dirname(os.path.abspath(__file__))
FOX = os.path.join(HERE, "..", "formats", "data", "khronos", "Fox.glb")
ACTION = "Run_root"
FRAMES = range(0, 28)
FPS = 24
TARGET = 1e-5


def y_up(scale):
    """Blender world -> a +Y-up file in units of 1/``scale`` m, and back."""
    to_file = lambda p: scale * np.stack([p[..., 0], p[..., 2], -p[..., 1]], axis=-1)
    return to_file, lambda p: oracle.TO_BLENDER["Y"](p) / scale


KEEP = (lambda p: p, lambda p: p)


def import_fox(env):
    """The Fox with Run as its armature's only action, frames 0-27 at 24 fps; the mesh object.
    Blender 3.4's glTF importer still calls numpy's removed ``np.bool`` (Debian's numpy 1.24),
    so the alias is restored for it."""
    if not os.path.isfile(FOX):
        env.skip(f"the Khronos Fox ({os.path.normpath(FOX)}) is missing")
    if not hasattr(np, "bool"):
        np.bool = bool
    assert bpy.ops.import_scene.gltf(filepath=FOX) == {"FINISHED"}
    mesh = next(o for o in bpy.data.objects if o.type == "MESH")
    armature = mesh.find_armature()
    for track in list(armature.animation_data.nla_tracks):
        armature.animation_data.nla_tracks.remove(track)
    armature.animation_data.action = bpy.data.actions[ACTION]
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = FRAMES[0], FRAMES[-1]
    scene.render.fps, scene.render.fps_base = FPS, 1.0
    bpy.ops.object.select_all(action="DESELECT")
    mesh.select_set(True)
    bpy.context.view_layer.objects.active = mesh
    return mesh


def blender_frames(mesh):
    """Blender's evaluated vertices of every frame, world space: (T, V, 3)."""
    world = np.array(mesh.matrix_world)
    frames = []
    for frame in FRAMES:
        local = oracle.evaluated_positions(bpy, mesh, frame).astype(np.float64)
        frames.append(local @ world[:3, :3].T + world[:3, 3])
    return np.stack(frames)


def obj(path, animation=False):
    """The selected mesh as Blender's OBJ exporter writes it in Blender's axes (+Z up, +Y
    forward), modifiers applied: one file, or with ``animation`` one per frame."""
    result = bpy.ops.wm.obj_export(
        filepath=path, export_animation=animation, start_frame=FRAMES[0], end_frame=FRAMES[-1],
        forward_axis="Y", up_axis="Z", apply_modifiers=True, export_selected_objects=True,
        export_uv=False, export_normals=False, export_materials=False,
        export_triangulated_mesh=False)
    assert result == {"FINISHED"}, path


def export_glb(work):
    path = os.path.join(work, "fox.glb")
    bpy.context.scene.frame_set(FRAMES[0])
    result = bpy.ops.export_scene.gltf(
        filepath=path, export_format="GLB", export_yup=True, export_skins=True,
        export_animations=True, export_frame_range=True, export_force_sampling=True,
        export_nla_strips=False, export_optimize_animation_size=False, export_materials="NONE",
        use_selection=False)
    assert result == {"FINISHED"}
    return path


def export_fbx(work):
    return oracle.export_fbx(bpy, os.path.join(work, "fox.fbx"), all_actions=False)


def export_mdd(work):
    path = os.path.join(work, "fox.mdd")
    bpy.context.scene.frame_set(FRAMES[0])
    obj(os.path.join(work, "fox.obj"))
    result = bpy.ops.export_shape.mdd(
        filepath=path, fps=FPS, frame_start=FRAMES[0], frame_end=FRAMES[-1],
        use_rest_frame=False)
    assert result == {"FINISHED"}
    return path


def export_pc2(work):
    path = os.path.join(work, "fox.pc2")
    bpy.context.scene.frame_set(FRAMES[0])
    obj(os.path.join(work, "fox.obj"))
    result = bpy.ops.export_shape.pc2(
        filepath=path, rot_x90=False, world_space=True, apply_modifiers=True,
        range_start=FRAMES[0], range_end=FRAMES[-1], sampling="1")
    assert result == {"FINISHED"}
    return path


def export_obj_sequence(work):
    folder = os.path.join(work, "frames")
    os.makedirs(folder)
    obj(os.path.join(folder, "fox.obj"), animation=True)
    return folder


# name, exporter, (Blender world -> file, file -> Blender world), add-on it needs
FORMATS = [
    ("skinned glTF", export_glb, y_up(1.0), None),
    ("FBX", export_fbx, y_up(100.0), None),
    ("MDD + OBJ", export_mdd, KEEP, "io_shape_mdd"),
    ("OBJ + PC2", export_pc2, KEEP, "io_export_pc2"),
    ("OBJ sequence", export_obj_sequence, KEEP, None),
]


def write_points(path, positions):
    with open(path, "w") as f:
        f.write("id,x,y,z\n")
        f.writelines(f"v{i},{x!r},{y!r},{z!r}\n" for i, (x, y, z) in enumerate(positions))


def read_tracks(path, points, frames):
    """tracks.csv as (T, V, 3), every (point, frame) present exactly once."""
    tracks = np.full((frames, points, 3), np.nan)
    with open(path) as f:
        for row in csv.DictReader(line for line in f if not line.startswith("#")):
            t, v = int(row["frame"]), int(row["id"][1:])
            assert np.isnan(tracks[t, v, 0]), f"{path}: v{v} frame {t} twice"
            tracks[t, v] = [float(row[c]) for c in "xyz"]
    assert not np.isnan(tracks).any(), f"{path}: not every point has every frame"
    return tracks


def track_error(cli, work, sequence, to_file, to_blender, expected):
    """Tracks ``expected[0]`` (in the file's axes) through ``sequence`` with the CLI, in
    ``work``; the largest distance from Blender's vertex, absolute and as a fraction of the
    size, and the size."""
    points, out = os.path.join(work, "points.csv"), os.path.join(work, "tracks.csv")
    write_points(points, to_file(expected[0]))
    run = subprocess.run(
        [cli, "track", "--sequence", sequence, "--points", points, "--out", out, "--strict"],
        capture_output=True, text=True)
    assert run.returncode == 0, f"tagsplat track failed:\n{run.stdout}{run.stderr}"
    tracks = to_blender(read_tracks(out, expected.shape[1], expected.shape[0]))
    size = float(np.linalg.norm(expected[0].max(axis=0) - expected[0].min(axis=0)))
    error = float(np.linalg.norm(tracks - expected, axis=-1).max())
    return error, error / size, size


def test_every_exported_format_tracks_blenders_own_vertices(env):
    cli = env.require_cli()
    mesh = import_fox(env)
    expected = blender_frames(mesh)
    failures = []
    for name, export, (to_file, to_blender), addon in FORMATS:
        if addon:
            addon_utils.enable(addon, default_set=True, handle_error=None)
        work = os.path.join(env.work, name.replace(" ", "_").replace("+", "and"))
        os.makedirs(work)
        try:
            sequence = export(work)
            error, fraction, size = track_error(cli, work, sequence, to_file, to_blender, expected)
        except AssertionError as e:
            print(f"formats: {name}: {e}", flush=True)
            failures.append(f"{name} (failed)")
            continue
        print(f"formats: {name}: max error {fraction:.2e} of the size ({error:.2e} Blender units, "
              f"size {size:.4g}), {expected.shape[1]} vertices x {expected.shape[0]} frames",
              flush=True)
        if not fraction <= TARGET:
            failures.append(f"{name} {fraction:.2e}")
    assert not failures, f"beyond {TARGET} of the size: {', '.join(failures)}"
