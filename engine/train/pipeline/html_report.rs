//! `OUT/report.html`: one page per run that opens anywhere, offline — every image a PNG data
//! URI, every plot inline SVG, nothing fetched. It holds the per-frame table (with the
//! benchmark scores when `tagsplat eval` left `eval.json` in OUT), the PSNR and time plots (and
//! `eval.svg`), and for up to [`MAX_VIEWS`] evaluation views the target, the Gaussian render and
//! the mesh render side by side on the first, middle and last frame. It is built from the files
//! of OUT (`report.json`, the frames) and the dataset that report names, so an evaluation run
//! later can rebuild it with its scores.

use super::FrameReport;
use crate::camera::Camera;
use crate::dataset::{Dataset, LoadOptions, PixelCenters};
use crate::eval::psnr;
use crate::gpu::GpuContext;
use crate::io::image::{encode_png, Image};
use crate::io::plot::{escape, svg, Panel, Series};
use crate::io::write_atomically;
use crate::mesh::TriMesh;
use crate::splat::{GaussianBuffers, RenderSettings, Splatter};
use crate::train::fit::scene_extent;
use crate::train::mesh_term::MeshTerm;
use crate::train::output::SequenceOutput;
use crate::train::{load_targets, TrainError, ViewTarget};
use serde::de::DeserializeOwned;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Evaluation views shown: enough to judge a run, few enough to keep the page small.
const MAX_VIEWS: usize = 4;

const STYLE: &str = "body{font-family:sans-serif;margin:1.5em;color:#222}\
table{border-collapse:collapse;font-size:13px}td,th{border:1px solid #ccc;padding:2px 8px;\
text-align:right}th{background:#f2f2f2}td.text{text-align:left}svg{max-width:100%;height:auto}\
.row{display:flex;gap:8px;align-items:flex-start}figure{margin:0 0 8px;flex:1;max-width:400px}\
figure img{width:100%;height:auto;image-rendering:pixelated;border:1px solid #ccc}\
figcaption{font-size:12px}";

/// What the page reads from `OUT/report.json` (a [`super::TrainReport`]).
#[derive(serde::Deserialize)]
struct Run {
    data: PathBuf,
    device: String,
    eval_views: String,
    total_wall_s: f64,
    vertices: usize,
    faces: usize,
    frames: Vec<FrameReport>,
    /// Reports written before the field existed were trained on the default, black.
    #[serde(default)]
    background: [f32; 3],
    /// Reports written before the field existed used the layout's default.
    #[serde(default)]
    pixel_centers: Option<PixelCenters>,
    /// Reports written before the field existed trained at the files' size.
    #[serde(default)]
    scale: Option<f64>,
}

/// `OUT/eval.json` of `tagsplat eval` on a benchmark: the per-frame scores the page shows.
#[derive(serde::Deserialize)]
struct Eval {
    frames: Vec<FrameScores>,
}

/// Fractions of the subject's size.
#[derive(serde::Deserialize)]
struct FrameScores {
    frame: usize,
    tracking_rmse_over_size: Option<f64>,
    /// Absent from the files of evaluations before it was scored.
    tracking_along_surface_over_size: Option<f64>,
    chamfer_over_size: Option<f64>,
}

/// Writes `out/report.html` (atomically) from the run in `out`; returns its path. Errors name
/// the file: no or unreadable `report.json`, an `eval.json` that is not an evaluation's, the
/// dataset or a frame that cannot be read.
pub fn write_html_report(ctx: &Arc<GpuContext>, out: &Path) -> Result<PathBuf, TrainError> {
    let report = out.join("report.json");
    let run: Run = read_json(&report)?.ok_or_else(|| TrainError::Read {
        path: report,
        error: std::io::ErrorKind::NotFound.into(),
    })?;
    let eval: Option<Eval> = read_json(&out.join("eval.json"))?;
    let eval_plot = if eval.is_some() { read_text(&out.join("eval.svg"))? } else { None };
    let load = LoadOptions { pixel_centers: run.pixel_centers, scale: run.scale };
    let dataset = Dataset::load_with(&run.data, &load)?;
    let views = views_section(ctx, &dataset, out, &run)?;
    let page = page(out, &run, eval.as_ref(), eval_plot.as_deref(), &views);
    let path = out.join("report.html");
    write_atomically(&path, |w| w.write_all(page.as_bytes()))
        .map_err(|error| TrainError::Io { path: path.clone(), error })?;
    Ok(path)
}

