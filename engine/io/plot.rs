//! Plots as SVG: text is drawn by whatever displays the file, so axis labels, tick values and
//! legends need no font here. One plot is a row of panels; a panel has a title, labelled axes
//! with "nice" tick values (steps of 1, 2 or 5 × 10^k) and one polyline per series, its name in
//! the legend. Non-finite points are left out (a gap in the line).

use super::write_atomically;
use std::fmt::Write as _;
use std::path::Path;

/// One named polyline, (x, y) in data units.
#[derive(Clone, Debug, Default)]
pub struct Series {
    /// Name in the legend.
    pub name: String,
    /// The points in order; non-finite ones leave a gap.
    pub points: Vec<[f64; 2]>,
}

/// One plot panel: a title, labelled axes and the series drawn in it.
#[derive(Clone, Debug, Default)]
pub struct Panel {
    /// Title above the plot area.
    pub title: String,
    /// Label of the x axis.
    pub x_label: String,
    /// Label of the y axis.
    pub y_label: String,
    /// The series, drawn in order with colours by index ([`colour`]).
    pub series: Vec<Series>,
    /// One data unit is as long on both axes (for positions in space).
    pub equal_scale: bool,
}

const WIDTH: f64 = 560.0;
const HEIGHT: f64 = 420.0;
/// Plot area inside a panel: left (tick values and y label), right, top (title), bottom.
const INSET: [f64; 4] = [78.0, 16.0, 34.0, 52.0];
/// Legend rows shown; more series are summarised in one line.
const LEGEND_ROWS: usize = 8;
const PALETTE: [[u8; 3]; 8] = [
    [0xd6, 0x27, 0x28],
    [0x1f, 0x77, 0xb4],
    [0x2c, 0xa0, 0x2c],
    [0xff, 0x7f, 0x0e],
    [0x94, 0x67, 0xbd],
    [0x8c, 0x56, 0x4b],
    [0xe3, 0x77, 0xc2],
    [0x17, 0xbe, 0xcf],
];

/// The colour of series `i` as 8-bit RGB, the same in every panel (and in `track`'s image
/// overlays).
pub fn colour_rgb(i: usize) -> [u8; 3] {
    PALETTE[i % PALETTE.len()]
}

/// The colour of series `i` as an SVG colour (`#rrggbb`).
pub fn colour(i: usize) -> String {
    let [r, g, b] = colour_rgb(i);
    format!("#{r:02x}{g:02x}{b:02x}")
}

/// Writes `panels` side by side as one SVG file, atomically.
pub fn write_svg(path: &Path, panels: &[Panel]) -> std::io::Result<()> {
    let svg = svg(panels);
    write_atomically(path, |w| std::io::Write::write_all(w, svg.as_bytes()))
}

/// The SVG text of `panels` side by side.
pub fn svg(panels: &[Panel]) -> String {
    let width = WIDTH * panels.len().max(1) as f64;
    let mut out = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{width}\" height=\"{HEIGHT}\" \
         viewBox=\"0 0 {width} {HEIGHT}\" font-family=\"sans-serif\" font-size=\"12\">\n\
         <rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
    );
    for (i, panel) in panels.iter().enumerate() {
        let _ = writeln!(out, "<g transform=\"translate({})\">", i as f64 * WIDTH);
        draw_panel(&mut out, panel);
        out += "</g>\n";
    }
    out + "</svg>\n"
}

/// Data ranges to pixels: `x0 + (x − min) · scale`, y upwards.
struct Frame {
    x: [f64; 2],
    y: [f64; 2],
    scale: [f64; 2],
}

impl Frame {
    fn new(panel: &Panel) -> Frame {
        let finite = || {
            panel.series.iter().flat_map(|s| &s.points).filter(|p| p.iter().all(|v| v.is_finite()))
        };
        let range = |k: usize| {
            let (lo, hi) = finite().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p[k]), hi.max(p[k]))
            });
            match (lo.is_finite(), hi - lo) {
                (false, _) => [0.0, 1.0],
                (true, span) if span <= f64::EPSILON * lo.abs().max(1.0) => [lo - 0.5, lo + 0.5],
                _ => [lo, hi],
            }
        };
        let (mut x, mut y) = (nice_range(range(0)), nice_range(range(1)));
        let area = [WIDTH - INSET[0] - INSET[1], HEIGHT - INSET[2] - INSET[3]];
        let mut scale = [area[0] / (x[1] - x[0]), area[1] / (y[1] - y[0])];
        if panel.equal_scale {
            let s = scale[0].min(scale[1]);
            let grow = |r: [f64; 2], length: f64| {
                let pad = (length / s - (r[1] - r[0])) / 2.0;
                [r[0] - pad, r[1] + pad]
            };
            (x, y, scale) = (grow(x, area[0]), grow(y, area[1]), [s, s]);
        }
        Frame { x, y, scale }
    }

    fn px(&self, p: [f64; 2]) -> (f64, f64) {
        (
            INSET[0] + (p[0] - self.x[0]) * self.scale[0],
            HEIGHT - INSET[3] - (p[1] - self.y[0]) * self.scale[1],
        )
    }
}

