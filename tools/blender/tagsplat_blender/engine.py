"""Access to the ``tagsplat`` Python package: imported on first use from the folder the
preferences name, and one GPU context per (device, validation) for the whole Blender session,
since opening a Vulkan device takes a noticeable fraction of a second."""

import importlib
import os
import sys

import bpy

from . import preferences


class UserError(Exception):
    """Something the user can put right (a selection, a setting, a path); the message says what."""


class PackageMissing(UserError):
    """The ``tagsplat`` package cannot be imported; the message says where it was looked for."""


_contexts = {}


def module(context):
    """The ``tagsplat`` module, with the preferences' package folder put first on ``sys.path``.

    Raises :class:`PackageMissing` naming the folder and the import error.
    """
    folder = preferences.get(context).package_folder
    where = "on Blender's sys.path"
    if folder:
        folder = os.path.normpath(bpy.path.abspath(folder))
        where = f"in {folder} (the add-on's Python package folder) or on Blender's sys.path"
        if folder not in sys.path:
            sys.path.insert(0, folder)
    try:
        return importlib.import_module("tagsplat")
    except ImportError as e:
        raise PackageMissing(
            f"the tagsplat Python package is not installed {where}: {e}. Install its wheel with "
            "`python3.11 -m pip install --target FOLDER --no-deps tagsplat-*.whl` and set "
            "FOLDER in the add-on's preferences"
        ) from e


def gpu_context(context):
    """The session's ``tagsplat.Context`` for the preferences' device and validation setting,
    opened on first use and kept (the engine's context is shared by every job)."""
    ts = module(context)
    prefs = preferences.get(context)
    key = (prefs.device or None, prefs.validation)
    if key not in _contexts:
        _contexts[key] = ts.Context(device=key[0], validation=key[1])
    return _contexts[key]


def reported(operator, action):
    """``action()``'s result; a :class:`UserError` or a ``tagsplat.Error`` (whose message is the
    engine's, naming the file or argument) becomes an ERROR report on ``operator`` and
    ``{'CANCELLED'}``. Anything else is a bug and propagates with its traceback."""
    try:
        return action()
    except Exception as e:
        ts = sys.modules.get("tagsplat")
        if not (isinstance(e, UserError) or (ts is not None and isinstance(e, ts.Error))):
            raise
        operator.report({"ERROR"}, str(e))
        return {"CANCELLED"}
