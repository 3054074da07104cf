//! The first mesh of a frame built from its multi-view masks, so no external reconstruction
//! tool is needed: visual hull → surface → largest piece → vertex colours.
//!
//! 1. Each mask has its small enclosed holes filled ([`holes`]) and becomes a signed pixel
//!    distance to its outline ([`distance`]). The hull field at a point is the
//!    (tolerance + 1)-th smallest of the views' distances converted to scene units ([`field`]):
//!    positive inside, continuous, so the surface is found with sub-voxel accuracy.
//! 2. [`bounds`] finds a box around the hull by conservative coarse carving, starting from the
//!    point where the rays through the silhouette centres meet.
//! 3. The field is sampled on a grid whose voxel is `voxel_pixels` pixels wide in the typical
//!    view (the median over views at the box centre), coarsened to fit `max_grid_bytes`.
//!    Enclosed cavities are filled and the outer layer forced outside ([`extract::close_grid`]),
//!    then marching tetrahedra ([`extract`]) gives a closed, oriented 2-manifold (CCW from
//!    outside), of which the largest piece is kept ([`components`]).
//! 4. Isotropic remeshing ([`remesh`], on the topology module's split / collapse / flip)
//!    evens the triangles out at a target edge length: `edge_pixels` pixels of the typical
//!    view, or the length that gives the wanted vertex count on the hull's area (then a
//!    correction of the length and a few more rounds bring the count close).
//! 5. Vertex colours come from the views that see each vertex, with a depth test ([`color`]).
//!
//! The library entry is [`init_mesh`] (a dataset frame); [`init_mesh_from_views`] takes
//! cameras, masks and images as plain values.

pub mod bounds;
pub mod color;
pub mod components;
pub mod distance;
pub mod extract;
pub mod field;
pub mod holes;
pub mod remesh;

use crate::camera::Camera;
use crate::dataset::{Dataset, DatasetError};
use crate::io::host::parallel_map;
use crate::io::image::Image;
use crate::mesh::TriMesh;
use crate::topology::ManifoldMesh;
use bounds::{hull_bounds, Aabb, BoundsProblem};
use field::{GridFrame, HullField, ViewField};
use glam::DVec3;
use serde::Serialize;
use std::sync::Arc;

/// How the initial mesh is built. Lengths are in pixels of the typical view (scale-free).
#[derive(Clone, Debug, PartialEq)]
pub struct InitOptions {
    /// Views that may call a kept point background (noisy masks); 0 is the strict hull.
    pub tolerance: usize,
    /// Voxel width in pixels of the typical view.
    pub voxel_pixels: f64,
    /// Upper bound on the bytes of the sampled grid (4 per sample); the voxel grows to fit.
    pub max_grid_bytes: usize,
    /// Enclosed mask holes up to this fraction of the silhouette's area are filled.
    pub mask_hole_fraction: f64,
    /// Target edge length of the remeshed surface, pixels of the typical view.
    pub edge_pixels: f64,
    /// The most pixels the subject's box diagonal counts in the typical view when the voxel
    /// and the edge length are set: beyond it a finer capture adds no vertices (a 1080² view
    /// would otherwise give a mesh of ~90 000 vertices and take minutes to build).
    pub max_subject_pixels: f64,
    /// Wanted vertex count; overrides `edge_pixels`.
    pub vertices: Option<usize>,
    /// Remeshing rounds; 0 keeps the marching-tetrahedra mesh as it is.
    pub remesh_rounds: usize,
    /// Colour the vertices from the images.
    pub colors: bool,
}

impl Default for InitOptions {
    fn default() -> Self {
        Self {
            tolerance: 0,
            voxel_pixels: 2.0,
            max_grid_bytes: 256 << 20,
            mask_hole_fraction: 0.005,
            edge_pixels: 3.0,
            max_subject_pixels: 400.0,
            vertices: None,
            remesh_rounds: 6,
            colors: true,
        }
    }
}

/// One view of the subject: camera, mask (one value per pixel in [0, 1], > 0.5 foreground,
/// row-major) and, for colours, the image.
#[derive(Clone, Debug)]
pub struct HullView {
    /// Camera name, for messages.
    pub name: String,
    /// The view's camera.
    pub camera: Camera,
    /// One value per pixel in [0, 1], row-major, `width × height` of the camera.
    pub mask: Vec<f32>,
    /// The image, the camera's size; vertex colours need one in every view.
    pub image: Option<Arc<Image>>,
}

