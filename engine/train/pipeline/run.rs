//! The whole reconstruction: the initial mesh (given or built from the masks), the canonical
//! frame, then every later frame from its predecessor; each frame written as it finishes, so
//! running the same job again resumes after the last complete frame.

use super::camera_colour::{read_maps, write_maps, CameraMaps, ColourUse};
use super::config::{CaptureStep, TrainConfig};
use super::correspondences::{SeenPose, VertexTracks};
use super::frame::{optimize_frame, FrameReport, FrameTask, MatchSources};
use super::html_report::write_html_report;
use super::run_log::RunLog;
use crate::camera::mean_up;
use crate::dataset::{Dataset, LoadOptions, PixelCenters};
use crate::gpu::GpuContext;
use crate::init::{init_mesh, InitOptions};
use crate::io::host::{peak_resident_bytes, total_memory_bytes};
use crate::io::lock::OutputLock;
use crate::io::write_json_atomically;
use crate::mesh::TriMesh;
use crate::sequence::orient::{SignedAxis, UpAxis};
use crate::splat::GaussianScene;
use crate::topology::{gaussians_from_mesh, import, InitConfig, ManifoldMesh, TopologyError};
use crate::train::memory::{mib, refusal, CaptureMemory};
use crate::train::output::{dc_vertex_colors, SequenceOutput};
use crate::train::temporal::extrapolate;
use crate::train::{load_targets, load_targets_counted, TrainError, ViewTarget};
use std::ops::{ControlFlow, Range};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

/// A reconstruction run (`tagsplat train`); see [`run_train`].
pub struct TrainJob {
    /// The dataset folder.
    pub data: PathBuf,
    /// The output folder (see [`SequenceOutput`]); a run into one with complete frames resumes.
    pub out: PathBuf,
    /// The frame-0 mesh (PLY or OBJ); without one it is built from the masks.
    pub mesh: Option<PathBuf>,
    /// The pipeline configuration.
    pub config: TrainConfig,
    /// Frames to produce (default: all). Frames before the range must be complete already.
    pub frames: Option<Range<usize>>,
    /// The exports' up axis; None follows the capture ([`Orientation::for_export`]).
    ///
    /// [`Orientation::for_export`]: crate::sequence::orient::Orientation::for_export
    pub up: Option<UpAxis>,
    /// What the dataset's files leave open (the intrinsics' pixel centres).
    pub load: LoadOptions,
    /// The exports' frame rate; None takes the layout's ([`Dataset::fps`]), or 30 without one.
    pub fps: Option<f64>,
}

impl TrainJob {
    /// A job over every frame of `data` into `out`: the frame-0 mesh built from the masks,
    /// exports oriented after the capture, the layout's own pixel-centre convention.
    pub fn new(data: impl Into<PathBuf>, out: impl Into<PathBuf>, config: TrainConfig) -> Self {
        let (data, out) = (data.into(), out.into());
        TrainJob {
            data,
            out,
            mesh: None,
            config,
            frames: None,
            up: None,
            load: LoadOptions::default(),
            fps: None,
        }
    }
}

/// Where the run is, for a progress display.
#[derive(Clone, Copy, Debug)]
pub struct TrainProgress {
    /// What `iteration` and `iterations` count.
    pub stage: Stage,
    /// The frame being optimised (the run's first frame while the plates are built).
    pub frame: usize,
    /// One past the last frame of the run.
    pub frames_end: usize,
    /// The frame's last finished iteration, 1-based (the graph stage reports none), or the
    /// cameras whose plate is built.
    pub iteration: u32,
    /// The frame's iteration cap (a later frame may stop before it), or the training cameras.
    pub iterations: u32,
    /// The frame's mean loss over its last statistics interval (`report.stats_every`
    /// iterations); None before the first interval ends and outside `Stage::Frame`.
    pub loss: Option<f64>,
    /// Seconds since [`run_train`] started.
    pub elapsed_s: f64,
}

impl TrainProgress {
    /// `iteration` of `iterations` of `stage` on `frame`, without a loss; [`run_train`] fills in
    /// the time when it passes the report on.
    fn at(
        stage: Stage,
        frame: usize,
        frames_end: usize,
        (iteration, iterations): (u32, u32),
    ) -> Self {
        Self { stage, frame, frames_end, iteration, iterations, loss: None, elapsed_s: 0.0 }
    }
}

