//! Tracking surface points through a topology-consistent mesh sequence.
//!
//! A query point is bound once, on frame 0, to (face, barycentric) — by the closest surface point
//! for a 3D point, by the first hit of the pixel's ray for a 2D point — and followed through
//! every frame as Σ bₖ·vₖ(t) (docs/conventions.md, "Tracking"). The surface queries are the
//! internal `geometry` module's (BVH closest point and ray casts).
//! - [`bind`]: query points → bindings, refusing points too far from the surface.
//! - [`trajectory`]: bindings → positions in every frame; [`frame`]: bindings → orientation
//!   frames (normal, tangent) in every frame.
//! - [`queries`]: `points.csv` / `pixels.csv` readers; [`bindings`]: `bindings.csv` read, checked
//!   against the mesh and written; [`output`]: `tracks.csv` / JSON writers on a [`clock`];
//!   [`pins`]: a GLB of animated empties, one per point.
//! - [`plot`]: an SVG of the trajectories; [`project`]: tracks seen through a camera;
//!   [`overlay`]: those drawn over the camera's images.
//! - [`run`]: one tracking run from queries to report, and the run on a sequence as read.
//! - [`bench`](mod@bench): the `bench track` measurement.

pub mod bench;
pub mod bind;
pub mod bindings;
pub mod clock;
pub mod frame;
pub mod output;
pub mod overlay;
pub mod pins;
pub mod plot;
pub mod project;
pub mod queries;
pub mod run;
pub mod trajectory;

pub use bind::{bind_point, bind_ray, Binding, Unbound};
pub use clock::Clock;
pub use frame::SurfaceFrame;
pub use output::{TrackReport, TrackedPoint, UnboundPoint};
pub use project::{project_tracks, ImagePoint};
pub use run::{track, track_sequence, Queries, RunError, Targets, Tracked};
pub use trajectory::trajectories;

use crate::geometry::SurfaceError;
use std::path::PathBuf;

/// What can go wrong while tracking; file errors name the file.
#[derive(Debug, thiserror::Error)]
pub enum TrackError {
    /// A mesh is unusable for surface queries (e.g. no faces, a non-finite position), or there
    /// are no frames.
    #[error(transparent)]
    Surface(#[from] SurfaceError),
    /// The binding tolerance is negative or NaN.
    #[error(
        "max_distance {0}: must be a non-negative fraction of the frame-0 diagonal (inf: no limit)"
    )]
    MaxDistance(f64),
    /// A frame's vertex count differs from frame 0's.
    #[error("frame {frame} has {found} vertices, frame 0 has {expected}")]
    FrameVertexCount {
        /// Index of the frame.
        frame: usize,
        /// Its vertex count.
        found: usize,
        /// Frame 0's vertex count.
        expected: usize,
    },
    /// A binding's face, or a vertex of it, is out of range in some frame.
    #[error("binding {binding} refers to face {face}, which is not among the {faces} faces or uses a vertex the frame lacks")]
    FaceOutOfRange {
        /// Index of the binding.
        binding: usize,
        /// The face it refers to.
        face: u32,
        /// The sequence's face count.
        faces: usize,
    },
    /// A given binding is unusable on the mesh (see [`bindings::check_binding`]).
    #[error("binding of point {id}: {problem}")]
    Binding {
        /// The point's id.
        id: String,
        /// What is wrong with its binding.
        problem: String,
    },
    /// A polygon map does not have one entry per face.
    #[error("{polygons} polygon entries for {faces} faces")]
    Polygons {
        /// Entries in the map.
        polygons: usize,
        /// Faces of the sequence.
        faces: usize,
    },
    /// A clock is unusable, or does not match the frames.
    #[error("clock: {0}")]
    Clock(String),
    /// A pins GLB cannot be written.
    #[error("{}: cannot write: {problem}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// Why not.
        problem: String,
    },
    /// A query CSV file is malformed.
    #[error("{path}: line {line}: {message}")]
    Csv {
        /// The CSV file.
        path: PathBuf,
        /// The offending line, counted from 1.
        line: usize,
        /// What is wrong with it.
        message: String,
    },
    /// Reading or writing a file failed.
    #[error("{path}: {error}")]
    Io {
        /// The file concerned.
        path: PathBuf,
        /// The underlying I/O error.
        error: std::io::Error,
    },
}
