"""The sidebar panel (3D Viewport > Sidebar > tagsplat): import, track, reconstruct."""

import bpy

# Settings handed from Scene.tagsplat to each operator, by the name they share.
IMPORT_SETTINGS = ("filepath", "up_axis", "cache_folder")
TRAIN_SETTINGS = ("data", "out", "config", "use_frames", "frame_first", "frame_end")


def _operator_with(layout, idname, text, settings, names):
    """A button for ``idname`` whose properties ``names`` are taken from ``settings``."""
    op = layout.operator(idname, text=text)
    for name in names:
        setattr(op, name, getattr(settings, name))


class TAGSPLAT_PT_sequence(bpy.types.Panel):
    """tagsplat's three tools and their settings"""

    bl_idname = "TAGSPLAT_PT_sequence"
    bl_label = "tagsplat"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "tagsplat"

    def draw(self, context):
        """Three boxes: the sequence to import, tracking, the reconstruction."""
        settings = context.scene.tagsplat
        box = self.layout.box()
        box.label(text="Sequence", icon="MESH_DATA")
        for name in IMPORT_SETTINGS:
            box.prop(settings, name)
        _operator_with(box, "tagsplat.import_sequence", "Import", settings, IMPORT_SETTINGS)

        box = self.layout.box()
        box.label(text="Tracks", icon="EMPTY_AXIS")
        box.label(text="Select vertices in Edit Mode")
        box.operator("tagsplat.track_vertices")

        box = self.layout.box()
        box.label(text="Reconstruction", icon="SHADING_RENDERED")
        for name in ("data", "out", "config", "use_frames"):
            box.prop(settings, name)
        if settings.use_frames:
            row = box.row(align=True)
            row.prop(settings, "frame_first")
            row.prop(settings, "frame_end")
        _operator_with(box, "tagsplat.train", "Reconstruct", settings, TRAIN_SETTINGS)