/// What a run's progress callback sees and answers: `Break` cancels the run
/// ([`TrainError::Cancelled`]) at its next report.
type Progress<'a> = &'a mut dyn FnMut(TrainProgress) -> ControlFlow<()>;

/// The stage a [`TrainProgress`] counts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// The training cameras' background plates, before frame 0, where the masks are refined
    /// from the images (each camera's frames are decoded: minutes on a large capture).
    Plates,
    /// A frame's views being decoded (`iteration` of `iterations` views, held-out ones too).
    Views,
    /// A frame's optimisation.
    Frame,
}

/// What a run reports (`OUT/report.json`, rewritten after every frame).
#[derive(Clone, Debug, serde::Serialize)]
pub struct TrainReport {
    /// The GPU's name.
    pub device: String,
    /// The dataset folder.
    pub data: PathBuf,
    /// This run's wall time so far, seconds.
    pub total_wall_s: f64,
    /// What the PSNR/SSIM figures are measured on: "held-out" views or "training" views.
    pub eval_views: &'static str,
    /// Frames already complete on disk when this run started.
    pub resumed_frames: Vec<usize>,
    /// Every frame of the run so far, those finished by earlier runs (from their report) too.
    pub frames: Vec<FrameReport>,
    /// Mesh vertices.
    pub vertices: usize,
    /// Live mesh faces (the topology after frame 0's densification and pruning).
    pub faces: usize,
    /// The files written: per-frame folders and the sequence exports.
    pub outputs: Vec<PathBuf>,
    /// Which frames the exports hold, at what frame rate and from where it came, or why there
    /// are none.
    pub export: String,
    /// The exports' up axes and how the capture was turned onto them (the capture's up is the
    /// signed axis nearest the cameras' mean up vector).
    pub up_axis: String,
    /// Where the dataset's intrinsics were read to put pixel centres.
    pub pixel_centers: PixelCenters,
    /// The factor the views were scaled by (`LoadOptions::scale`), None at the files' size.
    pub scale: Option<f64>,
    /// The colour behind the renders and the targets they are scored against (the config's).
    pub background: [f32; 3],
    /// Where the time before frame 0's first iteration went.
    pub startup: Startup,
    /// The most memory the process has held so far, bytes (None where the system does not
    /// say).
    pub peak_host_bytes: Option<u64>,
    /// The most device memory the GPU context's buffers have held at once, bytes.
    pub peak_device_bytes: u64,
    /// What the run was estimated to need before it started.
    pub memory_estimate: CaptureMemory,
}

/// Where a run's time went before frame 0's first iteration, seconds from the run's start.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct Startup {
    /// Reading the dataset's metadata.
    pub dataset_s: f64,
    /// Building the frame-0 mesh from the masks, their decoding included (0 with a given mesh
    /// or a frame 0 already on disk).
    pub mesh_s: f64,
    /// Decoding frame 0's training and evaluation views.
    pub views_s: f64,
    /// From the run's start to the end of frame 0's first iteration (None when frame 0 was on
    /// disk already).
    pub first_iteration_s: Option<f64>,
}

/// Runs (or resumes) `job`; `OUT/report.json` is rewritten after every frame, `OUT/report.html`
/// written at the end, and `OUT/run.log` gains what the run did (its end or its error included).
/// `progress` sees every iteration; [`run_train_with`] lets it cancel.
pub fn run_train(
    ctx: &Arc<GpuContext>,
    job: &TrainJob,
    progress: &mut dyn FnMut(TrainProgress),
) -> Result<TrainReport, TrainError> {
    run_train_with(ctx, job, &mut |p| {
        progress(*p);
        ControlFlow::Continue(())
    })
}

