"""Types of the extension module ``tagsplat._tagsplat`` (re-exported by ``tagsplat``)."""

import os
from collections.abc import Callable, Mapping, Sequence as Seq
from typing import Any, final

import numpy as np
from numpy.typing import ArrayLike, NDArray

_Path = str | os.PathLike[str]
_Frames = range | tuple[int, int]

__version__: str
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

class Error(Exception):
    """Base class of every tagsplat error."""

class BadInputError(Error, ValueError):
    """An argument, path, config value or array the caller can fix (also a ValueError)."""

class FileFormatError(Error):
    """A file exists but cannot be read as what it should be."""

class DeviceError(Error):
    """The Vulkan device failed."""

class CancelledError(Error):
    """The job was cancelled."""

@final
class Device:
    """A Vulkan device as ``tagsplat devices`` lists it."""

    @property
    def index(self) -> int: ...
    @property
    def name(self) -> str: ...
    @property
    def type(self) -> str: ...
    @property
    def driver(self) -> str: ...
    @property
    def missing(self) -> list[str]: ...
    @property
    def chosen(self) -> bool: ...

def devices() -> list[Device]:
    """The Vulkan devices."""

@final
class Context:
    """A Vulkan context on one device."""

    def __new__(
        cls,
        device: int | str | None = None,
        validation: bool | None = None,
        device_memory: int | str | None = None,
    ) -> Context: ...
    @property
    def device(self) -> Device: ...
    @property
    def validation(self) -> bool: ...
    def validation_messages(self) -> list[str]: ...

def dataset_info(ctx: Context, data: _Path, scale: float = 1.0, check: bool = False) -> dict[str, Any]:
    """What ``tagsplat dataset info --json`` says."""

@final
class Sequence:
    """A topology-consistent mesh sequence."""

    def __new__(cls, faces: ArrayLike, positions: ArrayLike, colors: ArrayLike | None = None) -> Sequence: ...
    @staticmethod
    def read(
        path: _Path, *, animation: str | None = None, fps: float | None = None, mesh: str | None = None
    ) -> Sequence: ...
    @property
    def fps(self) -> float | None: ...
    @property
    def times(self) -> list[float] | None: ...
    @property
    def up(self) -> str | None: ...
    @property
    def meters_per_unit(self) -> float | None: ...
    @property
    def notes(self) -> list[str]: ...
    def write(
        self,
        path: _Path,
        fps: float = 24.0,
        up: str = "y",
        from_up: str | None = None,
        frame_format: str = "ply",
    ) -> None: ...
    @property
    def faces(self) -> NDArray[np.uint32]: ...
    @property
    def positions(self) -> NDArray[np.float32]: ...
    @property
    def colors(self) -> NDArray[np.uint8] | None: ...
    @property
    def vertex_count(self) -> int: ...
    def __len__(self) -> int: ...

@final
class Tracks:
    """The result of ``track``."""

    @property
    def ids(self) -> list[str]: ...
    @property
    def positions(self) -> NDArray[np.float64]: ...
    @property
    def normals(self) -> NDArray[np.float64]: ...
    @property
    def tangents(self) -> NDArray[np.float64]: ...
    @property
    def orientation_held(self) -> NDArray[np.bool_]: ...
    @property
    def bindings(self) -> tuple[NDArray[np.uint32], NDArray[np.float64]]: ...
    @property
    def polygons(self) -> NDArray[np.uint32]: ...
    @property
    def distances(self) -> NDArray[np.float64]: ...
    @property
    def times(self) -> NDArray[np.float64]: ...
    @property
    def fps(self) -> float: ...
    @property
    def start_frame(self) -> float: ...
    @property
    def unbound(self) -> list[dict[str, Any]]: ...
    @property
    def max_distance(self) -> float: ...
    @property
    def engine_s(self) -> float: ...
    def write_csv(self, path: _Path) -> None: ...
    def write_json(self, path: _Path) -> None: ...
    def write_pins(self, path: _Path, from_up: str | None = None) -> None: ...
    def write_bindings(self, path: _Path) -> None: ...
    def __len__(self) -> int: ...

@final
class Camera:
    """A pinhole camera with OpenCV axes."""

    def __new__(
        cls,
        width: int,
        height: int,
        fx: float,
        fy: float,
        cx: float,
        cy: float,
        world_to_camera: ArrayLike,
    ) -> Camera: ...
    @staticmethod
    def read(path: _Path) -> Camera: ...
    def write(self, path: _Path) -> None: ...
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def fx(self) -> float: ...
    @property
    def fy(self) -> float: ...
    @property
    def cx(self) -> float: ...
    @property
    def cy(self) -> float: ...
    @property
    def world_to_camera(self) -> NDArray[np.float64]: ...

