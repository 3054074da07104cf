//! Where a run's time goes between the host and the device. Every submission of a
//! [`Recorder`](super::Recorder) adds the time its commands took to record, the time from its
//! submit until its fence signalled, and the device time its command buffer spanned
//! (timestamps at its first and last command). Two [`ClockReading`]s around any stretch of
//! work give its share: the stretch's wall time minus its device time is the time the device
//! waited for the host (recording, submitting, waking up, reading back, the host's own work).

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

/// The context's running totals (nanoseconds), added to by every submission.
#[derive(Default)]
pub(crate) struct HostClock {
    submissions: AtomicU64,
    timed_submissions: AtomicU64,
    recording_ns: AtomicU64,
    waiting_ns: AtomicU64,
    device_ns: AtomicU64,
}

impl HostClock {
    /// Adds one submission: its recording and waiting wall times, and its device span (None
    /// where the queue writes no timestamps).
    pub(crate) fn add(&self, recording: Duration, waiting: Duration, device_ms: Option<f64>) {
        self.submissions.fetch_add(1, Ordering::Relaxed);
        self.recording_ns.fetch_add(ns(recording), Ordering::Relaxed);
        self.waiting_ns.fetch_add(ns(waiting), Ordering::Relaxed);
        if let Some(ms) = device_ms {
            self.timed_submissions.fetch_add(1, Ordering::Relaxed);
            self.device_ns.fetch_add((ms.max(0.0) * 1e6) as u64, Ordering::Relaxed);
        }
    }

    /// Adds the recording time of a command buffer recorded once and replayed (its
    /// submissions add their waiting and device time with zero recording).
    pub(crate) fn add_recording(&self, recording: Duration) {
        self.recording_ns.fetch_add(ns(recording), Ordering::Relaxed);
    }

    pub(crate) fn read(&self) -> ClockReading {
        let s = |a: &AtomicU64| a.load(Ordering::Relaxed) as f64 * 1e-9;
        ClockReading {
            submissions: self.submissions.load(Ordering::Relaxed),
            timed_submissions: self.timed_submissions.load(Ordering::Relaxed),
            recording_s: s(&self.recording_ns),
            waiting_s: s(&self.waiting_ns),
            device_s: s(&self.device_ns),
        }
    }
}

fn ns(d: Duration) -> u64 {
    d.as_nanos().min(u64::MAX as u128) as u64
}

/// A context's totals since it was created ([`GpuContext::clock`](super::GpuContext::clock));
/// [`ClockReading::since`] turns two into the totals of the stretch between them.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct ClockReading {
    /// Submissions waited for.
    pub submissions: u64,
    /// Those whose device span was measured (all, where the queue writes timestamps).
    pub timed_submissions: u64,
    /// Host seconds spent recording commands (from a recorder's creation to its submit).
    pub recording_s: f64,
    /// Seconds from each submit until its fence signalled (the device's work and its latency).
    pub waiting_s: f64,
    /// Device seconds: each submission's span from its first to its last command.
    pub device_s: f64,
}

impl ClockReading {
    /// The totals of the stretch from `earlier` to `self`.
    pub fn since(&self, earlier: &ClockReading) -> ClockReading {
        ClockReading {
            submissions: self.submissions - earlier.submissions,
            timed_submissions: self.timed_submissions - earlier.timed_submissions,
            recording_s: self.recording_s - earlier.recording_s,
            waiting_s: self.waiting_s - earlier.waiting_s,
            device_s: self.device_s - earlier.device_s,
        }
    }

    /// The totals of two stretches together.
    pub fn plus(&self, other: &ClockReading) -> ClockReading {
        ClockReading {
            submissions: self.submissions + other.submissions,
            timed_submissions: self.timed_submissions + other.timed_submissions,
            recording_s: self.recording_s + other.recording_s,
            waiting_s: self.waiting_s + other.waiting_s,
            device_s: self.device_s + other.device_s,
        }
    }

    /// The share of `wall_s` the device spent waiting for the host: 1 − device / wall, in
    /// [0, 1]; None when a submission went untimed or `wall_s` is not positive.
    pub fn host_share(&self, wall_s: f64) -> Option<f64> {
        let timed = self.timed_submissions == self.submissions;
        (timed && wall_s > 0.0).then(|| (1.0 - self.device_s / wall_s).clamp(0.0, 1.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stretch_is_the_difference_of_two_readings() {
        let clock = HostClock::default();
        clock.add(Duration::from_millis(3), Duration::from_millis(10), Some(8.0));
        let before = clock.read();
        clock.add(Duration::from_millis(2), Duration::from_millis(20), Some(15.0));
        let stretch = clock.read().since(&before);
        assert_eq!((stretch.submissions, stretch.timed_submissions), (1, 1));
        assert!((stretch.recording_s - 0.002).abs() < 1e-12);
        assert!((stretch.device_s - 0.015).abs() < 1e-12);
        assert!((stretch.host_share(0.025).unwrap() - 0.4).abs() < 1e-9);
        clock.add(Duration::ZERO, Duration::ZERO, None);
        assert_eq!(clock.read().since(&before).host_share(1.0), None, "an untimed submission");
    }
}
