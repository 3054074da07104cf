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
    let expected = format!("id,{}", columns.join(","));
    let table = Table::parse(text, path, &expected)?;
    let mut cols = [0usize; N];
    for (c, name) in cols.iter_mut().zip(columns) {
        *c = table.require(name)?;
    }
    table
        .rows()?
        .into_iter()
        .map(|row| {
            let mut values = [0.0; N];
            for (value, (&c, name)) in values.iter_mut().zip(cols.iter().zip(columns)) {
                *value = row.number(c, name)?;
            }
            Ok((row.id.to_owned(), values))
        })
        .collect()
}

/// A CSV table as the module describes it: the header's column names and the rows after it.
pub(crate) struct Table<'a> {
    path: &'a Path,
    expected: &'a str,
    header_line: usize,
    header: &'a str,
    names: Vec<&'a str>,
    lines: Vec<(usize, &'a str)>,
}

/// One row of a [`Table`]: its line (from 1), its unique id and its fields.
pub(crate) struct Row<'a> {
    path: &'a Path,
    pub line: usize,
    pub id: &'a str,
    fields: Vec<&'a str>,
}

impl<'a> Table<'a> {
    /// The header and the rows of `text`; `expected` is the header the errors suggest.
    /// Errors: no header.
    pub fn parse(text: &'a str, path: &'a Path, expected: &'a str) -> Result<Self, TrackError> {
        let mut lines = text
            .lines()
            .enumerate()
            .map(|(i, l)| (i + 1, l.trim()))
            .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
        let (header_line, header) = lines.next().ok_or_else(|| {
            csv_error(path, 1, format!("empty file; expected a header `{expected}`"))
        })?;
        let names = header.split(',').map(str::trim).collect();
        Ok(Table { path, expected, header_line, header, names, lines: lines.collect() })
    }

    /// The index of column `name` (case-insensitive), if the header has it.
    pub fn column(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n.eq_ignore_ascii_case(name))
    }

    /// The index of column `name`; an error naming the header when it lacks it.
    pub fn require(&self, name: &str) -> Result<usize, TrackError> {
        self.column(name).ok_or_else(|| {
            let (header, expected) = (self.header, self.expected);
            let message =
                format!("header `{header}` has no column `{name}`; expected `{expected}`");
            csv_error(self.path, self.header_line, message)
        })
    }

    /// An error on the header line.
    pub fn header_error(&self, message: String) -> TrackError {
        csv_error(self.path, self.header_line, message)
    }

    /// Every row, its id checked. Errors: an id column missing, a row with fewer fields than
    /// the header, an empty, quoted or repeated id, no rows.
    pub fn rows(&self) -> Result<Vec<Row<'a>>, TrackError> {
        let id_col = self.require("id")?;
        let mut seen = HashSet::new();
        let mut rows = Vec::with_capacity(self.lines.len());
        for &(line, text) in &self.lines {
            let fields: Vec<&str> = text.split(',').map(str::trim).collect();
            let err = |message: String| csv_error(self.path, line, message);
            if fields.len() < self.names.len() {
                let (found, expected) = (fields.len(), self.names.len());
                return Err(err(format!("{found} fields, the header has {expected}")));
            }
            let id = fields[id_col];
            if id.is_empty() || id.contains('"') {
                return Err(err(format!("invalid id `{id}` (empty or quoted)")));
            }
            if !seen.insert(id) {
                return Err(err(format!("duplicate id `{id}`")));
            }
            rows.push(Row { path: self.path, line, id, fields });
        }
        if rows.is_empty() {
            return Err(self.header_error("no rows after the header".into()));
        }
        Ok(rows)
    }
}

impl Row<'_> {
    /// The field of column `c`, trimmed (the row has every column of the header).
    pub fn field(&self, c: usize) -> &str {
        self.fields[c]
    }

    /// An error on this row's line.
    pub fn error(&self, message: String) -> TrackError {
        csv_error(self.path, self.line, message)
    }

    /// The field of column `c` (called `name`) as a finite number.
    pub fn number(&self, c: usize, name: &str) -> Result<f64, TrackError> {
        let text = self.field(c);
        text.parse::<f64>().ok().filter(|v| v.is_finite()).ok_or_else(|| {
            self.error(format!("`{text}` is not a finite number for column `{name}`"))
        })
    }

    /// The field of column `c` (called `name`) as an index (an unsigned 32-bit integer).
    pub fn index(&self, c: usize, name: &str) -> Result<u32, TrackError> {
        let text = self.field(c);
        text.parse::<u32>().map_err(|_| {
            self.error(format!("`{text}` is not an index (0 to 4294967295) for column `{name}`"))
        })
    }
}

fn csv_error(path: &Path, line: usize, message: String) -> TrackError {
    TrackError::Csv { path: path.to_owned(), line, message }
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
