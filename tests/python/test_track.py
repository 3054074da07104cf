"""`track` through Python against the program's `tagsplat track` on the same sequence and
queries (identical numbers and files), its orientation frames against the mesh's own triangles,
given bindings written and read back, and its bad inputs."""

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


# A Z-up USD strip of two quads (each fanned into two triangles) over scene frames 10 to 12 at
# 24 per second, beside a second mesh, so the read needs mesh=.
STRIP_USDA = """#usda 1.0
(
    startTimeCode = 10
    endTimeCode = 12
    timeCodesPerSecond = 24
    upAxis = "Z"
)

def Mesh "Strip"
{
    int[] faceVertexCounts = [4, 4]
    int[] faceVertexIndices = [0, 1, 4, 3, 1, 2, 5, 4]
    point3f[] points.timeSamples = {
        10: [(0, 0, 0), (1, 0, 0), (2, 0, 0), (0, 1, 0), (1, 1, 0), (2, 1, 0)],
        11: [(0, 0, 0), (1, 0, 0.2), (2, 0, 0.6), (0, 1, 0.1), (1, 1, 0.3), (2, 1, 0.7)],
        12: [(0, 0, 0.1), (1, 0.1, 0.5), (2, 0, 1.2), (0, 1, 0.2), (1, 1.1, 0.6), (2, 1, 1.4)],
    }
}

def Mesh "Other"
{
    int[] faceVertexCounts = [3]
    int[] faceVertexIndices = [0, 1, 2]
    point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
}
"""
STRIP_POINTS = np.array([[0.3, 0.6, 0.0], [1.7, 0.2, 0.0], [1.2, 0.9, 0.0], [0.8, 0.1, 0.0]])


@pytest.fixture(scope="module")
def strip(tmp_path_factory):
    path = tmp_path_factory.mktemp("strip") / "strip.usda"
    path.write_text(STRIP_USDA)
    return path


def surface_frames(seq, faces):
    """Per point per frame, the normal and first-edge tangent of its triangle, from the mesh:
    (N, T, 3) each (docs/conventions.md's winding: counter-clockwise seen from outside)."""
    corners = seq.positions.astype(np.float64)[:, seq.faces[faces]]  # (T, N, 3 corners, 3)
    e1, e2 = corners[..., 1, :] - corners[..., 0, :], corners[..., 2, :] - corners[..., 0, :]
    n = np.cross(e1, e2)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    t = e1 - n * np.sum(e1 * n, axis=-1, keepdims=True)
    t /= np.linalg.norm(t, axis=-1, keepdims=True)
    return n.transpose(1, 0, 2), t.transpose(1, 0, 2)


def glb_json(path):
    """The JSON chunk of a GLB."""
    data = path.read_bytes()
    assert data[:4] == b"glTF"
    length = int.from_bytes(data[12:16], "little")
    return json.loads(data[20:20 + length])