/// [`run_train`] whose `progress` may cancel the run by answering `Break`. The run then ends at
/// its next report (the next iteration, decoded frame or built plate) with
/// [`TrainError::Cancelled`], leaving what a killed run leaves: the frames finished before,
/// which the next run on the same output resumes after. While it runs it holds `OUT`'s lock
/// (`OUT/.lock`): a second run into the same folder, from this process or another, is refused
/// with [`TrainError::OutputInUse`].
pub fn run_train_with(
    ctx: &Arc<GpuContext>,
    job: &TrainJob,
    progress: &mut dyn FnMut(&TrainProgress) -> ControlFlow<()>,
) -> Result<TrainReport, TrainError> {
    let _lock = OutputLock::take(&job.out)?;
    let log = RunLog::open(&job.out)?;
    log.line(&start_line(ctx, job))?;
    let started = Instant::now();
    let mut timed = |mut p: TrainProgress| {
        p.elapsed_s = started.elapsed().as_secs_f64();
        progress(&p)
    };
    match run_logged(ctx, job, &mut timed, &log) {
        Ok(report) => {
            let frames = report.frames.len();
            log.line(&format!("run finished: {frames} frames, {:.1} s", report.total_wall_s))?;
            Ok(report)
        }
        Err(error) => {
            // The run's own error matters more than a log line that cannot be written.
            let _ = log.line(&format!("run failed: {error}"));
            Err(error)
        }
    }
}

/// Refines the training masks from the images when `when` says so (`auto`: the images of
/// `frame` carry a background) and logs it; `done(cameras done, cameras)` after each plate.
fn refine_masks(
    dataset: &mut Dataset,
    when: CaptureStep,
    frame: usize,
    log: &RunLog,
    done: &mut dyn FnMut(usize, usize),
) -> Result<(), TrainError> {
    if let Some(refined) = dataset.refine_masks_when(when, frame, done)? {
        let cameras = dataset.train.len();
        log.line(&format!(
            "masks refined along their outline against a background plate: {refined} of {cameras} training cameras"
        ))?;
    }
    Ok(())
}

