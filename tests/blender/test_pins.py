"""Pins: the GLB of animated empties ``tagsplat track --glb`` writes, imported by Blender's own
glTF importer. Each point becomes an empty named by its id whose world position and rotation at
every frame are the tracks CSV's (turned from glTF's +Y up to Blender's +Z up, as the importer
turns them), and whose rotation is the one Blender's three-vertex parent gives a child of the
bound triangle (an independent implementation of the orientation frame)."""

import csv
import json
import os
import subprocess

import bpy
import numpy as np
from mathutils import Matrix

import oracle

# glTF (+Y up) to Blender (+Z up), as the importer turns every node: (x, y, z) -> (x, -z, y).
Y_UP_TO_Z_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])


def tracked_sheet(env, frames=5):
    """Tracks a few points of the oracle's bending sheet with the CLI; returns the faces, the
    positions (T, V, 3), the CSV rows by id, the JSON report and the GLB's path."""
    cli = env.require_cli()
    faces, positions = oracle.deforming_grid(frames=frames)
    pc2 = oracle.write_obj_pc2(env.work, "sheet", faces, positions)
    # Two vertices and two points inside triangles (their corners' mean), by frame-0 position.
    inside = [positions[0][faces[f]].astype(np.float64).mean(axis=0) for f in (3, 14)]
    queries = [("v0", positions[0][0]), ("v7", positions[0][7]), ("f3", inside[0]), ("f14", inside[1])]
    points = os.path.join(env.work, "points.csv")
    with open(points, "w") as f:
        f.write("id,x,y,z\n")
        for name, p in queries:
            f.write(f"{name},{','.join(repr(float(c)) for c in p)}\n")
    out, report, glb = (os.path.join(env.work, n) for n in ("tracks.csv", "tracks.json", "pins.glb"))
    subprocess.run([cli, "track", "--sequence", pc2, "--points", points, "--out", out,
                    "--json", report, "--glb", glb], check=True)
    rows = {}
    with open(out) as f:
        for r in csv.DictReader(f):
            rows.setdefault(r["id"], []).append(r)
    with open(report) as f:
        report = json.load(f)
    assert sorted(rows) == sorted(name for name, _ in queries)
    return faces, positions, rows, report, glb


def frame_matrix(row):
    """The CSV row's orientation as a rotation matrix: columns tangent, normal × tangent,
    normal."""
    n = np.array([float(row[k]) for k in ("nx", "ny", "nz")])
    t = np.array([float(row[k]) for k in ("tx", "ty", "tz")])
    return np.column_stack([t, np.cross(n, t), n])


def test_pins_import_as_empties_on_the_tracks_at_every_frame(env):
    _, _, rows, _, glb = tracked_sheet(env)
    assert bpy.ops.import_scene.gltf(filepath=glb) == {"FINISHED"}
    scene = bpy.context.scene
    fps = float(rows["v0"][0]["fps"])
    assert scene.render.fps / scene.render.fps_base == fps, "the importer keys at the scene rate"
    worst_position = worst_rotation = 0.0
    for name, track in rows.items():
        empty = bpy.data.objects[name]
        assert empty.type == "EMPTY", f"{name} is a {empty.type}"
        for row in track:
            scene.frame_set(int(round(float(row["start_frame"]))) + int(row["frame"]))
            world = np.array(empty.matrix_world)
            position = Y_UP_TO_Z_UP @ np.array([float(row[k]) for k in "xyz"])
            rotation = Y_UP_TO_Z_UP @ frame_matrix(row)
            worst_position = max(worst_position, float(np.abs(world[:3, 3] - position).max()))
            worst_rotation = max(worst_rotation, float(np.abs(world[:3, :3] - rotation).max()))
    print(f"pins: largest position difference {worst_position:.3g}, rotation {worst_rotation:.3g}")
    assert worst_position <= 1e-6, worst_position
    assert worst_rotation <= 1e-5, worst_rotation


def test_pin_rotations_are_blenders_three_vertex_parent(env):
    faces, positions, rows, report, _ = tracked_sheet(env)
    mesh = bpy.data.meshes.new("sheet")
    mesh.from_pydata(positions[0].tolist(), [], faces.tolist())
    sheet = bpy.data.objects.new("sheet", mesh)
    bpy.context.collection.objects.link(sheet)
    children = {}
    for point in report["points"]:
        child = bpy.data.objects.new(f"parented {point['id']}", None)
        bpy.context.collection.objects.link(child)
        child.parent = sheet
        child.parent_type = "VERTEX_3"
        child.parent_vertices = [int(v) for v in faces[point["face"]]]
        child.matrix_parent_inverse = Matrix.Identity(4)
        children[point["id"]] = child
    worst = 0.0
    for t, frame in enumerate(positions):
        mesh.vertices.foreach_set("co", frame.astype(np.float32).ravel())
        mesh.update()
        bpy.context.view_layer.update()
        for name, child in children.items():
            rotation = np.array(child.matrix_world)[:3, :3]
            worst = max(worst, float(np.abs(rotation - frame_matrix(rows[name][t])).max()))
    print(f"three-vertex parent: largest rotation difference {worst:.3g}")
    assert worst <= 1e-5, worst
