//! Sequence formats: round trips through every layout, the Khronos glTF validator on written
//! GLB files, and clear errors for damaged sequences.

mod common;
mod deforming;

use deforming::{affine, bend, sequence, temp_dir};
use std::path::Path;
use std::process::Command;
use tagsplat::mesh::TriMesh;
use tagsplat::sequence::{FrameFormat, MeshSequence};

/// Largest |a − b| over all coordinates of all frames.
fn max_difference(a: &MeshSequence, b: &MeshSequence) -> f32 {
    assert_eq!(a.frames.len(), b.frames.len());
    a.frames
        .iter()
        .flatten()
        .zip(b.frames.iter().flatten())
        .flat_map(|(p, q)| (0..3).map(move |k| (p[k] - q[k]).abs()))
        .fold(0.0, f32::max)
}

fn frame0_colours_everywhere(s: &MeshSequence) -> MeshSequence {
    let colors = s.colors.as_ref().map(|c| vec![c[0].clone(); s.frames.len()]);
    MeshSequence { colors, ..s.clone() }
}

#[test]
fn folders_of_ply_and_obj_round_trip_exactly() {
    let dir = temp_dir("seq-folders");
    let seq = sequence(3, 11, bend);
    for (format, name) in [(FrameFormat::Ply, "ply"), (FrameFormat::Obj, "obj")] {
        let folder = dir.join(name);
        seq.write(&folder, format, 24.0).unwrap();
        assert!(folder.join(format!("frame_000010.{name}")).is_file());
        assert_eq!(MeshSequence::read(&folder).unwrap(), seq, "{name}");
        // Writing over existing frames is refused.
        let again = seq.write(&folder, format, 24.0).unwrap_err().to_string();
        assert!(again.contains("already holds frame files"), "{again}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn obj_plus_pc2_round_trips_positions_exactly_and_frame0_colours() {
    let dir = temp_dir("seq-pc2");
    let seq = sequence(3, 9, bend);
    let path = dir.join("anim.pc2");
    seq.write(&path, FrameFormat::Ply, 24.0).unwrap();
    assert!(dir.join("anim.obj").is_file());
    assert_eq!(std::fs::metadata(&path).unwrap().len(), 32 + 12 * 9 * seq.frames[0].len() as u64);
    assert_eq!(MeshSequence::read(&path).unwrap(), frame0_colours_everywhere(&seq));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn glb_round_trips_to_float_precision() {
    let dir = temp_dir("seq-glb");
    let seq = sequence(3, 14, affine);
    let path = dir.join("anim.glb");
    seq.write(&path, FrameFormat::Ply, 30.0).unwrap();
    let back = MeshSequence::read(&path).unwrap();
    assert_eq!(back.faces, seq.faces);
    assert_eq!(back.colors, frame0_colours_everywhere(&seq).colors);
    assert_eq!(back.frames[0], seq.frames[0], "frame 0 is the base mesh itself");
    // Frame t is base + (v(t) − base), each step rounded once in f32: a few ulps at most.
    let extent =
        seq.frames.iter().flatten().flat_map(|p| p.iter()).fold(0.0f32, |m, c| m.max(c.abs()));
    let difference = max_difference(&back, &seq);
    assert!(difference <= 4.0 * f32::EPSILON * extent, "{difference} at extent {extent}");
    // And through the other formats: GLB -> folder -> GLB keeps the faces and positions.
    back.write(&dir.join("frames"), FrameFormat::Obj, 24.0).unwrap();
    assert_eq!(MeshSequence::read(&dir.join("frames")).unwrap(), back);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn written_glb_passes_the_khronos_validator() {
    let dir = temp_dir("seq-validator");
    for (name, seq) in [
        ("colours.glb", sequence(2, 5, bend)),
        ("plain.glb", MeshSequence { colors: None, ..sequence(1, 1, affine) }),
    ] {
        let path = dir.join(name);
        seq.write(&path, FrameFormat::Ply, 24.0).unwrap();
        common::validate_gltf(&path);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn frames_are_read_in_natural_order() {
    let dir = temp_dir("seq-natural");
    let seq = sequence(1, 12, affine);
    // Unpadded names: plain string order would put frame_10 before frame_2.
    for t in 0..12 {
        seq.frame_mesh(t).unwrap().write_obj(&dir.join(format!("frame_{}.obj", t + 1))).unwrap();
    }
    assert_eq!(MeshSequence::read(&dir).unwrap().frames, seq.frames);
    std::fs::remove_dir_all(&dir).unwrap();
}

fn error_of(path: &Path) -> String {
    MeshSequence::read(path).unwrap_err().to_string()
}

#[test]
fn damaged_sequences_are_clear_errors_naming_the_frame() {
    let dir = temp_dir("seq-damaged");
    let seq = sequence(2, 6, bend);
    let folder = dir.join("frames");
    seq.write_folder(&folder, FrameFormat::Ply).unwrap();

    // A changed face list in frame 4.
    let mut changed = seq.frame_mesh(4).unwrap();
    changed.faces[7] = [changed.faces[7][1], changed.faces[7][0], changed.faces[7][2]];
    changed.write_ply(&folder.join("frame_000004.ply")).unwrap();
    let e = error_of(&folder);
    assert!(
        e.contains("frame_000004.ply")
            && e.contains("frame 4 differs from frame 0 (frame_000000.ply) at face 7"),
        "{e}"
    );

    // Fewer faces, then fewer vertices.
    let mut fewer = seq.frame_mesh(4).unwrap();
    fewer.faces.pop();
    fewer.write_ply(&folder.join("frame_000004.ply")).unwrap();
    assert!(error_of(&folder).contains(&format!("frame 4 has {} faces", seq.faces.len() - 1)));
    let small = TriMesh { positions: vec![[0.0; 3]; 3], faces: vec![[0, 1, 2]], colors: None };
    small.write_ply(&folder.join("frame_000004.ply")).unwrap();
    assert!(error_of(&folder).contains("frame 4 has 3 vertices"));
    seq.frame_mesh(4).unwrap().write_ply(&folder.join("frame_000004.ply")).unwrap();
    assert!(MeshSequence::read(&folder).is_ok());

    // A missing frame file.
    std::fs::remove_file(folder.join("frame_000003.ply")).unwrap();
    let e = error_of(&folder);
    assert!(
        e.contains("frame file(s) 3..3 missing between frame_000002.ply and frame_000004.ply"),
        "{e}"
    );
    // A stray OBJ among PLY frames; an empty folder; no such path.
    std::fs::write(folder.join("notes.obj"), "v 0 0 0\n").unwrap();
    assert!(error_of(&folder).contains("keep one kind of frame file"));
    assert!(error_of(&temp_dir("seq-empty")).contains("no .ply or .obj frame files"));
    assert!(error_of(&dir.join("nothing.glb")).contains("nothing.glb: no such file or folder"));

    // A truncated PC2, a PC2 without its base OBJ, a PC2 of another vertex count.
    let pc2 = dir.join("anim.pc2");
    seq.write(&pc2, FrameFormat::Ply, 24.0).unwrap();
    let bytes = std::fs::read(&pc2).unwrap();
    std::fs::write(&pc2, &bytes[..bytes.len() - 5]).unwrap();
    let e = error_of(&pc2);
    assert!(e.contains("anim.pc2") && e.contains("truncated"), "{e}");
    std::fs::write(&pc2, &bytes).unwrap();
    small.write_obj(&dir.join("anim.obj")).unwrap();
    assert!(error_of(&pc2).contains("the base mesh"));
    std::fs::remove_file(dir.join("anim.obj")).unwrap();
    assert!(error_of(&pc2).contains("anim.obj is missing"));

    // A truncated GLB.
    let glb = dir.join("anim.glb");
    seq.write(&glb, FrameFormat::Ply, 24.0).unwrap();
    let bytes = std::fs::read(&glb).unwrap();
    std::fs::write(&glb, &bytes[..bytes.len() - 100]).unwrap();
    let e = error_of(&glb);
    assert!(e.contains("anim.glb") && e.contains("truncated"), "{e}");

    // Writing a sequence whose frames disagree is refused before anything is written.
    let mut ragged = seq.clone();
    ragged.frames[2].pop();
    let e = ragged.write(&dir.join("ragged.glb"), FrameFormat::Ply, 24.0).unwrap_err().to_string();
    assert!(e.contains("frame 2 has"), "{e}");
    assert!(!dir.join("ragged.glb").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `tagsplat convert` reads every form it writes: each written form converted into each other
/// one gives back the sequence's faces and positions (to float precision).
#[test]
fn cli_round_trips_between_every_pair_it_writes() {
    let dir = temp_dir("seq-pairs");
    let seq = sequence(3, 5, bend);
    seq.write_folder(&dir.join("src"), FrameFormat::Ply).unwrap();
    let forms: [(&str, &[&str]); 6] = [
        ("ply", &[]),
        ("obj", &["--frame-format", "obj"]),
        ("a.pc2", &[]),
        ("a.mdd", &[]),
        ("a.glb", &[]),
        ("a.usda", &[]),
    ];
    let convert = |from: &Path, to: &Path, extra: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_tagsplat"))
            .args(["convert", "--sequence"])
            .arg(from)
            .arg("--to")
            .arg(to)
            .args(extra)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{} -> {}: {stderr}", from.display(), to.display());
    };
    for (i, (source, extra)) in forms.iter().enumerate() {
        let from = dir.join(format!("{i}")).join(source);
        std::fs::create_dir_all(from.parent().unwrap()).unwrap();
        convert(&dir.join("src"), &from, extra);
        for (j, (target, extra)) in forms.iter().enumerate() {
            let to = dir.join(format!("{i}-{j}")).join(target);
            std::fs::create_dir_all(to.parent().unwrap()).unwrap();
            convert(&from, &to, extra);
            let back = MeshSequence::read(&to).unwrap();
            assert_eq!(back.faces, seq.faces, "{source} -> {target}");
            let error = max_difference(&back, &seq);
            assert!(error < 1e-6, "{source} -> {target}: {error}");
        }
    }
}

#[test]
fn cli_converts_between_every_layout() {
    let dir = temp_dir("seq-cli");
    let seq = sequence(2, 4, bend);
    seq.write_folder(&dir.join("a"), FrameFormat::Ply).unwrap();
    let convert = |from: &str, to: &str, extra: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_tagsplat"))
            .args(["convert", "--sequence"])
            .arg(dir.join(from))
            .arg("--to")
            .arg(dir.join(to))
            .args(extra)
            .output()
            .unwrap();
        assert!(out.status.success(), "{from} -> {to}: {}", String::from_utf8_lossy(&out.stderr));
    };
    convert("a", "b.pc2", &[]);
    convert("b.pc2", "c.glb", &["--fps", "12"]);
    convert("c.glb", "d", &["--frame-format", "obj"]);
    let back = MeshSequence::read(&dir.join("d")).unwrap();
    assert_eq!(back.faces, seq.faces);
    assert!(max_difference(&back, &seq) < 1e-6);
    // A Z-up input turned Y-up, as glTF viewers expect: (x, y, z) -> (x, z, -y) (the GLB's
    // morph targets store offsets from frame 0, so later frames read back within rounding).
    convert("a", "f.glb", &["--from-up", "+z", "--up", "y"]);
    let turned = MeshSequence::read(&dir.join("f.glb")).unwrap();
    let expected = MeshSequence {
        frames: seq
            .frames
            .iter()
            .map(|f| f.iter().map(|p| [p[0], p[2], -p[1]]).collect())
            .collect(),
        ..seq.clone()
    };
    assert_eq!(turned.faces, seq.faces);
    assert!(max_difference(&turned, &expected) < 1e-6);
    convert("a", "g.pc2", &["--from-up", "-y", "--up", "z"]);
    let turned = MeshSequence::read(&dir.join("g.pc2")).unwrap();
    assert!(turned.frames[1].iter().zip(&seq.frames[1]).all(|(t, p)| t[2] == -p[1]), "-Y onto +Z");
    // A folder of PLY frames turned too (the only way to turn train's meshes/): exact, since a
    // quarter turn copies or negates coordinates.
    convert("a", "h", &["--from-up", "+z", "--up", "y"]);
    let turned = MeshSequence::read(&dir.join("h")).unwrap();
    assert_eq!(turned.faces, seq.faces);
    assert_eq!(turned.frames, expected.frames, "+Z onto +Y, frame by frame in PLY");
    // USD from convert, and from track with the tracked points (vertices 0 and 5 of frame 0).
    convert("a", "e.usda", &["--up", "z", "--fps", "12"]);
    let points = [0, 5].map(|v| {
        format!("v{v},{},{},{}", seq.frames[0][v][0], seq.frames[0][v][1], seq.frames[0][v][2])
    });
    std::fs::write(dir.join("points.csv"), format!("id,x,y,z\n{}\n", points.join("\n"))).unwrap();
    let tracked = Command::new(env!("CARGO_BIN_EXE_tagsplat"))
        .args(["track", "--sequence"])
        .arg(dir.join("a"))
        .arg("--points")
        .arg(dir.join("points.csv"))
        .arg("--out")
        .arg(dir.join("tracks.csv"))
        .arg("--usd")
        .arg(dir.join("tracks.usda"))
        .output()
        .unwrap();
    assert!(tracked.status.success(), "{}", String::from_utf8_lossy(&tracked.stderr));
    if let Some(usd) = read_with_pxr(&dir.join("e.usda")) {
        assert_eq!(
            (usd["up_axis"].as_str(), usd["time_codes_per_second"].as_f64()),
            (Some("Z"), Some(12.0))
        );
        let frames: Vec<Vec<[f32; 3]>> = triples(&usd["points"])
            .iter()
            .map(|f| f.iter().map(|p| p.map(|v| v as f32)).collect())
            .collect();
        assert_eq!(frames, seq.frames);
        let usd = read_with_pxr(&dir.join("tracks.usda")).unwrap();
        assert_eq!(usd["track_ids"], serde_json::json!(["v0", "v5"]));
        for (t, frame) in triples(&usd["tracks"]).iter().enumerate() {
            let expected = [0, 5].map(|v| seq.frames[t][v]);
            let read: Vec<[f32; 3]> = frame.iter().map(|p| p.map(|v| v as f32)).collect();
            let off = read
                .iter()
                .zip(&expected)
                .flat_map(|(a, b)| (0..3).map(move |k| (a[k] - b[k]).abs()))
                .fold(0.0, f32::max);
            assert!(off < 1e-5, "frame {t}: {read:?} against {expected:?}");
        }
    }
    let out = Command::new(env!("CARGO_BIN_EXE_tagsplat"))
        .args(["convert", "--sequence"])
        .arg(dir.join("missing"))
        .arg("--to")
        .arg(dir.join("x.glb"))
        .output()
        .unwrap();
    assert!(
        !out.status.success()
            && String::from_utf8_lossy(&out.stderr).contains("missing: no such file or folder")
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// What Pixar's USD library reads from `path` (scripts/read_usd.py), or None with SKIPPED
/// when usd-core is not installed (scripts/setup.sh installs it; CI requires it).
fn read_with_pxr(path: &Path) -> Option<serde_json::Value> {
    let python = Path::new(env!("CARGO_MANIFEST_DIR")).join(".tools/usd/bin/python");
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/read_usd.py");
    let has_pxr = Command::new(&python).args(["-c", "import pxr"]).output();
    if !has_pxr.is_ok_and(|o| o.status.success()) {
        common::skipped(
            &format!("reading {} with Pixar's USD library", path.display()),
            "usd-core is not installed in .tools/usd (run scripts/setup.sh)",
        );
        return None;
    }
    let out = Command::new(&python).arg(script).arg(path).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "read_usd.py {}: {stderr}", path.display());
    Some(serde_json::from_slice(&out.stdout).unwrap())
}

fn triples(value: &serde_json::Value) -> Vec<Vec<[f64; 3]>> {
    let number = |v: &serde_json::Value| v.as_f64().unwrap();
    let triple = |p: &serde_json::Value| [0, 1, 2].map(|k| number(&p[k]));
    let frame = |f: &serde_json::Value| f.as_array().unwrap().iter().map(triple).collect();
    value.as_array().unwrap().iter().map(frame).collect()
}

#[test]
fn usd_export_reads_back_exactly_in_pixars_library_and_passes_its_compliance_checker() {
    use tagsplat::sequence::orient::{Orientation, UpAxis};
    use tagsplat::sequence::usd::{write_usda, UsdTracks};
    let dir = temp_dir("seq-usd");
    let seq = sequence(2, 5, bend);
    let ids = ["nose".to_string(), "tail \"tip\"".to_string()];
    let trajectories: Vec<Vec<[f64; 3]>> =
        (0..2).map(|i| seq.frames.iter().map(|f| f[i * 7].map(f64::from)).collect()).collect();
    let tracks = UsdTracks { ids: &ids, trajectories: &trajectories };
    let path = dir.join("sequence.usda");
    write_usda(&path, &seq, 30.0, Orientation::keep(UpAxis::Z), Some(&tracks)).unwrap();
    let Some(usd) = read_with_pxr(&path) else { return };
    // usdchecker's validators (30 in usd-core 26.11) found nothing to report.
    assert!(usd["validators"].as_u64() >= Some(20), "{}", usd["validators"]);
    let (errors, warnings) = (&usd["errors"], &usd["warnings"]);
    assert!(
        errors.as_array().unwrap().is_empty() && warnings.as_array().unwrap().is_empty(),
        "{errors} {warnings}"
    );
    assert_eq!(
        (usd["up_axis"].as_str(), usd["time_codes_per_second"].as_f64()),
        (Some("Z"), Some(30.0))
    );
    assert_eq!((usd["start"].as_f64(), usd["end"].as_f64()), (Some(0.0), Some(4.0)));
    let indices: Vec<u64> = seq.faces.iter().flatten().map(|&i| u64::from(i)).collect();
    let read: Vec<u64> = usd["face_vertex_indices"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap())
        .collect();
    assert_eq!(read, indices);
    // Every frame's points are the f32 values written, bit for bit.
    let points = triples(&usd["points"]);
    assert_eq!(points.len(), seq.frames.len());
    for (read, written) in points.iter().zip(&seq.frames) {
        let read: Vec<[f32; 3]> = read.iter().map(|p| p.map(|v| v as f32)).collect();
        assert_eq!(&read, written);
    }
    // Colours: per vertex, linear (sRGB decoded, IEC 61966-2-1), every frame.
    assert_eq!(usd["color_interpolation"], "vertex");
    let decode = |c: u8| {
        let c = f64::from(c) / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    let colors = triples(&usd["colors"]);
    for (read, written) in colors.iter().zip(seq.colors.as_ref().unwrap()) {
        for (r, w) in read.iter().zip(written) {
            assert!((0..3).all(|k| (r[k] - decode(w[k])).abs() < 1e-6), "{r:?} against {w:?}");
        }
    }
    assert_eq!(usd["track_ids"], serde_json::json!(ids));
    let tracked = triples(&usd["tracks"]);
    for (t, frame) in tracked.iter().enumerate() {
        for (i, p) in frame.iter().enumerate() {
            assert_eq!(p.map(|v| v as f32), trajectories[i][t].map(|v| v as f32));
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