def track(
    sequence: Sequence | _Path,
    *,
    points: Mapping[str, ArrayLike] | ArrayLike | None = None,
    pixels: ArrayLike | None = None,
    bindings: _Path | tuple[ArrayLike, ArrayLike] | ArrayLike | None = None,
    ids: Seq[str] | None = None,
    camera: Camera | _Path | None = None,
    max_distance: float = 0.01,
    animation: str | None = None,
    fps: float | None = None,
    mesh: str | None = None,
) -> Tracks:
    """Tracks points, pixels or given bindings through a sequence."""

def render_splats(
    ctx: Context,
    scene: _Path,
    camera: Camera | _Path,
    *,
    background: tuple[float, float, float] = ...,
    sh_degree: int = 3,
    near: float = 0.01,
    far: float = 1e4,
    mask: bool = False,
) -> NDArray[np.float32]:
    """Renders a 3DGS PLY scene: (H, W, 4) float32."""

def render_mesh(
    ctx: Context,
    mesh: Sequence | _Path,
    camera: Camera | _Path,
    frame: int = 0,
    *,
    near: float | None = None,
) -> NDArray[np.float32]:
    """Renders a mesh frame: (H, W, 4) float32."""

def eval(
    pred: _Path,
    gt: _Path,
    frames: tuple[int, int] | None = None,
    *,
    chamfer_samples: int | None = None,
    emd_samples: int | None = None,
    seed: int = 0,
) -> dict[str, Any]:
    """What ``tagsplat eval --json`` measures."""

@final
class Progress:
    """A job's latest report."""

    @property
    def stage(self) -> str: ...
    @property
    def frame(self) -> int: ...
    @property
    def frames_end(self) -> int: ...
    @property
    def iteration(self) -> int: ...
    @property
    def iterations(self) -> int: ...
    @property
    def loss(self) -> float | None: ...
    @property
    def elapsed_s(self) -> float: ...
    @property
    def update(self) -> int: ...

_Callback = Callable[[Progress], bool | None]

@final
class TrainJob:
    """A training run in progress."""

    def poll(self) -> Progress | None: ...
    def cancel(self) -> None: ...
    @property
    def done(self) -> bool: ...
    @property
    def progress(self) -> Progress: ...
    def wait(self, timeout: float | None = None) -> dict[str, Any]: ...

@final
class FitJob:
    """A fit in progress."""

    def poll(self) -> Progress | None: ...
    def cancel(self) -> None: ...
    @property
    def done(self) -> bool: ...
    @property
    def progress(self) -> Progress: ...
    def wait(self, timeout: float | None = None) -> dict[str, Any]: ...

def start_train(
    ctx: Context,
    data: _Path,
    out: _Path,
    *,
    config: Mapping[str, Any] | _Path | None = None,
    frames: _Frames | None = None,
    mesh: _Path | None = None,
    fps: float | None = None,
    up: str | None = None,
    scale: float | None = None,
    pixel_centers: str | None = None,
) -> TrainJob:
    """Starts a training run."""

def train(
    ctx: Context,
    data: _Path,
    out: _Path,
    *,
    config: Mapping[str, Any] | _Path | None = None,
    frames: _Frames | None = None,
    mesh: _Path | None = None,
    fps: float | None = None,
    up: str | None = None,
    scale: float | None = None,
    pixel_centers: str | None = None,
    progress: _Callback | None = None,
) -> dict[str, Any]:
    """Trains and blocks until the run ends."""

def start_fit(
    ctx: Context,
    data: _Path,
    frame: int = 0,
    *,
    out: _Path | None = None,
    config: Mapping[str, Any] | _Path | None = None,
    iterations: int | None = None,
    init: _Path | None = None,
    pixel_centers: str | None = None,
) -> FitJob:
    """Starts a fit."""

def fit(
    ctx: Context,
    data: _Path,
    frame: int = 0,
    *,
    out: _Path | None = None,
    config: Mapping[str, Any] | _Path | None = None,
    iterations: int | None = None,
    init: _Path | None = None,
    pixel_centers: str | None = None,
    progress: _Callback | None = None,
) -> dict[str, Any]:
    """Fits and blocks until it ends."""
