//! The MDD reader against Blender and against a writer of this test's own.
//!
//! - Independent: `data/blender/strip.mdd` and its base `strip.obj` were written by Blender's
//!   io_shape_mdd (with "Rest Frame", which repeats the first frame) and OBJ exporter, and
//!   `strip.json` holds Blender's evaluated vertices (tests/blender/make_fixtures.py).
//! - [`mdd_bytes`] writes the layout by hand (big-endian counts, times, positions), apart from
//!   the engine's writer, for the round trip and the damaged files.

use serde_json::Value;
use std::path::{Path, PathBuf};
use tagsplat::sequence::{FrameFormat, MeshSequence, ReadOptions, SequenceInfo};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/formats/data/blender").join(name)
}

fn read(path: &Path) -> Result<(MeshSequence, SequenceInfo), String> {
    MeshSequence::read_with(path, &ReadOptions::default()).map_err(|e| e.to_string())
}

/// An MDD file: `frames` frames, times and positions, big-endian.
fn mdd_bytes(times: &[f32], frames: &[Vec<[f32; 3]>]) -> Vec<u8> {
    let mut bytes = (frames.len() as i32).to_be_bytes().to_vec();
    bytes.extend((frames.first().map_or(0, Vec::len) as i32).to_be_bytes());
    times.iter().for_each(|t| bytes.extend(t.to_be_bytes()));
    frames.iter().flatten().flatten().for_each(|c| bytes.extend(c.to_be_bytes()));
    bytes
}

/// A scratch folder for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tagsplat-mdd-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

const SQUARE_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";

fn square(t: usize) -> Vec<[f32; 3]> {
    let z = 0.1 * t as f32;
    vec![[0.0, 0.0, z], [1.0, 0.0, -z], [1.0, 1.0, z], [0.0, 1.0, 0.5 * z]]
}

/// `dir/anim.mdd` of `frames` at `times` beside the square's OBJ; its path.
fn square_files(dir: &Path, times: &[f32], frames: &[Vec<[f32; 3]>]) -> PathBuf {
    std::fs::write(dir.join("anim.obj"), SQUARE_OBJ).unwrap();
    std::fs::write(dir.join("anim.mdd"), mdd_bytes(times, frames)).unwrap();
    dir.join("anim.mdd")
}

#[test]
fn blenders_export_is_blenders_evaluation_with_its_rest_frame() {
    let (sequence, info) = read(&data("strip.mdd")).unwrap();
    let blender: Value =
        serde_json::from_str(&std::fs::read_to_string(data("strip.json")).unwrap()).unwrap();
    let expected = blender["mdd"]["frames"].as_array().unwrap();
    assert_eq!(sequence.frames.len(), expected.len(), "Blender's frames and its rest frame");
    let mut worst = 0.0f64;
    for (frame, blender) in sequence.frames.iter().zip(expected) {
        for (p, b) in frame.iter().zip(blender.as_array().unwrap()) {
            (0..3)
                .for_each(|i| worst = worst.max((f64::from(p[i]) - b[i].as_f64().unwrap()).abs()));
        }
    }
    println!("MDD (Blender's io_shape_mdd): max coordinate error {worst:.2e}");
    assert!(worst <= 1e-6, "{worst:.2e} from Blender's vertices");
    assert_eq!(sequence.frames[0], sequence.frames[1], "the rest frame repeats the first");
    let times = blender["mdd"]["times"].as_array().unwrap();
    let got = info.times.unwrap();
    assert!(got.iter().zip(times).all(|(a, b)| (a - b.as_f64().unwrap()).abs() < 1e-7), "{got:?}");
    assert!((info.fps.unwrap() - 24.0).abs() < 1e-3);
    assert_eq!(sequence.faces.len(), 2 + 2 + 4, "two quads and a hexagon, fanned");
}

#[test]
fn a_hand_written_file_reads_as_written_and_round_trips_through_the_writer() {
    let dir = scratch("hand");
    let frames: Vec<_> = (0..3).map(square).collect();
    let (sequence, info) = read(&square_files(&dir, &[0.5, 0.54, 0.58], &frames)).unwrap();
    assert_eq!(sequence.frames, frames);
    assert_eq!(sequence.faces, [[0, 1, 2], [0, 2, 3]]);
    assert_eq!(info.times.as_deref(), Some(&[0.5f32 as f64, 0.54f32 as f64, 0.58f32 as f64][..]));
    assert!((info.fps.unwrap() - 25.0).abs() < 1e-3);

    let out = dir.join("out/copy.mdd");
    std::fs::create_dir_all(out.parent().unwrap()).unwrap();
    sequence.write(&out, FrameFormat::Obj, 25.0).unwrap();
    let written = std::fs::read(&out).unwrap();
    let times: Vec<f32> = (0..3).map(|t| (t as f64 / 25.0) as f32).collect();
    assert_eq!(written, mdd_bytes(&times, &frames), "the layout this test writes by hand");
    let (back, info) = read(&out).unwrap();
    assert_eq!(back, sequence);
    assert!((info.fps.unwrap() - 25.0).abs() < 1e-3);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_files_are_errors_naming_the_file_and_the_problem() {
    let dir = scratch("bad");
    let frames: Vec<_> = (0..2).map(square).collect();
    let path = square_files(&dir, &[0.0, 0.04], &frames);
    let good = std::fs::read(&path).unwrap();
    let name = path.display().to_string();
    let fails = |bytes: &[u8]| {
        std::fs::write(&path, bytes).unwrap();
        let e = read(&path).unwrap_err();
        assert!(e.starts_with(&name), "{e}");
        e
    };
    assert!(fails(&good[..good.len() - 4]).contains("truncated"));
    assert!(fails(&mdd_bytes(&[0.04, 0.0], &frames)).contains("time samples out of order"));
    let mut nan = frames.clone();
    nan[1][2][0] = f32::NAN;
    assert!(fails(&mdd_bytes(&[0.0, 0.04], &nan)).contains("frame 1"));
    let three: Vec<_> = frames.iter().map(|f| f[..3].to_vec()).collect();
    let e = fails(&mdd_bytes(&[0.0, 0.04], &three));
    assert!(e.contains("3 points per frame, the base mesh") && e.contains("anim.obj has 4"), "{e}");
    let huge = [&i32::MAX.to_be_bytes()[..], &4i32.to_be_bytes(), &good[8..]].concat();
    assert!(fails(&huge).contains("the header promises 2147483647 frames"));
    assert!(fails(&mdd_bytes(&[], &[])).contains("no frames"));
    std::fs::write(&path, &good).unwrap();
    let e =
        MeshSequence::read_with(&path, &ReadOptions { fps: Some(30.0), ..ReadOptions::default() })
            .unwrap_err()
            .to_string();
    assert!(e.contains("--fps has no meaning for a mdd"), "{e}");
    std::fs::remove_file(dir.join("anim.obj")).unwrap();
    assert!(
        fails(&good).contains("the base mesh") && read(&path).unwrap_err().contains("is missing")
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
