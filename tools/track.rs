//! `tagsplat track`, `tagsplat convert` and `tagsplat bench track`: parse, call the library, print.

use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use std::path::{Path, PathBuf};
use tagsplat::camera::Camera;
use tagsplat::dataset::Dataset;
use tagsplat::io::image::write_png;
use tagsplat::sequence::orient::{Orientation, SignedAxis, UpAxis};
use tagsplat::sequence::source::CLOCKLESS_FPS;
use tagsplat::sequence::usd::{write_usda, UsdTracks};
use tagsplat::sequence::{FrameFormat, MeshSequence, ReadOptions, SequenceInfo};
use tagsplat::track::bench::{bench_track, TrackBenchReport};
use tagsplat::track::bindings::{read_bindings, write_bindings_csv};
use tagsplat::track::output::{
    write_image_tracks_csv, write_pinned_tracks_csv, write_report_json, write_unbound_csv,
};
use tagsplat::track::overlay::{draw_marks, mark_colour, mark_radius, rgb_of, Mark};
use tagsplat::track::pins::write_pins_glb;
use tagsplat::track::plot::write_plot;
use tagsplat::track::queries::{read_pixels, read_points};
use tagsplat::track::{
    project_tracks, track_sequence, ImagePoint, Queries, RunError, Targets, TrackReport,
};

#[derive(Args)]
pub struct TrackArgs {
    /// The sequence (any form `tagsplat convert` reads).
    #[arg(long)]
    sequence: PathBuf,
    #[command(flatten)]
    read: ReadArgs,
    /// Frame-0 points to track: CSV with header `id,x,y,z`.
    #[arg(
        long,
        required_unless_present_any = ["pixels", "bindings"],
        conflicts_with_all = ["pixels", "bindings"]
    )]
    points: Option<PathBuf>,
    /// Points bound already, instead of --points or --pixels: CSV `id,face,u,v,w` (barycentric
    /// on a triangle of the sequence) or `id,vertex`, as --bindings-out writes them (one
    /// binding serves every sequence of the same mesh).
    #[arg(long, conflicts_with = "pixels")]
    bindings: Option<PathBuf>,
    /// Also write the bindings used: CSV `id,face,u,v,w,polygon` (polygon: the file's face the
    /// triangle was fanned from), which --bindings reads.
    #[arg(long)]
    bindings_out: Option<PathBuf>,
    /// Pixels to track: CSV with header `id,u,v` (pixel (i, j) is centred at (i+0.5, j+0.5)),
    /// ray-cast onto frame 0 through --camera.
    #[arg(long, requires = "camera")]
    pixels: Option<PathBuf>,
    /// A camera: a cam.json file (width, height, fx, fy, cx, cy, world_to_camera) or, with
    /// --data, the name of one of that dataset's cameras (e.g. c01). The one --pixels are in,
    /// and the one every point is projected into, per frame, with its visibility (OUT's
    /// `.2d.csv`: id, frame, u, v, visible).
    #[arg(long)]
    camera: Option<PathBuf>,
    /// The dataset whose camera --camera names (in its own pixel-centre convention, see
    /// `tagsplat dataset info`).
    #[arg(long, requires = "camera")]
    data: Option<PathBuf>,
    /// With --data and --camera: a folder of PNGs, one per frame (000000.png, ...), each that
    /// camera's image of the frame with every tracked point drawn in its plot colour, a disk
    /// where the camera sees it and a ring where the frame's surface hides it.
    #[arg(long, requires = "data")]
    overlay: Option<PathBuf>,
    /// Trajectories out: CSV `id,frame,x,y,z,nx,ny,nz,tx,ty,tz,time,fps,start_frame`: per point
    /// per frame its position, the bound triangle's normal and tangent (its first edge), the
    /// time in seconds, the frame rate and the scene frame of frame 0.
    #[arg(long)]
    out: PathBuf,
    /// Also write a JSON report: the clock (fps, start_frame, times), bindings (face,
    /// barycentric, distance, polygon), trajectories, normals and tangents.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Also write the tracks as a GLB of animated empty nodes, one per point named by its id,
    /// translated and rotated by its position and orientation frame at every frame's time
    /// (+Y up: turned from --from-up, else the file's up, else --up).
    #[arg(long)]
    glb: Option<PathBuf>,
    /// Also write the sequence with the tracked points as USD (time-sampled mesh and points).
    #[arg(long)]
    usd: Option<PathBuf>,
    /// Up axis of the --usd file.
    #[command(flatten)]
    up: UpArgs,
    /// Also plot the trajectories as SVG (left: projected on the two axes of largest spread;
    /// right: distance from the frame-0 position against the frame; ids in the legend).
    #[arg(long)]
    plot: Option<PathBuf>,
    /// Largest distance from a point to the frame-0 surface, as a fraction of the frame-0
    /// bounding-box diagonal. Farther points are not bound.
    #[arg(long, default_value_t = 0.01)]
    max_distance: f64,
    /// Fail when any point cannot be bound. Without it the others are tracked and the unbound
    /// ones listed on stderr and in OUT's `.unbound.csv` (id, distance, tolerance, reason).
    #[arg(long)]
    strict: bool,
}