/// The text of `path`; None when there is no such file.
fn read_text(path: &Path) -> Result<Option<String>, TrainError> {
    match std::fs::read_to_string(path) {
        Ok(text) => Ok(Some(text)),
        Err(error) if error.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(error) => Err(TrainError::Read { path: path.to_owned(), error }),
    }
}

fn read_json<T: DeserializeOwned>(path: &Path) -> Result<Option<T>, TrainError> {
    let Some(text) = read_text(path)? else { return Ok(None) };
    serde_json::from_str(&text).map(Some).map_err(|e| TrainError::Invalid {
        path: path.to_owned(),
        problem: format!("not what the HTML report reads: {e}"),
    })
}

fn page(
    out: &Path,
    run: &Run,
    eval: Option<&Eval>,
    eval_plot: Option<&str>,
    views: &str,
) -> String {
    let title = format!("tagsplat run {}", escape(&out.display().to_string()));
    let mut html = format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <title>{title}</title><style>{STYLE}</style></head><body>\n<h1>{title}</h1>\n\
         <p>Data {}; device {}; {} frames, {} vertices, {} faces; {:.1} s of training; \
         scores on the {} views.</p>\n",
        escape(&run.data.display().to_string()),
        escape(&run.device),
        run.frames.len(),
        run.vertices,
        run.faces,
        run.total_wall_s,
        escape(&run.eval_views),
    );
    html += "<h2>Frames</h2>\n";
    html += &frame_table(&run.frames, eval);
    html += "<h2>Plots</h2>\n";
    html += &svg(&frame_panels(&run.frames));
    if let Some(plot) = eval_plot {
        html += "<p>Benchmark scores (<code>tagsplat eval</code>):</p>\n";
        html += plot;
    }
    html += &format!("<h2>The {} views</h2>\n{views}</body></html>\n", escape(&run.eval_views));
    html
}

/// One row per frame; the score columns only when the evaluation exists.
fn frame_table(frames: &[FrameReport], eval: Option<&Eval>) -> String {
    let scores: BTreeMap<usize, &FrameScores> =
        eval.iter().flat_map(|e| &e.frames).map(|s| (s.frame, s)).collect();
    let mut html = String::from(
        "<table><tr><th>frame</th><th>graph iterations</th><th>iterations</th><th>stop</th>\
         <th>seconds</th><th>Gaussians</th><th>PSNR Gaussians dB</th><th>SSIM Gaussians</th><th>PSNR colour-corrected dB</th>\
         <th>the same through the masks dB</th><th>PSNR mesh dB</th>",
    );
    if eval.is_some() {
        html += "<th>tracking RMSE % of size</th><th>of which along the surface</th>\
                 <th>Chamfer % of size</th>";
    }
    html += "<th>warnings</th></tr>\n";
    for f in frames {
        let graph: u32 = f.graph.iter().flat_map(|g| &g.levels).map(|l| l.iterations).sum();
        let _ =
            write!(
            html,
            "<tr><td>{}</td><td>{graph}</td><td>{}</td><td class=\"text\">{:?}</td><td>{:.1}</td>\
             <td>{}</td><td>{:.2}</td><td>{:.4}</td><td>{:.2}</td><td>{:.2}</td><td>{:.2}</td>",
            f.frame, f.iterations, f.stop_reason, f.wall_s, f.gaussians, f.psnr_gs, f.ssim_gs,
            f.psnr_gs_affine, f.psnr_gs_affine_masked, f.psnr_mesh
        );
        if eval.is_some() {
            let s = scores.get(&f.frame);
            let percent = |v: Option<f64>| v.map_or("-".into(), |v| format!("{:.3}", v * 100.0));
            let _ = write!(
                html,
                "<td>{}</td><td>{}</td><td>{}</td>",
                percent(s.and_then(|s| s.tracking_rmse_over_size)),
                percent(s.and_then(|s| s.tracking_along_surface_over_size)),
                percent(s.and_then(|s| s.chamfer_over_size))
            );
        }
        let _ = writeln!(html, "<td class=\"text\">{}</td></tr>", escape(&warnings(f)));
    }
    html + "</table>\n"
}

