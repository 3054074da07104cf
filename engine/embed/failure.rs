//! One error type for the fronts: any engine error, classified once, with the message the
//! command-line program prints.

use crate::dataset::DatasetError;
use crate::gpu::GpuError;
use crate::panic_payload::panic_text;
use crate::sequence::SequenceError;
use crate::train::TrainError;
use std::error::Error;
use std::panic::{catch_unwind, AssertUnwindSafe};

/// What kind of failure an engine error is: the fronts map it onto their own error types (a
/// Python exception class, a C status code).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ErrorKind {
    /// An argument, a path, a config value or an array that is wrong: the caller can fix it.
    BadInput,
    /// A file that exists but cannot be read as what it should be.
    FileFormat,
    /// The Vulkan device: none suitable, out of memory, lost, a validation failure.
    Device,
    /// The job was cancelled by its caller.
    Cancelled,
    /// Reading or writing a file failed for a reason other than its content.
    Io,
    /// A bug: the engine panicked. The message says where.
    Internal,
}

/// An engine error as the fronts report it: its kind and the command-line program's one-line
/// message (the cause chain joined by ": "), which names the file or argument.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Failure {
    /// What kind of failure it is.
    pub kind: ErrorKind,
    /// The message, on one line.
    pub message: String,
}

impl std::fmt::Display for Failure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl Error for Failure {}

impl Failure {
    /// Classifies `error` by the first link of its cause chain whose kind is known (a
    /// cancellation, the device, a file's content, a failed read or write); an error none of
    /// whose links is known is bad input. The message is the whole chain, as the CLI prints it.
    pub fn of(error: &(dyn Error + 'static)) -> Self {
        let kind = chain(error).find_map(known_kind).unwrap_or(ErrorKind::BadInput);
        let mut message = error.to_string();
        for cause in chain(error).skip(1) {
            let text = cause.to_string();
            // thiserror's transparent variants repeat their source's text.
            if !message.ends_with(&text) {
                message = format!("{message}: {text}");
            }
        }
        Self { kind, message }
    }

    /// A front's own check of an argument failed (a wrong dtype or shape, a NaN, a NULL).
    pub fn bad_input(message: impl Into<String>) -> Self {
        Self { kind: ErrorKind::BadInput, message: message.into() }
    }

    /// The job was cancelled.
    pub fn cancelled() -> Self {
        Self::of(&TrainError::Cancelled)
    }
}

/// Runs `work`, turning a panic into a [`Failure`] of kind [`ErrorKind::Internal`]: no unwinding
/// leaves this call, so a front may call it from a foreign frame (C, Python).
pub fn guard<T>(work: impl FnOnce() -> Result<T, Failure>) -> Result<T, Failure> {
    catch_unwind(AssertUnwindSafe(work)).unwrap_or_else(|payload| Err(panicked(&*payload)))
}

/// The failure a panic's payload describes.
pub(crate) fn panicked(payload: &(dyn std::any::Any + Send)) -> Failure {
    let what = panic_text(payload);
    let message = format!("internal error (a bug in tagsplat, please report it): {what}");
    Failure { kind: ErrorKind::Internal, message }
}

/// `error`, then each of its sources.
fn chain<'a>(error: &'a (dyn Error + 'static)) -> impl Iterator<Item = &'a (dyn Error + 'static)> {
    std::iter::successors(Some(error), |&e| e.source())
}

/// The kind of one link of a chain, when it says.
fn known_kind(error: &(dyn Error + 'static)) -> Option<ErrorKind> {
    if let Some(train) = error.downcast_ref::<TrainError>() {
        return train_kind(train);
    }
    if let Some(sequence) = error.downcast_ref::<SequenceError>() {
        return Some(sequence_kind(sequence));
    }
    if let Some(dataset) = error.downcast_ref::<DatasetError>() {
        return dataset_kind(dataset);
    }
    if error.is::<GpuError>() {
        return Some(ErrorKind::Device);
    }
    error.downcast_ref::<std::io::Error>().map(io_kind)
}

/// A missing file is the caller's to fix; any other failed read or write is the system's.
fn io_kind(error: &std::io::Error) -> ErrorKind {
    match error.kind() {
        std::io::ErrorKind::NotFound => ErrorKind::BadInput,
        _ => ErrorKind::Io,
    }
}

fn train_kind(error: &TrainError) -> Option<ErrorKind> {
    use crate::{deform::DeformError, raster::RasterError};
    use crate::{regularize::RegularizeError, splat::SplatError};
    match error {
        TrainError::Cancelled => Some(ErrorKind::Cancelled),
        TrainError::Gpu(_)
        | TrainError::Splat(SplatError::Gpu(_))
        | TrainError::Raster(RasterError::Gpu(_))
        | TrainError::Regularize(RegularizeError::Gpu(_))
        | TrainError::Deform(DeformError::Gpu(_)) => Some(ErrorKind::Device),
        TrainError::Io { error, .. } => Some(io_kind(error)),
        TrainError::Dataset(dataset) => dataset_kind(dataset),
        TrainError::Sequence(sequence) => Some(sequence_kind(sequence)),
        TrainError::Mesh(_)
        | TrainError::Scene(_)
        | TrainError::Image(_)
        | TrainError::Ply(_)
        | TrainError::Usd(_) => Some(ErrorKind::FileFormat),
        _ => None,
    }
}

/// A path that is no sequence or lacks a file is the caller's to fix; a frame, cache or GLB
/// that does not read is the file's.
fn sequence_kind(error: &SequenceError) -> ErrorKind {
    match error {
        SequenceError::Invalid { .. } => ErrorKind::BadInput,
        _ => ErrorKind::FileFormat,
    }
}

fn dataset_kind(error: &DatasetError) -> Option<ErrorKind> {
    match error {
        DatasetError::Unknown(_) | DatasetError::MissingImage(_) => Some(ErrorKind::BadInput),
        DatasetError::File { .. } | DatasetError::Camera { .. } | DatasetError::Image(_) => {
            Some(ErrorKind::FileFormat)
        }
        _ => None,
    }
}
