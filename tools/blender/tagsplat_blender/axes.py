"""Axes: a sequence file's positions are in the file's own axes (tagsplat writes its exports
Y-up or Z-up, docs/conventions.md); Blender's scene is Z-up with -Y forward. The Mesh Cache
modifier turns its file's positions into the object's space with its Forward and Up settings;
everything here follows those settings, so the base mesh, the cache and the tracks agree.

A Y-up file is read as Blender's OBJ and glTF importers read one: file +Y becomes +Z and file
-Z becomes +Y, so (x, y, z) in the file is (x, -z, y) in Blender. A Z-up file is kept as is.

The modifier's Forward/Up settings work the other way round from the importers' of the same
name: it applies the transpose (the inverse) of ``axis_conversion(forward, up)``, because Blender
reads that function's table as a column-major C matrix. So the importers' "Forward -Z, Up Y" is
the modifier's "Forward +Z, Up -Y"; tests/blender checks the result against (x, -z, y).
"""

import numpy as np
from bpy_extras.io_utils import axis_conversion

# The Mesh Cache modifier's (forward_axis, up_axis) for each file up.
MODIFIER_AXES = {"Y": ("POS_Z", "NEG_Y"), "Z": ("POS_Y", "POS_Z")}

UP_ITEMS = (
    ("Y", "Y up", "The file is Y-up (glTF, most OBJ and PC2 exports): turned to Blender's Z-up"),
    ("Z", "Z up", "The file is Z-up, as Blender is: positions kept as they are"),
)


def _axis_name(modifier_axis):
    """'NEG_Z' -> '-Z', 'POS_Y' -> 'Y': the spelling of ``bpy_extras.io_utils.axis_conversion``."""
    sign, axis = modifier_axis.split("_")
    return ("-" if sign == "NEG" else "") + axis


def matrix(forward_axis, up_axis, flip_axis=()):
    """The 3×3 matrix a Mesh Cache modifier with these settings applies to its file's positions
    (object space = M · file): its Forward/Up conversion, then its Flip Axis signs, as Blender
    computes it (``forward_axis`` and ``up_axis`` spelt as the modifier's, e.g. 'NEG_Z'): the
    transpose of ``axis_conversion``'s matrix (see the module's note)."""
    turn = axis_conversion(from_forward=_axis_name(forward_axis), from_up=_axis_name(up_axis))
    flips = np.array([-1.0 if a in flip_axis else 1.0 for a in "XYZ"])
    return flips[:, None] * np.array(turn, dtype=np.float64).T


def cache_matrix(modifier):
    """:func:`matrix` of a Mesh Cache ``modifier``'s own settings."""
    return matrix(modifier.forward_axis, modifier.up_axis, modifier.flip_axis)


def apply(matrix, points):
    """``points`` (..., 3) in a file's axes, as float32 in the object's space (``matrix`` · p).
    Every entry of these matrices is 0 or ±1, so each coordinate is copied or negated exactly."""
    return (np.asarray(points, dtype=np.float64) @ matrix.T).astype(np.float32)
