"""glTF morph targets, parent chains and the three sampler interpolations, and FBX animation
stacks, each in a small scene built here, exported by Blender 3.4's own exporters and read back
by ``tagsplat convert`` (to a PC2): every vertex of every sample must lie within 1e-5 of the
figure's size (its first sample's bounding-box diagonal) of Blender's evaluated vertex at the
same time, in world space.

- Morph targets: three shape keys with animated values, written as a glTF ``weights``
  animation, once as Blender's LINEAR keys (sampled at four times their rate, so the blend
  between keys is tested) and once sampled by the exporter at every frame.
- Parent chains: a mesh under three animated empties (location, Euler rotation, non-uniform
  scale, so the chain shears), and a skinned mesh whose armature sits under an animated empty.
  Blender writes the skinned mesh as a child of the armature's node and leaves its transform
  identity; the glTF specification ignores that transform, so the animated empty reaches the
  mesh only through the joints.
- Samplers: with sampling off (``export_force_sampling=False``) Blender writes its keys as they
  are: CONSTANT as STEP, LINEAR as LINEAR and BEZIER as CUBICSPLINE, the tangents being the
  slopes of the key's handles. A Bezier segment whose handles sit a third of the way along the
  interval in time is the glTF Hermite spline exactly, so the handles are set there (FREE, with
  seeded slopes) and Blender's evaluation is the specification's value. The test checks that
  premise on every CUBICSPLINE channel against the specification's Hermite evaluated in numpy
  from the file's own accessors (2.8e-7 apart). Rotations are keyed as quaternions: Blender
  interpolates each component and normalises, as CUBICSPLINE does, but their handles are flat
  (tangents 0): Blender's exporter normalises the point one frame along a handle before
  differencing it with the key, so a sloped quaternion handle is written as another tangent
  (with sloped quaternion handles the premise check fails, 2.0e-2 apart in normalised
  components, measured once), an approximation of the exporter's. The LINEAR parent is keyed
  in location and scale only: Blender blends rotation keys component by component where glTF
  slerps (tests/blender/test_gltf_fox.py bounds that difference). The file is asserted to hold
  the three interpolations, and it is sampled at 96 per second, four times the frame rate, so
  most samples fall between keys.
- FBX: one file holding two armature actions as two animation stacks
  (``bake_anim_use_all_actions``): without ``--animation`` the reader must refuse and name both;
  with ``--animation NAME`` each must match Blender playing that action. Blender writes each
  stack from 0 s, so the stack's frame k is its action's first frame + k.

FBX point caches are not tested: Blender's FBX exporter cannot write one (its MDD and PC2
exporters write separate files, which tests/blender/test_formats.py covers).

Blender writes glTF +Y up: Blender (x, y, z) is the file's (x, z, -y); its FBX here is +Y up in
centimetres. The scenes run at 24 frames per second and a key at Blender frame f is at f / 24 s.
"""

import json
import os
import subprocess

import bpy
import numpy as np
from mathutils import Quaternion, Vector

import oracle

FPS = 24
TARGET = 1e-5


def cli_samples(env, sequence, *options):
    """``tagsplat convert --sequence SEQUENCE --to .pc2 OPTIONS``: the samples (T, V, 3) in the
    file's axes, as float64."""
    pc2 = os.path.join(env.work, os.path.basename(sequence) + ".pc2")
    command = [env.require_cli(), "convert", "--sequence", sequence, "--to", pc2, *options]
    done = subprocess.run(command, capture_output=True, text=True)
    assert done.returncode == 0, f"{' '.join(command)} failed:\n{done.stderr}"
    print(done.stderr.strip(), flush=True)
    return oracle.read_pc2(pc2).astype(np.float64)


