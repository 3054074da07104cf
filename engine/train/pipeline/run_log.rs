//! `OUT/run.log`: what every `train` run of an output folder did, appended line by line (start,
//! device, frames, config, resume point, each frame with its warnings, exports, the end or the
//! error), so a run that failed overnight can be read the next morning. Unlike every other
//! output it is appended to, not replaced: each line is complete when written, and a crash
//! loses at most the line being written.

use crate::train::TrainError;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{SystemTime, UNIX_EPOCH};

pub struct RunLog {
    path: PathBuf,
}

impl RunLog {
    /// The log of output folder `out` (created when missing).
    pub fn open(out: &Path) -> Result<Self, TrainError> {
        std::fs::create_dir_all(out)
            .map_err(|error| TrainError::Io { path: out.to_owned(), error })?;
        Ok(Self { path: out.join("run.log") })
    }

    /// Appends `text`, each of its lines prefixed with the UTC time.
    pub fn line(&self, text: &str) -> Result<(), TrainError> {
        let stamp = utc_timestamp(SystemTime::now());
        let block: String = text.lines().map(|l| format!("{stamp} {l}\n")).collect();
        std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(&self.path)
            .and_then(|mut file| file.write_all(block.as_bytes()))
            .map_err(|error| TrainError::Io { path: self.path.clone(), error })
    }
}

/// `YYYY-MM-DDTHH:MM:SSZ` (a time before 1970 prints as the epoch).
fn utc_timestamp(time: SystemTime) -> String {
    let seconds = time.duration_since(UNIX_EPOCH).map_or(0, |d| d.as_secs());
    let (days, rest) = (seconds / 86_400, seconds % 86_400);
    let (year, month, day) = civil_from_days(days as i64);
    let (h, m, s) = (rest / 3600, rest % 3600 / 60, rest % 60);
    format!("{year:04}-{month:02}-{day:02}T{h:02}:{m:02}:{s:02}Z")
}

/// The proleptic Gregorian date `days` after 1970-01-01 (Howard Hinnant's algorithm).
fn civil_from_days(days: i64) -> (i64, u32, u32) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let month = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    let year = yoe + era * 400 + (month <= 2) as i64;
    (year, month, day)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn timestamps_match_known_dates() {
        let at = |s| utc_timestamp(UNIX_EPOCH + Duration::from_secs(s));
        assert_eq!(at(0), "1970-01-01T00:00:00Z");
        // 2000-02-29 (a leap day of a year divisible by 400) and 2026-11-25 12:34:56.
        assert_eq!(at(951_782_400), "2000-02-29T00:00:00Z");
        assert_eq!(at(1_795_610_096), "2026-11-25T12:34:56Z");
    }

    #[test]
    fn appends_lines_with_their_time() {
        let dir = std::env::temp_dir().join(format!("tagsplat_run_log_{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let log = RunLog::open(&dir).unwrap();
        log.line("first").unwrap();
        log.line("second\nthird").unwrap();
        let text = std::fs::read_to_string(dir.join("run.log")).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 3);
        assert!(lines.iter().zip(["first", "second", "third"]).all(|(l, w)| l.ends_with(w)));
        assert!(lines[0].len() == "1970-01-01T00:00:00Z first".len() && lines[0].contains('T'));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