fn draw_panel(out: &mut String, panel: &Panel) {
    let frame = Frame::new(panel);
    let (left, top, right, bottom) = (INSET[0], INSET[2], WIDTH - INSET[1], HEIGHT - INSET[3]);
    let _ = writeln!(
        out,
        "<text x=\"{}\" y=\"22\" text-anchor=\"middle\" font-size=\"14\">{}</text>",
        (left + right) / 2.0,
        escape(&panel.title)
    );
    for x in ticks(frame.x) {
        let (px, _) = frame.px([x, frame.y[0]]);
        let _ = writeln!(out, "<line x1=\"{px:.1}\" y1=\"{top}\" x2=\"{px:.1}\" y2=\"{bottom}\" stroke=\"#e4e4e4\"/><text x=\"{px:.1}\" y=\"{}\" text-anchor=\"middle\">{}</text>", bottom + 16.0, tick_label(x));
    }
    for y in ticks(frame.y) {
        let (_, py) = frame.px([frame.x[0], y]);
        let _ = writeln!(out, "<line x1=\"{left}\" y1=\"{py:.1}\" x2=\"{right}\" y2=\"{py:.1}\" stroke=\"#e4e4e4\"/><text x=\"{}\" y=\"{:.1}\" text-anchor=\"end\">{}</text>", left - 6.0, py + 4.0, tick_label(y));
    }
    let _ = writeln!(
        out,
        "<rect x=\"{left}\" y=\"{top}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"#777\"/>",
        right - left,
        bottom - top
    );
    let _ = writeln!(
        out,
        "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{}</text>",
        (left + right) / 2.0,
        HEIGHT - 12.0,
        escape(&panel.x_label)
    );
    let _ = writeln!(
        out,
        "<text transform=\"translate(16 {}) rotate(-90)\" text-anchor=\"middle\">{}</text>",
        (top + bottom) / 2.0,
        escape(&panel.y_label)
    );
    for (i, series) in panel.series.iter().enumerate() {
        draw_series(out, &frame, series, &colour(i));
    }
    draw_legend(out, &panel.series, right);
}

/// The series as polylines broken at non-finite points.
fn draw_series(out: &mut String, frame: &Frame, series: &Series, colour: &str) {
    for run in series.points.split(|p| !p.iter().all(|v| v.is_finite())).filter(|r| !r.is_empty()) {
        let points: Vec<String> =
            run.iter().map(|&p| frame.px(p)).map(|(x, y)| format!("{x:.1},{y:.1}")).collect();
        let _ = writeln!(
            out,
            "<polyline points=\"{}\" fill=\"none\" stroke=\"{colour}\" stroke-width=\"1.5\"/>",
            points.join(" ")
        );
    }
}

fn draw_legend(out: &mut String, series: &[Series], right: f64) {
    let shown = series.len().min(LEGEND_ROWS);
    let mut rows: Vec<(String, Option<String>)> = series[..shown]
        .iter()
        .enumerate()
        .map(|(i, s)| (escape(&s.name), Some(colour(i))))
        .collect();
    if series.len() > shown {
        rows.push((format!("… {} more", series.len() - shown), None));
    }
    if !rows.is_empty() {
        // A light backing keeps the legend readable over the curves.
        let height = 16.0 * rows.len() as f64 + 8.0;
        let _ = writeln!(out, "<rect x=\"{}\" y=\"{}\" width=\"146\" height=\"{height}\" fill=\"white\" fill-opacity=\"0.85\" stroke=\"#ccc\"/>", right - 154.0, INSET[2] + 4.0);
    }
    for (row, (name, colour)) in rows.iter().enumerate() {
        let y = INSET[2] + 16.0 + 16.0 * row as f64;
        if let Some(colour) = colour {
            let _ = writeln!(out, "<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke=\"{colour}\" stroke-width=\"3\"/>", right - 150.0, y - 4.0, right - 134.0, y - 4.0);
        }
        let _ = writeln!(out, "<text x=\"{}\" y=\"{y}\">{name}</text>", right - 128.0);
    }
}

