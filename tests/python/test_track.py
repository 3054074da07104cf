"""`track` through Python against the program's `tagsplat track` on the same sequence and
queries (identical numbers), and its bad inputs."""

import csv
import json
import os

import numpy as np
import pytest

import tagsplat
from conftest import run_cli


@pytest.fixture(scope="module")
def seq(data):
    return tagsplat.Sequence.read(data / "meshes")


@pytest.fixture(scope="module")
def points(seq):
    """Vertices of frame 0 pushed off the surface a little, and two points far from it."""
    rng = np.random.default_rng(3)
    frame0 = seq.positions[0].astype(np.float64)
    picked = frame0[rng.choice(len(frame0), 40, replace=False)]
    near = picked + rng.normal(scale=1e-3, size=picked.shape)
    far = frame0.mean(axis=0) + np.array([[10.0, 0, 0], [0, -10.0, 0]])
    return np.vstack([near, far])


def write_table(path, header, ids, rows):
    with open(path, "w", newline="") as f:
        out = csv.writer(f)
        out.writerow(header)
        for i, r in zip(ids, rows):
            out.writerow([i, *(repr(float(v)) for v in r)])


def read_tracks_csv(path):
    """{id: (T, 3)} from the program's tracks CSV."""
    rows = {}
    with open(path) as f:
        for r in csv.DictReader(f):
            rows.setdefault(r["id"], []).append((int(r["frame"]), [float(r[k]) for k in "xyz"]))
    return {i: np.array([p for _, p in sorted(v)]) for i, v in rows.items()}


def assert_same_as_cli(tracks, out):
    theirs = read_tracks_csv(out)
    assert list(theirs) == tracks.ids
    for k, i in enumerate(tracks.ids):
        assert np.array_equal(tracks.positions[k], theirs[i]), i
    report = json.loads(out.with_suffix(".json").read_text())
    faces, bary = tracks.bindings
    assert [p["face"] for p in report["points"]] == faces.tolist()
    assert [p["barycentric"] for p in report["points"]] == bary.tolist()
    assert [u["id"] for u in report["unbound"]] == [u["id"] for u in tracks.unbound]


def test_points_are_tracked_as_the_program_tracks_them(cli, data, seq, points, tmp_path):
    ids = [f"p{i}" for i in range(len(points))]
    write_table(tmp_path / "points.csv", ["id", "x", "y", "z"], ids, points)
    out = tmp_path / "tracks.csv"
    run_cli(cli, "track", "--sequence", data / "meshes", "--points", tmp_path / "points.csv",
            "--out", out, "--json", out.with_suffix(".json"))
    tracks = tagsplat.track(seq, points=points, ids=ids)
    assert len(tracks) == len(points) - 2 and len(tracks.unbound) == 2
    assert tracks.positions.shape == (len(tracks), len(seq), 3)
    assert_same_as_cli(tracks, out)
    # The same through a path and through a dict.
    by_path = tagsplat.track(data / "meshes", points=dict(zip(ids, points.tolist())))
    assert np.array_equal(by_path.positions, tracks.positions)


def test_pixels_are_tracked_as_the_program_tracks_them(cli, data, seq, tmp_path):
    centre = seq.positions[0].mean(axis=0).astype(np.float64)
    world_to_camera = np.eye(4)
    world_to_camera[:3, 3] = -centre + [0.0, 0.0, 3.0]
    camera = tagsplat.Camera(64, 48, 60.0, 60.0, 32.0, 24.0, world_to_camera)
    camera.write(tmp_path / "cam.json")
    uv = np.array([[32.5, 24.5], [30.0, 20.0], [1.0, 1.0], [34.5, 26.0]])
    ids = ["a", "b", "c", "d"]
    write_table(tmp_path / "pixels.csv", ["id", "u", "v"], ids, uv)
    out = tmp_path / "tracks.csv"
    run_cli(cli, "track", "--sequence", data / "meshes", "--pixels", tmp_path / "pixels.csv",
            "--camera", tmp_path / "cam.json", "--out", out, "--json", out.with_suffix(".json"))
    tracks = tagsplat.track(seq, pixels=uv, ids=ids, camera=camera)
    assert len(tracks) >= 1
    assert_same_as_cli(tracks, out)


def test_bad_queries_are_refused_by_name(seq, points):
    with pytest.raises(TypeError, match="points: expected float32 or float64"):
        tagsplat.track(seq, points=points.astype(np.int64))
    with pytest.raises(ValueError, match=r"points: expected an array of shape \(N, 3\)"):
        tagsplat.track(seq, points=points[:, :2])
    nan = points.copy()
    nan[3, 1] = np.nan
    with pytest.raises(tagsplat.BadInputError, match="points: row 3"):
        tagsplat.track(seq, points=nan)
    with pytest.raises(tagsplat.BadInputError, match="ids: 2 ids for"):
        tagsplat.track(seq, points=points, ids=["a", "b"])
    with pytest.raises(tagsplat.BadInputError, match="max_distance"):
        tagsplat.track(seq, points=points, max_distance=-1.0)
    with pytest.raises(tagsplat.BadInputError, match="pixels: need camera"):
        tagsplat.track(seq, pixels=points[:, :2])
    with pytest.raises(tagsplat.BadInputError):
        tagsplat.track(seq)
    with pytest.raises(tagsplat.BadInputError, match="no_such_sequence"):
        tagsplat.track("no_such_sequence", points=points)
    # A non-contiguous array is copied, not refused.
    strided = np.asfortranarray(points)
    assert np.array_equal(tagsplat.track(seq, points=strided).positions,
                          tagsplat.track(seq, points=points).positions)


def test_nan_in_a_camera_is_refused_by_name():
    matrix = np.eye(4)
    matrix[0, 3] = np.nan
    with pytest.raises(tagsplat.BadInputError, match="world_to_camera"):
        tagsplat.Camera(64, 48, 60.0, 60.0, 32.0, 24.0, matrix)
    with pytest.raises(tagsplat.BadInputError, match="focal"):
        tagsplat.Camera(64, 48, np.nan, 60.0, 32.0, 24.0, np.eye(4))
    with pytest.raises(ValueError, match=r"world_to_camera: expected an array of shape \(4, 4\)"):
        tagsplat.Camera(64, 48, 60.0, 60.0, 32.0, 24.0, np.eye(3))


def resident_bytes():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def test_a_thousand_tracks_keep_resident_memory_flat(seq, points):
    for _ in range(50):
        tagsplat.track(seq, points=points)
    before = resident_bytes()
    for _ in range(1000):
        tracks = tagsplat.track(seq, points=points)
        tracks.positions.sum()
    grown = resident_bytes() - before
    # One call's arrays are a few kB; a leak of even one copy of the sequence per call would
    # be over 100 MB here.
    assert grown < 8 << 20, f"resident memory grew {grown} bytes over 1000 calls"
