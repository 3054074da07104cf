//! An SVG of trajectories, with labelled axes and the points' ids in the legend.
//!
//! Left panel: every trajectory projected on the two world axes along which the points spread
//! most, equal scale on both. Right panel: each point's distance from its frame-0 position
//! against the frame index. One colour per point, the same in both panels.

use super::TrackError;
use crate::io::plot::{write_svg, Panel, Series};
use glam::DVec3;
use std::path::Path;

/// The two panels for `ids[i]` at `trajectories[i][t]` (point i in frame t).
pub fn trajectory_panels(ids: &[String], trajectories: &[Vec<DVec3>]) -> [Panel; 2] {
    let (a, b) = spread_axes(trajectories);
    let series = |point: &dyn Fn(&[DVec3]) -> Vec<[f64; 2]>| {
        let named = ids.iter().zip(trajectories);
        named.map(|(id, t)| Series { name: id.clone(), points: point(t) }).collect()
    };
    let axis = ["x", "y", "z"];
    let projected = Panel {
        title: format!("Trajectories on the {}{} plane", axis[a], axis[b]),
        x_label: format!("{} (scene units)", axis[a]),
        y_label: format!("{} (scene units)", axis[b]),
        series: series(&|t| t.iter().map(|p| [p[a], p[b]]).collect()),
        equal_scale: true,
    };
    let displacement = Panel {
        title: "Distance from the frame-0 position".into(),
        x_label: "frame".into(),
        y_label: "distance (scene units)".into(),
        series: series(&|t| {
            t.iter().enumerate().map(|(f, p)| [f as f64, p.distance(t[0])]).collect()
        }),
        equal_scale: false,
    };
    [projected, displacement]
}

/// Draws the plot and writes it as SVG, atomically.
pub fn write_plot(
    path: &Path,
    ids: &[String],
    trajectories: &[Vec<DVec3>],
) -> Result<(), TrackError> {
    write_svg(path, &trajectory_panels(ids, trajectories))
        .map_err(|error| TrackError::Io { path: path.to_owned(), error })
}

/// The two axes with the largest coordinate range over all points, in axis order.
fn spread_axes(trajectories: &[Vec<DVec3>]) -> (usize, usize) {
    let (mut min, mut max) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for p in trajectories.iter().flatten() {
        min = min.min(*p);
        max = max.max(*p);
    }
    let range = (max - min).max(DVec3::ZERO);
    let smallest = (0..3).min_by(|&i, &j| range[i].total_cmp(&range[j])).unwrap_or(2);
    match smallest {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::plot::svg;

    #[test]
    fn names_each_point_and_survives_degenerate_input() {
        let moving = vec![DVec3::ZERO, DVec3::new(1.0, 0.0, 0.0), DVec3::new(1.0, 1.0, 0.0)];
        let still = vec![DVec3::new(0.5, 0.5, 0.0); 3];
        let ids = ["nose".to_string(), "tail".to_string()];
        let text = svg(&trajectory_panels(&ids, &[moving, still]));
        assert!(text.contains("xy plane") && text.contains(">nose<") && text.contains(">tail<"));
        assert_eq!(text.matches("<polyline").count(), 4, "each point in both panels");
        // Nothing, one frame, NaN: no panic, and the axes are still drawn.
        let one = ["a".to_string()];
        for t in [vec![], vec![vec![DVec3::ONE]], vec![vec![DVec3::NAN, DVec3::ONE]]] {
            let text = svg(&trajectory_panels(&one[..t.len()], &t));
            assert!(text.contains(">frame<") && !text.contains("NaN"), "{text}");
        }
    }
}
