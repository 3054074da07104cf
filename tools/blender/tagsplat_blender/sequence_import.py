"""Importing a mesh sequence onto one mesh object: the mesh is built from frame 0 and animated
by a Mesh Cache modifier reading a .pc2, so the .blend holds no positions per frame.

The .pc2 is the source itself when it is one; any other layout tagsplat reads (a folder of PLY
or OBJ frames, a .glb) is written once as a .pc2 (with its base .obj beside it) by
``tagsplat.Sequence.write``, into the chosen cache folder or next to the saved .blend.
"""

import os

import bpy
import numpy as np

from . import axes, engine


def _absolute(path):
    """``path`` with Blender's ``//`` prefix resolved against the .blend, normalised."""
    return os.path.normpath(bpy.path.abspath(path))


def _name(path):
    """A sequence's name: its file's stem, or its folder's name."""
    return os.path.splitext(os.path.basename(path.rstrip(os.sep)))[0] or "sequence"


def _cache_folder(cache_folder):
    """The folder new caches go into: ``cache_folder``, else the saved .blend's folder."""
    if cache_folder:
        return _absolute(cache_folder)
    if not bpy.data.filepath:
        raise engine.UserError(
            "the sequence is no .pc2, so it needs a .pc2 cache written for it: save the .blend "
            "first (the cache goes beside it) or choose a cache folder"
        )
    return os.path.dirname(bpy.data.filepath)


def _free_cache_path(folder, stem):
    """``folder/stem.pc2``, or ``stem.001.pc2``, … : the first whose .pc2 and .obj are both
    free, so an earlier import's cache is never overwritten."""
    for n in range(1000):
        name = stem if n == 0 else f"{stem}.{n:03d}"
        path = os.path.join(folder, name + ".pc2")
        if not os.path.exists(path) and not os.path.exists(path[:-4] + ".obj"):
            return path
    raise engine.UserError(f"{folder}: no free name for a cache of {stem} (1000 taken)")


def cache_for(sequence, path, cache_folder):
    """The .pc2 the Mesh Cache modifier reads for ``sequence`` read from ``path``: ``path``
    itself when it is a .pc2, else a .pc2 written from ``sequence`` (positions as read)."""
    if path.lower().endswith(".pc2"):
        return path
    folder = _cache_folder(cache_folder)
    os.makedirs(folder, exist_ok=True)
    target = _free_cache_path(folder, _name(path))
    sequence.write(target)
    return target


def build_mesh(name, faces, positions):
    """A mesh of ``positions`` (V, 3) and triangle ``faces`` (F, 3), vertex order kept (the
    Mesh Cache modifier matches its samples to vertices by index)."""
    faces = np.ascontiguousarray(faces, dtype=np.int32)
    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(len(positions))
    mesh.vertices.foreach_set("co", np.ascontiguousarray(positions, dtype=np.float32).ravel())
    mesh.loops.add(faces.size)
    mesh.loops.foreach_set("vertex_index", faces.ravel())
    mesh.polygons.add(len(faces))
    mesh.polygons.foreach_set("loop_start", np.arange(0, faces.size, 3, dtype=np.int32))
    mesh.polygons.foreach_set("loop_total", np.full(len(faces), 3, dtype=np.int32))
    mesh.update(calc_edges=True)
    return mesh


def add_cache_modifier(obj, pc2, up, frame_start):
    """A Mesh Cache modifier on ``obj`` playing ``pc2`` (whose up is ``up``, 'Y' or 'Z') so that
    sample t shows at scene frame ``frame_start + t``, linearly blended between frames."""
    modifier = obj.modifiers.new("tagsplat sequence", "MESH_CACHE")
    modifier.cache_format = "PC2"
    modifier.filepath = bpy.path.relpath(pc2) if bpy.data.filepath else pc2
    modifier.deform_mode = "OVERWRITE"
    modifier.interpolation = "LINEAR"
    modifier.time_mode = "FRAME"
    modifier.play_mode = "SCENE"
    modifier.frame_start = frame_start
    modifier.frame_scale = 1.0
    modifier.forward_axis, modifier.up_axis = axes.MODIFIER_AXES[up]
    return modifier


def import_sequence(context, path, up, cache_folder="", frame_start=1, set_frame_range=True):
    """Reads the sequence at ``path`` with tagsplat and links one new object animated by it
    into the active collection; returns the object. Frame t shows at ``frame_start + t``;
    ``set_frame_range`` makes the scene's range exactly the sequence's."""
    ts = engine.module(context)
    path = _absolute(path)
    sequence = ts.Sequence.read(path)
    pc2 = cache_for(sequence, path, cache_folder)
    name = _name(path)
    # The base mesh is frame 0 in the object's axes, as the modifier shows it, so the two agree
    # where the modifier is off (edit mode, a disabled modifier).
    base = axes.apply(axes.matrix(*axes.MODIFIER_AXES[up]), sequence.positions[0])
    obj = bpy.data.objects.new(name, build_mesh(name, sequence.faces, base))
    add_cache_modifier(obj, pc2, up, frame_start)
    context.collection.objects.link(obj)
    if set_frame_range:
        context.scene.frame_start = frame_start
        context.scene.frame_end = frame_start + len(sequence.positions) - 1
    return obj


class TAGSPLAT_OT_import_sequence(bpy.types.Operator):
    """Import a mesh sequence (folder of PLY/OBJ frames, .pc2 + .obj, .glb) onto one object
    animated by a Mesh Cache modifier"""

    bl_idname = "tagsplat.import_sequence"
    bl_label = "Import Sequence"
    bl_options = {"REGISTER", "UNDO"}

    filepath: bpy.props.StringProperty(
        name="Sequence",
        description="A folder of frame files, a .pc2 (its .obj beside it) or a .glb",
        subtype="FILE_PATH",
    )
    directory: bpy.props.StringProperty(subtype="DIR_PATH", options={"HIDDEN", "SKIP_SAVE"})
    up_axis: bpy.props.EnumProperty(name="File up", items=axes.UP_ITEMS, default="Y")
    cache_folder: bpy.props.StringProperty(
        name="Cache folder",
        description="Where the .pc2 of a source that is no .pc2 is written (empty: beside the .blend)",
        subtype="DIR_PATH",
    )
    frame_start: bpy.props.IntProperty(
        name="Start frame", description="Scene frame showing the sequence's frame 0", default=1
    )
    set_frame_range: bpy.props.BoolProperty(
        name="Set frame range", description="Make the scene's frame range the sequence's", default=True
    )

    def invoke(self, context, event):
        """Imports at once when a path is set (the panel sets it), else opens the file browser."""
        if self.filepath:
            return self.execute(context)
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}

    def execute(self, context):
        """Imports the sequence; the file browser's folder stands for the path when no file in
        it was picked (a folder of frames)."""
        path = self.filepath
        if self.directory and (not path or path.rstrip(os.sep) == self.directory.rstrip(os.sep)):
            path = self.directory
        if not path:
            self.report({"ERROR"}, "no sequence chosen: set its path")
            return {"CANCELLED"}

        def run():
            obj = import_sequence(
                context, path, self.up_axis, self.cache_folder, self.frame_start, self.set_frame_range
            )
            self.report({"INFO"}, f"imported {path} onto {obj.name}")
            return {"FINISHED"}

        return engine.reported(self, run)