pub fn track(args: TrackArgs) -> Result<()> {
    let (sequence, info) = args.read.read(&args.sequence)?;
    // The outputs' folders are made, as `train` makes OUT.
    let outputs = [&args.json, &args.usd, &args.plot, &args.glb, &args.bindings_out];
    for path in std::iter::once(Some(&args.out)).chain(outputs.map(Option::as_ref)) {
        if let Some(folder) = path.and_then(|p| p.parent()).filter(|f| !f.as_os_str().is_empty()) {
            std::fs::create_dir_all(folder)
                .with_context(|| format!("cannot create the folder {}", folder.display()))?;
        }
    }
    let footage = match (&args.camera, &args.data) {
        (Some(name), Some(data)) => Some(dataset_camera(data, &name.to_string_lossy())?),
        _ => None,
    };
    let camera = match (&args.camera, &footage) {
        (_, Some((dataset, index))) => Some(dataset.cameras[*index]),
        (Some(file), None) => Some(Camera::load_json(file)?),
        (None, None) => None,
    };
    let targets = match (&args.bindings, &args.points, &args.pixels, &camera) {
        (Some(bindings), ..) => Targets::File(read_bindings(bindings)?),
        (None, Some(points), _, _) => Targets::Queries(Queries::Points(read_points(points)?)),
        (None, None, Some(pixels), Some(camera)) => {
            Targets::Queries(Queries::Pixels { camera: *camera, pixels: read_pixels(pixels)? })
        }
        _ => bail!("give --points, --bindings, or --pixels with --camera"),
    };
    let tracked =
        track_sequence(&sequence.faces, &sequence.frames, &info, &targets, args.max_distance)
            .map_err(|e| on_sequence(e, &args.sequence))?;
    let (report, clock) = (&tracked.report, &tracked.clock);
    if report.unbound.is_empty() {
        // A list from an earlier run would describe points that are now tracked.
        let _ = std::fs::remove_file(unbound_path(&args.out));
    } else {
        report_unbound(&args, &targets, report)?;
    }
    write_pinned_tracks_csv(&args.out, &report.points, clock)?;
    if let Some(json) = &args.json {
        write_report_json(json, report, clock)?;
    }
    if let Some(glb) = &args.glb {
        let orientation = tracked.pins_orientation(args.up.from_up, args.up.up.into());
        write_pins_glb(glb, &report.points, clock, orientation)?;
    }
    if let Some(path) = &args.bindings_out {
        write_bindings_csv(path, &report.points)?;
    }
    if let Some(camera) = &camera {
        let seen = project_tracks(&sequence.faces, &sequence.frames, &report.points, camera)?;
        write_image_tracks_csv(&args.out.with_extension("2d.csv"), &seen)?;
        if let (Some(folder), Some((dataset, index))) = (&args.overlay, &footage) {
            write_overlays(folder, dataset, *index, &seen, report.points.len())?;
        }
    }
    if let Some(usd) = &args.usd {
        let ids: Vec<String> = report.points.iter().map(|p| p.id.clone()).collect();
        let trajectories: Vec<_> = report.points.iter().map(|p| p.trajectory.clone()).collect();
        let tracks = UsdTracks { ids: &ids, trajectories: &trajectories };
        write_usda(usd, &sequence, clock.fps, args.up.orientation(info.up), Some(&tracks))?;
    }
    if let Some(plot) = &args.plot {
        let paths: Vec<Vec<glam::DVec3>> = report
            .points
            .iter()
            .map(|p| p.trajectory.iter().map(|&x| glam::DVec3::from(x)).collect())
            .collect();
        let ids: Vec<String> = report.points.iter().map(|p| p.id.clone()).collect();
        write_plot(plot, &ids, &paths)?;
    }
    println!(
        "tracked {} of {} points through {} frames ({} vertices, {} faces) -> {}",
        report.points.len(),
        report.points.len() + report.unbound.len(),
        report.frames,
        report.vertices,
        report.faces,
        args.out.display()
    );
    Ok(())
}