def compare(name, ours, obj, frames):
    """Prints, and holds to TARGET of the size, the largest distance of ``ours`` (T, V, 3,
    Blender's axes and units) from ``obj``'s evaluated vertices at ``frames`` (T scene frames),
    the size being their first sample's bounding-box diagonal. Vertices are
    paired by their nearest neighbour in the first sample, and every one of Blender's must be
    someone's pair (an exporter may split vertices, never drop them)."""
    assert len(ours) == len(frames), f"{name}: {len(ours)} samples, expected {len(frames)}"
    first = oracle.evaluated_world(bpy, obj, frames[0])
    size = float(np.linalg.norm(first.max(axis=0) - first.min(axis=0)))
    distance = np.linalg.norm(ours[0][:, None, :] - first[None, :, :], axis=2)
    pair = distance.argmin(axis=1)
    far = float(distance.min(axis=1).max()) / size
    assert len(set(pair)) == len(first), (
        f"{name}: {len(set(pair))} of {len(first)} vertices paired in the first sample "
        f"(the farthest pair {far:.2e} of the size apart)")
    error = max(
        float(np.linalg.norm(sample - oracle.evaluated_world(bpy, obj, frame)[pair], axis=1).max())
        for sample, frame in zip(ours, frames)
    )
    print(f"{name}: {len(ours)} samples x {len(ours[0])} vertices (Blender {len(first)}), "
          f"size {size:.4g}: max error {error:.3e} ({error / size:.2e} of the size)", flush=True)
    assert error <= TARGET * size, f"{name}: {error / size:.2e} of the size, beyond {TARGET}"


def sample_frames(first_frame, last_frame, rate):
    """The scene frames of samples at ``rate`` per second from ``first_frame`` to
    ``last_frame``: what the reader samples between the first and the last key."""
    count = int(np.floor((last_frame - first_frame) / FPS * rate + 1e-6)) + 1
    return [first_frame + k * FPS / rate for k in range(count)]


def export_gltf(env, name, sampled):
    """The scene as a .gltf (JSON beside its .bin) in +Y up, every object, animations merged
    into one; ``sampled`` bakes every frame, else the keys are written as they are. Returns the
    path and the JSON."""
    path = os.path.join(env.work, name + ".gltf")
    result = bpy.ops.export_scene.gltf(
        filepath=path, export_format="GLTF_SEPARATE", export_yup=True, export_skins=True,
        export_animations=True, export_frame_range=True, export_force_sampling=sampled,
        export_nla_strips=False, export_optimize_animation_size=False, export_materials="NONE",
        export_normals=False, export_texcoords=False, export_morph=True,
        export_morph_normal=False, use_selection=False)
    assert result == {"FINISHED"}, path
    with open(path) as f:
        return path, json.load(f)


def interpolations(document):
    """{(node name, path): interpolation} of every channel of the file's animations."""
    found = {}
    for animation in document["animations"]:
        for channel in animation["channels"]:
            node = document["nodes"][channel["target"]["node"]]["name"]
            sampler = animation["samplers"][channel["sampler"]]
            found[(node, channel["target"]["path"])] = sampler.get("interpolation", "LINEAR")
    return found


def accessor(document, folder, index):
    """Float accessor ``index`` of a .gltf whose buffers lie in ``folder``, (count, width)
    float64; tightly packed, as Blender writes them."""
    spec = document["accessors"][index]
    view = document["bufferViews"][spec["bufferView"]]
    width = {"SCALAR": 1, "VEC3": 3, "VEC4": 4}[spec["type"]]
    assert spec["componentType"] == 5126 and view.get("byteStride", 4 * width) == 4 * width, spec
    with open(os.path.join(folder, document["buffers"][view["buffer"]]["uri"]), "rb") as f:
        data = f.read()
    start = view.get("byteOffset", 0) + spec.get("byteOffset", 0)
    values = np.frombuffer(data, "<f4", spec["count"] * width, start)
    return values.reshape(spec["count"], width).astype(np.float64)


def spec_cubic(times, keys, t):
    """The glTF specification's CUBICSPLINE value at ``t`` seconds (between the first and the
    last key) of ``keys`` (K, 3, width: in-tangent, value, out-tangent) at ``times`` (K)."""
    k = int(np.clip(np.searchsorted(times, t, side="right") - 1, 0, len(times) - 2))
    td = times[k + 1] - times[k]
    s = (t - times[k]) / td
    return ((2 * s**3 - 3 * s**2 + 1) * keys[k, 1] + td * (s**3 - 2 * s**2 + s) * keys[k, 2]
            + (-2 * s**3 + 3 * s**2) * keys[k + 1, 1] + td * (s**3 - s**2) * keys[k + 1, 0])


# Blender's value of an animated property turned into the glTF node's (+Y up), by path.
GLTF_VALUE = {
    "translation": lambda v: np.array([v[0], v[2], -v[1]]),
    "scale": lambda v: np.array([v[0], v[2], v[1]]),
    "rotation": lambda q: np.array([q[1], q[3], -q[2], q[0]]) / np.linalg.norm(q),
    "weights": np.array,
}
BLENDER_PATH = {"translation": "location", "scale": "scale", "rotation": "rotation_quaternion"}


