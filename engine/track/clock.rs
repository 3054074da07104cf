//! The clock tracks are written on: each frame's time, the frame rate and the start frame, so a
//! tool places frame k of a track at scene frame `start_frame + k` (time `times[k]` seconds).

use super::TrackError;
use crate::sequence::source::CLOCKLESS_FPS;
use crate::sequence::SequenceInfo;

/// When each frame of a sequence is shown.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Clock {
    /// Frames per second.
    pub fps: f64,
    /// The scene frame of frame 0: `times[0] · fps` (0 when the file has no clock).
    pub start_frame: f64,
    /// Time of each frame in seconds, strictly increasing.
    pub times: Vec<f64>,
}

impl Clock {
    /// `frames` frames at `fps`, frame 0 at scene frame `start_frame`: frame k at
    /// `(start_frame + k) / fps` seconds.
    ///
    /// Errors: `fps` not positive and finite, `start_frame` not finite.
    pub fn uniform(fps: f64, start_frame: f64, frames: usize) -> Result<Clock, TrackError> {
        if !(fps.is_finite() && fps > 0.0 && start_frame.is_finite()) {
            return Err(TrackError::Clock(format!(
                "frame rate {fps} and start frame {start_frame}: the rate must be positive and both finite"
            )));
        }
        let times = (0..frames).map(|k| (start_frame + k as f64) / fps).collect();
        Ok(Clock { fps, start_frame, times })
    }

    /// The clock a read reported for its `frames` frames: the file's times and rate. Times with
    /// uneven steps (no single rate) get their mean rate; one timed frame, or a file without a
    /// clock, [`CLOCKLESS_FPS`] (without a clock, frame 0 at time 0).
    ///
    /// Errors: a number of times other than `frames`.
    pub fn of(info: &SequenceInfo, frames: usize) -> Result<Clock, TrackError> {
        let Some(times) = &info.times else {
            return Clock::uniform(info.fps.unwrap_or(CLOCKLESS_FPS), 0.0, frames);
        };
        if times.len() != frames {
            return Err(TrackError::Clock(format!(
                "{} frame times for {frames} frames",
                times.len()
            )));
        }
        let span = times.last().zip(times.first()).map_or(0.0, |(b, a)| b - a);
        let mean = (frames > 1 && span > 0.0).then(|| (frames - 1) as f64 / span);
        let fps = info.fps.or(mean).unwrap_or(CLOCKLESS_FPS);
        Ok(Clock { fps, start_frame: times.first().map_or(0.0, |t| t * fps), times: times.clone() })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_without_a_clock_plays_at_24_from_frame_0() {
        let clock = Clock::of(&SequenceInfo::default(), 3).unwrap();
        assert_eq!(
            clock,
            Clock { fps: 24.0, start_frame: 0.0, times: vec![0.0, 1.0 / 24.0, 2.0 / 24.0] }
        );
    }

    #[test]
    fn a_timed_file_keeps_its_times_and_starts_where_they_do() {
        let times = vec![1.0 / 30.0, 2.0 / 30.0, 3.0 / 30.0];
        let info =
            SequenceInfo { times: Some(times.clone()), fps: Some(30.0), ..Default::default() };
        let clock = Clock::of(&info, 3).unwrap();
        assert_eq!((clock.fps, clock.times), (30.0, times));
        assert!((clock.start_frame - 1.0).abs() < 1e-12);
        let uneven = SequenceInfo { times: Some(vec![0.0, 0.1, 0.4]), ..Default::default() };
        assert!((Clock::of(&uneven, 3).unwrap().fps - 5.0).abs() < 1e-12);
        assert!(Clock::of(&uneven, 2).is_err());
        assert!(Clock::uniform(0.0, 0.0, 2).is_err());
        assert!(Clock::uniform(24.0, f64::NAN, 2).is_err());
    }
}
