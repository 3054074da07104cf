//! The USD reader against Pixar's own library: usd-core (`.tools/usd`, scripts/setup.sh) writes
//! the fixtures at test time (text and binary encodings of the same stages) and evaluates them:
//! each mesh's points at every time code, through `ComputeLocalToWorldTransform`. The reader's
//! frames must match to 1e-6 of the figure's size; its polygons must be pxr's, reversed for a
//! `leftHanded` or mirrored mesh. The engine's own `.usda` export must read back as written.

#[path = "../common/mod.rs"]
mod common;

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;
use tagsplat::sequence::orient::{Orientation, SignedAxis, UpAxis};
use tagsplat::sequence::usd::write_usda;
use tagsplat::sequence::{usd_read, MeshSequence, ReadOptions};

/// Writes the fixtures into `dir` and prints, per file, what pxr evaluates (see `evaluate`).
const FIXTURES: &str = r#"import json, sys
from pxr import Usd, UsdGeom, Gf, Vt, Sdf

out = sys.argv[1]

def body_points(t):
    # Two quads and a triangle on five-plus vertices that bend over time.
    base = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (2, 0, 0), (2, 1, 0), (3, 0.5, 0.2)]
    return [Gf.Vec3f(x, y + 0.1 * t * x, z + 0.05 * t * t * y) for x, y, z in base]

def animated(path):
    stage = Usd.Stage.CreateNew(path)
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    UsdGeom.SetStageMetersPerUnit(stage, 0.01)
    stage.SetTimeCodesPerSecond(30)
    stage.SetStartTimeCode(1)
    stage.SetEndTimeCode(5)
    world = UsdGeom.Xform.Define(stage, "/World")
    move = world.AddTranslateOp()
    move.Set(Gf.Vec3d(0, 0, 0), 1)
    move.Set(Gf.Vec3d(4, -2, 1), 5)
    world.AddRotateXYZOp().Set(Gf.Vec3f(10, 20, 30))
    world.AddScaleOp().Set(Gf.Vec3f(2, 2, 2))
    body = UsdGeom.Mesh.Define(stage, "/World/Rig/Body")
    body.CreateFaceVertexCountsAttr([4, 4, 3])
    body.CreateFaceVertexIndicesAttr([0, 1, 2, 3, 1, 4, 5, 2, 4, 6, 5])
    for t in [1, 2, 3, 4, 5]:
        body.GetPointsAttr().Set(body_points(t), t)
    body.AddTransformOp().Set(Gf.Matrix4d(1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0.5, 0.25, -1, 1))
    pivot = body.AddTranslateOp(opSuffix="pivot")
    pivot.Set(Gf.Vec3d(1, 0.5, 0))
    turn = body.AddOrientOp()
    turn.Set(Gf.Quatf(1, 0, 0, 0), 1)
    turn.Set(Gf.Quatf(0.8, 0.36, 0.48, 0).GetNormalized(), 2.5)
    turn.Set(Gf.Quatf(0, 0, 1, 0), 5)
    body.AddRotateYXZOp().Set(Gf.Vec3f(5, -15, 25))
    body.AddTranslateOp(opSuffix="pivot", isInverseOp=True)
    UsdGeom.Xform.Define(stage, "/World/Rig")
    other = UsdGeom.Mesh.Define(stage, "/World/Other")
    other.CreateFaceVertexCountsAttr([3])
    other.CreateFaceVertexIndicesAttr([0, 1, 2])
    other.CreatePointsAttr([(0, 0, 0), (1, 0, 0), (0, 1, 0)])
    stage.GetRootLayer().Save()

