//! A folder of per-frame mesh files: which files are frames, and in what order.
//!
//! Frames are the visible `.ply` or `.obj` files (never both kinds) in natural order
//! (`frame_2` before `frame_10`). When every name is one template with a number in it
//! (`walk_0007.ply`), the numbers must run without a gap or a repeat, so a missing frame file
//! is an error rather than a silent jump in time.

use super::SequenceError;
use std::cmp::Ordering;
use std::path::{Path, PathBuf};

/// The file kinds a folder frame can be.
pub const FRAME_EXTENSIONS: [&str; 2] = ["ply", "obj"];

/// The frame files of `dir`, in order. Errors: unreadable folder, no frame files, both PLY
/// and OBJ files, a gap or a repeat in the frame numbers.
pub fn frame_files(dir: &Path) -> Result<Vec<PathBuf>, SequenceError> {
    let invalid = |problem: String| SequenceError::Invalid { path: dir.to_path_buf(), problem };
    let mut names = frame_names(dir)?;
    if names.is_empty() {
        return Err(invalid("no .ply or .obj frame files".into()));
    }
    let first_ext = frame_extension(&names[0]);
    if let Some(other) = names.iter().find(|n| frame_extension(n) != first_ext) {
        return Err(invalid(format!(
            "has both {} and {other}: keep one kind of frame file",
            names[0]
        )));
    }
    names.sort_by(|a, b| natural_cmp(a, b));
    check_numbering(&names).map_err(invalid)?;
    Ok(names.into_iter().map(|n| dir.join(n)).collect())
}

/// Names of the visible `.ply` / `.obj` files in `dir`, unordered.
pub fn frame_names(dir: &Path) -> Result<Vec<String>, SequenceError> {
    let invalid = |e: std::io::Error| SequenceError::Invalid {
        path: dir.to_path_buf(),
        problem: format!("cannot list the folder: {e}"),
    };
    let mut names = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(invalid)? {
        let entry = entry.map_err(invalid)?;
        let name = entry.file_name().to_string_lossy().into_owned();
        if !name.starts_with('.') && frame_extension(&name).is_some() && entry.path().is_file() {
            names.push(name);
        }
    }
    Ok(names)
}

/// The lower-case frame extension of `name`, if it has one of [`FRAME_EXTENSIONS`].
pub fn frame_extension(name: &str) -> Option<&'static str> {
    let ext = Path::new(name).extension()?.to_str()?.to_ascii_lowercase();
    FRAME_EXTENSIONS.into_iter().find(|e| *e == ext)
}

/// Natural order: runs of digits compare as numbers (then shorter first, so `2` < `02`),
/// everything else byte by byte.
pub fn natural_cmp(a: &str, b: &str) -> Ordering {
    let (a, b) = (a.as_bytes(), b.as_bytes());
    let (mut i, mut j) = (0, 0);
    while i < a.len() && j < b.len() {
        if a[i].is_ascii_digit() && b[j].is_ascii_digit() {
            let (ra, rb) = (digit_run(&a[i..]), digit_run(&b[j..]));
            let (ta, tb) = (trim_zeros(ra), trim_zeros(rb));
            let order = ta
                .len()
                .cmp(&tb.len())
                .then_with(|| ta.cmp(tb))
                .then_with(|| ra.len().cmp(&rb.len()));
            if order != Ordering::Equal {
                return order;
            }
            (i, j) = (i + ra.len(), j + rb.len());
        } else {
            if a[i] != b[j] {
                return a[i].cmp(&b[j]);
            }
            (i, j) = (i + 1, j + 1);
        }
    }
    (a.len() - i).cmp(&(b.len() - j))
}

fn digit_run(s: &[u8]) -> &[u8] {
    &s[..s.iter().position(|c| !c.is_ascii_digit()).unwrap_or(s.len())]
}

fn trim_zeros(s: &[u8]) -> &[u8] {
    &s[s.iter().position(|&c| c != b'0').unwrap_or(s.len())..]
}

/// With one shared template (text, number, text), consecutive names must be consecutive
/// numbers. Names without a shared template are not checked.
fn check_numbering(sorted: &[String]) -> Result<(), String> {
    let parts: Option<Vec<(&str, u64, &str)>> = sorted.iter().map(|n| template(n)).collect();
    let Some(parts) = parts else { return Ok(()) };
    if parts.iter().any(|p| (p.0, p.2) != (parts[0].0, parts[0].2)) {
        return Ok(());
    }
    for (k, pair) in parts.windows(2).enumerate() {
        let (a, b) = (pair[0].1, pair[1].1);
        if b == a {
            return Err(format!("{} and {} are both frame {a}", sorted[k], sorted[k + 1]));
        }
        if b != a + 1 {
            return Err(format!(
                "frame file(s) {}..{} missing between {} and {}",
                a + 1,
                b - 1,
                sorted[k],
                sorted[k + 1]
            ));
        }
    }
    Ok(())
}

/// (text before, number, text after) of the last digit run of `name`.
fn template(name: &str) -> Option<(&str, u64, &str)> {
    let end = name.rfind(|c: char| c.is_ascii_digit())? + 1;
    let start = name[..end].rfind(|c: char| !c.is_ascii_digit()).map_or(0, |i| i + 1);
    Some((&name[..start], name[start..end].parse().ok()?, &name[end..]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn natural_order_puts_2_before_10() {
        let mut names = vec!["f10.ply", "f2.ply", "f1.ply", "f02.ply", "a.ply", "f.ply", "g1.ply"];
        names.sort_by(|a, b| natural_cmp(a, b));
        assert_eq!(
            names,
            vec!["a.ply", "f.ply", "f1.ply", "f2.ply", "f02.ply", "f10.ply", "g1.ply"]
        );
    }

    #[test]
    fn numbering_gaps_and_repeats_are_named() {
        let names = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        assert!(check_numbering(&names(&["m_8.obj", "m_9.obj", "m_10.obj"])).is_ok());
        assert_eq!(
            check_numbering(&names(&["m_1.obj", "m_2.obj", "m_4.obj"])).unwrap_err(),
            "frame file(s) 3..3 missing between m_2.obj and m_4.obj"
        );
        assert_eq!(
            check_numbering(&names(&["m_1.obj", "m_01.obj"])).unwrap_err(),
            "m_1.obj and m_01.obj are both frame 1"
        );
        // No shared template: order only.
        assert!(check_numbering(&names(&["rest.obj", "walk_1.obj", "walk_5.obj"])).is_ok());
    }
}
