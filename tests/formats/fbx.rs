//! The FBX reader against Blender: `data/blender/strip.fbx` was written by Blender's FBX
//! exporter from a skinned strip with an animated shape key and an animated unskinned prop,
//! and `strip.json` holds Blender's own evaluated vertices of both at each frame, in the file's
//! axes and units (both made by tests/blender/make_fixtures.py; see `data/blender/README.md`).

use serde_json::Value;
use std::path::{Path, PathBuf};
use tagsplat::sequence::orient::SignedAxis;
use tagsplat::sequence::{MeshSequence, ReadOptions, SequenceInfo};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/formats/data/blender").join(name)
}

fn blender() -> Value {
    let text = std::fs::read_to_string(data("strip.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

fn read(options: ReadOptions) -> Result<(MeshSequence, SequenceInfo), String> {
    MeshSequence::read_with(&data("strip.fbx"), &options).map_err(|e| e.to_string())
}

fn mesh(name: &str) -> ReadOptions {
    ReadOptions { mesh: Some(name.into()), ..ReadOptions::default() }
}

/// Blender's frames of mesh `name`, (T, V, 3).
fn blender_frames(name: &str) -> Vec<Vec<[f64; 3]>> {
    let frames = &blender()["fbx"]["meshes"][name]["frames"];
    let point = |p: &Value| [0, 1, 2].map(|i| p[i].as_f64().unwrap());
    frames
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_array().unwrap().iter().map(point).collect())
        .collect()
}

/// The largest distance of a frame's vertex from Blender's, as a fraction of Blender's
/// frame-0 bounding-box diagonal.
fn worst_error(read: &[Vec<[f32; 3]>], expected: &[Vec<[f64; 3]>]) -> f64 {
    assert_eq!(read.len(), expected.len(), "frame count");
    let (lo, hi) = expected[0].iter().fold(([f64::MAX; 3], [f64::MIN; 3]), |(lo, hi), p| {
        ([0, 1, 2].map(|i| lo[i].min(p[i])), [0, 1, 2].map(|i| hi[i].max(p[i])))
    });
    let size = (0..3).map(|i| (hi[i] - lo[i]).powi(2)).sum::<f64>().sqrt();
    let distance = |a: &[f32; 3], b: &[f64; 3]| {
        (0..3).map(|i| (f64::from(a[i]) - b[i]).powi(2)).sum::<f64>().sqrt()
    };
    let mut worst = 0.0f64;
    for (frame, blender) in read.iter().zip(expected) {
        assert_eq!(frame.len(), blender.len(), "vertex count");
        worst = frame.iter().zip(blender).map(|(a, b)| distance(a, b)).fold(worst, f64::max);
    }
    worst / size
}

/// Blender's polygons fanned from their first vertex, and the polygon of each triangle.
fn fans(polygons: &Value) -> (Vec<[u32; 3]>, Vec<u32>) {
    let mut faces = Vec::new();
    let mut of = Vec::new();
    for (p, polygon) in polygons.as_array().unwrap().iter().enumerate() {
        let v: Vec<u32> =
            polygon.as_array().unwrap().iter().map(|i| i.as_u64().unwrap() as u32).collect();
        for k in 1..v.len() - 1 {
            faces.push([v[0], v[k], v[k + 1]]);
            of.push(p as u32);
        }
    }
    (faces, of)
}

#[test]
fn the_skinned_strip_with_its_shape_key_is_blenders_evaluation_at_every_frame() {
    let (sequence, info) = read(mesh("Strip")).unwrap();
    let error = worst_error(&sequence.frames, &blender_frames("Strip"));
    println!("FBX strip (skin + blend shape): max error {error:.2e} of the size");
    assert!(error <= 1e-6, "{error:.2e} of the size from Blender's vertices");
    let (faces, polygon_of) = fans(&blender()["fbx"]["meshes"]["Strip"]["polygons"]);
    assert_eq!(sequence.faces, faces, "the file's polygons over its control points");
    assert_eq!(info.polygon_of, Some(polygon_of));
    let times: Vec<f64> =
        blender()["times"].as_array().unwrap().iter().map(|t| t.as_f64().unwrap()).collect();
    let got = info.times.as_deref().unwrap();
    assert!(got.iter().zip(&times).all(|(a, b)| (a - b).abs() < 1e-9), "{got:?} vs {times:?}");
    assert!((info.fps.unwrap() - 24.0).abs() < 1e-9);
    assert_eq!(info.up, Some(SignedAxis { axis: 1, negative: false }));
    assert_eq!(info.meters_per_unit, Some(0.01), "Blender writes centimetres");
    assert!(
        info.notes.iter().any(|n| n.contains("skinned (2 bones), 1 blend shapes")),
        "{:?}",
        info.notes
    );
}

#[test]
fn the_unskinned_prop_moves_with_its_node() {
    let (sequence, _) = read(mesh("Prop")).unwrap();
    let error = worst_error(&sequence.frames, &blender_frames("Prop"));
    println!("FBX prop (node animation): max error {error:.2e} of the size");
    assert!(error <= 1e-6, "{error:.2e} of the size from Blender's vertices");
    assert_eq!(sequence.faces, [[0, 1, 2]]);
}

#[test]
fn choices_are_required_named_and_checked() {
    let file = data("strip.fbx").display().to_string();
    let e = read(ReadOptions::default()).unwrap_err();
    assert!(
        e.starts_with(&file) && e.contains("2 mesh nodes") && e.contains("`Strip`, `Prop`"),
        "{e}"
    );
    let e = read(mesh("Nothing")).unwrap_err();
    assert!(e.contains("no mesh node is named `Nothing`; the mesh nodes: `Strip`, `Prop`"), "{e}");
    let by =
        |animation: &str| read(ReadOptions { animation: Some(animation.into()), ..mesh("Strip") });
    let (by_index, _) = by("0").unwrap();
    let (only, _) = read(mesh("Strip")).unwrap();
    assert_eq!(by_index, only, "the only stack by index");
    let e = by("Walk").unwrap_err();
    assert!(e.contains("no animation stack `Walk`; the stacks: 0: "), "{e}");
    let e = read(ReadOptions { fps: Some(0.0), ..mesh("Strip") }).unwrap_err();
    assert!(e.contains("--fps 0"), "{e}");
}

#[test]
fn another_rate_samples_between_the_frames_and_on_them() {
    let (at_24, _) = read(mesh("Strip")).unwrap();
    let (at_48, info) = read(ReadOptions { fps: Some(48.0), ..mesh("Strip") }).unwrap();
    assert_eq!(at_48.frames.len(), 9, "1/24 s to 5/24 s at 48 per second");
    assert!((info.fps.unwrap() - 48.0).abs() < 1e-9);
    for (t, frame) in at_24.frames.iter().enumerate() {
        let error = worst_error(
            std::slice::from_ref(&at_48.frames[2 * t]),
            &[frame.iter().map(|p| p.map(f64::from)).collect()],
        );
        assert!(error <= 1e-6, "frame {t}: {error:.2e}");
    }
}

#[test]
fn damaged_files_are_errors_naming_the_file() {
    let good = std::fs::read(data("strip.fbx")).unwrap();
    let dir = std::env::temp_dir().join(format!("tagsplat-fbx-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("bad.fbx");
    let mut flipped = good.clone();
    (0..flipped.len()).step_by(97).for_each(|i| flipped[i] ^= 0x5a);
    // A bit-flipped file may still read (a flip inside a float); it must not panic.
    for (bytes, must_fail) in [
        (Vec::new(), true),
        (good[..good.len() / 2].to_vec(), true),
        (good[..40].to_vec(), true),
        (vec![0xff; 4096], true),
        (
            b"; FBX 7.4.0 project file\nObjects: {\n Geometry: 1, \"Geometry::\", \"Mesh\" {\n"
                .to_vec(),
            true,
        ),
        (flipped, false),
    ] {
        std::fs::write(&path, &bytes).unwrap();
        match MeshSequence::read_with(&path, &mesh("Strip")) {
            Ok(_) => assert!(!must_fail, "{} bytes read as a sequence", bytes.len()),
            Err(e) => assert!(e.to_string().starts_with(&path.display().to_string()), "{e}"),
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
