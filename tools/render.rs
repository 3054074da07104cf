//! `tagsplat render`: one view of a 3DGS PLY scene, as PNG (colour, optionally alpha) and a
//! single-channel EXR (expected depth; `io::image` writes only RGB(A) EXR).

use anyhow::{Context, Result};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use tagsplat::camera::Camera;
use tagsplat::gpu::GpuContext;
use tagsplat::io::image::{write_png, Image};
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
    let settings = RenderSettings {
        background,
        near: args.near,
        far: args.far,
        sh_degree: args.sh_degree,
        mask_mode: args.mask,
    };
    let buffers = GaussianBuffers::from_scene(ctx, &scene)
        .with_context(|| format!("{}: cannot upload", args.splats.display()))?;
    let mut splatter = Splatter::renderer(ctx)?;
    splatter.forward(&buffers, &camera, &settings)?;
    let rgba = splatter.read_rgba()?;
    let (width, height) = (camera.width, camera.height);
    let rgb = rgba.iter().flat_map(|p| [p[0], p[1], p[2]]).collect();
    write_png(&args.out, &Image { width, height, channels: 3, data: rgb })?;
    if let Some(path) = &args.alpha {
        write_png(
            path,
            &Image { width, height, channels: 1, data: rgba.iter().map(|p| p[3]).collect() },
        )?;
    }
    if let Some(path) = &args.depth {
        write_depth_exr(path, width, height, splatter.read_depth()?)?;
    }
    println!("rendered {} Gaussians to {} ({width}x{height})", scene.len(), args.out.display());
    Ok(())
}

fn write_depth_exr(path: &Path, width: u32, height: u32, depth: Vec<f32>) -> Result<()> {
    use exr::prelude::*;
    let channel = AnyChannel::new("Z", FlatSamples::F32(depth));
    let layer = Layer::new(
        (width as usize, height as usize),
        LayerAttributes::named("depth"),
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort(SmallVec::from_vec(vec![channel])),
    );
    write_atomically(path, |w| {
        Image::from_layer(layer).write().to_buffered(w).map_err(std::io::Error::other)
    })
    .with_context(|| format!("{}: cannot write EXR", path.display()))
}
