//! Result files, and the README's table of figures made from them.
//!
//! A result file is what a measuring command prints with `--json` (`bench
//! sort|splat|render|train|mesh|track`, `bench sequence`, `demo`), its [`Provenance`] first: the command line, commit, date, device,
//! driver and host. The repository keeps them in `benches/results/`; `tagsplat figures` turns
//! each into one row of the README's table, so a figure there is always one a file holds, and
//! `--check` (and the test below) fails when the README says anything else.

use anyhow::{bail, Context, Result};
use serde::Serialize;
use serde_json::Value;
use std::path::{Path, PathBuf};
use tagsplat::bench::Provenance;
use tagsplat::gpu::DeviceInfo;

/// The lines around the generated table in the README.
const BEGIN: &str = "<!-- figures: written by `tagsplat figures` from benches/results/*.json -->";
const END: &str = "<!-- end of figures -->";

#[derive(clap::Args)]
pub struct FiguresArgs {
    /// Folder of result files, relative to the README's folder (the table links into it).
    #[arg(long, default_value = "benches/results")]
    results: PathBuf,
    /// The README whose table (between the figures comments) is rewritten.
    #[arg(long, default_value = "README.md")]
    readme: PathBuf,
    /// Only compare: fail when the README's table differs from the result files.
    #[arg(long)]
    check: bool,
}

/// Prints `report` as one JSON object with the run's provenance as its first field.
pub fn print_result<T: Serialize>(report: &T, device: Option<&DeviceInfo>) -> Result<()> {
    #[derive(Serialize)]
    struct Recorded<'a, T> {
        provenance: Provenance,
        #[serde(flatten)]
        report: &'a T,
    }
    let recorded = Recorded { provenance: Provenance::of_run(device), report };
    println!("{}", serde_json::to_string_pretty(&recorded)?);
    Ok(())
}

pub fn run(args: FiguresArgs) -> Result<()> {
    let base = args.readme.parent().unwrap_or(Path::new(""));
    let table = figures_table(&base.join(&args.results), &args.results)?;
    let readme = std::fs::read_to_string(&args.readme)
        .with_context(|| format!("cannot read {}", args.readme.display()))?;
    let (before, current, after) = split_readme(&readme)
        .with_context(|| format!("{}: no figures table", args.readme.display()))?;
    if args.check {
        if current != table {
            bail!(
                "{}: the figures table differs from {}",
                args.readme.display(),
                args.results.display()
            );
        }
        println!("{}: the figures table matches {}", args.readme.display(), args.results.display());
        return Ok(());
    }
    let text = format!("{before}{table}{after}");
    tagsplat::io::write_atomically(&args.readme, |w| std::io::Write::write_all(w, text.as_bytes()))
        .with_context(|| format!("cannot write {}", args.readme.display()))?;
    println!("wrote {}", args.readme.display());
    Ok(())
}

/// The README's text before the table (through the opening comment's line), the table, and
/// the rest (from the closing comment).
fn split_readme(readme: &str) -> Option<(&str, &str, &str)> {
    let start = readme.find(BEGIN)? + BEGIN.len() + 1;
    let end = start + readme.get(start..)?.find(END)?;
    Some((&readme[..start], &readme[start..end], &readme[end..]))
}

/// The table of every `*.json` in `dir`, one row each, in a fixed order of kinds, then by file
/// name; `link` is `dir` as the README's links name it.
pub fn figures_table(dir: &Path, link: &Path) -> Result<String> {
    let listing =
        std::fs::read_dir(dir).with_context(|| format!("cannot list {}", dir.display()))?;
    let mut paths = Vec::new();
    for entry in listing {
        let path = entry.with_context(|| format!("cannot list {}", dir.display()))?.path();
        if path.extension().is_some_and(|e| e == "json") {
            paths.push(path);
        }
    }
    paths.sort();
    let mut rows = Vec::new();
    for path in &paths {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("cannot read {}", path.display()))?;
        let value: Value =
            serde_json::from_str(&text).with_context(|| format!("{}: not JSON", path.display()))?;
        let file = path.file_name().unwrap_or_default().to_string_lossy();
        let row = table_row(&value, &format!("{}/{file}", link.display()))
            .with_context(|| format!("{}", path.display()))?;
        rows.push(row);
    }
    rows.sort_by_key(|(order, _)| *order); // stable: file-name order within a kind
    let mut table = String::from("| figure | value | device | date | result file |\n");
    table += "|---|---|---|---|---|\n";
    rows.iter().for_each(|(_, row)| table += row);
    Ok(table)
}

