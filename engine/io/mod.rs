//! File formats and the one way this project writes files.
//!
//! - [`ply`]: generic PLY (ascii and binary in, binary little-endian out).
//! - [`image`]: PNG / EXR as float arrays.
//! - [`host`]: work spread over the host's threads, the process's peak memory.
//! - [`pc2`] and [`mdd`]: the point-cache containers; [`trajectories`]: the trajectory CSV.
//! - [`ogawa`]: the container of Alembic files.
//! - [`write_atomically`]: every output goes to a temporary name and is renamed into place, so a
//!   crash never leaves a half-written file behind.

pub mod host;
pub mod image;
pub mod lock;
pub mod mdd;
pub mod ogawa;
pub mod pc2;
pub mod plot;
pub mod ply;
pub mod resample;
pub mod trajectories;

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Writes `path` through `write` into a temporary file beside it, then renames it into place.
/// On any error the temporary file is removed and `path` is left as it was.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let temporary = temporary_name(path);
    let result = File::create(&temporary).and_then(|file| {
        let mut writer = BufWriter::new(file);
        write(&mut writer)?;
        writer.flush()?;
        writer.get_ref().sync_all()
    });
    let result = result.and_then(|()| std::fs::rename(&temporary, path));
    if result.is_err() {
        let _ = std::fs::remove_file(&temporary);
    }
    result
}

/// Writes `value` to `path` as pretty JSON and a newline, atomically ([`write_atomically`]).
pub fn write_json_atomically<T: serde::Serialize + ?Sized>(
    path: &Path,
    value: &T,
) -> std::io::Result<()> {
    write_atomically(path, |w| {
        serde_json::to_writer_pretty(&mut *w, value)?;
        writeln!(w)
    })
}

/// `dir/.name.tmp-<pid>`: same directory (so the rename is atomic), hidden, unique per process.
fn temporary_name(path: &Path) -> PathBuf {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    path.with_file_name(format!(".{name}.tmp-{}", std::process::id()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failed_write_leaves_nothing() {
        let dir = std::env::temp_dir().join(format!("tagsplat-atomic-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("out.txt");
        std::fs::write(&path, "old").unwrap();
        let failed = write_atomically(&path, |w| {
            w.write_all(b"half")?;
            Err(std::io::Error::other("interrupted"))
        });
        assert!(failed.is_err());
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "old");
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1, "temporary file left behind");
        write_atomically(&path, |w| w.write_all(b"new")).unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "new");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