/// A failed run on `--sequence`, in the words of the step that failed.
fn on_sequence(error: RunError, sequence: &Path) -> anyhow::Error {
    let (step, cause) = match error {
        RunError::Bindings(cause) => ("cannot use the bindings on", cause),
        RunError::Track(cause) => ("cannot track on", cause),
    };
    anyhow::Error::new(cause).context(format!("{step} {}", sequence.display()))
}

/// Lists the points that were not bound on stderr and beside `--out`, or fails with `--strict`.
fn report_unbound(args: &TrackArgs, targets: &Targets, report: &TrackReport) -> Result<()> {
    let level = if args.strict { "error" } else { "warning" };
    for u in &report.unbound {
        eprintln!("{level}: point {} not bound: {}", u.id, u.reason);
    }
    let total = report.unbound.len() + report.points.len();
    if args.strict {
        let hint = match targets {
            Targets::Queries(Queries::Points(_)) => format!(
                " (farther than --max-distance {} x the frame-0 extent = {})",
                args.max_distance, report.max_distance
            ),
            _ => String::new(),
        };
        bail!(
            "{} of {total} points not bound{hint}; --strict refuses the run",
            report.unbound.len()
        );
    }
    let listed = unbound_path(&args.out);
    write_unbound_csv(&listed, report)?;
    eprintln!(
        "{} of {total} points not bound (tolerance {} scene units), listed in {}",
        report.unbound.len(),
        report.max_distance,
        listed.display()
    );
    Ok(())
}

/// The dataset at `data` and the index of its camera called `name`; the error lists the names
/// it has.
fn dataset_camera(data: &Path, name: &str) -> Result<(Dataset, usize)> {
    let dataset = Dataset::load(data)
        .with_context(|| format!("cannot load the dataset {} for --camera", data.display()))?;
    match dataset.camera_names.iter().position(|n| n == name) {
        Some(i) => Ok((dataset, i)),
        None => bail!(
            "{}: no camera named '{name}'; it has {}",
            data.display(),
            dataset.camera_names.join(", ")
        ),
    }
}

