"""Tracking the selected vertices of a sequence object: tagsplat binds each vertex on frame 0
and follows it through the sequence the object's Mesh Cache modifier plays; each track becomes
an empty parented to the object with one location and one rotation keyframe per frame.

The rotation is the engine's orientation frame of the bound triangle (columns: its tangent, the
normal × tangent, the normal), the frame Blender's three-vertex parent gives a child of that
triangle, so an empty turns with the surface as a rivet or uvPin does.
"""

import os

import bpy
import numpy as np
from mathutils import Matrix

from . import axes, engine

# The keyframe_points "interpolation" enum's value for LINEAR: between frames an empty moves
# as the Mesh Cache blends the vertices (linearly), so it stays on its point at subframes too.
_LINEAR = 1


def sequence_cache(obj):
    """``obj``'s PC2 Mesh Cache modifier, checked to play as the tracks assume: the scene's
    frame, counted in frames, overwriting the mesh in full. Raises :class:`engine.UserError`."""
    if obj is None or obj.type != "MESH":
        raise engine.UserError("select a mesh object imported as a sequence (it has no mesh)")
    found = [m for m in obj.modifiers if m.type == "MESH_CACHE" and m.cache_format == "PC2"]
    if not found:
        raise engine.UserError(
            f"{obj.name} has no Mesh Cache modifier reading a .pc2: import it as a sequence first"
        )
    modifier = found[0]
    wrong = [
        f"{name} is {value!r}, not {expected!r}"
        for name, value, expected in (
            ("Play mode", modifier.play_mode, "SCENE"),
            ("Time mode", modifier.time_mode, "FRAME"),
            ("Deform mode", modifier.deform_mode, "OVERWRITE"),
            ("Influence", modifier.factor, 1.0),
        )
        if value != expected
    ]
    if wrong:
        problems = "; ".join(wrong)
        raise engine.UserError(f"{obj.name}'s Mesh Cache modifier cannot be tracked: {problems}")
    return modifier


def selected_vertices(obj):
    """Indices of ``obj``'s selected vertices (the edit-mode selection when in edit mode)."""
    if obj.mode == "EDIT":
        obj.update_from_editmode()
    selected = np.zeros(len(obj.data.vertices), dtype=bool)
    obj.data.vertices.foreach_get("select", selected)
    return np.flatnonzero(selected)


def scene_frames(modifier, count):
    """The scene frame showing each of ``count`` samples: scene frame f shows sample
    ``frame_scale · f − frame_start`` (the Mesh Cache modifier's own rule)."""
    return (np.arange(count, dtype=np.float64) + modifier.frame_start) / modifier.frame_scale


def keyframe(action, path, group, frames, values):
    """One linear keyframe per frame on each component of ``path``: ``values`` (T, C) at
    ``frames``."""
    for axis in range(values.shape[1]):
        curve = action.fcurves.new(path, index=axis, action_group=group)
        points = curve.keyframe_points
        points.add(len(frames))
        points.foreach_set("co", np.column_stack([frames, values[:, axis]]).ravel())
        points.foreach_set("interpolation", np.full(len(frames), _LINEAR, dtype=np.int32))
        curve.update()


def frame_quaternions(matrix, normals, tangents):
    """Per frame, the rotation (w, x, y, z) whose columns are the tangent, normal × tangent and
    normal, turned into the object's space by ``matrix`` as the displayed triangle turns: its
    edges by ``matrix`` itself, its normal also reversed when ``matrix`` mirrors (the winding
    then reads the other way). Each quaternion is on the same side as the one before, so linear
    keys between frames take the short way round."""
    t = np.asarray(tangents, dtype=np.float64) @ matrix.T
    n = np.linalg.det(matrix) * (np.asarray(normals, dtype=np.float64) @ matrix.T)
    rotations = np.stack([t, np.cross(n, t), n], axis=-1)
    quaternions = np.array([tuple(Matrix(r.tolist()).to_quaternion()) for r in rotations])
    for k in range(1, len(quaternions)):
        if np.dot(quaternions[k], quaternions[k - 1]) < 0.0:
            quaternions[k] = -quaternions[k]
    return quaternions


def keyframe_track(empty, frames, locations, rotations):
    """``empty``'s action: its ``locations`` (T, 3) and quaternion ``rotations`` (T, 4) keyed
    linearly at ``frames``."""
    action = bpy.data.actions.new(f"{empty.name} track")
    empty.animation_data_create().action = action
    empty.rotation_mode = "QUATERNION"
    keyframe(action, "location", "Location", frames, locations)
    keyframe(action, "rotation_quaternion", "Rotation", frames, rotations)


def track_selected(context, obj):
    """Tracks ``obj``'s selected vertices through its cache's sequence; returns the new
    empties, linked into a new collection ``"<object> tracks"`` under the active one, and the
    engine's list of queries it could not bind (none for a vertex: it lies on the surface)."""
    modifier = sequence_cache(obj)
    indices = selected_vertices(obj)
    if len(indices) == 0:
        raise engine.UserError(f"no vertex of {obj.name} is selected: select some in Edit Mode")
    ts = engine.module(context)
    path = os.path.normpath(bpy.path.abspath(modifier.filepath, library=obj.library))
    sequence = ts.Sequence.read(path)
    positions = sequence.positions
    if positions.shape[1] != len(obj.data.vertices):
        raise engine.UserError(
            f"{path} has {positions.shape[1]} vertices, {obj.name} has {len(obj.data.vertices)}"
        )
    tracks = ts.track(sequence, points=positions[0][indices], ids=[str(i) for i in indices])
    turn = axes.cache_matrix(modifier)
    moved = axes.apply(turn, tracks.positions)
    frames = scene_frames(modifier, positions.shape[0])
    triangles = sequence.faces[tracks.bindings[0]]
    collection = bpy.data.collections.new(f"{obj.name} tracks")
    context.collection.children.link(collection)
    size = max(obj.dimensions.length, 1e-6) * 0.01
    empties = []
    for k, vertex in enumerate(tracks.ids):
        empty = bpy.data.objects.new(f"{obj.name} v{vertex}", None)
        empty.empty_display_type = "ARROWS"
        empty.empty_display_size = size
        empty.parent = obj
        empty["tagsplat_vertex"] = int(vertex)  # the id given to track: the vertex index
        # The bound triangle's corners, in the order its frame is built from (a three-vertex
        # parent with these vertices turns as the empty does).
        empty["tagsplat_triangle"] = [int(v) for v in triangles[k]]
        rotations = frame_quaternions(turn, tracks.normals[k], tracks.tangents[k])
        keyframe_track(empty, frames, moved[k], rotations)
        collection.objects.link(empty)
        empties.append(empty)
    return empties, tracks.unbound


class TAGSPLAT_OT_track_vertices(bpy.types.Operator):
    """Track the selected vertices through the object's sequence as keyframed empties"""

    bl_idname = "tagsplat.track_vertices"
    bl_label = "Track Selected Vertices"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        """A mesh object is active."""
        obj = context.active_object
        return obj is not None and obj.type == "MESH"

    def execute(self, context):
        """Writes one empty per selected vertex; the mode (edit or object) is kept."""

        def run():
            empties, unbound = track_selected(context, context.active_object)
            self.report({"INFO"}, f"{len(empties)} vertices tracked")
            if unbound:
                self.report({"WARNING"}, f"not tracked (the engine could not bind them): {unbound}")
            return {"FINISHED"}

        return engine.reported(self, run)
