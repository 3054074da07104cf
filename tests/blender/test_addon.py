"""The add-on registers as Blender's preferences enable it: operators, panel, settings."""

import bpy

import tagsplat_blender


def test_registers_operators_panel_and_settings(env):
    assert tagsplat_blender.bl_info["blender"] == (3, 4, 0)
    for name in ("import_sequence", "track_vertices", "train"):
        assert hasattr(bpy.ops.tagsplat, name) and getattr(bpy.ops.tagsplat, name).get_rna_type()
    assert bpy.types.TAGSPLAT_PT_sequence.bl_space_type == "VIEW_3D"
    assert bpy.types.TAGSPLAT_PT_sequence.bl_region_type == "UI"
    settings = bpy.context.scene.tagsplat
    assert settings.up_axis == "Y" and settings.filepath == ""


def test_unregisters_and_registers_again(env):
    tagsplat_blender.unregister()
    assert not hasattr(bpy.types.Scene, "tagsplat")
    tagsplat_blender.register()
    assert bpy.context.scene.tagsplat.up_axis == "Y"