/// What went wrong in a frame, in a few words ("" when nothing did).
fn warnings(f: &FrameReport) -> String {
    let mut said = Vec::new();
    if !f.lost_views.is_empty() {
        said.push(format!("views without the subject: {}", f.lost_views.join(", ")));
    }
    if !f.colour_left_out.is_empty() {
        said.push(format!("colours left out: {}", f.colour_left_out.join("; ")));
    }
    if f.truncated_steps > 0 {
        said.push(format!("{} truncated steps", f.truncated_steps));
    }
    said.join("; ")
}

/// PSNR and optimisation time against the frame.
fn frame_panels(frames: &[FrameReport]) -> [Panel; 2] {
    let series = |name: &str, value: fn(&FrameReport) -> f64| Series {
        name: name.into(),
        points: frames.iter().map(|f| [f.frame as f64, value(f)]).collect(),
    };
    [
        Panel {
            title: "PSNR per frame".into(),
            x_label: "frame".into(),
            y_label: "PSNR, dB".into(),
            series: vec![
                series("Gaussians", |f| f.psnr_gs),
                series("Gaussians, colour-corrected per view", |f| f.psnr_gs_affine),
                series("the same, through the views' masks", |f| f.psnr_gs_affine_masked),
                series("mesh", |f| f.psnr_mesh),
            ],
            equal_scale: false,
        },
        Panel {
            title: "Optimisation time per frame".into(),
            x_label: "frame".into(),
            y_label: "seconds".into(),
            series: vec![series("wall time", |f| f.wall_s)],
            equal_scale: false,
        },
    ]
}

/// The first, middle and last of the run's frames (fewer when they coincide).
fn shown_frames(frames: &[FrameReport]) -> Vec<usize> {
    let mut all: Vec<usize> = frames.iter().map(|f| f.frame).collect();
    all.sort_unstable();
    let Some(&last) = all.last() else { return Vec::new() };
    let mut shown = vec![all[0], all[(all.len() - 1) / 2], last];
    shown.dedup();
    shown
}

/// A frame as the renderers take it.
struct ShownFrame {
    frame: usize,
    mesh: TriMesh,
    gaussians: GaussianBuffers,
    sh_degree: u32,
}

/// The shown frames (see [`shown_frames`]) that are complete on disk, uploaded.
fn load_shown_frames(
    ctx: &Arc<GpuContext>,
    out: &Path,
    run: &Run,
) -> Result<Vec<ShownFrame>, TrainError> {
    let output = SequenceOutput::create(out)?;
    let mut frames = Vec::new();
    for t in shown_frames(&run.frames).into_iter().filter(|&t| output.is_complete(t)) {
        let (mesh, scene) = output.read_frame(t)?;
        let gaussians = GaussianBuffers::from_scene(ctx, &scene)?;
        frames.push(ShownFrame { frame: t, mesh, gaussians, sh_degree: scene.sh_degree });
    }
    Ok(frames)
}

/// The Gaussian renderer with the training run's settings (see `optimize_frame`).
struct SplatRenderer {
    splatter: Splatter,
    settings: RenderSettings,
}

impl SplatRenderer {
    fn new(
        ctx: &Arc<GpuContext>,
        dataset: &Dataset,
        background: [f32; 3],
    ) -> Result<Self, TrainError> {
        let train: Vec<&Camera> = dataset.train.iter().map(|&c| &dataset.cameras[c]).collect();
        let extent = scene_extent(&train);
        let settings = RenderSettings {
            background,
            near: (extent * 1e-3) as f32,
            far: (extent * 1e3) as f32,
            sh_degree: 0,
            mask_mode: false,
        };
        Ok(Self { splatter: Splatter::renderer(ctx)?, settings })
    }

    /// RGB in [0, 1].
    fn render(&mut self, f: &ShownFrame, camera: &Camera) -> Result<Vec<f32>, TrainError> {
        let settings = RenderSettings { sh_degree: f.sh_degree, ..self.settings };
        self.splatter.forward(&f.gaussians, camera, &settings)?;
        let rgba = self.splatter.read_rgba()?;
        Ok(rgba.iter().flat_map(|p| [p[0], p[1], p[2]]).map(|c| c.clamp(0.0, 1.0)).collect())
    }
}