def left_handed(path):
    stage = Usd.Stage.CreateNew(path)
    mesh = UsdGeom.Mesh.Define(stage, "/Left")
    mesh.CreateOrientationAttr(UsdGeom.Tokens.leftHanded)
    mesh.CreateFaceVertexCountsAttr([4, 3])
    mesh.CreateFaceVertexIndicesAttr([0, 1, 2, 3, 1, 4, 2])
    mesh.CreatePointsAttr([(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (2, 0.5, 0)])
    stage.GetRootLayer().Save()

def mirrored(path):
    stage = Usd.Stage.CreateNew(path)
    UsdGeom.Xform.Define(stage, "/Mirror").AddScaleOp().Set(Gf.Vec3f(-1, 1, 1))
    mesh = UsdGeom.Mesh.Define(stage, "/Mirror/Mesh")
    mesh.CreateFaceVertexCountsAttr([3, 4])
    mesh.CreateFaceVertexIndicesAttr([0, 1, 2, 1, 3, 4, 2])
    mesh.CreatePointsAttr([(0, 0, 0), (1, 0, 0), (0, 1, 0), (2, 0, 0), (2, 1, 0)])
    stage.GetRootLayer().Save()

def evaluate(path, mesh_path):
    """What pxr says: the world points of `mesh_path` at every time code of its points and of
    the xform ops on it and its ancestors."""
    stage = Usd.Stage.Open(path)
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath(mesh_path))
    codes = set(mesh.GetPointsAttr().GetTimeSamples())
    prim = mesh.GetPrim()
    while prim and not prim.IsPseudoRoot():
        xformable = UsdGeom.Xformable(prim)
        if xformable:
            for op in xformable.GetOrderedXformOps():
                codes.update(op.GetAttr().GetTimeSamples())
        prim = prim.GetParent()
    codes = sorted(codes) or [Usd.TimeCode.Default()]
    frames = []
    for t in codes:
        world = mesh.ComputeLocalToWorldTransform(t)
        frames.append([list(world.Transform(Gf.Vec3d(p))) for p in mesh.GetPointsAttr().Get(t)])
    return {
        "meshes": [str(p.GetPath()) for p in stage.Traverse() if p.IsA(UsdGeom.Mesh)],
        "codes": [c if isinstance(c, float) else None for c in codes],
        "frames": frames,
        "counts": list(mesh.GetFaceVertexCountsAttr().Get()),
        "indices": list(mesh.GetFaceVertexIndicesAttr().Get()),
        "orientation": mesh.GetOrientationAttr().Get(),
        "up": UsdGeom.GetStageUpAxis(stage),
        "meters_per_unit": UsdGeom.GetStageMetersPerUnit(stage),
        "time_codes_per_second": stage.GetTimeCodesPerSecond(),
    }

animated(f"{out}/anim.usda")
Sdf.Layer.FindOrOpen(f"{out}/anim.usda").Export(f"{out}/anim.usdc")
left_handed(f"{out}/left.usda")
mirrored(f"{out}/mirror.usda")
Sdf.Layer.FindOrOpen(f"{out}/left.usda").Export(f"{out}/left.usdc")
result = {name: evaluate(f"{out}/{name}", mesh) for name, mesh in [
    ("anim.usda", "/World/Rig/Body"), ("anim.usdc", "/World/Rig/Body"),
    ("left.usda", "/Left"), ("left.usdc", "/Left"), ("mirror.usda", "/Mirror/Mesh")]}
print(json.dumps(result))
"#;

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tagsplat-usd-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The fixtures written into `dir` and pxr's evaluation of them, or None (SKIPPED) without
/// usd-core.
fn pxr_fixtures(dir: &Path) -> Option<Value> {
    let python = Path::new(env!("CARGO_MANIFEST_DIR")).join(".tools/usd/bin/python");
    let has_pxr = Command::new(&python).args(["-c", "import pxr"]).output();
    if !has_pxr.is_ok_and(|o| o.status.success()) {
        common::skipped(
            "comparing the USD reader with Pixar's USD library",
            "usd-core is not installed in .tools/usd (run scripts/setup.sh)",
        );
        return None;
    }
    let out = Command::new(&python).args(["-c", FIXTURES]).arg(dir).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    Some(serde_json::from_slice(&out.stdout).unwrap())
}

fn options(mesh: &str) -> ReadOptions {
    ReadOptions { mesh: Some(mesh.to_owned()), ..ReadOptions::default() }
}

fn indices(value: &Value) -> Vec<u32> {
    value.as_array().unwrap().iter().map(|v| v.as_u64().unwrap() as u32).collect()
}

/// Each polygon of `indices` with its vertices in the opposite order, its first kept first.
fn reversed(counts: &[u32], indices: &[u32]) -> Vec<u32> {
    let mut out = Vec::new();
    let mut start = 0;
    for &count in counts {
        let polygon = &indices[start..start + count as usize];
        out.push(polygon[0]);
        out.extend(polygon[1..].iter().rev());
        start += count as usize;
    }
    out
}