fn run_logged(
    ctx: &Arc<GpuContext>,
    job: &TrainJob,
    progress: Progress,
    log: &RunLog,
) -> Result<TrainReport, TrainError> {
    job.config.check()?;
    let started = Instant::now();
    let mut dataset = Dataset::load_with(&job.data, &job.load)?;
    let (host_shared, scale) = (ctx.info().shares_host_memory(), job.load.scale.unwrap_or(1.0));
    let memory = CaptureMemory::of_dataset(&dataset, ctx.limits(), host_shared, scale);
    let at = |s| CaptureMemory::of_dataset(&dataset, ctx.limits(), host_shared, s);
    if let Some(problem) = refusal(at, scale, ctx.limits(), total_memory_bytes()) {
        return Err(TrainError::TooLarge { data: job.data.clone(), problem });
    }
    log.line(&format!(
        "memory (an upper estimate): up to {} on the device, {} on the host",
        mib(memory.device_bytes),
        mib(memory.host_bytes)
    ))?;
    if let Some(streaming) = memory.streaming() {
        log.line(&format!("device memory: {streaming}"))?;
    }
    let frames = job.frames.clone().unwrap_or(0..dataset.frames.len());
    if frames.is_empty() || frames.end > dataset.frames.len() {
        let (data, available) = (job.data.clone(), dataset.frames.len());
        return Err(TrainError::FrameRange { frames, data, available });
    }
    let mut cancelled = false;
    let mut plates = |done: usize, cameras: usize| {
        let counts = (done as u32, cameras as u32);
        let report = TrainProgress::at(Stage::Plates, frames.start, frames.end, counts);
        cancelled |= progress(report).is_break();
    };
    refine_masks(&mut dataset, job.config.refine_masks, frames.start, log, &mut plates)?;
    if cancelled {
        return Err(TrainError::Cancelled);
    }
    let learn_colour = job.config.camera_colour.learn.applies(&dataset, frames.start)?;
    let out = SequenceOutput::create(&job.out)?;
    // A range that starts later continues frames already on disk.
    if let Some(missing) = [0, frames.start.saturating_sub(1)]
        .into_iter()
        .find(|&t| t < frames.start && !out.is_complete(t))
    {
        let out = job.out.clone();
        return Err(TrainError::MissingFrame { frame: frames.start, needs: missing, out });
    }
    let mut report = TrainReport {
        device: ctx.info().name.clone(),
        data: job.data.clone(),
        total_wall_s: 0.0,
        eval_views: if dataset.test.is_empty() { "training" } else { "held-out" },
        resumed_frames: (0..frames.end).filter(|&t| out.is_complete(t)).collect(),
        frames: Vec::new(),
        vertices: 0,
        faces: 0,
        outputs: vec![job.out.join("meshes"), job.out.join("gaussians")],
        up_axis: String::new(),
        export: String::new(),
        pixel_centers: dataset.pixel_centers,
        scale: job.load.scale,
        background: job.config.background,
        startup: Startup { dataset_s: started.elapsed().as_secs_f64(), ..Default::default() },
        peak_host_bytes: None,
        peak_device_bytes: 0,
        memory_estimate: memory,
    };
    let source = capture_up(&dataset, &mut report.up_axis);
    report.frames = earlier_frame_reports(&job.out, &report.resumed_frames);
    if !report.resumed_frames.is_empty() {
        log.line(&format!("resuming: frames {:?} are complete on disk", report.resumed_frames))?;
    }
    let colour = if learn_colour { ColourUse::Learn } else { ColourUse::Off };
    let (mut mesh, mut previous) = canonical_start(
        ctx,
        (&dataset, job, colour),
        (&out, log),
        (&mut report, started),
        progress,
    )?;
    let maps = frame0_maps(&out, learn_colour, log)?;
    let colour = if maps.is_empty() { ColourUse::Off } else { ColourUse::Apply(&maps) };
    if let Some(first) =
        report.frames.iter().find(|f| f.frame == 0 && !report.resumed_frames.contains(&0))
    {
        log.line(&frame_lines(first))?;
    }
    let frame0 = previous.clone();
    let temporal = &job.config.temporal;
    // A range that starts after frame 1 continues from the frame before it (checked above).
    let first = 1.max(frames.start);
    let mut tracks = start_tracks(&dataset, &out, (&frame0, &mesh), first, job)?;
    if first > 1 {
        previous = out.read_frame(first - 1)?.1;
    }
    let mut before_previous: Option<GaussianScene> = None;
    for t in first..frames.end {
        if out.is_complete(t) {
            if let Some(tracks) = tracks.as_mut() {
                replay_tracks(tracks, (&dataset, &out), t, &mesh, job)?;
            }
            before_previous = Some(std::mem::replace(&mut previous, out.read_frame(t)?.1));
            continue;
        }
        if before_previous.is_none() && t >= 2 && out.is_complete(t - 2) {
            before_previous = Some(out.read_frame(t - 2)?.1);
        }
        if !out.is_complete(t - 1) {
            let out = job.out.clone();
            return Err(TrainError::MissingFrame { frame: t, needs: t - 1, out });
        }
        let (train, eval) = views(&dataset, t, &job.config, (frames.end, progress))?;
        // Without held-out cameras every training view is scored, those that lost the subject too.
        let eval = eval.unwrap_or_else(|| train.clone());
        let (train, lost_views) = with_subject(train);
        let start = extrapolate(&previous, before_previous.as_ref());
        let previous_views = source_views(&dataset, t - 1, temporal.flow, job)?;
        // The tracks' step is part of the frame's time.
        let tracks_started = Instant::now();
        if let Some(tracks) = tracks.as_mut() {
            tracks.advance(&train, &start.positions, &mesh.live_faces());
        }
        let tracks_s = tracks_started.elapsed().as_secs_f64();
        let (scene, frame_report) = if train.is_empty() {
            let report = FrameReport::without_views(t, start.len(), lost_views);
            mesh.positions = start.positions.clone();
            (start, report)
        } else {
            let task = FrameTask {
                frame: t,
                train: &train,
                eval: &eval,
                start,
                mesh: &mut mesh,
                previous: Some(&previous),
                frame0: Some(&frame0),
                sources: MatchSources { previous: &previous_views, tracks: tracks.as_ref() },
                colour,
            };
            let (scene, report) = optimize_frame(ctx, task, &job.config, &mut |counts, loss| {
                let report = TrainProgress::at(Stage::Frame, t, frames.end, counts);
                progress(TrainProgress { loss, ..report })
            })?;
            (scene, FrameReport { lost_views, wall_s: report.wall_s + tracks_s, ..report })
        };
        write_frame(&out, t, &mesh, &scene)?;
        log.line(&frame_lines(&frame_report))?;
        before_previous = Some(std::mem::replace(&mut previous, scene));
        report.frames.push(frame_report);
        finish_report(ctx, &mut report, &mesh, started, &job.out)?;
    }
    let (frames_done, total) = (complete_prefix(&out, dataset.frames.len()), dataset.frames.len());
    let (fps, rate) = frame_rate(job, &dataset);
    report.export = export_sentence(frames_done, total, fps, &rate);
    if frames_done > 0 {
        let (exported, said) = out.export(0..frames_done, fps, source, job.up)?;
        report.up_axis = format!("{said}; {}", report.up_axis);
        let names: Vec<String> = exported.iter().map(|p| p.display().to_string()).collect();
        log.line(&format!(
            "exported {} ({}): {}",
            report.export,
            report.up_axis,
            names.join(", ")
        ))?;
        report.outputs.extend(exported);
    } else {
        log.line(&format!("not exported: {}", report.export))?;
    }
    finish_report(ctx, &mut report, &mesh, started, &job.out)?;
    let page = write_html_report(ctx, &job.out)?;
    log.line(&format!("report: {}", page.display()))?;
    Ok(report)
}

