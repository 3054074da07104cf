//! Fuzzing of every reader a user can feed: PLY meshes and Gaussian scenes, OBJ, OBJ + PC2 and
//! GLB sequences, a folder of frames, camera JSON, points and pixels CSV, the metadata of each
//! dataset layout, the benchmarks' ground truth and the two TOML configs.
//!
//! Each reader gets valid seed files (written by the library's own writers where it has them)
//! and reads thousands of mutations of them: byte-wise (bit flips, bytes set to 00/FF,
//! truncations, inserted bytes, duplicated and removed chunks) and format-aware (numbers in
//! text and headers, counts above all, replaced by huge or non-finite values, lines removed or
//! duplicated, binary words set to NaN, Inf or huge counts, a GLB's JSON or BIN chunk mutated
//! inside a rebuilt container). A case fails when the reader panics, runs past [`WATCHDOG`],
//! allocates more than [`allowance`] grants the input, or returns an error whose message does
//! not name the file.
//!
//! Every input that once failed is kept in `tests/fuzz_corpus/<reader>/` and replayed first. A
//! run is reproducible from `TAGSPLAT_FUZZ_SEED`; `TAGSPLAT_FUZZ_SECONDS` (default 60) bounds
//! the whole run, split evenly over the readers. A failing case prints its seed and saves its
//! input into the corpus folder, to be committed with the fix.

use glam::DVec3;
use serde_json::json;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::{mpsc, Mutex, OnceLock};
use std::time::{Duration, Instant};
use tagsplat::camera::Camera;
use tagsplat::dataset::Dataset;
use tagsplat::io::image::{write_png, Image};
use tagsplat::rng::SplitMix64;
use tagsplat::synth::{generate, SubjectSource, SynthOptions};
use tagsplat::track::bindings::read_bindings;
use tagsplat::track::queries::{read_pixels, read_points};
use tagsplat::train::FitConfig;
use tagsplat::{FrameFormat, GaussianScene, GroundTruth, MeshSequence, TrainConfig, TriMesh};

/// A case that takes longer than this is a hang: every input here is a few kilobytes.
const WATCHDOG: Duration = Duration::from_secs(2);
/// The whole run's default length, seconds (`TAGSPLAT_FUZZ_SECONDS`).
const DEFAULT_SECONDS: f64 = 60.0;
/// The default `TAGSPLAT_FUZZ_SEED`: fixed, so that CI runs the same cases every time.
const DEFAULT_SEED: u64 = 0x7a65_5f66_757a_7a00;

// ---------------------------------------------------------------------------------------------
// Allocation accounting

/// The most a reader may allocate at once for `input` bytes: 64 per byte (room for a file's
/// bytes widened to f64 and indexed) and 16 MiB, so that small files are not held to a few
/// kilobytes. Peak live bytes may reach four times this.
fn allowance(input: usize) -> usize {
    64 * input + (16 << 20)
}

/// A request this large is refused, which aborts the process (after naming the case): no
/// reader comes near it on kilobyte inputs, and granting it could exhaust the CI machine.
const HARD_CAP: usize = 1 << 30;

/// The largest single allocation and the peak of live bytes of one thread since it was reset.
#[derive(Clone, Copy)]
struct Usage {
    largest: usize,
    live: isize,
    peak: isize,
}

const NO_USAGE: Usage = Usage { largest: 0, live: 0, peak: 0 };

thread_local! {
    // Const-initialized and without a destructor, so the allocator may use it.
    static USAGE: Cell<Usage> = const { Cell::new(NO_USAGE) };
}

/// The case being read, for the message of a refused allocation.
static CURRENT: Mutex<String> = Mutex::new(String::new());

struct Guard;

#[global_allocator]
static GUARD: Guard = Guard;

fn account(allocated: usize, freed: usize) {
    // try_with: a thread being torn down may still free memory.
    let _ = USAGE.try_with(|usage| {
        let mut u = usage.get();
        u.largest = u.largest.max(allocated);
        u.live += allocated as isize - freed as isize;
        u.peak = u.peak.max(u.live);
        usage.set(u);
    });
}

/// Whether to refuse `size` bytes; names the case on stderr when it does. Formats into a
/// stack buffer: an allocator must not allocate.
fn refused(size: usize) -> bool {
    if size <= HARD_CAP {
        return false;
    }
    let mut message = [0u8; 1024];
    let mut out = &mut message[..];
    let case = CURRENT.try_lock();
    let case = case.as_deref().map_or("?", |c| c.as_str());
    let _ = writeln!(out, "fuzz: refused an allocation of {size} bytes in {case}");
    let written = 1024 - out.len();
    let _ = std::io::stderr().write_all(&message[..written]);
    true
}

unsafe impl GlobalAlloc for Guard {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if refused(layout.size()) {
            return std::ptr::null_mut();
        }
        account(layout.size(), 0);
        System.alloc(layout)
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        if refused(layout.size()) {
            return std::ptr::null_mut();
        }
        account(layout.size(), 0);
        System.alloc_zeroed(layout)
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        account(0, layout.size());
        System.dealloc(ptr, layout)
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if refused(new_size) {
            return std::ptr::null_mut();
        }
        let moved = System.realloc(ptr, layout, new_size);
        if !moved.is_null() {
            account(new_size, layout.size());
        }
        moved
    }
}

// ---------------------------------------------------------------------------------------------
// Readers and their seeds

/// Reads a case folder as the library's users do; the error's message.
type Read = fn(&Path) -> Result<(), String>;

#[derive(Clone, Copy, PartialEq)]
enum Kind {
    Text,
    Binary,
    Glb,
    /// Needed beside the others (images, meshes a loader only looks for), never mutated.
    Kept,
}

struct SeedFile {
    /// Relative to the case folder, '/'-separated.
    path: String,
    bytes: Vec<u8>,
    kind: Kind,
}

/// One valid input: the files of a case folder.
type Seed = Vec<SeedFile>;

struct Reader {
    /// Also the corpus folder's name.
    name: &'static str,
    read: Read,
    seeds: Vec<Seed>,
}

fn message<T, E: std::fmt::Display>(result: Result<T, E>) -> Result<(), String> {
    result.map(drop).map_err(|e| e.to_string())
}

fn binary(path: &str, bytes: Vec<u8>) -> SeedFile {
    SeedFile { path: path.into(), bytes, kind: Kind::Binary }
}

