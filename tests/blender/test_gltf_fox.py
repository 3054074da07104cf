"""The glTF reader against Blender's glTF importer on the Khronos Fox (tests/formats/data/khronos/Fox.glb;
CC0 model by PixelMannen, CC-BY 4.0 rigging and animation by tomkranis): for each of its three
animations, ``tagsplat convert --animation NAME`` writes a PC2, and every sample of it is
compared with Blender's own evaluation of the imported, skinned fox at the same time.

Blender places key time t at scene frame t · fps and blends rotation keys component-wise
(normalised), where glTF asks for slerp: at a key the two must agree exactly; between keys
they differ by the angle nlerp and slerp part by. So the tolerance is the target, 1e-5 of the
figure's size, at the keys, and the difference between keys is reported and bounded loosely:
Run's 16/24 s to 20.8/24 s gap differs by 2.4e-3 of the size, and by 4.9e-7 when the reader's
slerp is swapped for nlerp (measured once), so all of it is the interpolation's.
Survey and Walk are keyed evenly at 24 per second (their samples are their keys); Run's keys
jump from 16/24 s to 20.8/24 s, so it is sampled at 120 per second, where every key is a sample.
"""

import os
import subprocess

import bpy
import numpy as np

import oracle

FOX = os.path.join(os.path.dirname(__file__), "..", "formats", "data", "khronos", "Fox.glb")
# Animation: (the --fps asked for, None for the key rate; the rate of the samples).
ANIMATIONS = {"Survey": (None, 24.0), "Walk": (None, 24.0), "Run": (120.0, 120.0)}
AT_KEYS = 1e-5
BETWEEN_KEYS = 5e-3


def read_with_cli(env, animation, fps):
    """The CLI's samples of ``animation`` as a PC2, (T, V, 3) in the file's Y-up axes."""
    pc2 = os.path.join(env.work, animation + ".pc2")
    command = [env.require_cli(), "convert", "--sequence", FOX, "--animation", animation, "--to", pc2]
    if fps:
        command += ["--fps", str(fps)]
    done = subprocess.run(command, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    print(done.stderr.strip())
    return oracle.read_pc2(pc2).astype(np.float64)


def blender_world(obj, seconds, fps):
    """The fox's evaluated vertices in world space at ``seconds``, Blender's axes."""
    return oracle.evaluated_world(bpy, obj, seconds * fps)


def test_the_fox_matches_blender_in_each_animation(env):
    env.require_cli()
    if not os.path.isfile(FOX):
        env.skip(f"{FOX} is missing")
    # Blender 3.4's glTF importer still says np.bool, which numpy 1.24 removed (Debian ships
    # the two together): give it the builtin it meant.
    if "bool" not in vars(np):
        np.bool = bool
    assert bpy.ops.import_scene.gltf(filepath=FOX) == {"FINISHED"}
    fox = next(o for o in bpy.data.objects if o.type == "MESH")
    armature = next(o for o in bpy.data.objects if o.type == "ARMATURE")
    fps = bpy.context.scene.render.fps / bpy.context.scene.render.fps_base
    for animation, (asked, rate) in ANIMATIONS.items():
        track = armature.animation_data.nla_tracks[animation]
        armature.animation_data.action = track.strips[0].action
        keys = sorted({k.co[0] for c in track.strips[0].action.fcurves for k in c.keyframe_points})
        ours = oracle.TO_BLENDER["Y"](read_with_cli(env, animation, asked))
        first = blender_world(fox, 0.0, fps)
        # Blender's importer may split or merge the file's vertices: pair each of ours with
        # Blender's nearest at time 0.
        distance = np.linalg.norm(ours[0][:, None, :] - first[None, :, :], axis=2)
        pair = distance.argmin(axis=1)
        size = float(np.linalg.norm(first.max(axis=0) - first.min(axis=0)))
        worst = {"keys": 0.0, "between": 0.0}
        for k, frame in enumerate(ours):
            seconds = k / rate
            theirs = blender_world(fox, seconds, fps)[pair]
            error = float(np.linalg.norm(frame - theirs, axis=1).max())
            at_key = min(abs(seconds * fps - key) for key in keys) < 1e-3
            kind = "keys" if at_key else "between"
            worst[kind] = max(worst[kind], error)
        print(f"{animation}: {len(ours)} samples, {len(ours[0])} vertices (Blender {len(first)}), "
              f"size {size:.3f}: max error at keys {worst['keys']:.3e} ({worst['keys'] / size:.2e} of size), "
              f"between keys {worst['between']:.3e} ({worst['between'] / size:.2e})")
        assert worst["keys"] <= AT_KEYS * size, f"{animation}: {worst['keys'] / size:.2e} of size at keys"
        assert worst["between"] <= BETWEEN_KEYS * size, f"{animation}: {worst['between'] / size:.2e} between keys"