/// One result file's row and its kind's place in the table.
fn table_row(v: &Value, link: &str) -> Result<(usize, String)> {
    let provenance: Provenance = serde_json::from_value(field(v, "provenance")?.clone())
        .context("field \"provenance\" lacks command, commit, date, device, driver or host")?;
    let words: Vec<&str> = provenance.command.split_whitespace().skip(1).collect();
    let kind = match words.as_slice() {
        ["bench", kind, ..] => format!("bench {kind}"),
        [kind, ..] => kind.to_string(),
        [] => bail!("the command line is empty"),
    };
    let (order, figure, value) = match kind.as_str() {
        "bench sort" => (0, sort_figure(v)?, sort_value(v)?),
        "bench splat" => (1, splat_scene(v, "[splatting](docs/splatting.md)")?, splat_value(v)?),
        "bench render" => {
            (2, splat_scene(v, "[render only](docs/splatting.md)")?, render_value(v)?)
        }
        "bench train" => (3, train_figure(v)?, train_value(v)?),
        "bench mesh" => (4, mesh_figure(v)?, mesh_value(v)?),
        "bench track" => (5, track_figure(v)?, track_value(v)?),
        "demo" => (6, demo_figure(v)?, demo_value(v)?),
        "bench sequence" => (7, sequence_figure(v, &words)?, sequence_value(v)?),
        other => bail!("no table row for results of `tagsplat {other}`"),
    };
    let device = format!("{} on {}", provenance.device, provenance.host);
    let date = provenance.date.get(..10).unwrap_or(&provenance.date);
    let row =
        format!("| {figure} | {value} | {device} | {date} | [{}]({link}) |\n", provenance.commit);
    Ok((order, row))
}

fn sort_figure(v: &Value) -> Result<String> {
    Ok(format!("[sort](docs/sort.md), {} pairs, {}-bit keys", num(v, "n")?, num(v, "bits")?))
}

fn sort_value(v: &Value) -> Result<String> {
    Ok(format!(
        "{:.1} ms ({:.0} M pairs/s), {:.2} of the copy bound; `sort_unstable`, one core: {:.1} ms",
        num(v, "sort_ms")?,
        num(v, "keys_per_s")? / 1e6,
        num(v, "lsd_bound_fraction")?,
        num(v, "cpu_sort_ms")?
    ))
}

/// The splat bench's scene as a figure's words: `what`, Gaussians, SH degree, frame size.
fn splat_scene(v: &Value, what: &str) -> Result<String> {
    Ok(format!(
        "{what}, {} Gaussians, SH {}, {} × {}",
        num(v, "config.gaussians")?,
        num(v, "config.sh_degree")?,
        num(v, "config.width")?,
        num(v, "config.height")?
    ))
}

fn splat_value(v: &Value) -> Result<String> {
    Ok(format!(
        "forward + backward {:.1} ms per view ({:.1} views/s); forward alone {:.1} ms",
        num(v, "fwd_bwd_s")? * 1e3,
        num(v, "fwd_bwd_per_s")?,
        num(v, "fwd_s")? * 1e3
    ))
}

fn render_value(v: &Value) -> Result<String> {
    Ok(format!(
        "{:.1} ms per render ({:.1} per s), GPU passes {:.1} ms, of which the sort {:.1} ms",
        num(v, "wall_s")? * 1e3,
        num(v, "renders_per_s")?,
        num(v, "gpu_s")? * 1e3,
        num(v, "passes_ms.sort")?
    ))
}

fn train_figure(v: &Value) -> Result<String> {
    Ok(format!(
        "[training iteration](docs/splatting.md), {} Gaussians, {} views of {} × {}",
        num(v, "config.scene.gaussians")?,
        num(v, "config.scene.views")?,
        num(v, "config.scene.width")?,
        num(v, "config.scene.height")?
    ))
}

fn train_value(v: &Value) -> Result<String> {
    Ok(format!(
        "{:.1} ms ({:.1} it/s), the host {:.1} % of it; image loss, two renders against one \
         view: {:.2} ms; two targets on the device, the rest streamed: {:.1} ms",
        num(v, "s_per_iter")? * 1e3,
        num(v, "iters_per_s")?,
        num(v, "host_fraction")? * 100.0,
        num(v, "loss_ms.1")?,
        num(v, "streamed_s_per_iter")? * 1e3
    ))
}