fn text(path: &str, content: &str) -> SeedFile {
    SeedFile { path: path.into(), bytes: content.as_bytes().to_vec(), kind: Kind::Text }
}

/// Every file under `dir` whose kind `kind_of` gives (by relative path), in name order.
fn files_under(dir: &Path, kind_of: &dyn Fn(&str) -> Option<Kind>) -> Seed {
    let mut paths = vec![dir.to_owned()];
    let mut files = Vec::new();
    while let Some(path) = paths.pop() {
        if path.is_dir() {
            paths.extend(std::fs::read_dir(&path).unwrap().map(|e| e.unwrap().path()));
            continue;
        }
        let relative = path.strip_prefix(dir).unwrap().to_string_lossy().replace('\\', "/");
        if let Some(kind) = kind_of(&relative) {
            files.push(SeedFile { path: relative, bytes: std::fs::read(&path).unwrap(), kind });
        }
    }
    files.sort_by(|a, b| a.path.cmp(&b.path));
    files
}

/// What `write` writes into the fresh folder `dir`, as a seed.
fn written(dir: &Path, kind_of: &dyn Fn(&str) -> Option<Kind>, write: impl FnOnce(&Path)) -> Seed {
    let _ = std::fs::remove_dir_all(dir);
    std::fs::create_dir_all(dir).unwrap();
    write(dir);
    files_under(dir, kind_of)
}

fn by_extension(path: &str) -> Option<Kind> {
    match path.rsplit('.').next() {
        Some("ply" | "pc2") => Some(Kind::Binary),
        Some("glb") => Some(Kind::Glb),
        Some("png") => Some(Kind::Kept),
        _ => Some(Kind::Text),
    }
}

fn tetrahedron(lift: f32) -> TriMesh {
    TriMesh {
        positions: vec![[0.0, 0.0, lift], [1.0, 0.0, 0.0], [0.0, 1.0, 0.5], [0.2, 0.3, 1.0]],
        faces: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        colors: Some(vec![[255, 0, 0], [0, 255, 0], [0, 0, 255], [9, 99, 199]]),
    }
}

fn sequence() -> MeshSequence {
    let frames: Vec<TriMesh> = (0..3).map(|t| tetrahedron(0.25 * t as f32)).collect();
    MeshSequence {
        faces: frames[0].faces.clone(),
        colors: Some(frames.iter().map(|m| m.colors.clone().unwrap()).collect()),
        frames: frames.into_iter().map(|m| m.positions).collect(),
    }
}

const ASCII_PLY: &str = "ply\nformat ascii 1.0\ncomment by hand\nelement vertex 4\n\
    property float x\nproperty float y\nproperty float z\nproperty uchar red\n\
    property uchar green\nproperty uchar blue\nelement face 2\n\
    property list uchar int vertex_indices\nend_header\n\
    0 0 0 255 0 0\n1 0 0 0 255 0\n1 1 0 0 0 255\n0 1 0.5 9 9 9\n4 0 1 2 3\n3 0 2 3\n";

