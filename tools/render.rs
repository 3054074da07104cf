//! `tagsplat render`: one view of a 3DGS PLY scene, as PNG (colour, optionally alpha) and EXR
//! (expected depth).

use anyhow::{Context, Result};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use tagsplat::camera::Camera;
use tagsplat::gpu::GpuContext;
use tagsplat::io::write_atomically;
use tagsplat::splat::{GaussianBuffers, GaussianScene, RenderSettings, Splatter};

#[derive(clap::Args)]
pub struct RenderArgs {
    /// Gaussians in the 3DGS PLY layout.
    #[arg(long)]
    splats: PathBuf,
    /// Camera JSON: {"width", "height", "fx", "fy", "cx", "cy", "world_to_camera": [16, row-major, OpenCV]}.
    #[arg(long)]
    camera: PathBuf,
    /// Colour image (PNG, 8-bit RGB).
    #[arg(long)]
    out: PathBuf,
    /// Expected depth (single-channel float EXR, 0 where nothing was drawn).
    #[arg(long)]
    depth: Option<PathBuf>,
    /// Accumulated alpha (PNG, 8-bit grey).
    #[arg(long)]
    alpha: Option<PathBuf>,
    /// Background colour, three numbers in [0, 1].
    #[arg(long, num_args = 3, default_values_t = [0.0, 0.0, 0.0])]
    background: Vec<f32>,
    /// SH degree to use (at most the scene's).
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(0..=3))]
    sh_degree: u32,
    /// View depths kept: Gaussians outside [near, far] are culled.
    #[arg(long, default_value_t = 0.01)]
    near: f32,
    #[arg(long, default_value_t = 1e4)]
    far: f32,
    /// Render every Gaussian white with opacity 1 (the silhouette).
    #[arg(long)]
    mask: bool,
}

pub fn render(ctx: &Arc<GpuContext>, args: &RenderArgs) -> Result<()> {
    let scene = GaussianScene::read_ply(&args.splats)?;
    let camera = Camera::load_json(&args.camera)?;
    let background = [args.background[0], args.background[1], args.background[2]];
    let settings = RenderSettings { background, near: args.near, far: args.far, sh_degree: args.sh_degree, mask_mode: args.mask };
    let buffers = GaussianBuffers::from_scene(ctx, &scene).with_context(|| format!("{}: cannot upload", args.splats.display()))?;
    let mut splatter = Splatter::new(ctx)?;
    splatter.forward(&buffers, &camera, &settings)?;
    let rgba = splatter.read_rgba()?;
    let (width, height) = (camera.width, camera.height);
    let to_byte = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    let rgb: Vec<u8> = rgba.iter().flat_map(|p| [to_byte(p[0]), to_byte(p[1]), to_byte(p[2])]).collect();
    write_png(&args.out, width, height, image::ExtendedColorType::Rgb8, &rgb)?;
    if let Some(path) = &args.alpha {
        let alpha: Vec<u8> = rgba.iter().map(|p| to_byte(p[3])).collect();
        write_png(path, width, height, image::ExtendedColorType::L8, &alpha)?;
    }
    if let Some(path) = &args.depth {
        write_depth_exr(path, width, height, splatter.read_depth()?)?;
    }
    println!("rendered {} Gaussians to {} ({width}x{height})", scene.len(), args.out.display());
    Ok(())
}

fn write_png(path: &Path, width: u32, height: u32, color: image::ExtendedColorType, pixels: &[u8]) -> Result<()> {
    write_atomically(path, |w| {
        let encoder = image::codecs::png::PngEncoder::new(w);
        image::ImageEncoder::write_image(encoder, pixels, width, height, color).map_err(std::io::Error::other)
    })
    .with_context(|| format!("{}: cannot write PNG", path.display()))
}

fn write_depth_exr(path: &Path, width: u32, height: u32, depth: Vec<f32>) -> Result<()> {
    use exr::prelude::*;
    let channel = AnyChannel::new("Z", FlatSamples::F32(depth));
    let layer = Layer::new((width as usize, height as usize), LayerAttributes::named("depth"), Encoding::FAST_LOSSLESS, AnyChannels::sort(SmallVec::from_vec(vec![channel])));
    write_atomically(path, |w| Image::from_layer(layer).write().to_buffered(w).map_err(std::io::Error::other))
        .with_context(|| format!("{}: cannot write EXR", path.display()))
}