fn mesh_figure(v: &Value) -> Result<String> {
    Ok(format!(
        "[mesh rasterizer](docs/rasterizer.md), {} triangles at {}²",
        num(v, "triangles")?,
        num(v, "config.resolution")?
    ))
}

fn mesh_value(v: &Value) -> Result<String> {
    Ok(format!(
        "forward {:.0} ms, backward {:.0} ms per view",
        num(v, "forward_ms")?,
        num(v, "backward_ms")?
    ))
}

fn track_figure(v: &Value) -> Result<String> {
    Ok(format!(
        "[tracking queries](docs/tracking.md) on a {}-triangle mesh (BVH, CPU)",
        num(v, "triangles")?
    ))
}

fn track_value(v: &Value) -> Result<String> {
    Ok(format!(
        "build {:.0} ms; {:.0} k closest points/s ({:.0}× brute force), {:.0} k rays/s",
        num(v, "build_ms")?,
        num(v, "queries_per_s")? / 1e3,
        num(v, "queries_per_s")? / num(v, "brute_force_queries_per_s")?,
        num(v, "rays_per_s")? / 1e3
    ))
}

fn demo_figure(v: &Value) -> Result<String> {
    Ok(format!(
        "[demo](docs/pipeline.md), {} views at {}², {} frames",
        num(v, "options.views")?,
        num(v, "options.resolution")?,
        num(v, "options.frames")?
    ))
}

fn demo_value(v: &Value) -> Result<String> {
    Ok(format!(
        "{:.1} s; held-out PSNR {:.2} / {:.2} dB (Gaussians / mesh); Chamfer {:.3} % of the \
         diagonal; tracking {:.3} % of height",
        num(v, "scores.seconds")?,
        num(v, "scores.psnr_gs")?,
        num(v, "scores.psnr_mesh")?,
        num(v, "scores.chamfer_per_diagonal")? * 100.0,
        num(v, "scores.tracking_rmse_per_height")? * 100.0
    ))
}

/// The sequence's name and frames, and the config its command line (`words`) trained with.
fn sequence_figure(v: &Value, words: &[&str]) -> Result<String> {
    let data = text(v, "data")?;
    let name = Path::new(data).file_name().map_or(data.into(), |n| n.to_string_lossy());
    let frames = field(v, "scores.frames")?.as_array().context("\"scores.frames\" is no list")?;
    let (first, last) = match (frames.first(), frames.last()) {
        (Some(first), Some(last)) => (first, last),
        _ => bail!("\"scores.frames\" is empty"),
    };
    let figure = format!("[{name}](docs/benchmarks.md), frames {first}–{last}");
    Ok(match words.iter().position(|w| *w == "--config").and_then(|i| words.get(i + 1)) {
        Some(config) => {
            let stem = Path::new(config)
                .file_stem()
                .map_or(config.to_string(), |s| s.to_string_lossy().into_owned());
            format!("{figure}, with `{stem}` ([config]({config}))")
        }
        None => figure,
    })
}

fn sequence_value(v: &Value) -> Result<String> {
    let percent = |path: &str| num(v, path).map(|x| x * 100.0);
    Ok(format!(
        "tracking {:.2} % of size, {} (worst frame {}: {:.2} %; along the surface {:.2} %); \
         Chamfer ≤ {:.3} %; mesh PSNR {:.2} → {:.2} dB; {:.1} s per later frame",
        percent("scores.tracking_rmse_over_size")?,
        tracking_pixels(v)?,
        num(v, "scores.tracking_worst_frame.frame")?,
        percent("scores.tracking_worst_frame.value")?,
        percent("scores.tracking_along_surface_over_size")?,
        percent("scores.chamfer_worst_frame.value")?,
        num(v, "scores.psnr_mesh_first_db")?,
        num(v, "scores.psnr_mesh_last_db")?,
        num(v, "later_frame_mean_s")?
    ))
}

/// The tracking error in pixels (`eval::pixels`), or that the result file predates it (a
/// `null` means no training camera saw any tracked point, which `bench sequence` writes as such).
fn tracking_pixels(v: &Value) -> Result<String> {
    match v.pointer("/scores/tracking_rmse_px") {
        None => Ok("pixels not measured".into()),
        Some(Value::Null) => Ok("no point seen to measure in pixels".into()),
        Some(_) => Ok(format!("{:.2} px", num(v, "scores.tracking_rmse_px")?)),
    }
}