/// A big-endian binary PLY of a double-precision triangle with a ushort-counted face list.
fn big_endian_ply() -> Vec<u8> {
    let mut bytes = b"ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty double x\n\
        property double y\nproperty double z\nelement face 1\n\
        property list ushort uint vertex_index\nend_header\n"
        .to_vec();
    for p in [[0.0f64, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        p.iter().for_each(|c| bytes.extend(c.to_be_bytes()));
    }
    bytes.extend(3u16.to_be_bytes());
    [0u32, 1, 2].iter().for_each(|i| bytes.extend(i.to_be_bytes()));
    bytes
}

/// Comments, blank lines, columns in any order, an extra column.
const POINTS_CSV: &str =
    "# frame 0\nz, id ,x,y,extra\n\n3,nose,1,2.5,ignored\n-1e-3,chin,0,0,\n7,ear,1e3,-2,x\n";

const OBJ: &str = "# by hand\nmtllib m.mtl\no thing\nv 0 0 0\nv 1 0 0 1.0\nv 1 1 0\nv 0 1 0\n\
    vt 0 0\nvn 0 0 1\ng side\nf 1/1/1 2/1/1 3/1/1\nf -4//1 -2//1 -1//1\ns off\nf 1 2 3 4\n";

fn scene() -> GaussianScene {
    let n = 3;
    GaussianScene {
        positions: vec![[0.0, 0.0, 0.0], [1.0, -2.0, 0.5], [1e-3, 4.0, -7.0]],
        log_scales: vec![[-3.0; 3]; n],
        rotations: vec![[1.0, 0.0, 0.0, 0.0], [0.5, 0.5, 0.5, 0.5], [0.0, 1.0, 0.0, 0.0]],
        opacity_logits: vec![0.0, 2.0, -1.0],
        sh: (0..n * 4 * 3).map(|i| i as f32 * 0.01).collect(),
        sh_degree: 1,
    }
}

fn camera_json(dir: &Path) -> Seed {
    let camera = Camera::look_at(
        64,
        48,
        50.0,
        52.0,
        32.0,
        24.0,
        DVec3::new(0.5, 1.0, -3.0),
        DVec3::ZERO,
        DVec3::NEG_Y,
    )
    .unwrap();
    written(dir, &by_extension, |d| camera.save_json(&d.join("cam.json")).unwrap())
}

/// A 4×4 world-to-camera (OpenCV) or camera-to-world (OpenGL) matrix, rows: a rotation about
/// y by `angle` and a translation.
fn rigid(angle: f64, t: [f64; 3]) -> serde_json::Value {
    let (s, c) = angle.sin_cos();
    json!([[c, 0.0, s, t[0]], [0.0, 1.0, 0.0, t[1]], [-s, 0.0, c, t[2]], [0.0, 0.0, 0.0, 1.0]])
}

/// Panoptic metadata: `frames` frames of cameras `ids`.
fn panoptic_meta(frames: usize, ids: &[i64]) -> String {
    let each = |f: &dyn Fn(i64, usize) -> serde_json::Value| -> Vec<Vec<serde_json::Value>> {
        (0..frames).map(|t| ids.iter().map(|&id| f(id, t)).collect()).collect()
    };
    json!({
        "w": 8,
        "h": 6,
        "k": each(&|_, _| json!([[10.0, 0.0, 4.0], [0.0, 12.0, 3.0], [0.0, 0.0, 1.0]])),
        "w2c": each(&|id, _| rigid(0.3 * id as f64, [0.1 * id as f64, 0.0, 5.0])),
        "fn": each(&|id, t| json!(format!("{id}/{t:06}.jpg"))),
        "cam_id": each(&|id, _| json!(id)),
    })
    .to_string()
}

/// nerfstudio frames: one per (time, camera angle), images `<prefix>_<k>` (no extension).
fn nerfstudio_frames(times: &[f64], angles: &[f64], prefix: &str) -> Vec<serde_json::Value> {
    let mut frames = Vec::new();
    for &time in times {
        for (k, &angle) in angles.iter().enumerate() {
            let eye = [4.0 * angle.sin(), 0.0, 4.0 * angle.cos()];
            frames.push(json!({
                "file_path": format!("./images/{prefix}_{k}"),
                "time": time,
                "transform_matrix": rigid(angle, eye),
            }));
        }
    }
    frames
}

fn nerfstudio_seeds(dir: &Path) -> Vec<Seed> {
    let explicit = json!({
        "w": 8, "h": 6, "fl_x": 10.0, "fl_y": 12.0, "cx": 4.0, "cy": 3.0,
        "frames": nerfstudio_frames(&[0.0, 0.5, 1.0], &[0.2], "r"),
    });
    // Without w and h, the size comes from the images' headers.
    let angle_only = |angles: &[f64], prefix: &str| {
        let frames = nerfstudio_frames(&[0.0, 1.0], angles, prefix);
        json!({"camera_angle_x": 0.8, "frames": frames}).to_string()
    };
    let mut split = vec![
        text("transforms_train.json", &angle_only(&[0.0, 0.7], "train")),
        text("transforms_test.json", &angle_only(&[1.4], "test")),
    ];
    let pixels = Image { width: 8, height: 6, channels: 4, data: vec![0.5; 8 * 6 * 4] };
    let images = written(dir, &by_extension, |d| {
        for image in ["train_0", "train_1", "test_0"] {
            write_png(&d.join(format!("{image}.png")), &pixels).unwrap();
        }
    });
    split.extend(under("images", images));
    vec![vec![text("transforms.json", &explicit.to_string())], split]
}

fn own_dataset(dir: &Path) -> Seed {
    let options = SynthOptions {
        subject: SubjectSource::Procedural { subdivisions: 2 },
        views: 2,
        frames: 2,
        width: 8,
        height: 8,
        seed: 1,
        samples: 1,
        track_vertices: 2,
        track_surface: 2,
        ..Default::default()
    };
    // The loader reads dataset.json and the cameras; the images back the frame count.
    let kind_of = |path: &str| match path.split('/').next() {
        Some("dataset.json" | "cameras") => Some(Kind::Text),
        Some("images") => Some(Kind::Kept),
        _ => None,
    };
    written(dir, &kind_of, |d| _ = generate(&options, d).unwrap())
}

fn ground_truth(dir: &Path) -> Seed {
    let mut seed = vec![
        text("info.json", "{\"size\": 1.5, \"frames\": 2}"),
        text("points.csv", "id,x,y,z\np0,0,0,0\np1,1,0,0.5\n"),
        text(
            "tracks.csv",
            "id,frame,x,y,z\np0,0,0,0,0\np1,0,1,0,0.5\np0,1,0,0,0.1\np1,1,1,0,0.6\n",
        ),
    ];
    let meshes = written(dir, &|_| Some(Kind::Kept), |d| {
        (0..2)
            .for_each(|t| tetrahedron(t as f32).write_ply(&d.join(format!("{t:06}.ply"))).unwrap())
    });
    seed.extend(under("meshes", meshes));
    seed
}

/// The files of `seed` moved into `folder`.
fn under(folder: &str, seed: Seed) -> Seed {
    seed.into_iter().map(|f| SeedFile { path: format!("{folder}/{}", f.path), ..f }).collect()
}

fn readers(scratch: &Path) -> Vec<Reader> {
    let dir = |name: &str| scratch.join(name);
    let mesh = |d: &Path| tetrahedron(0.0).write_ply(&d.join("mesh.ply")).unwrap();
    let obj = |d: &Path| tetrahedron(0.0).write_obj(&d.join("mesh.obj")).unwrap();
    let folder =
        |format| move |d: &Path| sequence().write_folder(&d.join("frames"), format).unwrap();
    vec![
        Reader {
            name: "ply_mesh",
            read: |d| message(TriMesh::read_ply(&d.join("mesh.ply"))),
            seeds: vec![
                written(&dir("ply_mesh"), &by_extension, mesh),
                vec![text("mesh.ply", ASCII_PLY)],
                vec![binary("mesh.ply", big_endian_ply())],
            ],
        },
        Reader {
            name: "ply_scene",
            read: |d| message(GaussianScene::read_ply(&d.join("scene.ply"))),
            seeds: vec![written(&dir("ply_scene"), &by_extension, |d| {
                scene().write_ply(&d.join("scene.ply")).unwrap()
            })],
        },
        Reader {
            name: "obj",
            read: |d| message(TriMesh::read_obj(&d.join("mesh.obj"))),
            seeds: vec![written(&dir("obj"), &by_extension, obj), vec![text("mesh.obj", OBJ)]],
        },
        Reader {
            name: "pc2_sequence",
            read: |d| message(MeshSequence::read(&d.join("anim.pc2"))),
            seeds: vec![written(&dir("pc2"), &by_extension, |d| {
                sequence().write(&d.join("anim.pc2"), FrameFormat::Ply, 24.0).unwrap()
            })],
        },
        Reader {
            name: "glb_sequence",
            read: |d| message(MeshSequence::read(&d.join("anim.glb"))),
            seeds: vec![
                written(&dir("glb"), &by_extension, |d| {
                    sequence().write(&d.join("anim.glb"), FrameFormat::Ply, 24.0).unwrap()
                }),
                written(&dir("glb_plain"), &by_extension, |d| {
                    let plain = MeshSequence { colors: None, ..sequence() };
                    plain.write(&d.join("anim.glb"), FrameFormat::Ply, 24.0).unwrap()
                }),
            ],
        },
        // A two-joint skinned tetrahedron with a morph target and LINEAR rotation, STEP weights
        // and CUBICSPLINE translation channels, written by hand for this test (CC0).
        Reader {
            name: "gltf_animation",
            read: |d| message(MeshSequence::read(&d.join("anim.glb"))),
            seeds: vec![vec![SeedFile {
                path: "anim.glb".into(),
                bytes: include_bytes!("fuzz_corpus/gltf_animation/seed-anim.glb").to_vec(),
                kind: Kind::Glb,
            }]],
        },
        // Alembic files Maya wrote through the reference library (tests/formats/data/alembic);
        // the corpus starts with that library's own hostile test files (BSD 3-clause, see the
        // README there).
        Reader {
            name: "alembic_sequence",
            read: |d| message(MeshSequence::read(&d.join("anim.abc"))),
            seeds: [
                &include_bytes!("formats/data/alembic/animatedCube.abc")[..],
                &include_bytes!("formats/data/alembic/rotatingCube.abc")[..],
            ]
            .map(|abc| vec![binary("anim.abc", abc.to_vec())])
            .into(),
        },
        Reader {
            name: "frame_folder",
            read: |d| message(MeshSequence::read(&d.join("frames"))),
            seeds: vec![
                written(&dir("folder_ply"), &by_extension, folder(FrameFormat::Ply)),
                written(&dir("folder_obj"), &by_extension, folder(FrameFormat::Obj)),
            ],
        },
        Reader {
            name: "mdd_sequence",
            read: |d| message(MeshSequence::read(&d.join("anim.mdd"))),
            seeds: {
                let kind =
                    |p: &str| Some(if p.ends_with(".mdd") { Kind::Binary } else { Kind::Text });
                let blender =
                    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/formats/data/blender");
                vec![
                    written(&dir("mdd"), &kind, |d| {
                        sequence().write(&d.join("anim.mdd"), FrameFormat::Ply, 24.0).unwrap()
                    }),
                    written(&dir("mdd_blender"), &kind, |d| {
                        for ext in ["mdd", "obj"] {
                            let from = blender.join(format!("strip.{ext}"));
                            std::fs::copy(from, d.join(format!("anim.{ext}"))).unwrap();
                        }
                    }),
                ]
            },
        },
        Reader {
            name: "fbx_sequence",
            read: |d| {
                let options = tagsplat::sequence::ReadOptions {
                    mesh: Some("Strip".into()),
                    ..Default::default()
                };
                message(MeshSequence::read_with(&d.join("anim.fbx"), &options))
            },
            // Blender's skinned strip with a shape key (tests/formats/data/blender/README.md).
            seeds: vec![vec![binary(
                "anim.fbx",
                std::fs::read(
                    Path::new(env!("CARGO_MANIFEST_DIR"))
                        .join("tests/formats/data/blender/strip.fbx"),
                )
                .unwrap(),
            )]],
        },
        // The stage Pixar's usd-core writes for tests/formats/usd.rs, as text and as a crate
        // file: an animated mesh under animated xforms, and a static one beside it.
        Reader {
            name: "usd_sequence",
            read: |d| {
                let options = tagsplat::sequence::ReadOptions {
                    mesh: Some("/World/Rig/Body".into()),
                    ..Default::default()
                };
                let file = ["anim.usda", "anim.usdc"].map(|f| d.join(f));
                let file = file.iter().find(|f| f.exists()).expect("a seed's file");
                message(MeshSequence::read_with(file, &options))
            },
            seeds: vec![
                vec![text("anim.usda", include_str!("fuzz_corpus/usd_sequence/seed-anim.usda"))],
                vec![binary(
                    "anim.usdc",
                    include_bytes!("fuzz_corpus/usd_sequence/seed-anim.usdc").to_vec(),
                )],
            ],
        },
        Reader {
            name: "camera_json",
            read: |d| message(Camera::load_json(&d.join("cam.json"))),
            seeds: vec![camera_json(&dir("camera"))],
        },
        Reader {
            name: "points_csv",
            read: |d| message(read_points(&d.join("points.csv"))),
            seeds: vec![vec![text("points.csv", POINTS_CSV)]],
        },
        Reader {
            name: "bindings_csv",
            // Read, then checked against the tetrahedron (4 triangles, the first two one polygon).
            read: |d| {
                let mesh = tetrahedron(0.0);
                message(read_bindings(&d.join("bindings.csv")).and_then(|b| {
                    b.resolve(&mesh.faces, mesh.positions.len(), Some(&[0, 0, 1, 2]))
                }))
            },
            seeds: vec![vec![text(
                "bindings.csv",
                "# tetrahedron\nid,face,u,v,w,vertex,polygon\nmid,1,0.25,0.25,0.5,,0\n\
                 corner,,,,,3,\nedge,3,0.5,0.5,0,,2\n",
            )]],
        },
        Reader {
            name: "pixels_csv",
            read: |d| message(read_pixels(&d.join("pixels.csv"))),
            seeds: vec![vec![text("pixels.csv", "id,u,v\na,10.5,20.25\nb,0.5,0.5\nc,63.5,47\n")]],
        },
        Reader {
            name: "own_dataset",
            read: |d| message(Dataset::load(d)),
            seeds: vec![own_dataset(&dir("own"))],
        },
        Reader {
            name: "panoptic_dataset",
            read: |d| message(Dataset::load(d)),
            seeds: vec![vec![
                text("train_meta.json", &panoptic_meta(2, &[0, 3])),
                text("test_meta.json", &panoptic_meta(2, &[5])),
            ]],
        },
        Reader {
            name: "nerfstudio_dataset",
            read: |d| message(Dataset::load(d)),
            seeds: nerfstudio_seeds(&dir("nerfstudio")),
        },
        Reader {
            name: "ground_truth",
            read: |d| message(GroundTruth::read(d)),
            seeds: vec![ground_truth(&dir("ground_truth"))],
        },
        Reader {
            name: "train_config",
            read: |d| message(TrainConfig::load(&d.join("train.toml"))),
            seeds: vec![vec![text("train.toml", &TrainConfig::default().to_toml())]],
        },
        Reader {
            name: "fit_config",
            read: |d| message(FitConfig::load(&d.join("fit.toml"))),
            seeds: vec![vec![text("fit.toml", &FitConfig::default().to_toml())]],
        },
    ]
}

/// The readers with their seeds, built once for every test of this file.
fn all_readers() -> &'static [Reader] {
    static READERS: OnceLock<Vec<Reader>> = OnceLock::new();
    READERS.get_or_init(|| {
        let dir = scratch("seeds");
        let readers = readers(&dir);
        remove_scratch(&dir);
        readers
    })
}