/// The log's first lines: what runs where, on which frames, with which config.
fn start_line(ctx: &GpuContext, job: &TrainJob) -> String {
    let frames = job.frames.as_ref().map_or("all".into(), |f| format!("{}..{}", f.start, f.end));
    let mesh = job.mesh.as_ref().map_or("built from the masks".into(), |m| m.display().to_string());
    let config: String = job.config.to_toml().lines().map(|l| format!("\nconfig | {l}")).collect();
    let scale = job.load.scale.map_or(String::new(), |s| format!(", views scaled by {s}"));
    format!(
        "tagsplat {} train: data {}, out {}, frames {frames}, frame-0 mesh {mesh}{scale}, device {}{config}",
        env!("CARGO_PKG_VERSION"),
        job.data.display(),
        job.out.display(),
        ctx.info().name,
    )
}

/// A finished frame: what it ran and why it stopped, its scores, and its warnings.
fn frame_lines(f: &FrameReport) -> String {
    let graph = f.graph.as_ref().map_or(String::new(), |g| {
        let levels: Vec<String> = g
            .levels
            .iter()
            .map(|l| {
                format!(
                    "1/{} × {} nodes {} it {:?}",
                    l.factor, l.nodes, l.iterations, l.stop_reason
                )
            })
            .collect();
        format!("graph [{}], ", levels.join("; "))
    });
    let mut text = format!(
        "frame {}: {graph}{} iterations ({:?}){}, {:.1} s, {} Gaussians, PSNR {:.2} dB (Gaussians; {:.2} dB colour-corrected per view, {:.2} dB also through the views' masks) {:.2} dB (mesh)",
        f.frame,
        f.iterations,
        f.stop_reason,
        match f.colour_iterations {
            0 => String::new(),
            n => format!(" + {n} colour"),
        },
        f.wall_s,
        f.gaussians,
        f.psnr_gs,
        f.psnr_gs_affine,
        f.psnr_gs_affine_masked,
        f.psnr_mesh
    );
    if !f.lost_views.is_empty() {
        let views = f.lost_views.join(", ");
        text +=
            &format!("\nwarning: frame {}: views left out, their mask is empty: {views}", f.frame);
    }
    if !f.colour_left_out.is_empty() {
        let views = f.colour_left_out.join("; ");
        text += &format!("\nwarning: frame {}: colours left out (the image terms cannot match them; the masks still count): {views}", f.frame);
    }
    if let Some(c) = f.correspondences.as_ref().filter(|c| !c.unmatched_views.is_empty()) {
        let views = c.unmatched_views.join(", ");
        text += &format!("\nwarning: frame {}: nothing to match in these views (dark, saturated, textureless or the subject hidden; the correspondence terms skip them): {views}", f.frame);
    }
    if f.truncated_steps > 0 {
        let n = f.truncated_steps;
        text += &format!("\nwarning: frame {}: {n} steps outgrew the splatter's intersection buffers (rendered without the excess; the buffers grew)", f.frame);
    }
    text
}

/// The reports of `complete` frames from an earlier run's `report.json`, so the report keeps
/// every frame across resumes. A missing or unreadable report loses only those statistics.
fn earlier_frame_reports(out: &Path, complete: &[usize]) -> Vec<FrameReport> {
    #[derive(serde::Deserialize)]
    struct Earlier {
        frames: Vec<FrameReport>,
    }
    let earlier = std::fs::read_to_string(out.join("report.json"))
        .ok()
        .and_then(|text| serde_json::from_str::<Earlier>(&text).ok());
    let mut frames = earlier.map_or_else(Vec::new, |e| e.frames);
    frames.retain(|f| complete.contains(&f.frame));
    frames
}

