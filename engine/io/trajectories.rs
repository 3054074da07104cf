//! The trajectory CSV shared by the tracker, the generator and `eval`: a header line
//! `id,frame,x,y,z`, then one row per point and frame (id a non-empty name without commas or
//! quotes, as the tracker writes it; frame an unsigned integer; positions in scene units). Rows
//! may come in any order; an (id, frame) pair appears once. The header may name more columns
//! after these (the tracker's `tracks.csv` adds orientation and clock columns): every row then
//! has as many fields as the header, and the reader reads the first five.

use std::collections::HashSet;
use std::io::Write;
use std::path::{Path, PathBuf};

/// A trajectory CSV that cannot be read; names the file (and the line).
#[derive(Debug, thiserror::Error)]
pub enum TrajectoriesError {
    /// A line is malformed, has a non-finite coordinate, or repeats an (id, frame) pair.
    #[error("{}: line {line}: {problem}", path.display())]
    Csv {
        /// The file.
        path: PathBuf,
        /// The line, counted from 1.
        line: usize,
        /// What is wrong with it.
        problem: String,
    },
    /// The file cannot be read.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
}

/// One point of a trajectory: point `id` at `frame`.
#[derive(Clone, Debug, PartialEq)]
pub struct TrackPoint {
    /// Name of the point: non-empty, without commas or quotes.
    pub id: String,
    /// Frame index.
    pub frame: u32,
    /// Position, scene units.
    pub position: [f64; 3],
}

const HEADER: &str = "id,frame,x,y,z";

/// Writes the CSV (header and rows in the given order) with shortest round-trip floats.
pub fn write_trajectories_csv(out: &mut impl Write, points: &[TrackPoint]) -> std::io::Result<()> {
    writeln!(out, "{HEADER}")?;
    for p in points {
        writeln!(
            out,
            "{},{},{},{},{}",
            p.id, p.frame, p.position[0], p.position[1], p.position[2]
        )?;
    }
    Ok(())
}

/// Reads the CSV at `path`. Every malformed line, non-finite coordinate or repeated
/// (id, frame) pair is an error naming the file and the line.
pub fn read_trajectories_csv(path: &Path) -> Result<Vec<TrackPoint>, TrajectoriesError> {
    let text = std::fs::read_to_string(path)
        .map_err(|source| TrajectoriesError::Io { path: path.to_owned(), source })?;
    parse_trajectories_csv(&text).map_err(|(line, problem)| TrajectoriesError::Csv {
        path: path.to_owned(),
        line,
        problem,
    })
}

/// Parses CSV text; errors carry the 1-based line number.
pub fn parse_trajectories_csv(text: &str) -> Result<Vec<TrackPoint>, (usize, String)> {
    let mut lines = text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty());
    let columns = match lines.next() {
        Some((_, h)) if is_header(h) => h.split(',').count(),
        Some((i, h)) => {
            return Err((i + 1, format!("expected the header `{HEADER}`, found `{h}`")))
        }
        None => return Err((1, format!("empty file, expected the header `{HEADER}`"))),
    };
    let mut seen = HashSet::new();
    let mut points = Vec::new();
    for (i, line) in lines {
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        if fields.len() != columns {
            return Err((i + 1, format!("expected {columns} fields, found {}", fields.len())));
        }
        let id = fields[0];
        if id.is_empty() || id.contains('"') {
            return Err((i + 1, format!("invalid id `{id}` (empty or quoted)")));
        }
        let frame: u32 = fields[1]
            .parse()
            .map_err(|_| (i + 1, format!("frame `{}` is not an unsigned integer", fields[1])))?;
        let mut position = [0.0; 3];
        for (k, p) in position.iter_mut().enumerate() {
            *p = fields[2 + k]
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or((i + 1, format!("coordinate `{}` is not a finite number", fields[2 + k])))?;
        }
        if !seen.insert((id.to_owned(), frame)) {
            return Err((i + 1, format!("point {id} at frame {frame} appears twice")));
        }
        points.push(TrackPoint { id: id.to_owned(), frame, position });
    }
    Ok(points)
}

/// `id,frame,x,y,z` (spaces around names allowed), perhaps followed by more named columns.
fn is_header(line: &str) -> bool {
    let names: Vec<String> = line.split(',').map(|n| n.trim().to_owned()).collect();
    names.len() >= 5 && names[..5].join(",") == HEADER && names[5..].iter().all(|n| !n.is_empty())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_errors() {
        let pts = vec![
            TrackPoint { id: "3".into(), frame: 0, position: [0.1, -2.5e-7, 1.0 / 3.0] },
            TrackPoint { id: "nose".into(), frame: 1, position: [1e10, 0.0, -0.0] },
        ];
        let mut buf = Vec::new();
        write_trajectories_csv(&mut buf, &pts).unwrap();
        assert_eq!(parse_trajectories_csv(std::str::from_utf8(&buf).unwrap()).unwrap(), pts);
        assert_eq!(parse_trajectories_csv("x,y\n").unwrap_err().0, 1);
        assert_eq!(parse_trajectories_csv("id,frame,x,y,z\n1,0,1,2\n").unwrap_err().0, 2);
        assert_eq!(parse_trajectories_csv("id,frame,x,y,z\n1,0,1,2,nan\n").unwrap_err().0, 2);
        assert_eq!(
            parse_trajectories_csv("id,frame,x,y,z\n1,0,1,2,3\n\n1,0,1,2,3\n").unwrap_err().0,
            4
        );
        assert_eq!(parse_trajectories_csv("id,frame,x,y,z\n,0,1,2,3\n").unwrap_err().0, 2);
        assert_eq!(parse_trajectories_csv("id,frame,x,y,z\na,-1,1,2,3\n").unwrap_err().0, 2);
        assert!(parse_trajectories_csv("").is_err());
        // The tracker's columns after the five are read past; every row has them all.
        let wide = "id,frame,x,y,z,nx,fps\nnose,1,1e10,0,-0,0,24\n3,0,0.1,-2.5e-7,0.3333333333333333,1,24\n";
        let read = parse_trajectories_csv(wide).unwrap();
        assert_eq!(read[0], pts[1]);
        assert_eq!(read[1].position, pts[0].position);
        let short = "id,frame,x,y,z,nx\n1,0,1,2,3\n";
        assert_eq!(
            parse_trajectories_csv(short).unwrap_err(),
            (2, "expected 6 fields, found 5".into())
        );
        assert_eq!(parse_trajectories_csv("id,frame,x,y,z,\n1,0,1,2,3,\n").unwrap_err().0, 1);
    }
}