/// This process's scratch folder: in memory where the machine has /dev/shm, since writing
/// each case's files to a disk's file system costs more than reading them (a third of the
/// cases per second on ext4).
fn scratch_root() -> PathBuf {
    let shm = Path::new("/dev/shm");
    let base = if shm.is_dir() { shm.to_owned() } else { std::env::temp_dir() };
    base.join(format!("tagsplat-fuzz-{}", std::process::id()))
}

/// A fresh scratch folder.
fn scratch(name: &str) -> PathBuf {
    let dir = scratch_root().join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Removes a scratch folder, and the process's folder once it is empty.
fn remove_scratch(dir: &Path) {
    let _ = std::fs::remove_dir_all(dir);
    let _ = std::fs::remove_dir(scratch_root());
}

// ---------------------------------------------------------------------------------------------
// Mutations

type Mutation = (&'static str, fn(&mut Vec<u8>, &mut SplitMix64));

/// Mutations for every file kind; a PLY header's counts are text in a binary file, so the
/// number edits apply to both.
const COMMON_MUTATIONS: [Mutation; 8] = [
    ("bit flip", flip_bit),
    ("byte set to 00/FF", set_byte),
    ("truncation", truncate),
    ("inserted bytes", insert_bytes),
    ("duplicated chunk", duplicate_chunk),
    ("removed chunk", remove_chunk),
    ("huge number", huge_number),
    ("huge count", huge_count),
];

const TEXT_ONLY_MUTATIONS: &[Mutation] =
    &[("non-finite number", non_finite_number), ("line removed or repeated", edit_line)];

const BINARY_ONLY_MUTATIONS: &[Mutation] = &[("NaN/Inf/huge binary word", special_word)];

/// One mutation for a text or binary file: the common ones and the kind's own, equally likely.
fn pick_mutation(rng: &mut SplitMix64, text: bool) -> Mutation {
    let own = if text { TEXT_ONLY_MUTATIONS } else { BINARY_ONLY_MUTATIONS };
    let i = below(rng, COMMON_MUTATIONS.len() + own.len());
    COMMON_MUTATIONS.get(i).copied().unwrap_or_else(|| own[i - COMMON_MUTATIONS.len()])
}

/// Replacements for a number: counts and values far beyond what the file holds, from those a
/// reader's sanity limits let through to those that overflow its arithmetic.
const HUGE: &[&str] = &[
    "1000000",
    "10000000",
    "100000000",
    "4294967295",
    "4294967296",
    "2147483647",
    "-2147483648",
    "18446744073709551615",
    "9999999999999",
    "1000000000000",
    "1e300",
    "-1e300",
    "-1",
    "0",
    "-0",
    "1e-320",
];
const NON_FINITE: &[&str] = &["NaN", "nan", "inf", "-inf", "Infinity", "-Infinity", "1e400"];

/// Words written over binary data: float NaN/Inf/extremes, and counts.
const WORDS: &[&[u8]] = &[
    &f32::NAN.to_le_bytes(),
    &f32::INFINITY.to_le_bytes(),
    &f32::NEG_INFINITY.to_le_bytes(),
    &f32::MAX.to_le_bytes(),
    &f64::NAN.to_le_bytes(),
    &f64::INFINITY.to_le_bytes(),
    &u32::MAX.to_le_bytes(),
    &i32::MAX.to_le_bytes(),
    &i32::MIN.to_le_bytes(),
    &1_000_000_000u32.to_le_bytes(),
    &0u32.to_le_bytes(),
];

fn below(rng: &mut SplitMix64, n: usize) -> usize {
    (rng.next_u64() % n.max(1) as u64) as usize
}

fn pick<'a, T>(rng: &mut SplitMix64, items: &'a [T]) -> &'a T {
    &items[below(rng, items.len())]
}