/// `[lo, hi]` widened to whole tick steps.
fn nice_range([lo, hi]: [f64; 2]) -> [f64; 2] {
    let step = tick_step(hi - lo);
    [(lo / step).floor() * step, (hi / step).ceil() * step]
}

/// A 1-2-5 step giving about five intervals over `span` (> 0).
fn tick_step(span: f64) -> f64 {
    let rough = span / 5.0;
    let power = 10f64.powf(rough.log10().floor());
    let mantissa = [1.0, 2.0, 5.0, 10.0].into_iter().find(|m| m * power >= rough).unwrap_or(10.0);
    mantissa * power
}

/// Tick values inside `range`, at multiples of its step.
fn ticks(range: [f64; 2]) -> Vec<f64> {
    let step = tick_step(range[1] - range[0]);
    let first = (range[0] / step - 1e-9).ceil() as i64;
    let last = (range[1] / step + 1e-9).floor() as i64;
    (first..=last).map(|k| k as f64 * step).collect()
}

/// A tick value with as many decimals as its size needs, shortest form.
fn tick_label(v: f64) -> String {
    let v = if v.abs() < 1e-12 { 0.0 } else { v };
    let text = format!("{:.6}", v);
    let text = text.trim_end_matches('0').trim_end_matches('.');
    if v != 0.0 && (v.abs() >= 1e6 || v.abs() < 1e-4) {
        format!("{v:.1e}")
    } else {
        text.to_owned()
    }
}

/// `text` safe inside XML or HTML text and attribute values.
pub(crate) fn escape(text: &str) -> String {
    text.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_round_steps_inside_the_range() {
        assert_eq!(tick_step(10.0), 2.0);
        assert_eq!(tick_step(0.07), 0.02);
        assert_eq!(tick_step(900.0), 200.0);
        assert_eq!(nice_range([0.13, 0.87]), [0.0, 1.0]);
        assert_eq!(ticks([0.0, 1.0]), [0.0, 0.2, 0.4, 0.6000000000000001, 0.8, 1.0]);
        assert_eq!(tick_label(0.6000000000000001), "0.6");
        assert_eq!(
            (tick_label(-0.0), tick_label(25.0), tick_label(3e-6)),
            ("0".into(), "25".into(), "3.0e-6".into())
        );
    }

    #[test]
    fn a_plot_has_its_title_labels_ticks_and_legend_as_text() {
        let series = |name: &str, k: f64| Series {
            name: name.into(),
            points: (0..10).map(|t| [t as f64, k * t as f64]).chain([[f64::NAN, 0.0]]).collect(),
        };
        let panel = Panel {
            title: "Error per frame".into(),
            x_label: "frame".into(),
            y_label: "RMSE / size".into(),
            series: vec![series("tracking <RMSE>", 0.01), series("Chamfer", 0.02)],
            equal_scale: false,
        };
        let text = svg(&[panel.clone(), Panel { equal_scale: true, ..panel }]);
        for expected in [
            "Error per frame",
            ">frame<",
            "RMSE / size",
            "tracking &lt;RMSE&gt;",
            "Chamfer",
            ">0.15<",
            ">8<",
        ] {
            assert!(text.contains(expected), "{expected} missing");
        }
        assert_eq!(text.matches("<polyline").count(), 4);
        assert!(text.starts_with("<svg") && text.trim_end().ends_with("</svg>"));
        assert!(!text.contains("NaN") && !text.contains("inf"));
    }

    #[test]
    fn empty_and_flat_data_still_give_a_frame() {
        let flat = Series { name: "flat".into(), points: vec![[1.0, 5.0], [2.0, 5.0]] };
        let text = svg(&[Panel { series: vec![flat], ..Default::default() }, Panel::default()]);
        assert!(text.contains(">5<") && !text.contains("NaN"), "{text}");
    }

    #[test]
    fn a_long_legend_is_summarised() {
        let series: Vec<Series> = (0..20)
            .map(|i| Series { name: format!("p{i}"), points: vec![[0.0, 0.0], [1.0, i as f64]] })
            .collect();
        let text = svg(&[Panel { series, ..Default::default() }]);
        assert!(text.contains(">p7<") && !text.contains(">p8<") && text.contains("… 12 more"));
    }
}
