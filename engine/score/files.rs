//! The files of a sequence evaluation: `eval.csv` (one row per scored frame), `eval.json`
//! (frames and summary) and `eval.svg`, tracking RMSE and Chamfer (fractions of `size`) against
//! the frame, with labelled axes and a legend (see [`crate::io::plot`]).

use super::{FrameScores, SequenceEval, SequenceEvalError};
use crate::io::plot::{svg, Panel, Series};
use crate::io::{write_atomically, write_json_atomically};
use std::io::Write;
use std::path::{Path, PathBuf};

const HEADER: &str = "frame,tracking_rmse_over_size,tracking_max_over_size,tracking_off_surface_over_size,tracking_along_surface_over_size,tracking_seen_over_size,tracking_unseen_over_size,seen_share,tracking_rmse_px,chamfer_over_size,psnr_gs_db,psnr_mesh_db,iterations,wall_s,stop_reason";

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
    let (csv, json, plot) = (dir.join("eval.csv"), dir.join("eval.json"), dir.join("eval.svg"));
    write_atomically(&csv, |w| write_csv(w, &eval.frames)).map_err(io(&csv))?;
    write_json_atomically(&json, eval).map_err(io(&json))?;
    let text = svg(&[score_panel(&eval.frames)]);
    write_atomically(&plot, |w| w.write_all(text.as_bytes())).map_err(io(&plot))?;
    Ok(vec![csv, json, plot])
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
            f.tracking_off_surface_over_size,
            f.tracking_along_surface_over_size,
            f.sight.tracking_seen_over_size,
            f.sight.tracking_unseen_over_size,
            f.sight.seen_share,
            f.tracking_rmse_px,
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

/// Tracking RMSE / size, its part along the true surface, and Chamfer / size against the frame
/// (a frame without a value is a gap).
fn score_panel(frames: &[FrameScores]) -> Panel {
    let series = |name: &str, value: &dyn Fn(&FrameScores) -> Option<f64>| Series {
        name: name.into(),
        points: frames.iter().map(|f| [f.frame as f64, value(f).unwrap_or(f64::NAN)]).collect(),
    };
    Panel {
        title: "Error per frame".into(),
        x_label: "frame".into(),
        y_label: "fraction of the subject's size".into(),
        series: vec![
            series("tracking RMSE", &|f| f.tracking_rmse_over_size),
            series("tracking RMSE, along the surface", &|f| f.tracking_along_surface_over_size),
            series("Chamfer (point to surface)", &|f| Some(f.chamfer_over_size)),
        ],
        equal_scale: false,
    }
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
            tracking_off_surface_over_size: Some(0.3),
            tracking_along_surface_over_size: Some(0.4),
            sight: crate::score::SightScores { seen_share: Some(0.75), ..Default::default() },
            tracking_rmse_px: Some(1.5),
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
            [
                HEADER,
                "0,0.5,,0.3,0.4,,,0.75,1.5,0.25,,,50,,",
                "1,0.5,,0.3,0.4,,,0.75,1.5,0.25,,,50,,\"loss rose, twice\""
            ]
        );
    }

    #[test]
    fn plot_names_its_series_and_survives_one_frame_and_no_frames() {
        for frames in [vec![], vec![row(0, None)], vec![row(0, None), row(3, None)]] {
            let text = svg(&[score_panel(&frames)]);
            assert!(text.contains("tracking RMSE") && text.contains(">frame<"), "{text}");
        }
    }
}