def cubic_channels_follow_blender(document, folder, obj, frames):
    """The largest difference, over ``frames``, between the specification's Hermite evaluated
    in numpy from the file's accessors and Blender's own curves of ``obj``, for every
    CUBICSPLINE channel that targets ``obj``'s node: whether Blender's evaluation is the
    specification's value, the premise of comparing the reader with Blender."""
    worst = 0.0
    for animation in document["animations"]:
        for channel in animation["channels"]:
            sampler = animation["samplers"][channel["sampler"]]
            node = document["nodes"][channel["target"]["node"]]
            if sampler.get("interpolation") != "CUBICSPLINE" or node["name"] != obj.name:
                continue
            path = channel["target"]["path"]
            times = accessor(document, folder, sampler["input"])[:, 0]
            curves = (obj.data.shape_keys.animation_data.action.fcurves if path == "weights" else
                      [c for c in obj.animation_data.action.fcurves if c.data_path == BLENDER_PATH[path]])
            keys = accessor(document, folder, sampler["output"]).reshape(len(times), 3, len(curves))
            for frame in frames:
                ours = spec_cubic(times, keys, frame / FPS)
                if path == "rotation":
                    ours = ours / np.linalg.norm(ours)
                theirs = GLTF_VALUE[path]([c.evaluate(frame) for c in curves])
                worst = max(worst, float(np.abs(ours - theirs).max()))
    return worst


def to_blender(samples):
    """Samples in a Blender-written glTF's axes, turned into Blender's."""
    return oracle.TO_BLENDER["Y"](samples)


def grid(name, x, y):
    """A ``x`` × ``y``-vertex grid mesh object named ``name``, bent so that no two vertices of
    it, or of its shape keys, coincide."""
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=x - 1, y_subdivisions=y - 1, size=2.0)
    obj = bpy.context.active_object
    obj.name = name
    for v in obj.data.vertices:
        v.co.z = 0.2 * v.co.x * v.co.x - 0.1 * v.co.y + 0.05 * v.co.x * v.co.y
    return obj


def empty(name, parent=None):
    """An empty named ``name`` under ``parent``, with no parent inverse (its local transform
    is its own location, rotation and scale, as a glTF node's is)."""
    obj = bpy.data.objects.new(name, None)
    bpy.context.scene.collection.objects.link(obj)
    obj.parent = parent
    return obj


def keys(owner, path, frames, values, interpolation):
    """Keys ``owner.path`` to ``values[k]`` at ``frames[k]`` with ``interpolation`` on every
    key ('BEZIER' keeps Blender's automatic handles)."""
    for frame, value in zip(frames, values):
        setattr(owner, path, value)
        owner.keyframe_insert(path, frame=frame)
    action = owner.id_data.animation_data.action
    for curve in action.fcurves:
        if curve.data_path.endswith(path):
            for point in curve.keyframe_points:
                point.interpolation = interpolation


def hermite_handles(action, seed):
    """Every curve of ``action`` made Bezier with FREE handles a third of the way to each
    neighbouring key in time and seeded slopes (flat on quaternion curves, see the module doc):
    each segment is then the cubic Hermite spline of its two keys' values and slopes, the curve
    glTF's CUBICSPLINE defines."""
    rng = np.random.default_rng(seed)
    for curve in action.fcurves:
        steepness = 0.0 if curve.data_path == "rotation_quaternion" else 0.08
        points = curve.keyframe_points
        for i, point in enumerate(points):
            point.interpolation = "BEZIER"
            point.handle_left_type = point.handle_right_type = "FREE"
            before = point.co[0] - points[max(i - 1, 0)].co[0] or 1.0
            after = points[min(i + 1, len(points) - 1)].co[0] - point.co[0] or 1.0
            slope_in, slope_out = steepness * rng.uniform(-1.0, 1.0, 2)
            point.handle_left = (point.co[0] - before / 3, point.co[1] - slope_in * before / 3)
            point.handle_right = (point.co[0] + after / 3, point.co[1] + slope_out * after / 3)


