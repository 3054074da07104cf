"""``Scene.tagsplat``: what the sidebar panel shows and hands to the operators, kept with the
.blend so a scene remembers its sequence, dataset and output folders."""

import bpy

from . import axes


class TagsplatSettings(bpy.types.PropertyGroup):
    """The panel's settings; each is the operator property of the same name."""

    filepath: bpy.props.StringProperty(
        name="Sequence",
        description="A folder of PLY/OBJ frames, a .pc2 (its .obj beside it) or a .glb",
        subtype="FILE_PATH",
    )
    up_axis: bpy.props.EnumProperty(name="File up", items=axes.UP_ITEMS, default="Y")
    cache_folder: bpy.props.StringProperty(
        name="Cache folder",
        description="Where the .pc2 of a source that is no .pc2 is written (empty: beside the .blend)",
        subtype="DIR_PATH",
    )
    data: bpy.props.StringProperty(name="Dataset", description="The dataset folder", subtype="DIR_PATH")
    out: bpy.props.StringProperty(name="Output", description="The output folder", subtype="DIR_PATH")
    config: bpy.props.StringProperty(
        name="Config", description="A train.toml (empty: the defaults)", subtype="FILE_PATH"
    )
    use_frames: bpy.props.BoolProperty(name="Frame range", description="Reconstruct only some frames")
    frame_first: bpy.props.IntProperty(name="First", description="First frame, from 0", min=0)
    frame_end: bpy.props.IntProperty(name="End", description="One past the last frame", min=1, default=1)