/// Frame 0: read back when complete, else optimised from the initial mesh and written.
fn canonical_start(
    ctx: &Arc<GpuContext>,
    (dataset, job, colour): (&Dataset, &TrainJob, ColourUse),
    (out, log): (&SequenceOutput, &RunLog),
    (report, started): (&mut TrainReport, Instant),
    progress: Progress,
) -> Result<(ManifoldMesh, GaussianScene), TrainError> {
    if out.is_complete(0) {
        let (mesh, scene) = out.read_frame(0)?;
        let topology = ManifoldMesh::new(mesh.positions, mesh.faces)
            .map_err(|e| TopologyError::InFile { path: out.mesh_path(0), source: Box::new(e) })?;
        return Ok((topology, scene));
    }
    let stage = Instant::now();
    let (mut mesh, colors) = initial_mesh(dataset, job, log)?;
    report.startup.mesh_s = stage.elapsed().as_secs_f64();
    let init = InitConfig { sh_degree: job.config.sh_degree, ..Default::default() };
    let start = gaussians_from_mesh(&mesh, &colors, &init);
    let stage = Instant::now();
    let frames_end = job.frames.as_ref().map_or(dataset.frames.len(), |f| f.end);
    let (train, eval) = views(dataset, 0, &job.config, (frames_end, progress))?;
    report.startup.views_s = stage.elapsed().as_secs_f64();
    log.line(&format!(
        "frame 0: {} training and {} evaluation views decoded in {:.1} s",
        train.len(),
        eval.as_ref().map_or(0, Vec::len),
        report.startup.views_s
    ))?;
    let eval = eval.as_ref().unwrap_or(&train);
    let frames = job.frames.clone().unwrap_or(0..dataset.frames.len());
    let task = FrameTask {
        frame: 0,
        train: &train,
        eval,
        start,
        mesh: &mut mesh,
        previous: None,
        frame0: None,
        sources: MatchSources::default(),
        colour,
    };
    let first_iteration = &mut report.startup.first_iteration_s;
    let (scene, frame_report) = optimize_frame(ctx, task, &job.config, &mut |counts, loss| {
        first_iteration.get_or_insert_with(|| started.elapsed().as_secs_f64());
        let report = TrainProgress::at(Stage::Frame, 0, frames.end, counts);
        progress(TrainProgress { loss, ..report })
    })?;
    if let Some(s) = report.startup.first_iteration_s {
        log.line(&format!("frame 0: first iteration done {s:.1} s after the start"))?;
    }
    if !frame_report.camera_colour.is_empty() {
        write_maps(&out.camera_colour_path(), &frame_report.camera_colour)?;
    }
    write_frame(out, 0, &mesh, &scene)?;
    report.frames.push(frame_report);
    // Later frames start from the topology as written, exactly as a resumed run reads it back
    // (after densification the in-memory mesh orders its 1-rings differently, and the
    // regularizers sum in that order), so resuming gives the same bits as running through.
    let mesh = ManifoldMesh::new(scene.positions.clone(), mesh.live_faces())?;
    Ok((mesh, scene))
}

/// The colour maps frame 0 learned (read back from `out`, also when resumed), logged; none
/// when camera colour is not learned on this capture.
fn frame0_maps(out: &SequenceOutput, learn: bool, log: &RunLog) -> Result<CameraMaps, TrainError> {
    let maps = if learn { read_maps(&out.camera_colour_path())? } else { CameraMaps::new() };
    if !maps.is_empty() {
        let gains = |k: usize| {
            let g = maps.values().map(|m| m[k][k]);
            (g.clone().fold(f32::INFINITY, f32::min), g.fold(f32::NEG_INFINITY, f32::max))
        };
        let ranges: Vec<String> = (0..3)
            .map(gains)
            .zip(["red", "green", "blue"])
            .map(|((lo, hi), name)| format!("{name} {lo:.3}–{hi:.3}"))
            .collect();
        log.line(&format!(
            "camera colour: {} training cameras' maps learned on frame 0, gains {}",
            maps.len(),
            ranges.join(", ")
        ))?;
    }
    Ok(maps)
}

