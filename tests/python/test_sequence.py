"""Sequences: arrays in and out (zero-copy views), and every format the engine writes, checked
against the program's `tagsplat convert` and an independent PC2 reader."""

import struct

import numpy as np
import pytest

import tagsplat
from conftest import ROOT, run_cli


@pytest.fixture(scope="module")
def meshes(data):
    """The generated ground-truth sequence, a folder of frames."""
    return data / "meshes"


def read_pc2(path):
    """(T, V, 3) float32 from a PC2 file, read by its published layout (not the engine)."""
    raw = path.read_bytes()
    magic, version, points, _start, _rate, samples = struct.unpack("<12siiffi", raw[:32])
    assert magic == b"POINTCACHE2\0" and version == 1
    return np.frombuffer(raw[32:], dtype="<f4").reshape(samples, points, 3)


def test_arrays_are_views_of_the_sequence_without_a_copy(meshes):
    seq = tagsplat.Sequence.read(meshes)
    a, b = seq.positions, seq.positions
    assert a.base is not None and np.shares_memory(a, b)
    assert not a.flags.writeable and a.flags.c_contiguous
    assert a.dtype == np.float32 and a.shape == (len(seq), seq.vertex_count, 3)
    assert seq.faces.dtype == np.uint32 and seq.faces.shape[1] == 3
    assert np.shares_memory(seq.faces, seq.faces)
    assert seq.colors is None or seq.colors.dtype == np.uint8


@pytest.mark.parametrize("name", ["seq.pc2", "seq.glb", "seq.usda", "frames_ply", "frames_obj"])
def test_every_format_is_written_as_the_program_writes_it(cli, meshes, tmp_path, name):
    seq = tagsplat.Sequence.read(meshes)
    ours, theirs = tmp_path / "ours" / name, tmp_path / "cli" / name
    ours.parent.mkdir()
    theirs.parent.mkdir()
    fmt = "obj" if name.endswith("obj") else "ply"
    seq.write(ours, fps=30, up="z", frame_format=fmt)
    run_cli(cli, "convert", "--sequence", meshes, "--to", theirs, "--fps", 30, "--up", "z",
            "--frame-format", fmt)
    files = sorted(p.relative_to(theirs.parent) for p in theirs.parent.rglob("*") if p.is_file())
    assert files
    for f in files:
        assert (ours.parent / f).read_bytes() == (theirs.parent / f).read_bytes(), f


def test_positions_round_trip_through_files(meshes, tmp_path):
    seq = tagsplat.Sequence.read(meshes)
    seq.write(tmp_path / "a.pc2")
    assert np.array_equal(read_pc2(tmp_path / "a.pc2"), seq.positions)
    seq.write(tmp_path / "a.glb")
    seq.write(tmp_path / "frames")
    for target in ["a.pc2", "a.glb", "frames"]:
        back = tagsplat.Sequence.read(tmp_path / target)
        assert np.array_equal(back.faces, seq.faces), target
        if target == "a.glb":
            # Morph targets hold each frame's offset from the base: exact to float rounding.
            assert np.allclose(back.positions, seq.positions, rtol=0, atol=1e-6)
        else:
            assert np.array_equal(back.positions, seq.positions), target


def test_a_sequence_from_arrays_equals_the_one_read(meshes):
    seq = tagsplat.Sequence.read(meshes)
    made = tagsplat.Sequence(seq.faces.astype(np.int64), seq.positions.astype(np.float64))
    assert np.array_equal(made.positions, seq.positions)
    assert np.array_equal(made.faces, seq.faces)
    # A non-contiguous array is copied, not refused.
    strided = np.asfortranarray(seq.positions)
    assert np.array_equal(tagsplat.Sequence(seq.faces, strided).positions, seq.positions)


def test_wrong_arrays_are_refused_by_name(meshes):
    seq = tagsplat.Sequence.read(meshes)
    with pytest.raises(TypeError, match="positions: expected float32 or float64"):
        tagsplat.Sequence(seq.faces, seq.positions.astype(np.int32))
    with pytest.raises(TypeError, match="faces: expected integer values"):
        tagsplat.Sequence(seq.faces.astype(np.float32), seq.positions)
    with pytest.raises(ValueError, match=r"positions: expected an array of shape \(T, V, 3\)"):
        tagsplat.Sequence(seq.faces, seq.positions[..., :2])
    with pytest.raises(ValueError, match=r"colors: expected an array of shape"):
        tagsplat.Sequence(seq.faces, seq.positions, np.zeros((1, 2, 3), np.uint8))
    bad = seq.positions.copy()
    bad[1, 4, 2] = np.nan
    with pytest.raises(tagsplat.BadInputError, match="frame 1"):
        tagsplat.Sequence(seq.faces, bad)
    faces = seq.faces.astype(np.int64)
    faces[0, 0] = -1
    with pytest.raises(tagsplat.BadInputError, match="faces: row 0"):
        tagsplat.Sequence(faces, seq.positions)
    faces[0, 0] = seq.vertex_count
    with pytest.raises(tagsplat.BadInputError):
        tagsplat.Sequence(faces, seq.positions)


def test_paths_that_are_no_sequence_are_refused_by_name(tmp_path):
    with pytest.raises(tagsplat.BadInputError, match="nothing: no such file or folder"):
        tagsplat.Sequence.read(tmp_path / "nothing")
    text = tmp_path / "notes.txt"
    text.write_text("not a mesh")
    with pytest.raises(tagsplat.BadInputError, match="notes.txt: not a sequence"):
        tagsplat.Sequence.read(text)
    broken = tmp_path / "broken.glb"
    broken.write_bytes(b"glTF garbage")
    with pytest.raises(tagsplat.FileFormatError, match="broken.glb"):
        tagsplat.Sequence.read(broken)


def test_a_missing_sequence_file_is_bad_input(tmp_path):
    with pytest.raises(tagsplat.BadInputError, match="nothing.glb"):
        tagsplat.Sequence.read(tmp_path / "nothing.glb")


def test_read_options_reach_the_engine(meshes):
    fox = ROOT / "tests" / "formats" / "data" / "khronos" / "Fox.glb"
    run = tagsplat.Sequence.read(fox, animation="Run", fps=30.0)
    assert run.fps == 30.0 and len(run.times) == len(run) and run.times[0] == 0.0
    assert run.up == "+Y" and run.vertex_count == 1728
    assert any("Run" in note for note in run.notes)
    with pytest.raises(tagsplat.Error, match="Survey"):
        tagsplat.Sequence.read(fox)  # three animations and no choice: the error lists them
    with pytest.raises(tagsplat.BadInputError, match="--animation has no meaning for a folder"):
        tagsplat.Sequence.read(meshes, animation="Run")
    clocked = tagsplat.Sequence.read(meshes, fps=12.0)
    assert clocked.fps == 12.0 and clocked.times is None