/// Why no initial mesh was built.
#[derive(Debug, thiserror::Error)]
pub enum InitError {
    /// Reading a mask or an image of the dataset failed.
    #[error(transparent)]
    Dataset(#[from] DatasetError),
    /// The frame index is past the dataset's last frame.
    #[error("{}: frame {frame} does not exist (the dataset has {frames} frames)", root.display())]
    NoFrame {
        /// The dataset folder.
        root: std::path::PathBuf,
        /// The frame asked for.
        frame: usize,
        /// Number of frames in the dataset.
        frames: usize,
    },
    /// Fewer than 2 views were given.
    #[error("{count} view(s) [{names}]: a visual hull needs masks from at least 2 cameras looking from different directions")]
    TooFewViews {
        /// Number of views given.
        count: usize,
        /// Their names, comma-separated.
        names: String,
    },
    /// A mask's length is not the camera's pixel count.
    #[error("view {name}: the mask has {len} values but the camera is {width}×{height} pixels")]
    MaskSize {
        /// Name of the view.
        name: String,
        /// Values in the mask.
        len: usize,
        /// The camera's width in pixels.
        width: u32,
        /// The camera's height in pixels.
        height: u32,
    },
    /// An image's size differs from its camera's, it has no channels, or its data length is wrong.
    #[error("view {name}: the image is {image_width}×{image_height} with {channels} channels but the camera is {width}×{height} pixels")]
    ImageSize {
        /// Name of the view.
        name: String,
        /// Width of the image, in pixels.
        image_width: u32,
        /// Height of the image, in pixels.
        image_height: u32,
        /// Channels of the image.
        channels: u8,
        /// The camera's width in pixels.
        width: u32,
        /// The camera's height in pixels.
        height: u32,
    },
    /// Every mask is empty (no value above 0.5).
    #[error("the masks are empty in all {count} views [{names}]: nothing marks the subject")]
    EmptyMasks {
        /// Number of views.
        count: usize,
        /// Their names, comma-separated.
        names: String,
    },
    /// The subject cannot be located: the rays through the silhouette centres are (nearly)
    /// parallel, or fewer than 2 masks are non-empty.
    #[error("the rays through the silhouette centres of [{names}] are (nearly) parallel or fewer than 2 masks are non-empty: the cameras cannot locate the subject")]
    Parallel {
        /// Names of all views, comma-separated.
        names: String,
    },
    /// No region of space is inside enough silhouettes (all views but `tolerance`), or no grid
    /// sample is.
    #[error("the silhouette cones of the {count} views never intersect{tolerance}: the cameras or the masks are wrong{empty}")]
    Disjoint {
        /// Number of views.
        count: usize,
        /// Message fragment naming the tolerance; empty when it is 0.
        tolerance: String,
        /// Message fragment naming the views with empty masks; empty when there are none.
        empty: String,
    },
    /// An option is out of range; the message names it.
    #[error("invalid options: {0}")]
    Options(String),
    /// The hull cannot be queried for remeshing or colouring.
    #[error("colouring or remeshing: {0}")]
    Surface(#[from] crate::geometry::SurfaceError),
    /// The extracted hull is not a manifold (a bug).
    #[error("the extracted hull is not a manifold (a bug): {0}")]
    Topology(#[from] crate::topology::TopologyError),
}

/// What was built, with the figures that explain it.
#[derive(Clone, Debug, Serialize)]
pub struct InitReport {
    /// Number of views used.
    pub views: usize,
    /// Box the hull was carved in, scene units.
    pub bounds_lo: [f64; 3],
    /// Upper corner of the box the hull was carved in, scene units.
    pub bounds_hi: [f64; 3],
    /// The length `voxel_pixels` and `edge_pixels` count in, scene units: one pixel at the box
    /// centre in the typical view, or the box diagonal over `max_subject_pixels` if longer.
    pub pixel: f64,
    /// Grid vertex spacing, scene units, and vertex counts of the grid that gave the mesh.
    pub voxel: f64,
    /// Grid vertices along x, y and z.
    pub grid: [usize; 3],
    /// Mask pixels filled as small enclosed holes, over all views.
    pub mask_hole_pixels: usize,
    /// Grid samples filled as enclosed cavities (see [`extract::close_grid`]).
    pub cavity_samples: usize,
    /// Connected pieces of the extracted mesh dropped for the largest one.
    pub components_dropped: usize,
    /// Vertices of the marching-tetrahedra mesh before remeshing.
    pub extracted_vertices: usize,
    /// Target edge length of the remeshing, scene units, and what it did.
    pub edge_length: f64,
    /// Splits, collapses and flips of the remeshing (zero with no rounds).
    pub remesh: remesh::RemeshStats,
    /// Vertices of the final mesh.
    pub vertices: usize,
    /// Faces of the final mesh.
    pub faces: usize,
    /// Vertices no view saw (coloured from their neighbours); 0 without colours.
    pub unseen_vertices: usize,
    /// Wall-clock seconds of each stage and in all.
    pub seconds: StageSeconds,
}

/// Wall-clock seconds per stage.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct StageSeconds {
    /// Mask distances and the bounding box.
    pub silhouettes: f64,
    /// Field sampling, marching tetrahedra, largest component.
    pub extract: f64,
    /// Isotropic remeshing.
    pub remesh: f64,
    /// Vertex colours.
    pub color: f64,
    /// The whole build.
    pub total: f64,
}

/// The mesh and how it was made.
#[derive(Clone, Debug)]
pub struct InitMesh {
    /// The mesh: closed, oriented (counter-clockwise seen from outside), in scene units, with
    /// vertex colours when they were asked for and every view has an image.
    pub mesh: TriMesh,
    /// What was built and how long each stage took.
    pub report: InitReport,
}

/// Builds the initial mesh of `frame` from the dataset's training views (held-out cameras are
/// not used).
pub fn init_mesh(
    dataset: &Dataset,
    frame: usize,
    options: &InitOptions,
) -> Result<InitMesh, InitError> {
    let Some(f) = dataset.frames.get(frame) else {
        return Err(InitError::NoFrame {
            root: dataset.root.clone(),
            frame,
            frames: dataset.frames.len(),
        });
    };
    let chosen: Vec<(usize, &crate::dataset::View)> =
        f.views.iter().enumerate().filter(|(_, v)| dataset.train.contains(&v.camera)).collect();
    let views = parallel_map(&chosen, |&(k, v)| {
        Ok::<_, InitError>(HullView {
            name: dataset.camera_names[v.camera].clone(),
            camera: dataset.cameras[v.camera],
            mask: dataset.mask(frame, k)?,
            image: if options.colors { Some(dataset.image(frame, k)?) } else { None },
        })
    })?;
    init_mesh_from_views(&views, options)
}

/// Builds the mesh from plain views (see the module doc for the stages).
pub fn init_mesh_from_views(
    views: &[HullView],
    options: &InitOptions,
) -> Result<InitMesh, InitError> {
    let start = std::time::Instant::now();
    check(views, options)?;
    let names = |vs: &mut dyn Iterator<Item = &HullView>| {
        vs.map(|v| v.name.as_str()).collect::<Vec<_>>().join(", ")
    };
    // Each view's field on its own: the views are done side by side.
    let filled = parallel_map(views, |v| {
        let (w, h) = (v.camera.width as usize, v.camera.height as usize);
        let mut mask = v.mask.clone();
        let holes = holes::fill_small_holes(&mut mask, w, h, options.mask_hole_fraction);
        let field = ViewField {
            camera: v.camera,
            distance: distance::SignedDistance::from_mask(&mask, w, h),
        };
        Ok::<_, std::convert::Infallible>((field, holes))
    });
    let (fields, holes): (Vec<ViewField>, Vec<usize>) =
        filled.unwrap_or_else(|never| match never {}).into_iter().unzip();
    let mask_hole_pixels: usize = holes.iter().sum();
    let empty: Vec<&HullView> = views.iter().filter(|v| !v.mask.iter().any(|&m| m > 0.5)).collect();
    if empty.len() == views.len() {
        return Err(InitError::EmptyMasks { count: views.len(), names: names(&mut views.iter()) });
    }
    let disjoint = || InitError::Disjoint {
        count: views.len(),
        tolerance: if options.tolerance > 0 {
            format!(" (even with {} views allowed to disagree)", options.tolerance)
        } else {
            String::new()
        },
        empty: if empty.is_empty() {
            String::new()
        } else {
            format!("; empty masks in [{}]", names(&mut empty.iter().copied()))
        },
    };
    let aabb = hull_bounds(&fields, options.tolerance).map_err(|p| match p {
        BoundsProblem::Parallel => InitError::Parallel { names: names(&mut views.iter()) },
        BoundsProblem::Disjoint => disjoint(),
    })?;
    let mut seconds =
        StageSeconds { silhouettes: start.elapsed().as_secs_f64(), ..StageSeconds::default() };
    let pixel = typical_pixel(&fields, aabb).max(aabb.size().length() / options.max_subject_pixels);
    let field =
        HullField { views: fields, tolerance: options.tolerance, far: 1e3 * aabb.size().length() };

    let Surface { mesh: hull, voxel, grid, cavity_samples, components_dropped } =
        extract_surface(&field, aabb, pixel * options.voxel_pixels, options.max_grid_bytes)
            .ok_or_else(disjoint)?;
    seconds.extract = start.elapsed().as_secs_f64() - seconds.silhouettes;
    let area = surface_area(&hull);
    let edge_length = options
        .vertices
        .map_or(options.edge_pixels * pixel, |n| remesh::edge_for_vertices(area, n));
    let (mesh, stats) = remeshed(&hull, edge_length, options)?;
    seconds.remesh = start.elapsed().as_secs_f64() - seconds.silhouettes - seconds.extract;
    let mut unseen_vertices = 0;
    let mut colors = None;
    if options.colors && views.iter().all(|v| v.image.is_some()) {
        let sources: Vec<color::ColorSource> = views
            .iter()
            .filter_map(|v| {
                Some(color::ColorSource {
                    camera: &v.camera,
                    image: v.image.as_deref()?,
                    mask: &v.mask,
                })
            })
            .collect();
        let (c, unseen) =
            color::vertex_colors(&mesh, &sources, crate::topology::mean_edge_length(&mesh) as f64)?;
        colors = Some(c);
        unseen_vertices = unseen;
    }
    let mesh = TriMesh { faces: mesh.live_faces(), positions: mesh.positions, colors };
    seconds.total = start.elapsed().as_secs_f64();
    seconds.color = seconds.total - seconds.silhouettes - seconds.extract - seconds.remesh;
    let report = InitReport {
        views: views.len(),
        bounds_lo: aabb.lo.to_array(),
        bounds_hi: aabb.hi.to_array(),
        pixel,
        voxel,
        grid,
        mask_hole_pixels,
        cavity_samples,
        components_dropped,
        extracted_vertices: hull.positions.len(),
        edge_length,
        remesh: stats,
        vertices: mesh.positions.len(),
        faces: mesh.faces.len(),
        unseen_vertices,
        seconds,
    };
    Ok(InitMesh { mesh, report })
}

fn check(views: &[HullView], o: &InitOptions) -> Result<(), InitError> {
    let bad = |m: String| Err(InitError::Options(m));
    for (value, name) in [
        (o.voxel_pixels, "voxel width"),
        (o.edge_pixels, "edge length"),
        (o.max_subject_pixels, "subject diagonal"),
    ] {
        if !(value > 0.0 && value.is_finite()) {
            return bad(format!("{name} {value} pixels must be positive"));
        }
    }
    if !(0.0..1.0).contains(&o.mask_hole_fraction) {
        return bad(format!("mask hole fraction {} must be in [0, 1)", o.mask_hole_fraction));
    }
    if o.vertices.is_some_and(|n| n < 4) {
        return bad("a closed mesh needs at least 4 vertices".into());
    }
    if o.max_grid_bytes < 4 << 10 {
        return bad(format!("grid budget {} bytes is below 4 KiB", o.max_grid_bytes));
    }
    if views.len() < 2 {
        return Err(InitError::TooFewViews {
            count: views.len(),
            names: views.iter().map(|v| v.name.as_str()).collect::<Vec<_>>().join(", "),
        });
    }
    if o.tolerance + 2 > views.len() {
        return bad(format!(
            "tolerating {} disagreeing views leaves fewer than 2 of the {} views to carve",
            o.tolerance,
            views.len()
        ));
    }
    for v in views {
        let (width, height) = (v.camera.width, v.camera.height);
        if v.mask.len() != width as usize * height as usize {
            return Err(InitError::MaskSize {
                name: v.name.clone(),
                len: v.mask.len(),
                width,
                height,
            });
        }
        if let Some(image) = &v.image {
            let wrong = (image.width, image.height) != (width, height)
                || image.channels == 0
                || image.data.len() != (width * height) as usize * image.channels as usize;
            if wrong {
                return Err(InitError::ImageSize {
                    name: v.name.clone(),
                    image_width: image.width,
                    image_height: image.height,
                    channels: image.channels,
                    width,
                    height,
                });
            }
        }
    }
    Ok(())
}

/// Median over views of the size of one pixel at the box centre (depth / focal length).
fn typical_pixel(views: &[ViewField], aabb: Aabb) -> f64 {
    let center = 0.5 * (aabb.lo + aabb.hi);
    let mut sizes: Vec<f64> = views
        .iter()
        .filter_map(|v| {
            let z = v.camera.to_camera(center).z;
            (z > 0.0).then(|| z / (v.camera.fx * v.camera.fy).sqrt())
        })
        .collect();
    if sizes.is_empty() {
        // The centre is behind every camera: fall back on the box itself.
        return aabb.size().max_element() / 256.0;
    }
    sizes.sort_by(f64::total_cmp);
    sizes[sizes.len() / 2]
}

/// The extracted surface and the grid that gave it.
struct Surface {
    mesh: TriMesh,
    voxel: f64,
    grid: [usize; 3],
    cavity_samples: usize,
    components_dropped: usize,
}

/// Samples the field on a grid of spacing `voxel` (grown to fit `max_bytes`) over `aabb`
/// padded by two voxels, and returns the largest closed piece of its zero set; `None` when no
/// sample is inside (the conservative box can hold regions near cameras that the exact field
/// then carves away).
fn extract_surface(field: &HullField, aabb: Aabb, voxel: f64, max_bytes: usize) -> Option<Surface> {
    let cells = |step: f64| (aabb.size() / step).ceil() + 4.0;
    let mut step = voxel;
    let samples = |step: f64| cells(step).x * cells(step).y * cells(step).z;
    let budget = (max_bytes / 4) as f64;
    while samples(step) > budget {
        step *= (samples(step) / budget).cbrt().max(1.01);
    }
    let c = cells(step);
    let grid = GridFrame {
        origin: aabb.lo - DVec3::splat(2.0 * step),
        step,
        dims: [c.x as usize, c.y as usize, c.z as usize],
    };
    let mut values = field.sample_grid(&grid);
    let cavity_samples = extract::close_grid(&mut values, &grid);
    let (positions, faces) = extract::marching_tetrahedra(&values, &grid);
    if faces.is_empty() {
        return None;
    }
    let (positions, faces, components_dropped) = components::largest_component(&positions, &faces);
    Some(Surface {
        mesh: TriMesh { positions, faces, colors: None },
        voxel: step,
        grid: grid.dims,
        cavity_samples,
        components_dropped,
    })
}

/// The hull remeshed to `edge_length` (with a wanted count: corrected once by the count it
/// reached, counts going as 1 / length²), compacted; the hull itself with no rounds.
fn remeshed(
    hull: &TriMesh,
    edge_length: f64,
    options: &InitOptions,
) -> Result<(ManifoldMesh, remesh::RemeshStats), InitError> {
    let mut mesh = ManifoldMesh::new(hull.positions.clone(), hull.faces.clone())?;
    if options.remesh_rounds == 0 {
        return Ok((mesh, remesh::RemeshStats::default()));
    }
    let reference = crate::geometry::SurfaceBvh::build(&hull.positions, &hull.faces)?;
    let mut stats = remesh::remesh(&mut mesh, &reference, edge_length, options.remesh_rounds);
    if let Some(n) = options.vertices {
        let corrected = edge_length * (mesh.vertex_count() as f64 / n as f64).sqrt();
        let more =
            remesh::remesh(&mut mesh, &reference, corrected, options.remesh_rounds.div_ceil(2));
        stats = remesh::RemeshStats {
            splits: stats.splits + more.splits,
            collapses: stats.collapses + more.collapses,
            flips: stats.flips + more.flips,
        };
    }
    mesh.compact();
    Ok((mesh, stats))
}

fn surface_area(mesh: &TriMesh) -> f64 {
    let p = |i: u32| DVec3::from(mesh.positions[i as usize].map(f64::from));
    mesh.faces.iter().map(|f| 0.5 * (p(f[1]) - p(f[0])).cross(p(f[2]) - p(f[0])).length()).sum()
}