def shape_keys(obj, offsets):
    """Shape keys on ``obj``, one per (name, function of a vertex's position giving its
    offset), with sliders from -1 to 2 so that no value Blender plays is clamped."""
    obj.shape_key_add(name="Basis")
    blocks = []
    for name, offset in offsets:
        block = obj.shape_key_add(name=name)
        block.slider_min, block.slider_max = -1.0, 2.0
        for point in block.data:
            point.co += offset(point.co)
        blocks.append(block)
    return blocks


def morph_scene(interpolation):
    """A sheet with three shape keys whose values are keyed every 4 frames from 1 to 13 with
    ``interpolation``, placed by a fixed, non-uniform object transform."""
    sheet = grid("Sheet", 5, 4)
    sheet.location, sheet.rotation_euler, sheet.scale = (0.3, -0.2, 0.5), (0.2, 0.1, 0.4), (1.2, 0.8, 1.0)
    blocks = shape_keys(sheet, [
        ("Lift", lambda p: Vector((0.0, 0.0, 0.3 * (1.0 + p.x)))),
        ("Shear", lambda p: Vector((0.2 * p.y, -0.1, 0.0))),
        ("Pinch", lambda p: Vector((-0.15 * p.x, -0.1 * p.y * p.x, 0.05))),
    ])
    frames = [1, 5, 9, 13]
    weights = [(0.0, 0.0, 0.0), (0.7, 0.2, 1.0), (0.3, 0.9, -0.4), (1.0, 0.4, 0.5)]
    for block, values in zip(blocks, zip(*weights)):
        keys(block, "value", frames, values, interpolation)
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = frames[0], frames[-1]
    return sheet


def test_morph_target_weights_match_blender(env):
    env.require_cli()
    bpy.context.scene.render.fps = FPS
    sheet = morph_scene("LINEAR")
    path, document = export_gltf(env, "morph_keys", sampled=False)
    assert interpolations(document) == {("Sheet", "weights"): "LINEAR"}, interpolations(document)
    # Keys every 4 frames, sampled every frame: three of four samples between keys.
    ours = to_blender(cli_samples(env, path, "--fps", str(FPS)))
    compare("morph, LINEAR keys", ours, sheet, sample_frames(1, 13, FPS))
    for fcurve in sheet.data.shape_keys.animation_data.action.fcurves:
        for point in fcurve.keyframe_points:
            point.interpolation = "BEZIER"
    path, document = export_gltf(env, "morph_sampled", sampled=True)
    assert interpolations(document) == {("Sheet", "weights"): "LINEAR"}, interpolations(document)
    # Sampled by the exporter at every frame: the file's own rate is the frame rate.
    compare("morph, Bezier keys sampled", to_blender(cli_samples(env, path)), sheet,
            sample_frames(1, 13, FPS))


def test_parent_chains_match_blender(env):
    env.require_cli()
    scene = bpy.context.scene
    scene.render.fps = FPS
    root = empty("Root")
    middle = empty("Middle", root)
    tip = empty("Tip", middle)
    sheet = grid("Sheet", 4, 3)
    sheet.parent = tip
    frames = [1, 6, 11]
    motion = {
        root: ([(0, 0, 0), (0.5, 0.2, -0.3), (1.0, -0.4, 0.2)], [(0, 0, 0), (0.3, 0.1, 0.6), (0.8, -0.2, 1.1)],
               [(1.5, 0.6, 1.0), (1.2, 0.8, 1.4), (0.9, 1.1, 0.7)]),
        middle: ([(0.4, 0, 0.2), (0.6, 0.3, 0.1), (0.2, 0.5, -0.2)], [(0.5, 0, 0.2), (0.2, 0.7, -0.3), (-0.4, 0.3, 0.5)],
                 [(1, 2.0, 0.5), (1.3, 1.6, 0.8), (0.7, 1.2, 1.1)]),
        tip: ([(0, 0.3, 0), (0.2, 0.1, 0.4), (-0.1, 0.2, 0.3)], [(0.1, 0.2, 0.3), (0.6, -0.3, 0.2), (0.9, 0.4, -0.5)],
              [(1, 1, 1), (0.8, 1.1, 1.3), (1.2, 0.9, 0.6)]),
        sheet: ([(0.1, 0, 0), (0.3, -0.2, 0.1), (0.0, 0.1, -0.1)], [(0, 0, 0), (0.2, 0.1, 0), (0, 0.3, 0.2)],
                [(1, 1, 1), (1, 1, 1), (1.1, 0.9, 1)]),
    }
    for obj, (locations, rotations, scales) in motion.items():
        for path, values in (("location", locations), ("rotation_euler", rotations), ("scale", scales)):
            keys(obj, path, frames, values, "BEZIER")
    scene.frame_start, scene.frame_end = frames[0], frames[-1]
    path, document = export_gltf(env, "chain", sampled=True)
    animated = {node for node, _ in interpolations(document)}
    assert animated == {"Root", "Middle", "Tip", "Sheet"}, animated
    compare("parent chain", to_blender(cli_samples(env, path)), sheet, sample_frames(1, 11, FPS))


