"""Tracking selected vertices: each empty's keyframed location is, at every frame, Blender's
own evaluated position of the vertex it was made from (a vertex bound on frame 0 follows
itself), in the object's space and in the world; its keyed rotation is, at every frame, the
rotation Blender's own three-vertex parent on the bound triangle of the evaluated mesh gives
(an independent construction of the same frame), also when the Mesh Cache modifier mirrors."""

import bmesh
import bpy
import numpy as np
from mathutils import Matrix, Vector

import oracle
from tagsplat_blender import axes

SELECTED = (0, 7, 13, 19)
# Rotation matrix entries, against Blender's single-precision three-vertex parent.
ROTATION_TOLERANCE = 5e-5


def sequence_object(env, up="Y", frames=6):
    """An imported Y-up sheet, moved and turned so that parenting matters; made active."""
    faces, positions = oracle.deforming_grid(frames=frames)
    pc2 = oracle.write_obj_pc2(env.work, "sheet", faces, positions)
    assert bpy.ops.tagsplat.import_sequence(filepath=pc2, up_axis=up, frame_start=1) == {"FINISHED"}
    obj = bpy.data.objects["sheet"]
    obj.location = (1.0, -2.0, 0.5)
    obj.rotation_euler = (0.3, 0.0, 1.1)
    bpy.context.view_layer.objects.active = obj
    return obj


def select_in_edit_mode(obj, indices):
    """Enters edit mode with exactly ``indices`` selected, as a user's click would leave it."""
    bpy.ops.object.mode_set(mode="EDIT")
    bm = bmesh.from_edit_mesh(obj.data)
    for v in bm.verts:
        v.select = v.index in indices
    bm.select_flush_mode()
    bmesh.update_edit_mesh(obj.data)


def tracked(obj, indices):
    """The empties the track operator makes for ``indices`` selected in edit mode, by vertex."""
    select_in_edit_mode(obj, indices)
    assert bpy.ops.tagsplat.track_vertices() == {"FINISHED"}
    assert obj.mode == "EDIT", "the mode is kept"
    bpy.ops.object.mode_set(mode="OBJECT")
    empties = {e["tagsplat_vertex"]: e for e in bpy.data.objects if "tagsplat_vertex" in e}
    assert sorted(empties) == sorted(indices)
    return empties


def assert_follow(obj, empties, frames, subframe=0.0):
    """At each frame every empty sits on its vertex: its local location is the evaluated
    vertex, and its world position the object's transform of it. Returns the largest local
    difference."""
    worst = 0.0
    for frame in frames:
        vertices = oracle.evaluated_positions(bpy, obj, frame, subframe)
        for index, empty in empties.items():
            local = np.array(empty.matrix_local.translation)
            worst = max(worst, float(np.abs(local - vertices[index]).max()))
            world = obj.matrix_world @ Vector(vertices[index].tolist())
            np.testing.assert_allclose(empty.matrix_world.translation, world, rtol=0, atol=1e-5)
    return worst


def assert_turn(obj, empties, frames):
    """At each frame every empty's world rotation is a three-vertex parent's: a child of
    ``obj`` on the empty's bound triangle (Blender builds that frame from the evaluated mesh).
    Returns the largest difference of the rotation matrices' entries."""
    rivets = {}
    for index, empty in empties.items():
        rivet = bpy.data.objects.new(f"rivet {index}", None)
        bpy.context.collection.objects.link(rivet)
        rivet.parent, rivet.parent_type = obj, "VERTEX_3"
        rivet.parent_vertices = list(empty["tagsplat_triangle"])
        rivet.matrix_parent_inverse = Matrix.Identity(4)
        rivets[index] = rivet
    worst = 0.0
    for frame in frames:
        bpy.context.scene.frame_set(frame)
        for index, empty in empties.items():
            keyed = np.array(empty.matrix_world.to_3x3())
            rivet = np.array(rivets[index].matrix_world.to_3x3())
            worst = max(worst, float(np.abs(keyed - rivet).max()))
    for rivet in rivets.values():
        bpy.data.objects.remove(rivet)
    return worst


def test_selected_vertices_become_empties_on_their_vertices_at_every_frame(env):
    obj = sequence_object(env)
    empties = tracked(obj, SELECTED)
    for empty in empties.values():
        assert empty.parent == obj
        curves = empty.animation_data.action.fcurves
        paths = sorted(c.data_path for c in curves)
        assert paths == ["location"] * 3 + ["rotation_quaternion"] * 4, paths
        assert all(len(c.keyframe_points) == 6 for c in curves), "one key per frame"
    worst = assert_follow(obj, empties, range(1, 7))
    assert worst <= 1e-6, f"an empty is {worst} off its vertex"
    assert assert_follow(obj, empties, [2, 4], subframe=0.5) <= 1e-6
    turned = assert_turn(obj, empties, range(1, 7))
    print(f"track: keyed rotations within {turned:.2g} of a three-vertex parent's")
    # Blender builds the parent's frame in single precision from the evaluated (f32) mesh,
    # and the keys are f32 quaternions: entries agree to a few 1e-5 (a wrong edge or side
    # would be off by O(1)).
    assert turned <= ROTATION_TOLERANCE, f"an empty's rotation is {turned} off its triangle's"


def test_tracks_follow_the_modifier_axes_as_set_on_the_object(env):
    obj = sequence_object(env, up="Z", frames=3)
    modifier = obj.modifiers[0]
    modifier.forward_axis, modifier.up_axis, modifier.flip_axis = "NEG_X", "POS_Y", {"Z"}
    empties = tracked(obj, SELECTED[:2])
    assert assert_follow(obj, empties, range(1, 4)) <= 1e-6
    assert np.linalg.det(axes.cache_matrix(modifier)) < 0, "the settings mirror"
    assert assert_turn(obj, empties, range(1, 4)) <= ROTATION_TOLERANCE


def expect_error(words):
    """The track operator fails with an error report containing every one of ``words``."""
    try:
        bpy.ops.tagsplat.track_vertices()
    except RuntimeError as e:
        assert all(w in str(e) for w in words), str(e)
        return
    raise AssertionError("no error")


def test_an_empty_selection_or_an_object_without_a_sequence_is_refused(env):
    obj = sequence_object(env, frames=2)
    select_in_edit_mode(obj, ())
    expect_error(["no vertex of sheet is selected"])
    bpy.ops.object.mode_set(mode="OBJECT")
    obj.modifiers[0].play_mode = "CUSTOM"
    expect_error(["Play mode is 'CUSTOM'"])
    obj.modifiers.remove(obj.modifiers[0])
    expect_error(["sheet has no Mesh Cache modifier"])
    assert not [o for o in bpy.data.objects if o.type == "EMPTY"]
