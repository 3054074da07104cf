//! The glTF reader on the Khronos Fox (`tests/formats/data/khronos/Fox.glb`: skinned, 24 joints, the
//! animations Survey, Walk and Run; CC0 model by PixelMannen, CC-BY 4.0 rigging and animation
//! by tomkranis). Blender's evaluation of the same file is the oracle of
//! tests/blender/test_gltf_fox.py; here: the choices, the clock, and what any correct
//! evaluation keeps (the file's vertices, corners of one position moving together).

use std::path::{Path, PathBuf};
use tagsplat::sequence::{MeshSequence, ReadOptions, SequenceInfo};

/// The vendored Khronos Fox (tests/formats/data/khronos/README.md).
fn fox() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/formats/data/khronos/Fox.glb")
}

fn read(
    path: &Path,
    animation: Option<&str>,
    fps: Option<f64>,
) -> Result<(MeshSequence, SequenceInfo), String> {
    let options = ReadOptions { animation: animation.map(str::to_owned), fps, mesh: None };
    MeshSequence::read_with(path, &options).map_err(|e| e.to_string())
}

#[test]
fn the_fox_plays_each_of_its_three_animations_on_its_own_vertices() {
    let path = fox();
    let e = read(&path, None, None).unwrap_err();
    assert!(
        e.ends_with(
            "3 animations, choose one with --animation NAME|INDEX: 0: Survey, 1: Walk, 2: Run"
        ),
        "{e}"
    );
    // Survey and Walk are keyed at 24 per second, evenly: their keys are the frames. Run's keys
    // skip from 16/24 s to 20.8/24 s: 30 per second over its range, unless asked.
    for (animation, fps, frames, rate, last) in [
        ("Survey", None, 83, 24.0, 82.0 / 24.0),
        ("1", None, 18, 24.0, 17.0 / 24.0),
        ("Run", None, 35, 30.0, 34.0 / 30.0),
        ("Run", Some(120.0), 140, 120.0, 139.0 / 120.0),
    ] {
        let start = std::time::Instant::now();
        let (sequence, info) = read(&path, Some(animation), fps).unwrap();
        eprintln!("{animation}: {:.1} ms; {:?}", start.elapsed().as_secs_f64() * 1e3, info.notes);
        assert_eq!(
            (sequence.frames.len(), sequence.frames[0].len(), sequence.faces.len()),
            (frames, 1728, 576)
        );
        let times = info.times.unwrap();
        assert_eq!(times[0], 0.0);
        assert!(
            (times[frames - 1] - last).abs() < 1e-6,
            "{animation}: ends at {}",
            times[frames - 1]
        );
        assert!((info.fps.unwrap() - rate).abs() < 1e-3, "{animation}: {:?}", info.fps);
        assert_eq!(info.up.map(|u| (u.axis, u.negative)), Some((1, false)));
        assert!(info.notes.iter().any(|n| n.contains("of 3)")), "{:?}", info.notes);
        // The file splits corners at UV seams: corners at one position with the same skin
        // must stay together in every frame, and the figure must move.
        let first = &sequence.frames[0];
        let same: Vec<(usize, usize)> = (0..first.len())
            .flat_map(|a| (a + 1..first.len()).map(move |b| (a, b)))
            .filter(|&(a, b)| first[a] == first[b])
            .collect();
        assert!(same.len() > 1000, "{} coincident corner pairs", same.len());
        let apart = |f: &Vec<[f32; 3]>, (a, b): (usize, usize)| {
            (0..3).map(|k| (f[a][k] - f[b][k]).abs()).fold(0.0, f32::max)
        };
        let worst = sequence
            .frames
            .iter()
            .flat_map(|f| same.iter().map(move |&p| apart(f, p)))
            .fold(0.0, f32::max);
        assert!(worst < 1e-3, "{animation}: coincident corners drift {worst} apart");
        let moved = sequence
            .frames
            .iter()
            .flat_map(|f| f.iter().zip(first))
            .map(|(p, q)| (p[1] - q[1]).abs())
            .fold(0.0, f32::max);
        assert!(moved > 1.0, "{animation}: the fox hardly moves ({moved})");
    }
}
