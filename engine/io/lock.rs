//! An output folder's lock: one writer at a time, released when its holder ends however it
//! ends (a crash or a kill included), because the operating system drops it with the file.

use std::fs::{File, OpenOptions, TryLockError};
use std::path::{Path, PathBuf};

/// Why a folder's lock could not be taken.
#[derive(Debug, thiserror::Error)]
pub enum LockError {
    /// Another holder has it: a run into the same folder, in this process or another.
    #[error("{} is in use by another run (it holds {}); wait for it to end or write elsewhere", folder.display(), lock.display())]
    Held {
        /// The folder.
        folder: PathBuf,
        /// Its lock file.
        lock: PathBuf,
    },
    /// The folder or its lock file could not be made or locked.
    #[error("cannot lock {}: {error}", lock.display())]
    Io {
        /// The lock file.
        lock: PathBuf,
        /// The I/O error.
        #[source]
        error: std::io::Error,
    },
}

/// The exclusive lock on a folder (`FOLDER/.lock`, an advisory lock on that file), held until
/// dropped. The file itself stays behind: removing it would let a second holder lock a file
/// that a third no longer sees.
#[derive(Debug)]
pub struct OutputLock {
    _file: File,
}

impl OutputLock {
    /// Makes `folder` if missing and takes its lock, or says who holds it. Never blocks.
    pub fn take(folder: &Path) -> Result<Self, LockError> {
        let lock = folder.join(".lock");
        let io = |error| LockError::Io { lock: lock.clone(), error };
        std::fs::create_dir_all(folder).map_err(io)?;
        let file = OpenOptions::new().create(true).truncate(false).write(true).open(&lock);
        let file = file.map_err(io)?;
        match file.try_lock() {
            Ok(()) => Ok(Self { _file: file }),
            Err(TryLockError::WouldBlock) => {
                Err(LockError::Held { folder: folder.to_owned(), lock: lock.clone() })
            }
            Err(TryLockError::Error(error)) => Err(io(error)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_holder_is_refused_until_the_first_lets_go() {
        let folder = std::env::temp_dir().join(format!("tagsplat-lock-{}", std::process::id()));
        let first = OutputLock::take(&folder).unwrap();
        let refused = OutputLock::take(&folder).unwrap_err().to_string();
        assert!(refused.contains("in use by another run"), "{refused}");
        drop(first);
        OutputLock::take(&folder).unwrap();
        std::fs::remove_dir_all(&folder).unwrap();
    }
}
