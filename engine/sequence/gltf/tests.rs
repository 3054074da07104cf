//! The reader against f64 references of the glTF formulas, on small files built here: a
//! parent chain, a two-joint skin, morph targets with default and animated weights, the three
//! interpolations through the whole reader, and the errors a user meets.

use super::read;
use crate::sequence::source::{ReadOptions, SourceSequence};
use glam::{DMat4, DQuat, DVec3};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// A glTF document being built: its binary buffer, buffer views and accessors.
#[derive(Default)]
struct Builder {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Builder {
    /// An accessor of `values` (`component` 5126 float, 5123 u16) of type `ty`; its index.
    fn add(&mut self, bytes: Vec<u8>, component: u32, count: usize, ty: &str) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let view = json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()});
        self.views.push(view);
        self.bin.extend(bytes);
        let accessor = json!({"bufferView": self.views.len() - 1, "componentType": component, "count": count, "type": ty});
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    fn floats(&mut self, values: &[f32], ty: &str, width: usize) -> usize {
        let bytes = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let index = self.add(bytes, 5126, values.len() / width, ty);
        if ty == "SCALAR" {
            // Animation inputs need bounds.
            let (lo, hi) =
                values.iter().fold((f32::MAX, f32::MIN), |(l, h), &v| (l.min(v), h.max(v)));
            self.accessors[index]["min"] = json!([lo]);
            self.accessors[index]["max"] = json!([hi]);
        }
        index
    }

    fn u16s(&mut self, values: &[u16], ty: &str, width: usize) -> usize {
        let bytes = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        self.add(bytes, 5123, values.len() / width, ty)
    }

    /// A POSITION accessor (with the bounds glTF requires).
    fn positions(&mut self, p: &[[f32; 3]]) -> usize {
        let index = self.floats(&p.concat(), "VEC3", 3);
        let lo: Vec<f32> =
            (0..3).map(|k| p.iter().map(|v| v[k]).fold(f32::MAX, f32::min)).collect();
        let hi: Vec<f32> =
            (0..3).map(|k| p.iter().map(|v| v[k]).fold(f32::MIN, f32::max)).collect();
        self.accessors[index]["min"] = json!(lo);
        self.accessors[index]["max"] = json!(hi);
        index
    }

    /// Writes `doc` with this builder's buffer (a `.bin` beside it) into `dir/name`.
    fn write(self, mut doc: Value, dir: &Path, name: &str) -> PathBuf {
        let bin = format!("{name}.bin");
        std::fs::write(dir.join(&bin), &self.bin).unwrap();
        doc["asset"] = json!({"version": "2.0"});
        doc["buffers"] = json!([{"uri": bin, "byteLength": self.bin.len()}]);
        doc["bufferViews"] = json!(self.views);
        doc["accessors"] = json!(self.accessors);
        let path = dir.join(name);
        std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
        path
    }
}

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tagsplat-gltf-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn options(animation: Option<&str>, fps: Option<f64>) -> ReadOptions {
    ReadOptions { animation: animation.map(str::to_owned), fps, mesh: None }
}

fn close(p: [f32; 3], e: DVec3) -> bool {
    DVec3::from(p.map(f64::from)).distance(e) < 1e-5
}

const TRIANGLE: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 2.0, 0.0]];