/// The value at a dotted path (`a.b.0`: a list's element by index).
fn field<'a>(v: &'a Value, path: &str) -> Result<&'a Value> {
    path.split('.')
        .try_fold(v, |v, key| match key.parse::<usize>() {
            Ok(i) => v.get(i),
            Err(_) => v.get(key),
        })
        .filter(|v| !v.is_null())
        .with_context(|| format!("no field \"{path}\""))
}

fn num(v: &Value, path: &str) -> Result<f64> {
    field(v, path)?.as_f64().with_context(|| format!("field \"{path}\" is not a number"))
}

fn text<'a>(v: &'a Value, path: &str) -> Result<&'a str> {
    field(v, path)?.as_str().with_context(|| format!("field \"{path}\" is not text"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn root() -> &'static Path {
        Path::new(env!("CARGO_MANIFEST_DIR"))
    }

    #[test]
    fn readme_figures_are_the_result_files() {
        let link = Path::new("benches/results");
        let table = figures_table(&root().join(link), link).unwrap();
        let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
        let (_, current, _) = split_readme(&readme).expect("README.md has no figures table");
        assert_eq!(current, table, "README.md's figures differ: run `tagsplat figures`");
        assert!(table.lines().count() > 2, "no result file in benches/results");
    }

    /// The front door stays short: 200 lines, no table cell over 200 characters.
    #[test]
    fn readme_is_short_and_its_cells_too() {
        let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
        assert!(readme.lines().count() <= 200, "README.md: {} lines", readme.lines().count());
        for line in readme.lines().filter(|l| l.starts_with('|')) {
            for cell in line.split(" | ") {
                assert!(cell.chars().count() <= 200, "README.md: a cell of {cell:?}");
            }
        }
    }

    #[test]
    fn a_result_without_a_row_format_or_a_field_is_an_error_naming_it() {
        let provenance = |command: &str| {
            serde_json::json!({"command": command, "commit": "abc", "date": "2026-11-28T12:00:00Z",
                "device": "d", "driver": "x", "host": "h"})
        };
        let unknown = serde_json::json!({"provenance": provenance("tagsplat bench topology")});
        let error = table_row(&unknown, "r.json").unwrap_err().to_string();
        assert!(error.contains("bench topology"), "{error}");
        let partial = serde_json::json!({"provenance": provenance("tagsplat bench sort --n 8"),
            "n": 8, "bits": 32, "sort_ms": 1.0});
        let error = format!("{:#}", table_row(&partial, "r.json").unwrap_err());
        assert!(error.contains("keys_per_s"), "{error}");
        let sort = serde_json::json!({"provenance": provenance("tagsplat bench sort --n 8"),
            "n": 8, "bits": 32, "sort_ms": 1.3, "keys_per_s": 6.4e6,
            "lsd_bound_fraction": 0.5, "cpu_sort_ms": 2.0});
        let (order, row) = table_row(&sort, "r.json").unwrap();
        assert_eq!(order, 0);
        assert_eq!(
            row,
            "| [sort](docs/sort.md), 8 pairs, 32-bit keys | 1.3 ms (6 M pairs/s), 0.50 of the \
             copy bound; `sort_unstable`, one core: 2.0 ms | d on h | 2026-11-28 | [abc](r.json) |\n"
        );
    }

    /// A sequence row gives pixels only where the result file measured them.
    #[test]
    fn a_sequence_row_gives_pixels_where_measured() {
        let mut result = serde_json::json!({"later_frame_mean_s": 20.0, "scores": {
            "tracking_rmse_over_size": 0.0134, "tracking_worst_frame": {"frame": 12, "value": 0.02},
            "tracking_along_surface_over_size": 0.013, "chamfer_worst_frame": {"value": 0.0026},
            "psnr_mesh_first_db": 35.2, "psnr_mesh_last_db": 34.8}});
        assert!(sequence_value(&result)
            .unwrap()
            .starts_with("tracking 1.34 % of size, pixels not"));
        result["scores"]["tracking_rmse_px"] = serde_json::json!(2.414);
        assert!(sequence_value(&result).unwrap().starts_with("tracking 1.34 % of size, 2.41 px ("));
    }
}