/// The largest distance between our frames and pxr's, over the diagonal of pxr's frame-0 box.
fn relative_error(ours: &[Vec<[f32; 3]>], pxr: &Value) -> f64 {
    let pxr: Vec<Vec<Vec<f64>>> = serde_json::from_value(pxr.clone()).unwrap();
    assert_eq!(ours.len(), pxr.len(), "frame count");
    let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
    for p in &pxr[0] {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let size = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt();
    let mut worst = 0.0f64;
    for (frame, expected) in ours.iter().zip(&pxr) {
        assert_eq!(frame.len(), expected.len(), "vertex count");
        for (a, b) in frame.iter().zip(expected) {
            let d = (0..3).map(|k| (f64::from(a[k]) - b[k]).powi(2)).sum::<f64>().sqrt();
            worst = worst.max(d / size);
        }
    }
    worst
}

#[test]
fn frames_polygons_times_and_axes_match_pixars_evaluation() {
    let dir = temp_dir("pxr");
    let Some(pxr) = pxr_fixtures(&dir) else { return };
    for (file, mesh) in [
        ("anim.usda", "/World/Rig/Body"),
        ("anim.usdc", "/World/Rig/Body"),
        ("left.usda", "/Left"),
        ("left.usdc", "/Left"),
        ("mirror.usda", "/Mirror/Mesh"),
    ] {
        let expected = &pxr[file];
        let read = usd_read::read(&dir.join(file), &options(mesh)).unwrap();
        let error = relative_error(&read.frames, &expected["frames"]);
        eprintln!("{file}: {} frames, largest error {error:.2e} of the size", read.frames.len());
        assert!(error < 1e-6, "{file}: {error}");
        let counts = indices(&expected["counts"]);
        let mirrored = file.starts_with("left") || file.starts_with("mirror");
        let mut polygons = indices(&expected["indices"]);
        if mirrored {
            polygons = reversed(&counts, &polygons);
        }
        assert_eq!((&read.counts, &read.indices), (&counts, &polygons), "{file}");
        let rate = expected["time_codes_per_second"].as_f64().unwrap();
        let codes: Vec<f64> = expected["codes"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| c.as_f64().unwrap_or(0.0))
            .collect();
        let times: Vec<f64> = codes.iter().map(|c| c / rate).collect();
        assert_eq!(read.times, times, "{file}");
        let up = SignedAxis::parse(expected["up"].as_str().unwrap());
        assert_eq!((read.up, read.meters_per_unit), (up, expected["meters_per_unit"].as_f64()));
    }
    // The same through the engine's entry point: the polygons fanned, the axes reported.
    let (sequence, info) =
        MeshSequence::read_with(&dir.join("anim.usdc"), &options("/World/Rig/Body")).unwrap();
    assert_eq!(sequence.faces.len(), 5);
    assert_eq!(info.polygon_of, Some(vec![0, 0, 1, 1, 2]));
    assert_eq!(info.up, SignedAxis::parse("+Z"));
    assert_eq!(info.meters_per_unit, Some(0.01));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn several_meshes_need_a_choice_that_names_one_of_them() {
    let dir = temp_dir("choice");
    let Some(pxr) = pxr_fixtures(&dir) else { return };
    let path = dir.join("anim.usda");
    let error = MeshSequence::read_with(&path, &ReadOptions::default()).unwrap_err().to_string();
    let listed = pxr["anim.usda"]["meshes"].as_array().unwrap().iter().map(|m| m.as_str());
    assert!(listed.into_iter().all(|m| error.contains(m.unwrap())), "{error}");
    assert!(error.contains("anim.usda") && error.contains("--mesh"), "{error}");
    let error = MeshSequence::read_with(&path, &options("/World/Nothing")).unwrap_err();
    assert!(error.to_string().contains("no Mesh prim /World/Nothing"), "{error}");
    let (other, _) = MeshSequence::read_with(&path, &options("/World/Other")).unwrap();
    // Static itself, but under /World's animated translate: a frame at each of its keys.
    assert_eq!((other.frames.len(), other.faces.len()), (2, 1));
    let fps = ReadOptions { fps: Some(24.0), ..ReadOptions::default() };
    let error = MeshSequence::read_with(&path, &fps).unwrap_err().to_string();
    assert!(error.contains("--fps has no meaning"), "{error}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_engines_own_usda_reads_back_as_written() {
    let dir = temp_dir("round-trip");
    let frame = |t: f32| -> Vec<[f32; 3]> {
        let lift = 0.1 * t;
        vec![[0.0, 0.0, lift], [1.0, 0.0, 0.0], [0.0, 1.0, 0.5], [0.2, 0.3, 1.0 + lift / 3.0]]
    };
    let written = MeshSequence {
        faces: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        frames: (0..4).map(|t| frame(t as f32)).collect(),
        colors: None,
    };
    let path = dir.join("sequence.usda");
    write_usda(&path, &written, 25.0, Orientation::keep(UpAxis::Z), None).unwrap();
    let (read, info) = MeshSequence::read_with(&path, &ReadOptions::default()).unwrap();
    assert_eq!(read, written);
    assert_eq!(info.times, Some(vec![0.0, 0.04, 0.08, 0.12]));
    assert_eq!((info.up, info.meters_per_unit), (SignedAxis::parse("+Z"), Some(1.0)));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A stage of one mesh whose body (inside `def Mesh "M"`) is `body`.
fn stage_with(dir: &Path, name: &str, header: &str, body: &str) -> PathBuf {
    let path = dir.join(name);
    let text = format!("#usda 1.0\n{header}\ndef Mesh \"M\"\n{{\n{body}\n}}\n");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn changing_topology_unknown_ops_and_broken_composition_are_refused() {
    let dir = temp_dir("refused");
    let points = "point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 0)]";
    let counts = "int[] faceVertexCounts = [3]";
    let cases = [
        (
            "topology.usda",
            "",
            format!("{points}\n{counts}\nint[] faceVertexIndices.timeSamples = {{ 0: [0, 1, 2], 1: [1, 3, 2] }}"),
            "not one connectivity: /M.faceVertexIndices changes at time code 1",
        ),
        (
            "shear.usda",
            "",
            format!("{points}\n{counts}\nint[] faceVertexIndices = [0, 1, 2]\nfloat3 xformOp:shear = (1, 0, 0)\nuniform token[] xformOpOrder = [\"xformOp:shear\"]"),
            "/M.xformOp:shear: not an xformOp this reader knows",
        ),
        (
            "unset.usda",
            "",
            format!("{points}\n{counts}\nint[] faceVertexIndices = [0, 1, 2]\nuniform token[] xformOpOrder = [\"xformOp:translate\"]"),
            "/M.xformOp:translate: named in xformOpOrder but has no value",
        ),
        (
            "sublayer.usda",
            "(\n    subLayers = [@missing.usda@]\n)",
            format!("{points}\n{counts}\nint[] faceVertexIndices = [0, 1, 2]"),
            "composition failed",
        ),
        (
            "negative.usda",
            "",
            format!("{points}\n{counts}\nint[] faceVertexIndices = [0, -1, 2]"),
            "/M.faceVertexIndices[1] is -1",
        ),
        // Hostile text openusd 0.6 would never finish composing, or would overflow the stack
        // parsing: a prim whose path ends in `}`, an op that is no property name, deep nesting.
        (
            "brace.usda",
            "",
            format!("{points}\n{counts}\nint[] faceVertexIndices = [0, 1, 2]\ndef Xform \"A}}\" {{}}"),
            "the prim /M has a child named \"A}\", not an identifier",
        ),
        (
            "target.usda",
            "",
            format!("{points}\n{counts}\nint[] faceVertexIndices = [0, 1, 2]\nrel r = </A}}>"),
            "the path /A} has no root openusd can find",
        ),
        // A prim named "" is its parent again: traversing the stage would never end.
        (
            "unnamed.usda",
            "",
            format!("{points}\n{counts}\nint[] faceVertexIndices = [0, 1, 2]\ndef Xform \"\" {{}}"),
            "the prim /M has a child named \"\", not an identifier",
        ),
        (
            "op.usda",
            "",
            format!("{points}\n{counts}\nint[] faceVertexIndices = [0, 1, 2]\nuniform token[] xformOpOrder = [\"xformOp:translate}}\"]"),
            "/M.xformOp:translate}: not an xformOp this reader knows",
        ),
        (
            "nested.usda",
            &format!("(\n    customLayerData = {}\n)", "{ dictionary d = ".repeat(600) + &"}".repeat(600)),
            format!("{points}\n{counts}\nint[] faceVertexIndices = [0, 1, 2]"),
            "text nested 601 deep, more than 512",
        ),
    ];
    for (name, header, body, expected) in cases {
        let path = stage_with(&dir, name, header, &body);
        let error = MeshSequence::read_with(&path, &ReadOptions::default()).unwrap_err();
        let error = error.to_string();
        assert!(error.contains(name) && error.contains(expected), "{name}: {error}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