/// A random range of at most 64 bytes within `len` (empty when `len` is 0).
fn chunk(rng: &mut SplitMix64, len: usize) -> std::ops::Range<usize> {
    let start = below(rng, len);
    start..(start + 1 + below(rng, 64)).min(len)
}

#[allow(clippy::ptr_arg)] // a `Mutation`: the table's type takes the Vec other mutations resize
fn flip_bit(b: &mut Vec<u8>, rng: &mut SplitMix64) {
    if !b.is_empty() {
        let at = below(rng, b.len());
        b[at] ^= 1 << below(rng, 8);
    }
}

#[allow(clippy::ptr_arg)] // a `Mutation`: the table's type takes the Vec other mutations resize
fn set_byte(b: &mut Vec<u8>, rng: &mut SplitMix64) {
    if !b.is_empty() {
        let at = below(rng, b.len());
        b[at] = if rng.next_u64() & 1 == 0 { 0x00 } else { 0xFF };
    }
}

fn truncate(b: &mut Vec<u8>, rng: &mut SplitMix64) {
    let len = below(rng, b.len());
    b.truncate(len);
}

/// Random bytes, or characters that mean something to the text formats (half the time: random
/// bytes are rarely UTF-8, and a text reader would refuse them before parsing anything).
fn insert_bytes(b: &mut Vec<u8>, rng: &mut SplitMix64) {
    const SYNTAX: &[u8] = b" \n,.-+e0123456789[]{}\":=#/";
    let bytes: Vec<u8> = if rng.next_u64() & 1 == 0 {
        (0..1 + below(rng, 16)).map(|_| rng.next_u64() as u8).collect()
    } else {
        (0..1 + below(rng, 16)).map(|_| *pick(rng, SYNTAX)).collect()
    };
    let at = below(rng, b.len() + 1);
    b.splice(at..at, bytes);
}

fn duplicate_chunk(b: &mut Vec<u8>, rng: &mut SplitMix64) {
    let copy = b[chunk(rng, b.len())].to_vec();
    let at = below(rng, b.len() + 1);
    b.splice(at..at, copy);
}

fn remove_chunk(b: &mut Vec<u8>, rng: &mut SplitMix64) {
    let range = chunk(rng, b.len());
    b.drain(range);
}

/// The spans of numbers in `b` (not the digits inside names such as `f_rest_3` or `int32`).
fn numbers(b: &[u8]) -> Vec<std::ops::Range<usize>> {
    let part_of_number = |c: &u8| c.is_ascii_digit() || b"+-.eE".contains(c);
    let mut spans = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let digit_at = |k: usize| b.get(k).is_some_and(u8::is_ascii_digit);
        let starts = (digit_at(i) || (b[i] == b'-' && digit_at(i + 1)))
            && (i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b"_.".contains(&b[i - 1])));
        if starts {
            let end = i + 1 + b[i + 1..].iter().take_while(|c| part_of_number(c)).count();
            spans.push(i..end);
            i = end;
        } else {
            i += 1;
        }
    }
    spans
}

