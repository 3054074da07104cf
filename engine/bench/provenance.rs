//! Where a measured figure came from: the command line, the source commit, the date, the
//! Vulkan device and driver, and the host CPU. Every `--json` result the command-line program
//! writes carries one, so a figure copied out of a result file can be traced and rerun.

use crate::gpu::DeviceInfo;
use serde::{Deserialize, Serialize};
use std::time::{SystemTime, UNIX_EPOCH};

/// What a result file says about the run that measured it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Provenance {
    /// The command line, the program named `tagsplat` whatever path started it.
    pub command: String,
    /// `git describe --always` of the source checkout the program was built from, `-dirty`
    /// when a source file differs from it, read when it runs ("unknown" outside a checkout or
    /// without git).
    pub commit: String,
    /// When the run ended, UTC, ISO 8601 to the second.
    pub date: String,
    /// The Vulkan device's name ("none (host only)" for a measurement without one).
    pub device: String,
    /// The driver's name and version ("none" without a device).
    pub driver: String,
    /// The host CPU: model, hardware threads, and whether it has AVX-512 (lavapipe's subgroup
    /// size and speed follow it).
    pub host: String,
}

impl Provenance {
    /// The provenance of this process's run on `device` (None: the host alone), dated now.
    pub fn of_run(device: Option<&DeviceInfo>) -> Self {
        let mut args = std::env::args();
        let command = std::iter::once("tagsplat".to_owned())
            .chain(args.by_ref().skip(1))
            .collect::<Vec<_>>()
            .join(" ");
        Self {
            command,
            commit: source_commit().unwrap_or_else(|| "unknown".into()),
            date: utc_date_time(SystemTime::now()),
            device: device.map_or_else(|| "none (host only)".into(), |d| d.name.clone()),
            driver: device.map_or_else(|| "none".into(), |d| d.driver.clone()),
            host: host_description(),
        }
    }
}

/// `git describe --always` in the crate's source folder, with `-dirty` when a file other than
/// the measurements' own outputs (`benches/results/`, the README's table) differs from the
/// commit, so a script recording several results in a row names the commit it measured. None
/// when git or the checkout is missing, as for a crate built from a registry.
fn source_commit() -> Option<String> {
    let git = |args: &[&str]| {
        let out = std::process::Command::new("git")
            .args(["-C", env!("CARGO_MANIFEST_DIR")])
            .args(args)
            .output()
            .ok()?;
        out.status.success().then(|| String::from_utf8(out.stdout).ok()).flatten()
    };
    let commit = git(&["describe", "--always", "--abbrev=7"])?.trim().to_owned();
    let changes = git(&["status", "--porcelain", "--", ".", ":!benches/results", ":!README.md"])?;
    let dirty = if changes.trim().is_empty() { "" } else { "-dirty" };
    (!commit.is_empty()).then(|| format!("{commit}{dirty}"))
}

/// The first `model name` of /proc/cpuinfo (None elsewhere or when unreadable).
pub fn host_cpu_model() -> Option<String> {
    let text = std::fs::read_to_string("/proc/cpuinfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("model name"))?;
    Some(line.split_once(':')?.1.trim().to_owned())
}

/// "AMD EPYC 7B13, 2 threads, no AVX-512": the CPU model, the threads this process may use,
/// and whether the CPU has AVX-512 (when /proc/cpuinfo says).
pub fn host_description() -> String {
    let model = host_cpu_model().unwrap_or_else(|| "unknown CPU".into());
    let threads = std::thread::available_parallelism().map_or(0, |n| n.get());
    let flags = std::fs::read_to_string("/proc/cpuinfo").ok().and_then(|text| {
        let line = text.lines().find(|l| l.starts_with("flags"))?.to_owned();
        Some(line.split_whitespace().any(|f| f == "avx512f"))
    });
    match flags {
        Some(true) => format!("{model}, {threads} threads, AVX-512"),
        Some(false) => format!("{model}, {threads} threads, no AVX-512"),
        None => format!("{model}, {threads} threads"),
    }
}

/// `time` as `YYYY-MM-DDTHH:MM:SSZ` (UTC; the epoch for a time before it).
pub fn utc_date_time(time: SystemTime) -> String {
    let seconds = time.duration_since(UNIX_EPOCH).map_or(0, |d| d.as_secs());
    let (days, second_of_day) = (seconds / 86_400, seconds % 86_400);
    let (year, month, day) = civil_from_days(days as i64);
    let (h, m, s) = (second_of_day / 3600, second_of_day / 60 % 60, second_of_day % 60);
    format!("{year:04}-{month:02}-{day:02}T{h:02}:{m:02}:{s:02}Z")
}

/// The proleptic Gregorian date `days` after 1970-01-01 (Howard Hinnant's algorithm: eras of
/// 400 years, years starting in March so the leap day comes last).
fn civil_from_days(days: i64) -> (i64, u32, u32) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let day_of_era = z.rem_euclid(146_097);
    let year_of_era =
        (day_of_era - day_of_era / 1460 + day_of_era / 36_524 - day_of_era / 146_096) / 365;
    let day_of_year = day_of_era - (365 * year_of_era + year_of_era / 4 - year_of_era / 100);
    let mp = (5 * day_of_year + 2) / 153;
    let day = (day_of_year - (153 * mp + 2) / 5 + 1) as u32;
    let month = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    let year = year_of_era + era * 400 + i64::from(month <= 2);
    (year, month, day)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn dates_match_known_calendar_days() {
        let at = |s: u64| utc_date_time(UNIX_EPOCH + Duration::from_secs(s));
        assert_eq!(at(0), "1970-01-01T00:00:00Z");
        // 2000-02-29 (a leap day of a year divisible by 400) and the day after.
        assert_eq!(at(951_782_400), "2000-02-29T00:00:00Z");
        assert_eq!(at(951_868_799), "2000-02-29T23:59:59Z");
        assert_eq!(at(951_868_800), "2000-03-01T00:00:00Z");
        // 2100 is not a leap year: 28 February is followed by 1 March.
        assert_eq!(at(4_107_542_399), "2100-02-28T23:59:59Z");
        assert_eq!(at(4_107_542_400), "2100-03-01T00:00:00Z");
        assert_eq!(at(1_795_867_200), "2026-11-28T12:00:00Z");
    }
}
