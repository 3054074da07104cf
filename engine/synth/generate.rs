//! Writes a synthetic dataset with ground truth in the project's own layout
//! (`dataset::own`), plus:
//!
//! ```text
//! DIR/meshes/<t>.ply       ground-truth mesh of frame t: same faces every frame, vertex colours
//! DIR/bindings.csv         id,face,b0,b1,b2: each tracked point on the frame-0 mesh
//! DIR/trajectories.csv     id,frame,x,y,z: each tracked point at every frame
//! DIR/points.csv           id,x,y,z: the tracked points at frame 0 (the tracker's query file)
//! ```
//!
//! Cameras sit on a sphere around the subject's bounding sphere (over all frames) at 3 radii,
//! azimuths spread evenly (a seeded offset), elevations from −10° to 35°; the focal length
//! makes the bounding sphere fill 90 % of the image. Everything is checked (subject,
//! options, visibility) before the first file is written, every file is written atomically,
//! and `dataset.json` is written last, so a folder without it is an incomplete run.

use super::gltf::{load_gltf, GltfError};
use super::manifold::closed_manifold_problem;
use super::motion_stats::{motion_stats, MotionStats};
use super::raster::{render, RenderError};
use super::texture::{Pattern, Texture};
use super::Subject;
use crate::camera::{Camera, CameraError};
use crate::dataset::own::{self, OwnMeta};
use crate::eval::{sample_surface, EvalError};
use crate::io::image::{write_png, Image, ImageError};
use crate::io::trajectories::{write_trajectories_csv, TrackPoint};
use crate::mesh::{MeshError, TriMesh};
use crate::rng::SplitMix64;
use glam::DVec3;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// What to animate.
#[derive(Clone, Debug, PartialEq)]
pub enum SubjectSource {
    /// The procedural body with this many icosphere subdivisions (4: 2562 vertices).
    Procedural {
        /// Icosphere subdivision levels; [`load_subject`] accepts at most 6.
        subdivisions: u32,
    },
    /// A rigged glTF file and the animation to play (the first when `None`).
    Gltf {
        /// The `.glb` or `.gltf` file.
        path: PathBuf,
        /// Name of the animation to play; `None` for the file's first.
        animation: Option<String>,
    },
}

/// How fast the subject moves per captured frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MotionPreset {
    /// The animation at its own speed (the procedural body: one cycle in 48 frames).
    #[default]
    Gentle,
    /// Four times as fast: the procedural body's cycle in 12 frames, limbs moving up to about a
    /// tenth of the subject's size per frame, as a walk at capture frame rates.
    Walk,
    /// Five times as fast: the cycle in 9.6 frames, as a run.
    Run,
}

impl MotionPreset {
    /// The preset named `gentle`, `walk` or `run`.
    pub fn from_name(name: &str) -> Result<Self, String> {
        match name {
            "gentle" => Ok(MotionPreset::Gentle),
            "walk" => Ok(MotionPreset::Walk),
            "run" => Ok(MotionPreset::Run),
            other => Err(format!("unknown motion '{other}' (gentle, walk or run)")),
        }
    }

    /// Animation frames per captured frame.
    pub fn pace(self) -> f64 {
        match self {
            MotionPreset::Gentle => 1.0,
            MotionPreset::Walk => 4.0,
            MotionPreset::Run => 5.0,
        }
    }
}

/// What [`generate`] writes. [`generate`] rejects views outside 1..=1000, frames outside
/// 1..=100000, a width or height outside 8..=8192 and samples outside 1..=16.
#[derive(Clone, Debug, PartialEq)]
pub struct SynthOptions {
    /// What to animate.
    pub subject: SubjectSource,
    /// Number of cameras.
    pub views: usize,
    /// Number of captured frames.
    pub frames: usize,
    /// Width of every image, pixels.
    pub width: u32,
    /// Height of every image, pixels.
    pub height: u32,
    /// Seed of the camera azimuth offset and of the tracked-point choice.
    pub seed: u64,
    /// Samples per pixel along each axis (4 → 16 samples).
    pub samples: u32,
    /// Tracked points: this many random vertices and this many random surface points.
    pub track_vertices: usize,
    /// Number of area-uniform random surface points tracked (see `track_vertices`).
    pub track_surface: usize,
    /// How fast the subject moves per captured frame.
    pub motion: MotionPreset,
    /// What is printed on the subject's skin.
    pub pattern: Pattern,
}

impl Default for SynthOptions {
    fn default() -> Self {
        Self {
            subject: SubjectSource::Procedural { subdivisions: 4 },
            views: 8,
            frames: 8,
            width: 256,
            height: 256,
            seed: 0,
            samples: 4,
            track_vertices: 100,
            track_surface: 200,
            motion: MotionPreset::Gentle,
            pattern: Pattern::Smooth,
        }
    }
}