/// `folder/NNNNNN.png` for every frame of `seen` (frame-major, `points` per frame): camera
/// `camera`'s image of the frame with the points drawn (`tagsplat::track::overlay`). Frames
/// where the dataset has no image from that camera are named on stderr.
fn write_overlays(
    folder: &Path,
    dataset: &Dataset,
    camera: usize,
    seen: &[ImagePoint],
    points: usize,
) -> Result<()> {
    std::fs::create_dir_all(folder)
        .with_context(|| format!("cannot create the folder {}", folder.display()))?;
    let mut missing = Vec::new();
    for (t, frame) in seen.chunks(points.max(1)).enumerate() {
        let views = dataset.frames.get(t).map_or(&[][..], |f| &f.views);
        let Some(view) = views.iter().position(|v| v.camera == camera) else {
            missing.push(t);
            continue;
        };
        let mut image = rgb_of(&*dataset.image(t, view)?);
        let marks: Vec<Mark> = frame
            .iter()
            .enumerate()
            .map(|(i, p)| Mark { u: p.u, v: p.v, visible: p.visible, rgb: mark_colour(i) })
            .collect();
        let radius = mark_radius(image.width, image.height);
        draw_marks(&mut image, &marks, radius);
        write_png(&folder.join(format!("{t:06}.png")), &image)?;
    }
    if !missing.is_empty() {
        let name = &dataset.camera_names[camera];
        eprintln!("warning: no overlay for frames {missing:?}: the dataset has no image from {name} there");
    }
    Ok(())
}

/// `tracks.csv` → `tracks.unbound.csv`.
fn unbound_path(out: &Path) -> PathBuf {
    out.with_extension("unbound.csv")
}

#[derive(Clone, Copy, ValueEnum)]
pub enum FrameFormatArg {
    Ply,
    Obj,
}

#[derive(Args)]
pub struct ConvertArgs {
    /// The sequence to read: a folder of .ply/.obj frames, or a .pc2 (with its .obj), .mdd
    /// (with its .obj), .gltf, .glb, .usda, .usdc, .usd, .usdz, .abc or .fbx file.
    #[arg(long)]
    sequence: PathBuf,
    #[command(flatten)]
    read: ReadArgs,
    /// Where to write: FILE.pc2 or FILE.mdd (plus FILE.obj), FILE.glb, FILE.usda, or a folder
    /// (created; must hold no frame files yet).
    #[arg(long)]
    to: PathBuf,
    /// Frame file format when writing a folder.
    #[arg(long, value_enum, default_value = "ply")]
    frame_format: FrameFormatArg,
    #[command(flatten)]
    up: UpArgs,
}

/// What to read from a sequence file that holds more than one thing.
#[derive(Args)]
pub struct ReadArgs {
    /// glTF or FBX: the animation (take) to play, by name or index. A file with several needs
    /// one; the error lists them.
    #[arg(long)]
    animation: Option<String>,
    /// Frames per second: the rate a glTF or FBX animation is sampled at (default its key rate,
    /// else 30), or the clock of a folder or PC2 (default 24). Files with their own time samples
    /// (USD, Alembic, MDD) keep them.
    #[arg(long)]
    fps: Option<f64>,
    /// The mesh to read from a file that holds several: a USD prim path, an Alembic object
    /// path, a glTF or FBX node name. The error for a file with several lists them.
    #[arg(long, alias = "prim")]
    mesh: Option<String>,
}

impl ReadArgs {
    /// Reads `path` with these options, and says on stderr what the reader chose or noticed.
    fn read(&self, path: &Path) -> Result<(MeshSequence, SequenceInfo)> {
        let options = ReadOptions {
            animation: self.animation.clone(),
            fps: self.fps,
            mesh: self.mesh.clone(),
        };
        let (sequence, info) =
            MeshSequence::read_with(path, &options).context("cannot read the sequence")?;
        for note in &info.notes {
            eprintln!("{}: {note}", path.display());
        }
        if let Some(meters) = info.meters_per_unit.filter(|&m| m != 1.0) {
            eprintln!(
                "{}: one unit is {meters} m (positions are kept in file units)",
                path.display()
            );
        }
        Ok((sequence, info))
    }
}

/// The up axis of a written sequence, and the input's, turned onto it.
#[derive(Args)]
pub struct UpArgs {
    /// The written file's up axis (a .usda also declares it).
    #[arg(long, value_enum, default_value = "y")]
    up: UpArg,
    /// The input's up (+x, -x, +y, -y, +z or -z), turned onto --up by quarter turns. Default:
    /// the up axis the file declares (USD, FBX, glTF), else --up itself, so positions are
    /// written as read.
    #[arg(long, value_parser = parse_signed_axis, allow_hyphen_values = true)]
    from_up: Option<SignedAxis>,
}