def rig_scene():
    """A 4 × 6-vertex sheet skinned to a two-bone armature "Rig", its weights blending from
    the lower bone to the upper along z, and two actions on the armature: "Bend" (frames
    1-11) and "Twist" (frames 3-15). The armature plays "Bend"."""
    sheet = grid("Sheet", 4, 6)
    sheet.rotation_euler = (1.5707963267948966, 0.0, 0.0)
    sheet.location = (0.0, 0.0, 1.0)
    bpy.ops.object.transform_apply(location=True, rotation=True, scale=True)
    data = bpy.data.armatures.new("Rig")
    rig = bpy.data.objects.new("Rig", data)
    bpy.context.scene.collection.objects.link(rig)
    bpy.context.view_layer.objects.active = rig
    bpy.ops.object.mode_set(mode="EDIT")
    lower = data.edit_bones.new("Lower")
    lower.head, lower.tail = (0, 0, 0), (0, 0, 1)
    upper = data.edit_bones.new("Upper")
    upper.head, upper.tail, upper.parent = (0, 0, 1), (0.1, 0, 2), lower
    bpy.ops.object.mode_set(mode="OBJECT")
    sheet.parent = rig
    sheet.modifiers.new("Armature", "ARMATURE").object = rig
    groups = [sheet.vertex_groups.new(name=n) for n in ("Lower", "Upper")]
    for v in sheet.data.vertices:
        w = min(max(v.co.z / 2.0, 0.0), 1.0)
        groups[0].add([v.index], 1.0 - w, "REPLACE")
        groups[1].add([v.index], w, "REPLACE")
    rig.animation_data_create()
    for name, frames, turn in (("Twist", [3, 9, 15], (0.2, 0.3, 0.9)), ("Bend", [1, 6, 11], (0.7, 0.1, -0.2))):
        action = bpy.data.actions.new(name)
        action.use_fake_user = True
        rig.animation_data.action = action
        for bone, share in zip(rig.pose.bones, (1.0, -0.6)):
            bone.rotation_mode = "XYZ"
            values = [tuple(share * k * c for c in turn) for k in range(len(frames))]
            keys(bone, "rotation_euler", frames, values, "BEZIER")
    return sheet, rig


def test_skinned_mesh_under_an_animated_parent_matches_blender(env):
    env.require_cli()
    scene = bpy.context.scene
    scene.render.fps = FPS
    sheet, rig = rig_scene()
    carrier = empty("Carrier")
    rig.parent = carrier
    frames = [1, 6, 11]
    keys(carrier, "location", frames, [(0, 0.1, 0), (0.3, 0.1, -0.2), (0.6, -0.2, -0.4)], "BEZIER")
    keys(carrier, "rotation_euler", frames, [(0, 0.1, 0), (0.2, 0.1, 0.4), (0.4, -0.3, 0.8)], "BEZIER")
    keys(carrier, "scale", frames, [(1, 1, 1), (1.3, 1, 0.8), (1.6, 0.9, 0.6)], "BEZIER")
    scene.frame_start, scene.frame_end = frames[0], frames[-1]
    path, document = export_gltf(env, "skinned", sampled=True)
    mesh_node = next(n for n in document["nodes"] if n.get("name") == "Sheet")
    assert "skin" in mesh_node and not {"translation", "rotation", "scale", "matrix"} & set(mesh_node)
    assert ("Carrier", "rotation") in interpolations(document)
    compare("skinned under an animated parent", to_blender(cli_samples(env, path)), sheet,
            sample_frames(1, 11, FPS))