fn replace_number(b: &mut Vec<u8>, rng: &mut SplitMix64, values: &[&str]) {
    replace_one(b, rng, numbers(b), values)
}

fn replace_one(
    b: &mut Vec<u8>,
    rng: &mut SplitMix64,
    spans: Vec<std::ops::Range<usize>>,
    values: &[&str],
) {
    if !spans.is_empty() {
        let span = pick(rng, &spans).clone();
        let value = pick(rng, values).as_bytes();
        b.splice(span, value.iter().copied());
    }
}

fn huge_number(b: &mut Vec<u8>, rng: &mut SplitMix64) {
    replace_number(b, rng, HUGE)
}

/// A huge value for a number that a count's name precedes closely (`element vertex 4`,
/// `"count":4`, `"frames": 2`): among a GLB's hundred numbers, the few that size allocations.
fn huge_count(b: &mut Vec<u8>, rng: &mut SplitMix64) {
    const NAMES: [&[u8]; 3] = [b"count", b"element", b"frames"];
    let counts = numbers(b)
        .into_iter()
        .filter(|span| {
            let before = &b[span.start.saturating_sub(16)..span.start];
            NAMES.iter().any(|name| before.windows(name.len()).any(|w| w == *name))
        })
        .collect();
    replace_one(b, rng, counts, HUGE)
}

fn non_finite_number(b: &mut Vec<u8>, rng: &mut SplitMix64) {
    replace_number(b, rng, NON_FINITE)
}

fn edit_line(b: &mut Vec<u8>, rng: &mut SplitMix64) {
    let starts: Vec<usize> = std::iter::once(0)
        .chain(b.iter().enumerate().filter(|(_, &c)| c == b'\n').map(|(i, _)| i + 1))
        .collect();
    let k = below(rng, starts.len());
    let line = starts[k]..starts.get(k + 1).copied().unwrap_or(b.len());
    if rng.next_u64() & 1 == 0 {
        b.drain(line);
    } else {
        let copy = b[line.clone()].to_vec();
        b.splice(line.start..line.start, copy);
    }
}

/// A float or count word over the bytes at a random offset, 4-aligned half the time (the
/// fields of PC2 and of float-only PLY bodies are).
#[allow(clippy::ptr_arg)] // a `Mutation`: the table's type takes the Vec other mutations resize
fn special_word(b: &mut Vec<u8>, rng: &mut SplitMix64) {
    let mut at = below(rng, b.len());
    if rng.next_u64() & 1 == 0 {
        at &= !3;
    }
    let word = pick(rng, WORDS);
    let end = (at + word.len()).min(b.len());
    b[at..end].copy_from_slice(&word[..end - at]);
}

/// The JSON and BIN chunks of a GLB, when its container is intact enough to find them.
fn glb_chunks(b: &[u8]) -> Option<(Vec<u8>, Vec<u8>)> {
    let word = |at: usize| Some(u32::from_le_bytes(b.get(at..at + 4)?.try_into().ok()?) as usize);
    let json_end = 20 + word(12)?;
    let json = b.get(20..json_end)?.to_vec();
    let bin = match word(json_end) {
        Some(len) => b.get(json_end + 8..json_end + 8 + len)?.to_vec(),
        None => Vec::new(),
    };
    Some((json, bin))
}

/// A GLB container around `json` and `bin`, lengths and padding as the format requires.
fn glb(mut json: Vec<u8>, mut bin: Vec<u8>) -> Vec<u8> {
    json.resize(json.len().next_multiple_of(4), b' ');
    bin.resize(bin.len().next_multiple_of(4), 0);
    let bin_chunk = if bin.is_empty() { 0 } else { 8 + bin.len() };
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend(((12 + 8 + json.len() + bin_chunk) as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(json);
    if !bin.is_empty() {
        out.extend((bin.len() as u32).to_le_bytes());
        out.extend(b"BIN\0");
        out.extend(bin);
    }
    out
}

/// One mutation of a GLB: of its JSON chunk or its BIN chunk inside a rebuilt container (so
/// that the reader gets past the container's checks), or of the file as it is.
fn mutate_glb(b: &mut Vec<u8>, rng: &mut SplitMix64) -> String {
    let target = below(rng, 3);
    match glb_chunks(b) {
        Some((mut json, bin)) if target == 0 => {
            let (name, mutation) = pick_mutation(rng, true);
            mutation(&mut json, rng);
            *b = glb(json, bin);
            format!("JSON chunk: {name}")
        }
        Some((json, mut bin)) if target == 1 => {
            let (name, mutation) = pick_mutation(rng, false);
            mutation(&mut bin, rng);
            *b = glb(json, bin);
            format!("BIN chunk: {name}")
        }
        _ => {
            let (name, mutation) = pick_mutation(rng, false);
            mutation(b, rng);
            name.to_string()
        }
    }
}

/// One to four mutations of `file`, and their names.
fn mutate(file: &SeedFile, rng: &mut SplitMix64) -> (Vec<u8>, Vec<String>) {
    let mut bytes = file.bytes.clone();
    let applied = (0..1 + below(rng, 4))
        .map(|_| match file.kind {
            Kind::Glb => mutate_glb(&mut bytes, rng),
            kind => {
                let (name, mutation) = pick_mutation(rng, kind == Kind::Text);
                mutation(&mut bytes, rng);
                name.to_string()
            }
        })
        .collect();
    (bytes, applied)
}

// ---------------------------------------------------------------------------------------------
// Running cases

fn panic_text(payload: Box<dyn std::any::Any + Send>) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "a panic without a message".into())
}

/// A reader's outcome: None when it read the input, its error message otherwise.
type Outcome = Option<String>;

