//! Optical flow between images of one camera: where image points moved ([`LucasKanade`]), and
//! points followed through a whole sequence of frames ([`ImageTracks`]).

mod lucas_kanade;
mod tracks;

pub use lucas_kanade::{luma, GrayImage, LucasKanade, Warp, IDENTITY};
pub use tracks::ImageTracks;