impl UpArgs {
    /// The turn onto --up from --from-up, else from the file's own up (`file_up`), else none.
    fn orientation(&self, file_up: Option<SignedAxis>) -> Orientation {
        let up = UpAxis::from(self.up);
        self.from_up
            .or(file_up)
            .map_or(Orientation::keep(up), |source| Orientation::new(source, up))
    }
}

fn parse_signed_axis(text: &str) -> Result<SignedAxis, String> {
    SignedAxis::parse(text).ok_or_else(|| format!("'{text}' is not one of +x, -x, +y, -y, +z, -z"))
}

#[derive(Clone, Copy, ValueEnum)]
pub enum UpArg {
    Y,
    Z,
}

impl From<UpArg> for UpAxis {
    fn from(up: UpArg) -> Self {
        match up {
            UpArg::Y => UpAxis::Y,
            UpArg::Z => UpAxis::Z,
        }
    }
}

pub fn convert(args: ConvertArgs) -> Result<()> {
    let (sequence, info) = args.read.read(&args.sequence)?;
    let format = match args.frame_format {
        FrameFormatArg::Ply => FrameFormat::Ply,
        FrameFormatArg::Obj => FrameFormat::Obj,
    };
    let orientation = args.up.orientation(info.up);
    sequence
        .export(&args.to, format, info.fps.unwrap_or(CLOCKLESS_FPS), orientation)
        .context("cannot write the sequence")?;
    println!(
        "{} frames, {} vertices, {} faces -> {}",
        sequence.frames.len(),
        sequence.frames[0].len(),
        sequence.faces.len(),
        args.to.display()
    );
    Ok(())
}

#[derive(Args)]
pub struct BenchTrackArgs {
    /// Sphere subdivision level (7: 131 072 triangles).
    #[arg(long, default_value_t = 7, value_parser = clap::value_parser!(u32).range(0..=9))]
    level: u32,
    /// Random queries per kind (closest point, ray); brute force answers 1 % of them (at most 200).
    #[arg(long, default_value_t = 100_000, value_parser = clap::value_parser!(u64).range(1..=10_000_000))]
    queries: u64,
    /// BVH builds; the fastest is reported.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u64).range(1..=100))]
    repetitions: u64,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    json: bool,
}

pub fn bench(args: BenchTrackArgs) -> Result<()> {
    let r = bench_track(args.level, args.queries as usize, args.repetitions as usize)?;
    if args.json {
        crate::figures::print_result(&r, None)?;
    } else {
        print_bench(&r);
    }
    if !r.verified {
        bail!("BVH answers differ from brute force");
    }
    Ok(())
}

fn print_bench(r: &TrackBenchReport) {
    let speedup = |a: f64, b: f64| a / b;
    println!("mesh              {} triangles, {} vertices (unit sphere)", r.triangles, r.vertices);
    println!("BVH build         {:.2} ms (fastest of the builds, one thread)", r.build_ms);
    println!(
        "closest point     {:.0} queries/s BVH, {:.0} queries/s brute force ({:.0}x)",
        r.queries_per_s,
        r.brute_force_queries_per_s,
        speedup(r.queries_per_s, r.brute_force_queries_per_s)
    );
    println!(
        "ray cast          {:.0} rays/s BVH, {:.0} rays/s brute force ({:.0}x)",
        r.rays_per_s,
        r.brute_force_rays_per_s,
        speedup(r.rays_per_s, r.brute_force_rays_per_s)
    );
    println!(
        "checked           {} of {} queries of each kind against brute force: {}",
        r.brute_force_queries,
        r.queries,
        if r.verified { "equal" } else { "DIFFERENT" }
    );
}
