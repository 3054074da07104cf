//! The files of a sequence evaluation: `eval.csv` (one row per scored frame), `eval.json`
//! (frames and summary) and `eval.png`, a plot without text (see [`crate::io::plot`]): frame
//! index to the right, fractions of `size` upwards from 0 (the green line); tracking RMSE in
//! red, Chamfer in blue. The numbers are in the CSV beside it.

use super::{FrameScores, SequenceEval, SequenceEvalError};
use crate::io::plot::{draw_panel, write_png_rgb, BACKGROUND, PANEL};
use crate::io::write_atomically;
use glam::DVec2;
use image::RgbImage;
use std::io::Write;
use std::path::{Path, PathBuf};

const HEADER: &str = "frame,tracking_rmse_over_size,tracking_max_over_size,chamfer_over_size,psnr_gs_db,psnr_mesh_db,iterations,wall_s,stop_reason";

/// Writes the three files into `dir` (created when needed), each atomically; returns their
/// paths.
pub fn write_sequence_eval(
    dir: &Path,
    eval: &SequenceEval,
) -> Result<Vec<PathBuf>, SequenceEvalError> {
    let io = |path: &Path| {
        let path = path.to_owned();
        move |source| SequenceEvalError::Io { path, source }
    };
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    let (csv, json, png) = (dir.join("eval.csv"), dir.join("eval.json"), dir.join("eval.png"));
    write_atomically(&csv, |w| write_csv(w, &eval.frames)).map_err(io(&csv))?;
    write_atomically(&json, |w| {
        serde_json::to_writer_pretty(&mut *w, eval)?;
        writeln!(w)
    })
    .map_err(io(&json))?;
    write_png_rgb(&png, &draw_scores(&eval.frames)).map_err(io(&png))?;
    Ok(vec![csv, json, png])
}

/// The CSV rows; an absent value is an empty field.
fn write_csv(w: &mut impl Write, frames: &[FrameScores]) -> std::io::Result<()> {
    writeln!(w, "{HEADER}")?;
    let field = |v: Option<String>| v.unwrap_or_default();
    for f in frames {
        let t = &f.train;
        let numbers = [
            f.tracking_rmse_over_size,
            f.tracking_max_over_size,
            Some(f.chamfer_over_size),
            t.psnr_gs_db,
            t.psnr_mesh_db,
        ];
        let numbers: Vec<String> =
            numbers.iter().map(|v| field(v.map(|v| v.to_string()))).collect();
        let reason = field(t.stop_reason.as_deref().map(quoted));
        writeln!(
            w,
            "{},{},{},{},{}",
            f.frame,
            numbers.join(","),
            field(t.iterations.map(|v| v.to_string())),
            field(t.wall_s.map(|v| v.to_string())),
            reason
        )?;
    }
    Ok(())
}

/// A CSV field that may hold commas, quotes or line breaks (RFC 4180 quoting).
fn quoted(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_owned()
    }
}

/// One panel: tracking RMSE / size and Chamfer / size against the frame, with a zero line.
fn draw_scores(frames: &[FrameScores]) -> RgbImage {
    // y grows downwards in the panel: negate the values.
    let curve = |value: &dyn Fn(&FrameScores) -> Option<f64>| {
        frames
            .iter()
            .filter_map(|f| Some(DVec2::new(f.frame as f64, -value(f)?)))
            .collect::<Vec<_>>()
    };
    let span = |f: Option<&FrameScores>| f.map_or(0.0, |f| f.frame as f64);
    let zero = vec![DVec2::new(span(frames.first()), 0.0), DVec2::new(span(frames.last()), 0.0)];
    let curves =
        [curve(&|f| f.tracking_rmse_over_size), curve(&|f| Some(f.chamfer_over_size)), zero];
    let mut image = RgbImage::from_pixel(PANEL, PANEL, BACKGROUND);
    draw_panel(&mut image, 0, &curves, false);
    image
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::score::FrameTrainStats;

    fn row(frame: usize, reason: Option<&str>) -> FrameScores {
        let train = FrameTrainStats {
            iterations: Some(50),
            stop_reason: reason.map(str::to_owned),
            ..Default::default()
        };
        FrameScores {
            frame,
            tracking_rmse_over_size: Some(0.5),
            tracking_max_over_size: None,
            chamfer_over_size: 0.25,
            chamfer_pred_to_gt_over_size: 0.2,
            chamfer_gt_to_pred_over_size: 0.3,
            train,
        }
    }

    #[test]
    fn csv_leaves_absent_values_empty_and_quotes_reasons() {
        let mut buf = Vec::new();
        write_csv(&mut buf, &[row(0, None), row(1, Some("loss rose, twice"))]).unwrap();
        let text = String::from_utf8(buf).unwrap();
        assert_eq!(
            text.lines().collect::<Vec<_>>(),
            [HEADER, "0,0.5,,0.25,,,50,,", "1,0.5,,0.25,,,50,,\"loss rose, twice\""]
        );
    }

    #[test]
    fn plot_survives_one_frame_and_no_frames() {
        for frames in [vec![], vec![row(0, None)], vec![row(0, None), row(3, None)]] {
            assert_eq!(draw_scores(&frames).dimensions(), (PANEL, PANEL));
        }
    }
}
