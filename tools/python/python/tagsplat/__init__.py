"""tagsplat: topology-consistent mesh sequences from multi-view video, on Vulkan compute.

The package is a thin front over the engine (the Rust crate ``tagsplat``): every function calls
the engine function the ``tagsplat`` command-line program calls for the same job, so results,
files and error messages are the program's.

- ``devices()``, ``Context``: the Vulkan devices, and a context on one.
- ``dataset_info``: what ``tagsplat dataset info --json`` says of a dataset folder.
- ``train`` / ``start_train``, ``fit`` / ``start_fit``: reconstruction runs, blocking (with a
  progress callback that can cancel) or as job objects to poll.
- ``Sequence``: mesh sequences as zero-copy numpy arrays, read and written in every format.
- ``track``: points, pixels or given bindings followed through a sequence; ``Tracks`` holds
  their positions, orientation frames, polygons and clock, and writes the program's files.
- ``Camera``, ``render_splats``, ``render_mesh``: one view into an array.
- ``eval``: what ``tagsplat eval --json`` measures, as a dict.
- ``Error`` and its subclasses ``BadInputError`` (also a ``ValueError``), ``FileFormatError``,
  ``DeviceError``, ``CancelledError``.
"""

from ._tagsplat import (
    BadInputError,
    Camera,
    CancelledError,
    Context,
    Device,
    DeviceError,
    Error,
    FileFormatError,
    FitJob,
    Progress,
    Sequence,
    Tracks,
    TrainJob,
    __version__,
    dataset_info,
    devices,
    eval,
    fit,
    render_mesh,
    render_splats,
    start_fit,
    start_train,
    track,
    train,
)

__all__ = [
    "BadInputError",
    "Camera",
    "CancelledError",
    "Context",
    "Device",
    "DeviceError",
    "Error",
    "FileFormatError",
    "FitJob",
    "Progress",
    "Sequence",
    "Tracks",
    "TrainJob",
    "__version__",
    "dataset_info",
    "devices",
    "eval",
    "fit",
    "render_mesh",
    "render_splats",
    "start_fit",
    "start_train",
    "track",
    "train",
]