/// A triangle on node 2, child of node 1 (translation animated LINEAR 0 → (0, 0, 4) over 1 s,
/// rotated 90° about z, scaled 2), child of node 0 (translated (10, 0, 0)).
fn chain(dir: &Path) -> PathBuf {
    let mut b = Builder::default();
    let position = b.positions(&TRIANGLE);
    let times = b.floats(&[0.0, 1.0], "SCALAR", 1);
    let moves = b.floats(&[0.0, 0.0, 0.0, 0.0, 0.0, 4.0], "VEC3", 3);
    let q = DQuat::from_rotation_z(std::f64::consts::FRAC_PI_2).as_quat().to_array();
    let doc = json!({
        "scenes": [{"nodes": [0]}],
        "nodes": [
            {"name": "root", "translation": [10.0, 0.0, 0.0], "children": [1]},
            {"name": "arm", "rotation": q, "scale": [2.0, 2.0, 2.0], "children": [2]},
            {"name": "tri", "mesh": 0},
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": position}}]}],
        "animations": [{"name": "move", "channels": [{"sampler": 0, "target": {"node": 1, "path": "translation"}}],
            "samplers": [{"input": times, "output": moves}]}],
    });
    b.write(doc, dir, "chain.gltf")
}

#[test]
fn a_parent_chain_places_an_unskinned_mesh_by_its_global_transform() {
    let dir = temp("chain");
    let s = read(&chain(&dir), &options(None, Some(4.0))).unwrap();
    assert_eq!(s.times, [0.0, 0.25, 0.5, 0.75, 1.0]);
    assert_eq!((s.counts.clone(), s.indices.clone()), (vec![3], vec![0, 1, 2]));
    for (f, &t) in s.frames.iter().zip(&s.times) {
        // global = T(10, 0, 0) · T(0, 0, 4t) · Rz(90°) · S(2): (x, y, z) → (10 − 2y, 2x, 2z + 4t).
        for (p, q) in f.iter().zip(TRIANGLE) {
            let e = DVec3::new(
                10.0 - 2.0 * q[1] as f64,
                2.0 * q[0] as f64,
                2.0 * q[2] as f64 + 4.0 * t,
            );
            assert!(close(*p, e), "t {t}: {p:?} vs {e}");
        }
    }
    assert!(
        s.notes.iter().any(|n| n.contains("animation `move` (#0) (1 of 1): 5 frames")),
        "{:?}",
        s.notes
    );
    assert_eq!(s.up.map(|u| (u.axis, u.negative)), Some((1, false)));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Two joints: node 1 (the root, at the origin) and node 2 (its child at (0, 1, 0)), node 2
/// rotating LINEAR from 0° to 90° about z over 1 s; the skinned mesh node 0 carries a
/// translation that must be ignored. Vertices: two on joint 1, one on joint 2, one half-half.
fn two_joint_skin(dir: &Path, interpolation: &str) -> PathBuf {
    let mut b = Builder::default();
    let rest = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 2.0, 1.0]];
    let position = b.positions(&rest);
    let joints = b.u16s(&[0, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0], "VEC4", 4);
    let weights = b.floats(
        &[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.5, 0.5, 0.0, 0.0],
        "VEC4",
        4,
    );
    let indices = b.u16s(&[0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2], "SCALAR", 1);
    let ibm = [DMat4::IDENTITY, DMat4::from_translation(DVec3::new(0.0, -1.0, 0.0))];
    let ibm: Vec<f32> = ibm.iter().flat_map(|m| m.as_mat4().to_cols_array()).collect();
    let ibm = b.floats(&ibm, "MAT4", 16);
    let times = b.floats(&[0.0, 1.0], "SCALAR", 1);
    let q = DQuat::from_rotation_z(std::f64::consts::FRAC_PI_2).as_quat().to_array();
    let turns = b.floats(&[0.0, 0.0, 0.0, 1.0, q[0], q[1], q[2], q[3]], "VEC4", 4);
    let doc = json!({
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [
            {"name": "body", "mesh": 0, "skin": 0, "translation": [100.0, 0.0, 0.0]},
            {"children": [2]},
            {"translation": [0.0, 1.0, 0.0]},
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": position, "JOINTS_0": joints, "WEIGHTS_0": weights}, "indices": indices}]}],
        "skins": [{"joints": [1, 2], "inverseBindMatrices": ibm}],
        "animations": [{"name": "bend", "channels": [{"sampler": 0, "target": {"node": 2, "path": "rotation"}}],
            "samplers": [{"input": times, "output": turns, "interpolation": interpolation}]}],
    });
    b.write(doc, dir, &format!("skin-{interpolation}.gltf"))
}

#[test]
fn a_two_joint_skin_bends_by_global_times_inverse_bind_ignoring_the_node() {
    let dir = temp("skin");
    let s = read(&two_joint_skin(&dir, "LINEAR"), &options(None, Some(8.0))).unwrap();
    assert_eq!(s.frames.len(), 9);
    for (f, &t) in s.frames.iter().zip(&s.times) {
        // Slerp from 0° to 90° at t turns by 90° t, about joint 2's origin (0, 1, 0).
        let turn = |p: DVec3| {
            DQuat::from_rotation_z(t * std::f64::consts::FRAC_PI_2) * (p - DVec3::Y) + DVec3::Y
        };
        let expect = [
            DVec3::ZERO,
            DVec3::X,
            turn(DVec3::new(0.0, 2.0, 0.0)),
            0.5 * DVec3::new(0.0, 2.0, 1.0) + 0.5 * turn(DVec3::new(0.0, 2.0, 1.0)),
        ];
        for (p, e) in f.iter().zip(expect) {
            assert!(close(*p, e), "t {t}: {p:?} vs {e}");
        }
    }
    // STEP holds the first key until the second.
    let step = read(&two_joint_skin(&dir, "STEP"), &options(None, Some(2.0))).unwrap();
    assert_eq!(step.frames[1], step.frames[0]);
    assert!(close(step.frames[2][2], DVec3::new(-1.0, 1.0, 0.0)), "{:?}", step.frames[2][2]);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A triangle with two morph targets, default weights (0.5, 0) on the mesh, and (when
/// `animated`) weights keyed CUBICSPLINE at 0 s and 2 s.
fn morph(dir: &Path, animated: bool) -> PathBuf {
    let mut b = Builder::default();
    let position = b.positions(&TRIANGLE);
    let up = b.positions(&[[0.0, 0.0, 1.0]; 3]);
    let out = b.positions(&[[1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [3.0, 0.0, 0.0]]);
    let mut doc = json!({
        "nodes": [{"name": "m", "mesh": 0}],
        "meshes": [{"weights": [0.5, 0.0], "primitives": [{"attributes": {"POSITION": position}, "targets": [{"POSITION": up}, {"POSITION": out}]}]}],
    });
    if animated {
        let times = b.floats(&[0.0, 2.0], "SCALAR", 1);
        // Per key (in-tangents, values, out-tangents), two weights each.
        let keys =
            b.floats(&[0.0, 0.0, 0.5, 1.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0], "SCALAR", 1);
        doc["animations"] = json!([{"channels": [{"sampler": 0, "target": {"node": 0, "path": "weights"}}],
            "samplers": [{"input": times, "output": keys, "interpolation": "CUBICSPLINE"}]}]);
    }
    b.write(doc, dir, &format!("morph-{animated}.gltf"))
}

#[test]
fn morph_targets_blend_by_default_and_cubic_spline_weights() {
    let dir = temp("morph");
    let rest = read(&morph(&dir, false), &options(None, None)).unwrap();
    assert_eq!(rest.times, [0.0]);
    assert!(rest.notes.iter().any(|n| n == "no animation: one frame"), "{:?}", rest.notes);
    for (p, q) in rest.frames[0].iter().zip(TRIANGLE) {
        assert!(close(*p, DVec3::new(q[0] as f64, q[1] as f64, 0.5)), "{p:?}");
    }
    let s = read(&morph(&dir, true), &options(None, Some(4.0))).unwrap();
    assert_eq!(s.frames.len(), 9);
    for (f, &t) in s.frames.iter().zip(&s.times) {
        // Hermite with the key interval 2 s: values (0.5, 1) → (1, 0), out-tangents (0, 1) of key
        // 0, in-tangents (0, 0) of key 1.
        let u = t / 2.0;
        let (h00, h10, h01) = (
            2.0 * u * u * u - 3.0 * u * u + 1.0,
            u * u * u - 2.0 * u * u + u,
            -2.0 * u * u * u + 3.0 * u * u,
        );
        let w = [h00 * 0.5 + h01 * 1.0, h00 * 1.0 + 2.0 * h10 * 1.0];
        for (v, (p, q)) in f.iter().zip(TRIANGLE).enumerate() {
            let e = DVec3::new(q[0] as f64 + w[1] * (v + 1) as f64, q[1] as f64, w[0]);
            assert!(close(*p, e), "t {t} vertex {v}: {p:?} vs {e}");
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The first file's document with `edit` applied, written again beside it.
fn edited(path: &Path, edit: impl FnOnce(&mut Value)) -> PathBuf {
    let mut doc: Value = serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap();
    edit(&mut doc);
    let out =
        path.with_file_name(format!("edited-{}", path.file_name().unwrap().to_string_lossy()));
    std::fs::write(&out, serde_json::to_vec(&doc).unwrap()).unwrap();
    out
}

fn error(path: &Path, options: &ReadOptions) -> String {
    read(path, options).map(|s: SourceSequence| s.frames.len()).unwrap_err()
}

#[test]
fn choices_and_damage_are_errors_that_say_what_and_where() {
    let dir = temp("errors");
    let file = chain(&dir);
    let none = options(None, None);
    let twice = |d: &mut Value| {
        let first = d["animations"][0].clone();
        d["animations"].as_array_mut().unwrap().push(first);
    };
    let e = error(&edited(&file, twice), &none);
    assert_eq!(e, "2 animations, choose one with --animation NAME|INDEX: 0: move, 1: move");
    let e = error(&file, &options(Some("walk"), None));
    assert_eq!(e, "no animation `walk`; the animations: 0: move");
    let two = edited(&file, |d| d["nodes"][0]["mesh"] = json!(0));
    let e = error(&two, &none);
    assert_eq!(e, "2 mesh nodes, choose one with --mesh NAME: `root` (#0), `tri` (#2)");
    let root = read(&two, &ReadOptions { mesh: Some("root".into()), ..none.clone() }).unwrap();
    assert_eq!(root.frames[0][1], [11.0, 0.0, 0.0]);
    let e = error(&edited(&file, |d| d["meshes"][0]["primitives"][0]["mode"] = json!(1)), &none);
    assert_eq!(e, "mesh node `tri` (#2): primitive 0: its mode is Lines; only triangles are read");
    let e = error(&edited(&file, |d| d["nodes"][2]["children"] = json!([1])), &none);
    assert!(e.contains("has a cycle") || e.contains("two parents"), "{e}");
    let e = error(&edited(&file, |d| d["nodes"][2]["children"] = json!([0])), &none);
    assert_eq!(e, "the node hierarchy has a cycle through node `root` (#0)");
    let e = error(&edited(&file, |d| d["nodes"][0]["children"] = json!([1, 2])), &none);
    assert_eq!(
        e,
        "node `tri` (#2) has two parents, `root` (#0) and `arm` (#1) (glTF requires a tree)"
    );
    let e = error(
        &edited(&file, |d| d["animations"][0]["channels"][0]["target"]["node"] = json!(9)),
        &none,
    );
    assert_eq!(e, "animation `move` (#0): channel 0: targets node 9 of 3");
    // NaN and out-of-order key times, patched into the binary buffer.
    let bin = dir.join("chain.gltf.bin");
    let bytes = std::fs::read(&bin).unwrap();
    for (time, problem) in
        [(f32::NAN, "key 1 has time NaN"), (0.0, "key 1 at 0 s follows key 0 at 0 s")]
    {
        let mut damaged = bytes.clone();
        damaged[40..44].copy_from_slice(&time.to_le_bytes());
        std::fs::write(&bin, &damaged).unwrap();
        let e = error(&file, &none);
        assert!(e.starts_with("animation `move` (#0): channel 0: ") && e.contains(problem), "{e}");
    }
    std::fs::write(&bin, &bytes).unwrap();
    let e = error(&edited(&file, |d| d["accessors"][0]["count"] = json!(1u64 << 40)), &none);
    assert!(e.contains("would take more than the 8 MiB"), "{e}");
    let e = error(&edited(&file, |d| d["bufferViews"][0]["byteLength"] = json!(400)), &none);
    assert!(e.contains("buffer view 0 (bytes 0 + 400) runs past its buffer of 68 bytes"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}
