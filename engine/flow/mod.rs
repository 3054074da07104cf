//! Optical flow between consecutive frames of one camera: where image points moved.

mod lucas_kanade;

pub use lucas_kanade::{luma, GrayImage, LucasKanade};
