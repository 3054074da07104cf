//! The reconstruction pipeline (`tagsplat train`): multi-view video in, a topology-consistent
//! mesh sequence and per-frame Gaussians out. The canonical stage fits frame 0 with the
//! Gaussians on a manifold mesh (densified and pruned through the topology); the temporal stage
//! moves that mesh through every later frame with its topology frozen: a deformation graph
//! solved first, then every vertex refined, each stage until its loss stops improving.

mod camera_colour;
pub mod config;
mod correspondences;
mod frame;
mod graph_stage;
mod html_report;
mod run;
mod run_log;

pub use crate::train::plateau::StopReason;
pub use camera_colour::{CameraMaps, ColourUse};
pub use config::{CaptureStep, ReferencePose, TrainConfig};
pub use frame::{optimize_frame, FrameReport, FrameTask};
pub use graph_stage::{GraphReport, LevelReport};
pub use html_report::write_html_report;
pub use run::{run_train, run_train_with, Stage, TrainJob, TrainProgress, TrainReport};
