"""tagsplat for Blender: mesh sequences as Mesh Cache objects, vertex tracks as keyframed
empties, and reconstructions run as cancellable modal jobs.

Every behaviour is the engine's, reached through the ``tagsplat`` Python package (its wheel is
installed into a folder Blender can import from: see the add-on's preferences). This package
only moves data between Blender and that package.
"""

bl_info = {
    "name": "tagsplat",
    "author": "tagsplat authors",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "3D Viewport > Sidebar > tagsplat",
    "description": "Import mesh sequences, track vertices and run reconstructions with tagsplat",
    "category": "Import-Export",
}

import bpy

from . import panel, preferences, sequence_import, settings, track, train

_CLASSES = (
    preferences.TagsplatPreferences,
    settings.TagsplatSettings,
    sequence_import.TAGSPLAT_OT_import_sequence,
    track.TAGSPLAT_OT_track_vertices,
    train.TAGSPLAT_OT_train,
    panel.TAGSPLAT_PT_sequence,
)


def register():
    """Registers the operators, the panel, the preferences and ``Scene.tagsplat``."""
    for cls in _CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Scene.tagsplat = bpy.props.PointerProperty(type=settings.TagsplatSettings)


def unregister():
    """Removes everything :func:`register` added, in reverse order."""
    del bpy.types.Scene.tagsplat
    for cls in reversed(_CLASSES):
        bpy.utils.unregister_class(cls)