def test_step_linear_and_cubic_samplers_match_blender(env):
    env.require_cli()
    scene = bpy.context.scene
    scene.render.fps = FPS
    glider = empty("Glider")
    stepper = empty("Stepper", glider)
    sheet = grid("Sheet", 4, 3)
    sheet.parent = stepper
    sheet.rotation_mode = "QUATERNION"
    keys(glider, "location", [1, 10, 19], [(0, 0, 0), (0.8, -0.3, 0.4), (0.2, 0.5, 1.0)], "LINEAR")
    keys(glider, "scale", [1, 10, 19], [(1, 1, 1), (1.4, 0.7, 1.0), (0.8, 1.2, 1.5)], "LINEAR")
    keys(stepper, "location", [1, 6, 14, 19], [(0, 0, 0), (0.3, 0, 0.1), (-0.2, 0.4, 0), (0.1, 0.1, 0.5)], "CONSTANT")
    cubic = [1, 7, 10, 19]
    keys(sheet, "location", cubic, [(0, 0, 0), (0.4, 0.2, -0.1), (0.1, 0.6, 0.3), (0.5, -0.2, 0.2)], "BEZIER")
    turns = [Quaternion((0, 0, 1), 0.0), Quaternion((1, 0.2, 0), 0.8), Quaternion((0, 1, 0.5), 1.4),
             Quaternion((0.3, -0.4, 1), 2.2)]
    keys(sheet, "rotation_quaternion", cubic, [tuple(q) for q in turns], "BEZIER")
    keys(sheet, "scale", cubic, [(1, 1, 1), (1.3, 0.8, 1), (0.9, 1.2, 1.4), (1.1, 1, 0.7)], "BEZIER")
    blocks = shape_keys(sheet, [
        ("Lift", lambda p: Vector((0.0, 0.0, 0.4 * (1.0 + p.x)))),
        ("Shear", lambda p: Vector((0.3 * p.y, 0.0, -0.1))),
    ])
    for block, values in zip(blocks, ([0, 0.8, 0.2, 1.0], [0.5, 0.0, 0.9, 0.3])):
        keys(block, "value", cubic, values, "BEZIER")
    hermite_handles(sheet.animation_data.action, seed=1)
    hermite_handles(sheet.data.shape_keys.animation_data.action, seed=2)
    scene.frame_start, scene.frame_end = 1, 19
    path, document = export_gltf(env, "samplers", sampled=False)
    expected = {("Glider", "translation"): "LINEAR", ("Glider", "scale"): "LINEAR",
                ("Stepper", "translation"): "STEP", ("Sheet", "translation"): "CUBICSPLINE",
                ("Sheet", "rotation"): "CUBICSPLINE", ("Sheet", "scale"): "CUBICSPLINE",
                ("Sheet", "weights"): "CUBICSPLINE"}
    assert interpolations(document) == expected, interpolations(document)
    rate = 4 * FPS
    frames = sample_frames(1, 19, rate)
    premise = cubic_channels_follow_blender(document, env.work, sheet, frames)
    print(f"the specification's Hermite from the file's accessors against Blender's curves: "
          f"{premise:.2e} apart at most", flush=True)
    assert premise <= 1e-6, f"Blender's curves are not the file's cubic splines ({premise:.2e})"
    compare("STEP, LINEAR and CUBICSPLINE", to_blender(cli_samples(env, path, "--fps", str(rate))),
            sheet, frames)


def test_fbx_animation_stacks_are_listed_and_each_matches_blender(env):
    cli = env.require_cli()
    scene = bpy.context.scene
    scene.render.fps = FPS
    sheet, rig = rig_scene()
    path = oracle.export_fbx(bpy, os.path.join(env.work, "stacks.fbx"), all_actions=True)
    stacks = {"Rig|Bend": "Bend", "Rig|Twist": "Twist"}
    refused = subprocess.run([cli, "convert", "--sequence", path, "--to", path + ".pc2"],
                             capture_output=True, text=True)
    assert refused.returncode != 0, "an FBX with two stacks and no --animation was read"
    assert "--animation" in refused.stderr and all(s in refused.stderr for s in stacks), refused.stderr
    print(f"refused: {refused.stderr.strip()}", flush=True)
    for stack, action in stacks.items():
        rig.animation_data.action = bpy.data.actions[action]
        first, last = (int(f) for f in bpy.data.actions[action].frame_range)
        ours = oracle.TO_BLENDER["Y"](cli_samples(env, path, "--animation", stack)) / 100.0
        compare(f"FBX stack {stack}", ours, sheet, sample_frames(first, last, FPS))