def test_tracks_carry_the_programs_frames_polygons_clock_and_files(cli, strip, tmp_path):
    ids = ["a", "b", "c", "d"]
    write_table(tmp_path / "points.csv", ["id", "x", "y", "z"], ids, STRIP_POINTS)
    theirs = {k: tmp_path / f"cli.{k}" for k in ["csv", "json", "glb", "bindings.csv"]}
    run_cli(cli, "track", "--sequence", strip, "--mesh", "/Strip", "--points",
            tmp_path / "points.csv", "--out", theirs["csv"], "--json", theirs["json"],
            "--glb", theirs["glb"], "--bindings-out", theirs["bindings.csv"])
    tracks = tagsplat.track(strip, mesh="/Strip", points=STRIP_POINTS, ids=ids)
    ours = {k: tmp_path / f"py.{k}" for k in theirs}
    tracks.write_csv(ours["csv"])
    tracks.write_json(ours["json"])
    tracks.write_pins(ours["glb"])
    tracks.write_bindings(ours["bindings.csv"])
    for k in theirs:
        assert ours[k].read_bytes() == theirs[k].read_bytes(), k
    # The arrays are the files' numbers, and the mesh's own geometry.
    rows = list(csv.DictReader(open(theirs["csv"])))
    assert np.array_equal(tracks.normals.reshape(-1, 3),
                          [[float(r[k]) for k in ("nx", "ny", "nz")] for r in rows])
    assert np.array_equal(tracks.tangents.reshape(-1, 3),
                          [[float(r[k]) for k in ("tx", "ty", "tz")] for r in rows])
    seq = tagsplat.Sequence.read(strip, mesh="/Strip")
    faces, _ = tracks.bindings
    normals, tangents = surface_frames(seq, faces)
    assert np.abs(tracks.normals - normals).max() < 1e-12
    assert np.abs(tracks.tangents - tangents).max() < 1e-12
    assert not tracks.orientation_held.any() and tracks.orientation_held.shape == (4, 3)
    # Fanned quads: triangles 2q and 2q + 1 come from quad q.
    assert tracks.polygons.tolist() == (faces // 2).tolist() == [0, 1, 1, 0]
    assert np.allclose(tracks.times, np.array([10, 11, 12]) / 24, rtol=0, atol=1e-12)
    assert abs(tracks.fps - 24) < 1e-9 and abs(tracks.start_frame - 10) < 1e-9
    assert tracks.times.tolist() == [float(r["time"]) for r in rows[:3]]
    assert tracks.normals.base is not None and not tracks.normals.flags.writeable


def test_the_pins_glb_has_a_node_per_point_turned_from_the_files_up(strip, tmp_path):
    tracks = tagsplat.track(strip, mesh="/Strip", points=STRIP_POINTS, ids=["a", "b", "c", "d"])
    start = tracks.positions[:, 0].astype(np.float32)
    for from_up, turned in [(None, start[:, [0, 2, 1]] * [1, 1, -1]), ("+y", start)]:
        path = tmp_path / f"pins_{from_up}.glb"
        tracks.write_pins(path, from_up=from_up)
        document = glb_json(path)
        assert [n["name"] for n in document["nodes"]] == tracks.ids
        # Z up turned onto glTF's +Y: (x, y, z) -> (x, z, -y); the file's floats are float32.
        written = np.array([n["translation"] for n in document["nodes"]], dtype=np.float32)
        assert np.array_equal(written, turned.astype(np.float32)), from_up
        assert len(document["animations"][0]["channels"]) == 2 * len(tracks)
    with pytest.raises(tagsplat.BadInputError, match="from_up: 'up' is not one of"):
        tracks.write_pins(tmp_path / "bad.glb", from_up="up")


def test_bindings_written_and_given_back_track_the_same(seq, points, tmp_path):
    tracks = tagsplat.track(seq, points=points)
    tracks.write_bindings(tmp_path / "bindings.csv")
    from_file = tagsplat.track(seq, bindings=tmp_path / "bindings.csv")
    from_arrays = tagsplat.track(seq, bindings=tracks.bindings, ids=tracks.ids)
    for again in (from_file, from_arrays):
        assert again.ids == tracks.ids
        for name in ("positions", "normals", "tangents", "polygons"):
            assert np.array_equal(getattr(again, name), getattr(tracks, name)), name
        assert np.array_equal(again.bindings[1], tracks.bindings[1])
        assert not again.distances.any() and again.unbound == []
    # A vertex id follows that vertex exactly.
    vertices = [0, 7, 31]
    by_vertex = tagsplat.track(seq, bindings=vertices)
    assert by_vertex.ids == ["0", "1", "2"]
    assert np.array_equal(by_vertex.positions, seq.positions[:, vertices].transpose(1, 0, 2))


def test_bad_bindings_and_read_options_are_refused_by_name(seq, points, strip, tmp_path):
    faces, bary = tagsplat.track(seq, points=points).bindings
    with pytest.raises(tagsplat.BadInputError, match="give one of points, pixels with camera, or bindings"):
        tagsplat.track(seq, points=points, bindings=(faces, bary))
    with pytest.raises(ValueError, match=r"bindings barycentric: expected an array of shape \(N, 3\)"):
        tagsplat.track(seq, bindings=(faces, bary[:, :2]))
    with pytest.raises(tagsplat.BadInputError, match="bindings: 40 faces and 39 barycentric rows"):
        tagsplat.track(seq, bindings=(faces, bary[:-1]))
    far = faces.astype(np.int64)
    far[5] = len(seq.faces)
    with pytest.raises(tagsplat.BadInputError,
                       match=f"binding of point 5: face {len(seq.faces)} is out of range"):
        tagsplat.track(seq, bindings=(far, bary))
    with pytest.raises(tagsplat.BadInputError, match=r"bindings faces: row 2 \[-1\] is not a list of indices"):
        tagsplat.track(seq, bindings=(np.array([0, 1, -1]), bary[:3]))
    with pytest.raises(tagsplat.BadInputError, match="sums to 1.5, not 1"):
        tagsplat.track(seq, bindings=(faces[:1], [[0.5, 0.5, 0.5]]))
    with pytest.raises(tagsplat.BadInputError, match=f"vertex {seq.vertex_count} is out of range"):
        tagsplat.track(seq, bindings=[seq.vertex_count])
    with pytest.raises(TypeError, match="bindings: expected integer values"):
        tagsplat.track(seq, bindings=[0.5, 1.5])
    bad_file = tmp_path / "bad.csv"
    bad_file.write_text("id,face,u,v,w\nok,0,1,0,0\nfar,99999,1,0,0\n")
    with pytest.raises(tagsplat.BadInputError, match="bad.csv: line 3: face 99999 is out of range"):
        tagsplat.track(seq, bindings=bad_file)
    with pytest.raises(tagsplat.BadInputError, match="ids: not with a bindings file"):
        tagsplat.track(seq, bindings=bad_file, ids=["x"])
    with pytest.raises(tagsplat.BadInputError, match="animation, fps, mesh: only with the path"):
        tagsplat.track(seq, points=points, fps=30.0)
    with pytest.raises(tagsplat.FileFormatError, match="choose one with --mesh: /Strip, /Other"):
        tagsplat.track(strip, points=STRIP_POINTS)