/// The frame-0 mesh, imported as a manifold (welded, oriented; errors name the file), with
/// vertex colours in [0, 1] (grey where it has none).
fn initial_mesh(
    dataset: &Dataset,
    job: &TrainJob,
    log: &RunLog,
) -> Result<(ManifoldMesh, Vec<[f32; 3]>), TrainError> {
    let (mesh, path) = match &job.mesh {
        Some(path) => {
            let is_obj = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("obj"));
            let mesh = if is_obj { TriMesh::read_obj(path) } else { TriMesh::read_ply(path) };
            (mesh?, path.clone())
        }
        None => {
            let vertices =
                (job.config.init.vertices > 0).then_some(job.config.init.vertices as usize);
            let options = InitOptions {
                vertices,
                edge_pixels: job.config.init.edge_pixels,
                max_subject_pixels: job.config.init.max_subject_pixels,
                ..Default::default()
            };
            let started = Instant::now();
            let built = init_mesh(dataset, 0, &options)?;
            let (r, s, all) = (&built.report, &built.report.seconds, started.elapsed());
            log.line(&format!(
                "frame-0 mesh from {} masks: {} vertices, {} faces in {:.1} s (decoding {:.1} s, \
                 silhouettes {:.1} s, surface {:.1} s, remeshing {:.1} s, colours {:.1} s)",
                r.views,
                r.vertices,
                r.faces,
                all.as_secs_f64(),
                all.as_secs_f64() - s.total,
                s.silhouettes,
                s.extract,
                s.remesh,
                s.color
            ))?;
            (built.mesh, dataset.root.join("(mesh from masks)"))
        }
    };
    let imported = import(&mesh, &path, true)?;
    let colors = imported
        .old_of_new
        .iter()
        .map(|&old| {
            mesh.colors.as_ref().map_or([0.5; 3], |c| c[old as usize].map(|v| v as f32 / 255.0))
        })
        .collect();
    Ok((imported.mesh, colors))
}

/// The views of `views` that show the subject, and the names of those that lost it (an empty
/// mask): a later frame leaves them out, and a frame with no view left keeps its
/// extrapolated pose; the report names both.
fn with_subject(views: Vec<ViewTarget>) -> (Vec<ViewTarget>, Vec<String>) {
    let (shown, lost): (Vec<_>, Vec<_>) = views.into_iter().partition(ViewTarget::has_subject);
    (shown, lost.into_iter().map(|v| v.name).collect())
}

/// Training and evaluation targets of frame `t`: evaluation on the held-out cameras, None
/// when there are none (the training views serve, without a second copy). Progress counts
/// the views decoded (`Stage::Views`; `frames_end` as the run's); a cancel takes effect once
/// the views being decoded are done.
fn views(
    dataset: &Dataset,
    t: usize,
    config: &TrainConfig,
    (frames_end, progress): (usize, Progress),
) -> Result<(Vec<ViewTarget>, Option<Vec<ViewTarget>>), TrainError> {
    let all = (dataset.train.len() + dataset.test.len()) as u32;
    // The held-out views count on from the training views.
    let offset = std::cell::Cell::new(0);
    let cancelled = std::cell::Cell::new(false);
    let mut decoded = |done: usize| {
        let counts = ((offset.get() + done) as u32, all);
        let stop = progress(TrainProgress::at(Stage::Views, t, frames_end, counts)).is_break();
        cancelled.set(cancelled.get() || stop);
    };
    let with_masks = (config.background, true);
    let train = load_targets_counted(dataset, t, &dataset.train, with_masks, &mut decoded)?;
    offset.set(train.len());
    let eval = if dataset.test.is_empty() {
        None
    } else {
        Some(load_targets_counted(dataset, t, &dataset.test, with_masks, &mut decoded)?)
    };
    if cancelled.get() {
        return Err(TrainError::Cancelled);
    }
    Ok((train, eval))
}

/// Frame `t`'s training views when a correspondence term of `weight` matches against them
/// (none when it is off).
fn source_views(
    dataset: &Dataset,
    t: usize,
    weight: f32,
    job: &TrainJob,
) -> Result<Vec<ViewTarget>, TrainError> {
    if weight <= 0.0 {
        return Ok(Vec::new());
    }
    load_targets(dataset, t, &dataset.train, job.config.background, true)
}

