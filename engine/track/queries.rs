//! Query files: `points.csv` (`id,x,y,z`, frame-0 coordinates) and `pixels.csv` (`id,u,v`,
//! pixel coordinates, pixel (i, j) centred at (i + 0.5, j + 0.5)).
//!
//! Plain CSV: a header naming the columns (any order, extra columns ignored), one row per
//! point, no quoting (so an id cannot contain a comma or a quote). Blank lines and lines
//! starting with `#` are skipped. Ids must be unique.

use super::TrackError;
use std::collections::HashSet;
use std::path::Path;

/// Reads `id,x,y,z` rows.
pub fn read_points(path: &Path) -> Result<Vec<(String, [f64; 3])>, TrackError> {
    parse_id_table(&read_text(path)?, path, ["x", "y", "z"])
}

/// Reads `id,u,v` rows.
pub fn read_pixels(path: &Path) -> Result<Vec<(String, [f64; 2])>, TrackError> {
    parse_id_table(&read_text(path)?, path, ["u", "v"])
}

fn read_text(path: &Path) -> Result<String, TrackError> {
    std::fs::read_to_string(path).map_err(|error| TrackError::Io { path: path.to_owned(), error })
}

/// Parses a table with an `id` column and the numeric `columns`; `path` names the source in
/// errors. Errors: no header, a missing column, a short row, a bad or non-finite number, a
/// duplicate or invalid id, no rows.
pub fn parse_id_table<const N: usize>(
    text: &str,
    path: &Path,
    columns: [&str; N],
) -> Result<Vec<(String, [f64; N])>, TrackError> {
    let err =
        |line: usize, message: String| TrackError::Csv { path: path.to_owned(), line, message };
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let (header_line, header) = lines.next().ok_or_else(|| {
        err(1, format!("empty file; expected a header `id,{}`", columns.join(",")))
    })?;
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    let find = |name: &str| {
        names.iter().position(|n| n.eq_ignore_ascii_case(name)).ok_or_else(|| {
            err(
                header_line,
                format!(
                    "header `{header}` has no column `{name}`; expected `id,{}`",
                    columns.join(",")
                ),
            )
        })
    };
    let id_col = find("id")?;
    let mut cols = [0usize; N];
    for (c, name) in cols.iter_mut().zip(columns) {
        *c = find(name)?;
    }
    let mut seen = HashSet::new();
    let mut rows = Vec::new();
    for (line, row) in lines {
        let fields: Vec<&str> = row.split(',').map(str::trim).collect();
        if fields.len() < names.len() {
            return Err(err(
                line,
                format!("{} fields, the header has {}", fields.len(), names.len()),
            ));
        }
        let id = fields[id_col];
        if id.is_empty() || id.contains('"') {
            return Err(err(line, format!("invalid id `{id}` (empty or quoted)")));
        }
        if !seen.insert(id.to_owned()) {
            return Err(err(line, format!("duplicate id `{id}`")));
        }
        let mut values = [0.0; N];
        for ((value, &c), name) in values.iter_mut().zip(&cols).zip(columns) {
            *value = fields[c].parse::<f64>().ok().filter(|v| v.is_finite()).ok_or_else(|| {
                err(line, format!("`{}` is not a finite number for column `{name}`", fields[c]))
            })?;
        }
        rows.push((id.to_owned(), values));
    }
    if rows.is_empty() {
        return Err(err(header_line, "no rows after the header".into()));
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse3(text: &str) -> Result<Vec<(String, [f64; 3])>, TrackError> {
        parse_id_table(text, Path::new("points.csv"), ["x", "y", "z"])
    }

    #[test]
    fn reads_rows_in_any_column_order_with_comments_and_blank_lines() {
        let rows = parse3("# frame 0\nz, id ,x,y,extra\n\n3,nose,1,2.5,ignored\n-1e-3,chin,0,0,\n")
            .unwrap();
        assert_eq!(
            rows,
            vec![("nose".to_string(), [1.0, 2.5, 3.0]), ("chin".to_string(), [0.0, 0.0, -1e-3])]
        );
    }

    #[test]
    fn bad_input_names_the_file_and_line() {
        for (text, line, needle) in [
            ("", 1, "empty file"),
            ("id,x,y\n", 1, "no column `z`"),
            ("id,x,y,z\n", 1, "no rows"),
            ("id,x,y,z\na,1,2\n", 2, "3 fields, the header has 4"),
            ("id,x,y,z\na,1,2,zz\n", 2, "`zz` is not a finite number"),
            ("id,x,y,z\na,1,2,NaN\n", 2, "not a finite number"),
            ("id,x,y,z\na,1,2,3\n\na,4,5,6\n", 4, "duplicate id `a`"),
            ("id,x,y,z\n,1,2,3\n", 2, "invalid id"),
        ] {
            let e = parse3(text).unwrap_err().to_string();
            assert!(
                e.starts_with(&format!("points.csv: line {line}: ")) && e.contains(needle),
                "{text:?} -> {e}"
            );
        }
    }
}