/// For each evaluation view (held-out, or training without any), one row per shown frame:
/// target, Gaussian render, mesh render.
fn views_section(
    ctx: &Arc<GpuContext>,
    dataset: &Dataset,
    out: &Path,
    run: &Run,
) -> Result<String, TrainError> {
    let frames = load_shown_frames(ctx, out, run)?;
    let Some(first) = frames.first() else {
        return Ok("<p>No complete frame on disk.</p>\n".into());
    };
    let cameras = if dataset.test.is_empty() { &dataset.train } else { &dataset.test };
    let mut splats = SplatRenderer::new(ctx, dataset, run.background)?;
    let mut html = String::new();
    if cameras.len() > MAX_VIEWS {
        let _ = writeln!(html, "<p>The first {MAX_VIEWS} of {} views.</p>", cameras.len());
    }
    for &camera in cameras.iter().take(MAX_VIEWS) {
        let _ = writeln!(html, "<h3>{}</h3>", escape(&dataset.camera_names[camera]));
        let size = &dataset.cameras[camera];
        // One rasterizer per view, its size; the faces are the same in every frame.
        let mut mesh =
            MeshTerm::new(ctx, &first.mesh.positions, &first.mesh.faces, size.width, size.height)?;
        for f in &frames {
            // A frame without this view has no row.
            if let Some(target) =
                load_targets(dataset, f.frame, &[camera], run.background, true)?.pop()
            {
                html += &view_row(f, &target, (&mut splats, &mut mesh), run.background, out)?;
            }
        }
    }
    Ok(html)
}

/// Frame `f` from the target's view: the target, the Gaussian and the mesh render with their
/// PSNR against it.
fn view_row(
    f: &ShownFrame,
    target: &ViewTarget,
    (splats, mesh_term): (&mut SplatRenderer, &mut MeshTerm),
    background: [f32; 3],
    out: &Path,
) -> Result<String, TrainError> {
    let camera = &target.camera;
    let gaussians = splats.render(f, camera)?;
    mesh_term.set_mesh(&f.mesh.positions, &f.mesh.faces)?;
    let mesh = mesh_term.render(&f.gaussians, camera, background)?;
    let rgb = target.rgb();
    let mut html = String::from("<div class=\"row\">\n");
    html += &figure(&format!("frame {}: target", f.frame), &rgb, camera, out)?;
    for (name, render) in [("Gaussians", &gaussians), ("mesh", &mesh)] {
        let caption = format!("{name}, PSNR {:.2} dB", psnr(render, &rgb)?);
        html += &figure(&caption, render, camera, out)?;
    }
    Ok(html + "</div>\n")
}

/// An image as a figure with its caption, the pixels inline as a PNG data URI.
fn figure(caption: &str, rgb: &[f32], camera: &Camera, out: &Path) -> Result<String, TrainError> {
    let (width, height) = (camera.width, camera.height);
    let image = Image { width, height, channels: 3, data: rgb.to_vec() };
    let mut png = Vec::new();
    encode_png(&image, &mut png)
        .map_err(|error| TrainError::Io { path: out.join("report.html"), error })?;
    let caption = escape(caption);
    Ok(format!(
        "<figure><img src=\"data:image/png;base64,{}\" width=\"{width}\" height=\"{height}\" \
         alt=\"{caption}\"><figcaption>{caption}</figcaption></figure>\n",
        base64(&png)
    ))
}

/// Standard base64 (RFC 4648, with padding).
fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut text = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let n = chunk.iter().enumerate().fold(0u32, |n, (i, &b)| n | u32::from(b) << (16 - 8 * i));
        for k in 0..4 {
            // A chunk of n bytes fills n + 1 characters; '=' pads to four.
            let c =
                if k <= chunk.len() { ALPHABET[(n >> (18 - 6 * k) & 63) as usize] } else { b'=' };
            text.push(char::from(c));
        }
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_matches_rfc_4648() {
        let cases = [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ];
        for (plain, encoded) in cases {
            assert_eq!(base64(plain.as_bytes()), encoded);
        }
        assert_eq!(base64(&[0xff, 0xef, 0xbe]), "/+++");
    }

    #[test]
    fn first_middle_and_last_frames_without_repeats() {
        let frames = |ts: &[usize]| -> Vec<FrameReport> {
            ts.iter().map(|&t| FrameReport::without_views(t, 0, Vec::new())).collect()
        };
        assert_eq!(shown_frames(&frames(&[])), Vec::<usize>::new());
        assert_eq!(shown_frames(&frames(&[3])), [3]);
        assert_eq!(shown_frames(&frames(&[1, 0])), [0, 1]);
        assert_eq!(shown_frames(&frames(&[4, 0, 1, 2, 3])), [0, 2, 4]);
    }
}