/// Why [`generate`] or [`load_subject`] failed.
#[derive(Debug, thiserror::Error)]
pub enum SynthError {
    /// An option is out of range; the string says which.
    #[error("invalid options: {0}")]
    Options(String),
    /// The glTF subject could not be loaded.
    #[error(transparent)]
    Gltf(#[from] GltfError),
    /// The subject cannot be generated: a procedural body that is not a closed manifold,
    /// non-finite positions after skinning, or no spatial extent.
    #[error("the subject is not usable: {0}")]
    Subject(String),
    /// A camera could not be built or its JSON file written.
    #[error("camera {camera}: {source}")]
    Camera {
        /// Index of the camera.
        camera: usize,
        /// The underlying error.
        source: CameraError,
    },
    /// The reference renderer refused a view.
    #[error("frame {frame}, camera {camera}: {source}")]
    Render {
        /// The frame being rendered.
        frame: usize,
        /// Index of the camera.
        camera: usize,
        /// The underlying error.
        source: RenderError,
    },
    /// An image or mask PNG could not be written.
    #[error(transparent)]
    Image(#[from] ImageError),
    /// A ground-truth mesh PLY could not be written.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// The random surface points could not be sampled.
    #[error("tracked points: {0}")]
    Eval(#[from] EvalError),
    /// A directory or file could not be created or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The directory or file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
}

/// What [`generate`] wrote.
#[derive(Clone, Debug, Serialize)]
pub struct SynthReport {
    /// Vertices of the subject mesh.
    pub vertices: usize,
    /// Triangles of the subject mesh.
    pub faces: usize,
    /// Number of cameras.
    pub views: usize,
    /// Number of captured frames.
    pub frames: usize,
    /// Width of every image, pixels.
    pub width: u32,
    /// Height of every image, pixels.
    pub height: u32,
    /// Number of tracked points written (vertices plus surface points).
    pub tracked_points: usize,
    /// `None` for a closed manifold; otherwise why not (allowed for glTF input only).
    pub manifold_problem: Option<String>,
    /// Bounding-sphere radius of the subject over all frames, scene units.
    pub radius: f64,
    /// The motion preset used.
    pub motion: MotionPreset,
    /// Vertex motion between consecutive frames, fractions of the subject's size.
    pub motion_per_frame: MotionStats,
}

/// Loads the subject the options name.
pub fn load_subject(source: &SubjectSource) -> Result<Subject, SynthError> {
    match source {
        SubjectSource::Procedural { subdivisions } if *subdivisions <= 6 => {
            Ok(Subject::procedural(*subdivisions))
        }
        SubjectSource::Procedural { subdivisions } => {
            Err(SynthError::Options(format!("{subdivisions} subdivisions is more than 6")))
        }
        SubjectSource::Gltf { path, animation } => Ok(load_gltf(path, animation.as_deref())?),
    }
}

/// Generates the dataset into `out` (created if needed).
pub fn generate(options: &SynthOptions, out: &Path) -> Result<SynthReport, SynthError> {
    check_options(options)?;
    let subject = Subject { pace: options.motion.pace(), ..load_subject(&options.subject)? };
    let manifold_problem = closed_manifold_problem(subject.rest.len(), &subject.faces);
    if let (Some(problem), SubjectSource::Procedural { .. }) = (&manifold_problem, &options.subject)
    {
        return Err(SynthError::Subject(problem.clone()));
    }
    let frames: Vec<Vec<[f32; 3]>> = (0..options.frames).map(|t| subject.positions(t)).collect();
    if let Some(t) = frames.iter().position(|f| f.iter().flatten().any(|v| !v.is_finite())) {
        return Err(SynthError::Subject(format!(
            "frame {t} has non-finite vertex positions after skinning"
        )));
    }
    let (center, radius) = bounding_sphere(&frames);
    let cameras = place_cameras(options, center, radius)?;
    let tracks = track_points(&subject, options)?;
    let texture = Texture::fit(&subject.rest).with_pattern(options.pattern);
    let colors = texture.vertex_colors(&subject.rest);
    let names: Vec<String> = (0..cameras.len()).map(|c| format!("cam{c:03}")).collect();

    for dir in [out.join("cameras"), out.join("meshes")]
        .into_iter()
        .chain(names.iter().flat_map(|n| [out.join("images").join(n), out.join("masks").join(n)]))
    {
        std::fs::create_dir_all(&dir)
            .map_err(|source| SynthError::Io { path: dir.clone(), source })?;
    }
    for (k, (camera, name)) in cameras.iter().zip(&names).enumerate() {
        camera
            .save_json(&own::camera_path(out, name))
            .map_err(|source| SynthError::Camera { camera: k, source })?;
    }
    for (t, positions) in frames.iter().enumerate() {
        let mesh = TriMesh {
            positions: positions.clone(),
            faces: subject.faces.clone(),
            colors: Some(colors.clone()),
        };
        mesh.write_ply(&out.join("meshes").join(format!("{}.ply", own::frame_name(t))))?;
    }
    write_tracks(out, &subject, &frames, &tracks)?;
    render_all(options, out, &subject, &frames, &cameras, &names, &texture)?;

    let (_, test) = crate::dataset::every_eighth_held_out(cameras.len());
    let meta = OwnMeta {
        format: own::FORMAT_NAME.into(),
        version: 1,
        frames: options.frames,
        fps: super::gltf::FPS,
        cameras: names.clone(),
        test_cameras: test.iter().map(|&i| names[i].clone()).collect(),
    };
    let path = out.join(own::META);
    let text = serde_json::to_string_pretty(&meta).expect("plain data serializes");
    crate::io::write_atomically(&path, |w| std::io::Write::write_all(w, text.as_bytes()))
        .map_err(|source| SynthError::Io { path, source })?;
    Ok(SynthReport {
        vertices: subject.rest.len(),
        faces: subject.faces.len(),
        views: options.views,
        frames: options.frames,
        width: options.width,
        height: options.height,
        tracked_points: tracks.len(),
        manifold_problem,
        radius,
        motion: options.motion,
        motion_per_frame: motion_stats(&frames),
    })
}

fn check_options(o: &SynthOptions) -> Result<(), SynthError> {
    let bad = |m: &str| Err(SynthError::Options(m.into()));
    match () {
        _ if o.views == 0 || o.views > 1000 => bad("views must be 1..=1000"),
        _ if o.frames == 0 || o.frames > 100_000 => bad("frames must be 1..=100000"),
        _ if !(8..=8192).contains(&o.width) => bad("width must be 8..=8192 pixels"),
        _ if !(8..=8192).contains(&o.height) => bad("height must be 8..=8192 pixels"),
        _ if !(1..=16).contains(&o.samples) => bad("samples per pixel axis must be 1..=16"),
        _ => Ok(()),
    }
}

/// Centre of the bounding box of every position of every frame, and the largest distance from
/// it.
fn bounding_sphere(frames: &[Vec<[f32; 3]>]) -> (DVec3, f64) {
    let points = || frames.iter().flatten().map(|p| DVec3::from(p.map(f64::from)));
    let (lo, hi) = points()
        .fold((DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)), |(lo, hi), p| {
            (lo.min(p), hi.max(p))
        });
    let center = 0.5 * (lo + hi);
    (center, points().map(|p| p.distance(center)).fold(0.0, f64::max))
}

fn place_cameras(o: &SynthOptions, center: DVec3, radius: f64) -> Result<Vec<Camera>, SynthError> {
    if radius.is_nan() || radius <= 0.0 {
        return Err(SynthError::Subject("the subject has no extent".into()));
    }
    let distance = 3.0 * radius;
    let half_angle = (radius / distance).asin();
    // The subject fills 90 % of the shorter side.
    let (width, height) = (o.width as f64, o.height as f64);
    let focal = 0.5 * width.min(height) * 0.9 / half_angle.tan();
    let offset = SplitMix64::new(o.seed ^ 0x6361_6d65_7261).next_f64() * std::f64::consts::TAU;
    (0..o.views)
        .map(|k| {
            let azimuth = offset + std::f64::consts::TAU * k as f64 / o.views as f64;
            // Golden-ratio steps spread elevations evenly over [−10°, 35°] for any count.
            let elevation = (-10.0 + 45.0 * (k as f64 * 0.618_033_988_75).fract()).to_radians();
            let dir = DVec3::new(
                elevation.cos() * azimuth.sin(),
                elevation.sin(),
                elevation.cos() * azimuth.cos(),
            );
            Camera::look_at(
                o.width,
                o.height,
                focal,
                focal,
                0.5 * width,
                0.5 * height,
                center + distance * dir,
                center,
                DVec3::Y,
            )
            .map_err(|source| SynthError::Camera { camera: k, source })
        })
        .collect()
}

/// Tracked points on the frame-0 mesh: distinct random vertices (as a corner of one of their
/// faces) first, then area-uniform random surface points.
fn track_points(subject: &Subject, o: &SynthOptions) -> Result<Vec<(u32, [f64; 3])>, SynthError> {
    let mut corner_of = vec![None; subject.rest.len()];
    for (f, face) in subject.faces.iter().enumerate() {
        for (k, &v) in face.iter().enumerate() {
            corner_of[v as usize].get_or_insert((f as u32, k));
        }
    }
    let mut used: Vec<usize> =
        (0..subject.rest.len()).filter(|&v| corner_of[v].is_some()).collect();
    let mut rng = SplitMix64::new(o.seed);
    let n = o.track_vertices.min(used.len());
    for i in 0..n {
        let j = i + (rng.next_u64() % (used.len() - i) as u64) as usize;
        used.swap(i, j);
    }
    let mut points: Vec<(u32, [f64; 3])> = used[..n]
        .iter()
        .filter_map(|&v| corner_of[v])
        .map(|(f, k)| {
            let mut b = [0.0; 3];
            b[k] = 1.0;
            (f, b)
        })
        .collect();
    if o.track_surface > 0 {
        let frame0 = subject.positions(0);
        points.extend(
            sample_surface(&frame0, &subject.faces, o.track_surface, o.seed ^ 0x74_7261_636b)?
                .into_iter()
                .map(|s| (s.face, s.bary)),
        );
    }
    Ok(points)
}

fn write_tracks(
    out: &Path,
    subject: &Subject,
    frames: &[Vec<[f32; 3]>],
    tracks: &[(u32, [f64; 3])],
) -> Result<(), SynthError> {
    let io = |path: PathBuf| move |source| SynthError::Io { path, source };
    let path = out.join("bindings.csv");
    crate::io::write_atomically(&path, |w| {
        use std::io::Write;
        writeln!(w, "id,face,b0,b1,b2")?;
        for (id, (f, b)) in tracks.iter().enumerate() {
            writeln!(w, "{id},{f},{},{},{}", b[0], b[1], b[2])?;
        }
        Ok(())
    })
    .map_err(io(path))?;
    let mut rows = Vec::with_capacity(tracks.len() * frames.len());
    for (t, positions) in frames.iter().enumerate() {
        for (id, (f, b)) in tracks.iter().enumerate() {
            let face = subject.faces[*f as usize];
            let position = std::array::from_fn(|d| {
                (0..3).map(|k| b[k] * positions[face[k] as usize][d] as f64).sum()
            });
            rows.push(TrackPoint { id: id.to_string(), frame: t as u32, position });
        }
    }
    let path = out.join("trajectories.csv");
    crate::io::write_atomically(&path, |w| write_trajectories_csv(w, &rows)).map_err(io(path))?;
    // The frame-0 positions as the tracker's query file, so `tagsplat track --points` follows
    // the very same points.
    let path = out.join("points.csv");
    crate::io::write_atomically(&path, |w| {
        use std::io::Write;
        writeln!(w, "id,x,y,z")?;
        for p in rows.iter().take(tracks.len()) {
            writeln!(w, "{},{},{},{}", p.id, p.position[0], p.position[1], p.position[2])?;
        }
        Ok(())
    })
    .map_err(io(path))
}

/// Renders and writes every (frame, camera) image and mask, cameras split across threads.
fn render_all(
    o: &SynthOptions,
    out: &Path,
    subject: &Subject,
    frames: &[Vec<[f32; 3]>],
    cameras: &[Camera],
    names: &[String],
    texture: &Texture,
) -> Result<(), SynthError> {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get()).min(cameras.len());
    std::thread::scope(|scope| {
        let workers: Vec<_> = (0..threads)
            .map(|w| {
                scope.spawn(move || -> Result<(), SynthError> {
                    for c in (w..cameras.len()).step_by(threads) {
                        for (t, positions) in frames.iter().enumerate() {
                            let r = render(
                                &cameras[c],
                                positions,
                                &subject.rest,
                                &subject.faces,
                                texture,
                                o.samples,
                            )
                            .map_err(|source| SynthError::Render { frame: t, camera: c, source })?;
                            write_png(
                                &own::image_path(out, &names[c], t),
                                &Image {
                                    width: r.width,
                                    height: r.height,
                                    channels: 3,
                                    data: r.rgb,
                                },
                            )?;
                            write_png(
                                &own::mask_path(out, &names[c], t),
                                &Image {
                                    width: r.width,
                                    height: r.height,
                                    channels: 1,
                                    data: r.alpha,
                                },
                            )?;
                        }
                    }
                    Ok(())
                })
            })
            .collect();
        workers
            .into_iter()
            .try_for_each(|h| h.join().unwrap_or_else(|p| std::panic::resume_unwind(p)))
    })
}