/// Reads the case folder `dir` on a worker thread (8 MiB of stack, as a main thread has) under
/// the watchdog; Err says how the reader misbehaved: a panic, a hang, an allocation beyond the
/// allowance of `input` bytes, an error that does not contain `named`.
fn run_case(read: Read, dir: &Path, named: &Path, input: usize) -> Result<Outcome, String> {
    let (send, receive) = mpsc::channel();
    let case = dir.to_owned();
    std::thread::Builder::new()
        .stack_size(8 << 20)
        .spawn(move || {
            USAGE.with(|u| u.set(NO_USAGE));
            let result = std::panic::catch_unwind(|| read(&case)).map_err(panic_text);
            let _ = send.send((result, USAGE.with(Cell::get)));
        })
        .expect("a worker thread starts");
    let (result, usage) = receive
        .recv_timeout(WATCHDOG)
        .map_err(|_| format!("hang: no answer within {WATCHDOG:?}"))?;
    let result = result.map_err(|panic| format!("panic: {panic}"))?;
    let allowed = allowance(input);
    if usage.largest > allowed {
        return Err(format!(
            "over-allocation: one allocation of {} bytes for a {input}-byte input \
             (allowed {allowed})",
            usage.largest
        ));
    }
    if usage.peak > 4 * allowed as isize {
        return Err(format!(
            "over-allocation: {} bytes live at once for a {input}-byte input (allowed {})",
            usage.peak,
            4 * allowed
        ));
    }
    match result {
        Err(error) if !error.contains(&named.display().to_string()) => {
            Err(format!("the error does not name {}: {error}", named.display()))
        }
        Ok(()) => Ok(None),
        Err(error) => Ok(Some(error)),
    }
}

/// A reader's seed written into its own case folder, mutated one file at a time.
struct Case<'a> {
    reader: &'a Reader,
    seed: &'a Seed,
    dir: PathBuf,
}

impl<'a> Case<'a> {
    fn new(reader: &'a Reader, seed: &'a Seed, dir: PathBuf) -> Self {
        for file in seed {
            write_file(&dir.join(&file.path), &file.bytes);
        }
        Case { reader, seed, dir }
    }

    /// Reads the case with file `f` replaced by `bytes`, then puts the seed's file back. An
    /// error must name that file, or for a reader of several files, one inside the folder.
    fn run(&self, f: usize, bytes: &[u8], description: &str) -> Result<Outcome, String> {
        let path = self.dir.join(&self.seed[f].path);
        write_file(&path, bytes);
        *CURRENT.lock().unwrap() = format!("{description}, input {}", path.display());
        let named = if self.seed.len() == 1 { &path } else { &self.dir };
        let input =
            self.seed.iter().map(|s| s.bytes.len()).sum::<usize>() - self.seed[f].bytes.len();
        let outcome = run_case(self.reader.read, &self.dir, named, input + bytes.len());
        write_file(&path, &self.seed[f].bytes);
        outcome
    }
}

/// Writes `path` as a new file: ext4 flushes a file rewritten in place (truncated) when it is
/// closed, which made every case ten times slower.
fn write_file(path: &Path, bytes: &[u8]) {
    let _ = std::fs::remove_file(path);
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    std::fs::write(path, bytes).unwrap();
}

fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| (h ^ b as u64).wrapping_mul(0x100_0000_01b3))
}

fn corpus(reader: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_corpus").join(reader)
}

/// Saves a failing input as `<content hash>-<seed file, '/' as '+'>`; returns where.
fn save(reader: &str, file: &SeedFile, bytes: &[u8]) -> PathBuf {
    let name = format!("{:016x}-{}", fnv1a(bytes), file.path.replace('/', "+"));
    let path = corpus(reader).join(name);
    write_file(&path, bytes);
    path
}

/// Cases run and failures of one reader.
#[derive(Default)]
struct Tally {
    cases: usize,
    replayed: usize,
    /// Mutated inputs the reader accepted: how many cases got past its checks.
    accepted: usize,
    failures: Vec<String>,
}

/// Replays the reader's corpus, then fuzzes it until `share` has passed.
fn fuzz(reader: &Reader, base_seed: u64, share: Duration, dir: &Path) -> Tally {
    let deadline = Instant::now() + share;
    let cases: Vec<Case> = reader
        .seeds
        .iter()
        .enumerate()
        .map(|(s, seed)| Case::new(reader, seed, dir.join(s.to_string())))
        .collect();
    for case in &cases {
        match case.run(0, &case.seed[0].bytes, "a seed") {
            Ok(None) => {}
            other => panic!("{}: a seed does not read ({other:?}); fix the seed", reader.name),
        }
    }
    let mut tally = replay(reader, &cases);
    let mut stream = SplitMix64::new(base_seed ^ fnv1a(reader.name.as_bytes()));
    while Instant::now() < deadline {
        let case_seed = stream.next_u64();
        let mut rng = SplitMix64::new(case_seed);
        let case = pick(&mut rng, &cases);
        let mutable: Vec<usize> =
            (0..case.seed.len()).filter(|&f| case.seed[f].kind != Kind::Kept).collect();
        let f = *pick(&mut rng, &mutable);
        let (bytes, applied) = mutate(&case.seed[f], &mut rng);
        let description =
            format!("{} case seed {case_seed:#018x} ({})", reader.name, applied.join(", "));
        tally.cases += 1;
        match case.run(f, &bytes, &description) {
            Ok(outcome) => tally.accepted += outcome.is_none() as usize,
            Err(failure) => {
                let saved = save(reader.name, &case.seed[f], &bytes);
                let hang = failure.starts_with("hang");
                tally
                    .failures
                    .push(format!("{description}: {failure}; input saved to {}", saved.display()));
                // A hung reader still runs on its thread: stop feeding this one.
                if hang {
                    break;
                }
            }
        }
    }
    tally
}

/// Replays every corpus input of the reader in place of the seed file it names.
fn replay(reader: &Reader, cases: &[Case]) -> Tally {
    let mut tally = Tally::default();
    let Ok(entries) = std::fs::read_dir(corpus(reader.name)) else { return tally };
    let mut paths: Vec<PathBuf> = entries.map(|e| e.unwrap().path()).collect();
    paths.sort();
    for path in paths {
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let target = name.split_once('-').map(|(_, file)| file.replace('+', "/"));
        let found = cases.iter().find_map(|c| {
            let f = c.seed.iter().position(|s| Some(&s.path) == target.as_ref())?;
            Some((c, f))
        });
        tally.cases += 1;
        tally.replayed += 1;
        let failure = match found {
            None => Err(format!("names no seed file of {}", reader.name)),
            Some((case, f)) => {
                case.run(f, &std::fs::read(&path).unwrap(), &format!("corpus {}", path.display()))
            }
        };
        if let Err(failure) = failure {
            tally.failures.push(format!("corpus {}: {failure}", path.display()));
        }
    }
    tally
}

