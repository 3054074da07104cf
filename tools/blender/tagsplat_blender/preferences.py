"""The add-on's preferences: where the tagsplat Python package is installed, and which GPU
device the reconstructions run on."""

import bpy


class TagsplatPreferences(bpy.types.AddonPreferences):
    """Where the ``tagsplat`` wheel is installed and how its GPU context is opened."""

    bl_idname = __package__

    package_folder: bpy.props.StringProperty(
        name="Python package folder",
        description=(
            "Folder the tagsplat wheel was installed into (pip install --target FOLDER); "
            "empty: tagsplat must already be importable (e.g. from scripts/modules)"
        ),
        subtype="DIR_PATH",
    )
    device: bpy.props.StringProperty(
        name="Device",
        description=(
            "GPU device: its index in `tagsplat devices` or a piece of its name; empty: "
            "TAGSPLAT_DEVICE, else the engine's choice"
        ),
    )
    validation: bpy.props.BoolProperty(
        name="Vulkan validation",
        description="Open the GPU context with the Khronos validation layer (slow; for debugging)",
        default=False,
    )

    def draw(self, context):
        """Shows the three settings."""
        layout = self.layout
        layout.prop(self, "package_folder")
        layout.prop(self, "device")
        layout.prop(self, "validation")


def get(context):
    """This add-on's preferences."""
    return context.preferences.addons[__package__].preferences
