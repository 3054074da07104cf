"""The rest of the package: devices and contexts, dataset info and eval against the program's
JSON, rendering, the exception hierarchy, and docstrings on every public name."""

import inspect
import json

import numpy as np
import pytest

import tagsplat
from conftest import run_cli


def test_devices_and_the_context(ctx):
    devices = tagsplat.devices()
    assert devices and sum(d.chosen for d in devices) <= 1
    assert ctx.device.name in [d.name for d in devices]
    with pytest.raises(tagsplat.DeviceError, match="no Vulkan device matches"):
        tagsplat.Context(device="no-such-device")
    with pytest.raises(tagsplat.BadInputError, match="device_memory"):
        tagsplat.Context(device_memory="lots")


def test_dataset_info_says_what_the_program_says(cli, ctx, data):
    ours = tagsplat.dataset_info(ctx, data)
    theirs = json.loads(run_cli(cli, "dataset", "info", "--data", data, "--json"))
    assert ours["cameras"] == theirs["cameras"] and ours["frames"] == theirs["frames"]
    assert ours["memory"] == theirs["memory"] and ours["missing"] == theirs["missing"]
    with pytest.raises(tagsplat.Error, match="no_such_data"):
        tagsplat.dataset_info(ctx, data / "no_such_data")


def test_eval_gives_the_programs_figures(cli, data, tmp_path):
    ours = tagsplat.eval(data, data, chamfer_samples=500, emd_samples=50)
    theirs = json.loads(run_cli(cli, "eval", "--pred", data, "--gt", data, "--json",
                                "--chamfer-samples", 500, "--emd-samples", 50))
    assert ours == theirs


def test_render_mesh_covers_the_mesh_it_is_given(ctx, data):
    seq = tagsplat.Sequence.read(data / "meshes")
    centre = seq.positions[0].mean(axis=0).astype(np.float64)
    world_to_camera = np.eye(4)
    world_to_camera[:3, 3] = -centre + [0.0, 0.0, 3.0]
    camera = tagsplat.Camera(64, 48, 60.0, 60.0, 32.0, 24.0, world_to_camera)
    image = tagsplat.render_mesh(ctx, seq, camera, 1)
    assert image.shape == (48, 64, 4) and image.dtype == np.float32
    coverage = image[..., 3]
    assert coverage.max() > 0.99 and coverage.min() == 0.0
    with pytest.raises(tagsplat.BadInputError, match="frame: 99"):
        tagsplat.render_mesh(ctx, seq, camera, 99)


def test_errors_form_one_hierarchy():
    for kind in [tagsplat.BadInputError, tagsplat.FileFormatError, tagsplat.DeviceError,
                 tagsplat.CancelledError]:
        assert issubclass(kind, tagsplat.Error)
    assert issubclass(tagsplat.BadInputError, ValueError)
    assert tagsplat.BadInputError.__module__ == "tagsplat"


def test_every_public_name_has_a_docstring():
    assert tagsplat.__doc__ and tagsplat.__version__
    for name in tagsplat.__all__:
        if name == "__version__":
            continue
        value = getattr(tagsplat, name)
        assert inspect.getdoc(value), name
        if inspect.isclass(value) and not issubclass(value, BaseException):
            for member, attribute in vars(value).items():
                if not member.startswith("_"):
                    assert inspect.getdoc(attribute), f"{name}.{member}"