/// Writes a line to stderr directly: `eprintln!` output is captured by the test harness, and
/// CI's log should record the counts without `--nocapture`.
fn say(line: &str) {
    let _ = writeln!(std::io::stderr(), "{line}");
}

fn env_seconds() -> Duration {
    let seconds = std::env::var("TAGSPLAT_FUZZ_SECONDS").map_or(DEFAULT_SECONDS, |s| {
        s.parse().unwrap_or_else(|_| panic!("TAGSPLAT_FUZZ_SECONDS={s} is not a number"))
    });
    Duration::from_secs_f64(seconds)
}

fn env_seed() -> u64 {
    std::env::var("TAGSPLAT_FUZZ_SEED").map_or(DEFAULT_SEED, |s| {
        let parsed = match s.strip_prefix("0x") {
            Some(hex) => u64::from_str_radix(hex, 16),
            None => s.parse(),
        };
        parsed.unwrap_or_else(|_| panic!("TAGSPLAT_FUZZ_SEED={s} is not a u64"))
    })
}

#[test]
fn every_reader_survives_mutated_input() {
    let started = Instant::now();
    let (budget, seed) = (env_seconds(), env_seed());
    let readers = all_readers();
    let dir = scratch("cases");
    let (mut cases, mut failures) = (0, Vec::new());
    for (k, reader) in readers.iter().enumerate() {
        let share = budget.saturating_sub(started.elapsed()) / (readers.len() - k) as u32;
        let reader_started = Instant::now();
        let tally = fuzz(reader, seed, share, &dir.join(reader.name));
        say(&format!(
            "fuzz: {:<18} {:>7} cases ({} from the corpus, {} accepted) in {:.1} s, {} failures",
            reader.name,
            tally.cases,
            tally.replayed,
            tally.accepted,
            reader_started.elapsed().as_secs_f64(),
            tally.failures.len()
        ));
        cases += tally.cases;
        failures.extend(tally.failures);
    }
    say(&format!(
        "fuzz: {cases} cases in {:.1} s (TAGSPLAT_FUZZ_SEED={seed:#x}), {} failures",
        started.elapsed().as_secs_f64(),
        failures.len()
    ));
    failures.iter().for_each(|f| say(&format!("fuzz: FAILED {f}")));
    remove_scratch(&dir);
    assert!(failures.is_empty(), "{} fuzz cases failed (listed above)", failures.len());
}

/// Where a claim goes: the number after `key` (in a GLB, in its JSON chunk), or the binary
/// word at a byte offset.
enum Claim {
    After(&'static str),
    Word(usize),
}

/// The seed file `file` with a claim of about 10^12 elements.
fn claiming(file: &SeedFile, claim: &Claim) -> Vec<u8> {
    let replace_after = |b: &[u8], key: &str| -> Vec<u8> {
        let at =
            b.windows(key.len()).position(|w| w == key.as_bytes()).expect("the key is in the seed")
                + key.len();
        let span = numbers(&b[at..]).into_iter().next().expect("a number follows the key");
        [&b[..at + span.start], b"1000000000000", &b[at + span.end..]].concat()
    };
    match (claim, file.kind) {
        (Claim::After(key), Kind::Glb) => {
            let (json, bin) = glb_chunks(&file.bytes).unwrap();
            glb(replace_after(&json, key), bin)
        }
        (Claim::After(key), _) => replace_after(&file.bytes, key),
        (Claim::Word(at), _) => {
            let mut b = file.bytes.clone();
            b[*at..at + 4].copy_from_slice(&i32::MAX.to_le_bytes());
            b
        }
    }
}

/// Headers and metadata that claim about 10^12 elements (PLY rows, PC2 points and samples,
/// glTF accessor elements, dataset frames, USD polygons, and a crate file's sections and arrays)
/// are refused at once, within the allowance, by an error naming the file.
#[test]
fn claims_of_a_trillion_elements_are_refused_at_once() {
    let claims = [
        ("ply_mesh", "mesh.ply", Claim::After("element vertex ")),
        ("ply_mesh", "mesh.ply", Claim::After("element face ")),
        ("ply_scene", "scene.ply", Claim::After("element vertex ")),
        ("pc2_sequence", "anim.pc2", Claim::Word(16)),
        ("pc2_sequence", "anim.pc2", Claim::Word(28)),
        ("glb_sequence", "anim.glb", Claim::After("\"count\":")),
        ("frame_folder", "frames/frame_000001.ply", Claim::After("element vertex ")),
        ("own_dataset", "dataset.json", Claim::After("\"frames\": ")),
        ("usd_sequence", "anim.usda", Claim::After("faceVertexCounts = [")),
        ("usd_sequence", "anim.usda", Claim::After("faceVertexIndices = [")),
        // The seed crate file's table-of-contents offset, the size of its tokens' text, its
        // string, path and spec counts, and the element counts of two arrays (the body's
        // faceVertexCounts, the other mesh's points).
        ("usd_sequence", "anim.usdc", Claim::Word(16)),
        ("usd_sequence", "anim.usdc", Claim::Word(1396)),
        ("usd_sequence", "anim.usdc", Claim::Word(1779)),
        ("usd_sequence", "anim.usdc", Claim::Word(2205)),
        ("usd_sequence", "anim.usdc", Claim::Word(2307)),
        ("usd_sequence", "anim.usdc", Claim::Word(252)),
        ("usd_sequence", "anim.usdc", Claim::Word(328)),
    ];
    let dir = scratch("claims");
    for (k, (name, file, claim)) in claims.iter().enumerate() {
        let reader = all_readers().iter().find(|r| r.name == *name).unwrap();
        let seeds =
            reader.seeds.iter().enumerate().filter_map(|(s, seed)| {
                Some((s, seed, seed.iter().position(|sf| sf.path == *file)?))
            });
        let mut claimed = 0;
        for (s, seed, f) in seeds {
            claimed += 1;
            let case = Case::new(reader, seed, dir.join(format!("{k}-{s}")));
            let started = Instant::now();
            let outcome = case.run(f, &claiming(&seed[f], claim), &format!("{name} claim {k}"));
            let took = started.elapsed();
            match outcome {
                Ok(Some(_)) if took < Duration::from_secs(1) => {}
                other => panic!("{name} seed {s}, claim {k}: {other:?} after {took:?}"),
            }
        }
        assert!(claimed > 0, "claim {k}: no seed of {name} has {file}");
    }
    remove_scratch(&dir);
}