/// The anchor term's image tracks of frame 0's vertices, stepped through the training views
/// of frames 1..`first` (the frames a resumed run has on disk; a fresh run steps them as it
/// goes). None when the term is off.
fn start_tracks(
    dataset: &Dataset,
    out: &SequenceOutput,
    (frame0, mesh): (&GaussianScene, &ManifoldMesh),
    first: usize,
    job: &TrainJob,
) -> Result<Option<VertexTracks>, TrainError> {
    if job.config.temporal.anchor <= 0.0 {
        return Ok(None);
    }
    let frame0_views = source_views(dataset, 0, 1.0, job)?;
    let source = SeenPose { positions: &frame0.positions, views: &frame0_views };
    let mut tracks = VertexTracks::start(source, &mesh.live_faces());
    for t in 1..first {
        replay_tracks(&mut tracks, (dataset, out), t, mesh, job)?;
    }
    Ok(Some(tracks))
}

/// Steps the image tracks to frame `t`, which is on disk, as its training did: its training
/// views that show the subject, its starting pose extrapolated from frames t − 1 and t − 2.
fn replay_tracks(
    tracks: &mut VertexTracks,
    (dataset, out): (&Dataset, &SequenceOutput),
    t: usize,
    mesh: &ManifoldMesh,
    job: &TrainJob,
) -> Result<(), TrainError> {
    let previous = out.read_frame(t - 1)?.1;
    let before = if t >= 2 { Some(out.read_frame(t - 2)?.1) } else { None };
    let start = extrapolate(&previous, before.as_ref());
    let train = load_targets(dataset, t, &dataset.train, job.config.background, true)?;
    tracks.advance(&with_subject(train).0, &start.positions, &mesh.live_faces());
    Ok(())
}

fn write_frame(
    out: &SequenceOutput,
    t: usize,
    mesh: &ManifoldMesh,
    scene: &GaussianScene,
) -> Result<(), TrainError> {
    let tri = TriMesh {
        positions: scene.positions.clone(),
        faces: mesh.live_faces(),
        colors: Some(dc_vertex_colors(scene)),
    };
    out.write_frame(t, &tri, scene)
}

fn finish_report(
    ctx: &GpuContext,
    report: &mut TrainReport,
    mesh: &ManifoldMesh,
    started: Instant,
    out: &Path,
) -> Result<(), TrainError> {
    report.total_wall_s = started.elapsed().as_secs_f64();
    report.peak_host_bytes = peak_resident_bytes();
    report.peak_device_bytes = ctx.buffer_bytes().peak;
    report.vertices = mesh.positions.len();
    report.faces = mesh.live_faces().len();
    let path = out.join("report.json");
    write_json_atomically(&path, report).map_err(|error| TrainError::Io { path, error })
}

/// The signed axis nearest the cameras' mean up vector, and a sentence saying so.
fn capture_up(dataset: &Dataset, said: &mut String) -> SignedAxis {
    let mean = mean_up(&dataset.cameras);
    let source = SignedAxis::nearest(mean.to_array());
    *said = format!("the cameras' mean up {mean:.3} is nearest {source}");
    source
}

/// The exports' frame rate and where it came from: the job's, the layout's, or 30 assumed.
fn frame_rate(job: &TrainJob, dataset: &Dataset) -> (f64, String) {
    match (job.fps, dataset.fps) {
        (Some(fps), _) => (fps, "as asked".into()),
        (None, Some(fps)) => (fps, format!("the {} layout's", dataset.format.name())),
        (None, None) => (30.0, format!("assumed: the {} layout has none", dataset.format.name())),
    }
}

/// Frames 0..k complete on disk: what the exports can hold (a later frame without all before
/// it cannot join a sequence that plays from frame 0).
fn complete_prefix(out: &SequenceOutput, frames: usize) -> usize {
    (0..frames).take_while(|&t| out.is_complete(t)).count()
}

/// "frames 0-2 of 17 at 29.97 fps (the Panoptic layout's); frame 3 is not trained yet".
fn export_sentence(done: usize, total: usize, fps: f64, rate: &str) -> String {
    let held = match done {
        0 => return "no frame is complete".into(),
        1 => format!("frame 0 of {total}"),
        _ => format!("frames 0-{} of {total}", done - 1),
    };
    let rest = if done < total {
        format!("; frame {done} is not trained yet (a run over it extends them)")
    } else {
        String::new()
    };
    format!("{held} at {fps} fps ({rate}){rest}")
}
