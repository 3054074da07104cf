"""Importing a sequence onto one object: Blender's evaluated mesh at each frame is the file's
positions (read here with struct, not with tagsplat), turned to Blender's axes as documented,
and the .blend holds no positions per frame."""

import os

import bpy
import numpy as np

import oracle


def imported(**settings):
    """The object the import operator makes with ``settings``; the call must succeed."""
    before = set(bpy.data.objects)
    assert bpy.ops.tagsplat.import_sequence(**settings) == {"FINISHED"}
    (obj,) = set(bpy.data.objects) - before
    return obj


def assert_plays(obj, expected, frame_start, up):
    """At each scene frame ``frame_start + t`` the evaluated vertices are exactly
    ``expected[t]`` (file axes) turned for ``up``; halfway between frames, the blend of the two."""
    turned = oracle.TO_BLENDER[up](expected)
    for t in range(len(expected)):
        np.testing.assert_array_equal(oracle.evaluated_positions(bpy, obj, frame_start + t), turned[t])
    halfway = oracle.evaluated_positions(bpy, obj, frame_start + 1, subframe=0.5)
    np.testing.assert_allclose(halfway, 0.5 * (turned[1] + turned[2]), rtol=0, atol=1e-6)


def assert_no_positions_per_frame(obj):
    """The object's animation is its Mesh Cache modifier alone: no shape keys, no actions."""
    assert obj.data.shape_keys is None and obj.animation_data is None and obj.data.animation_data is None
    (modifier,) = obj.modifiers
    assert modifier.type == "MESH_CACHE" and modifier.cache_format == "PC2"
    return modifier


def test_a_y_up_pc2_plays_from_its_own_file_turned_to_z_up(env):
    faces, positions = oracle.deforming_grid()
    pc2 = oracle.write_obj_pc2(env.work, "sheet", faces, positions)
    obj = imported(filepath=pc2, up_axis="Y", frame_start=1)
    modifier = assert_no_positions_per_frame(obj)
    assert bpy.path.abspath(modifier.filepath) == pc2, "the source's own .pc2, no copy"
    assert (modifier.forward_axis, modifier.up_axis) == ("POS_Z", "NEG_Y")
    assert len(obj.data.polygons) == len(faces) and len(obj.data.vertices) == positions.shape[1]
    assert (bpy.context.scene.frame_start, bpy.context.scene.frame_end) == (1, len(positions))
    assert_plays(obj, oracle.read_pc2(pc2), 1, "Y")
    # The base mesh is frame 0 as shown, so edit mode sees what the viewport shows at frame 1.
    base = np.empty(positions.shape[1] * 3, dtype=np.float32)
    obj.data.vertices.foreach_get("co", base)
    np.testing.assert_array_equal(base.reshape(-1, 3), oracle.TO_BLENDER["Y"](positions[0]))


def test_a_z_up_pc2_is_kept_and_starts_at_the_chosen_frame(env):
    faces, positions = oracle.deforming_grid(frames=4)
    pc2 = oracle.write_obj_pc2(env.work, "sheet", faces, positions)
    obj = imported(filepath=pc2, up_axis="Z", frame_start=10, set_frame_range=False)
    assert_plays(obj, positions, 10, "Z")


def test_a_folder_of_frames_is_cached_once_beside_the_saved_blend(env):
    faces, positions = oracle.deforming_grid()
    source = oracle.write_obj_folder(os.path.join(env.work, "frames"), faces, positions)
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(env.work, "scene.blend"))
    obj = imported(filepath=source, up_axis="Y")
    modifier = assert_no_positions_per_frame(obj)
    assert modifier.filepath == "//frames.pc2", "relative to the saved .blend"
    cache = bpy.path.abspath(modifier.filepath)
    np.testing.assert_array_equal(oracle.read_pc2(cache), positions)
    assert_plays(obj, positions, 1, "Y")
    second = imported(filepath=source, up_axis="Y")
    assert second.modifiers[0].filepath == "//frames.001.pc2", "an earlier cache is kept"


def test_a_folder_goes_to_the_chosen_cache_folder(env):
    faces, positions = oracle.deforming_grid(frames=3)
    source = oracle.write_obj_folder(os.path.join(env.work, "frames"), faces, positions)
    caches = os.path.join(env.work, "caches")
    obj = imported(filepath=source, up_axis="Z", cache_folder=caches)
    assert obj.modifiers[0].filepath == os.path.join(caches, "frames.pc2")
    assert_plays(obj, positions, 1, "Z")


def expect_error(words, **settings):
    """The import fails with an error report containing every one of ``words``."""
    try:
        bpy.ops.tagsplat.import_sequence(**settings)
    except RuntimeError as e:
        assert all(w in str(e) for w in words), str(e)
        return
    raise AssertionError(f"no error for {settings}")


def test_bad_sources_are_reported_by_name(env):
    missing = os.path.join(env.work, "missing.pc2")
    expect_error([missing], filepath=missing)
    faces, positions = oracle.deforming_grid(frames=2)
    source = oracle.write_obj_folder(os.path.join(env.work, "frames"), faces, positions)
    assert bpy.data.filepath == "", "each test starts from an unsaved file"
    expect_error(["save the .blend", "cache folder"], filepath=source)
    expect_error(["no sequence chosen"], filepath="")
    assert not bpy.data.objects
