//! Vertex colours from the views that see each vertex. A view sees a vertex when the vertex
//! faces it, projects inside its image onto a fully covered mask pixel, and the first surface
//! hit along the camera's ray to it (BVH ray cast: a depth test) lies within `tolerance` of
//! it. The colour is the mean of those views' pixels weighted by the cosine between the
//! normal and the view direction; vertices no view sees take the mean of coloured neighbours.

use crate::camera::Camera;
use crate::geometry::{SurfaceBvh, SurfaceError};
use crate::io::image::Image;
use crate::topology::{vertex_normals, ManifoldMesh};
use glam::DVec3;

/// A view to colour from: its camera, image, and mask (one value per pixel).
#[derive(Clone, Copy, Debug)]
pub struct ColorSource<'a> {
    /// The view's camera.
    pub camera: &'a Camera,
    /// The view's image, the camera's size.
    pub image: &'a Image,
    /// The view's mask, one value per pixel in [0, 1], row-major; colour comes only from pixels
    /// at 0.99 or above.
    pub mask: &'a [f32],
}

/// 8-bit colours per vertex row of a compacted `mesh` and how many vertices no view saw
/// (coloured from neighbours).
pub fn vertex_colors(
    mesh: &ManifoldMesh,
    views: &[ColorSource],
    tolerance: f64,
) -> Result<(Vec<[u8; 3]>, usize), SurfaceError> {
    let (positions, faces) = (&mesh.positions, &mesh.live_faces());
    let bvh = SurfaceBvh::build(positions, faces)?;
    let normals = vertex_normals(mesh);
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let chunk = positions.len().div_ceil(threads).max(1);
    let mut seen: Vec<Option<DVec3>> = vec![None; positions.len()];
    std::thread::scope(|scope| {
        for (t, out) in seen.chunks_mut(chunk).enumerate() {
            let (bvh, normals) = (&bvh, &normals);
            scope.spawn(move || {
                for (i, o) in out.iter_mut().enumerate() {
                    let v = t * chunk + i;
                    *o = observed_color(
                        bvh,
                        DVec3::from(positions[v].map(f64::from)),
                        DVec3::from(normals[v].map(f64::from)),
                        views,
                        tolerance,
                    );
                }
            });
        }
    });
    let unseen = seen.iter().filter(|c| c.is_none()).count();
    let filled = fill_from_neighbours(seen, faces);
    Ok((
        filled
            .iter()
            .map(|c| c.to_array().map(|x| (x.clamp(0.0, 1.0) * 255.0).round() as u8))
            .collect(),
        unseen,
    ))
}

/// Weighted mean colour of `p` over the views that see it, `None` when none does.
fn observed_color(
    bvh: &SurfaceBvh,
    p: DVec3,
    normal: DVec3,
    views: &[ColorSource],
    tolerance: f64,
) -> Option<DVec3> {
    let (mut sum, mut weight) = (DVec3::ZERO, 0.0);
    for view in views {
        let origin = view.camera.center();
        let to_camera = origin - p;
        let cosine = normal.dot(to_camera.normalize_or_zero());
        if cosine.is_nan() || cosine <= 0.0 {
            continue;
        }
        let Some(uv) = view.camera.project(p) else { continue };
        let (w, h) = (view.image.width, view.image.height);
        if !(uv.x >= 0.0 && uv.y >= 0.0 && uv.x < w as f64 && uv.y < h as f64) {
            continue;
        }
        let (x, y) = (uv.x as u32, uv.y as u32);
        // Only fully covered pixels: outline pixels mix in the background.
        let m = view.mask[(y * w + x) as usize];
        if m.is_nan() || m < 0.99 {
            continue;
        }
        // Depth test: the first hit from the camera towards p must be p itself.
        let hit = bvh.ray_cast(origin, -to_camera);
        if hit.is_some_and(|h| (1.0 - h.distance) * to_camera.length() > tolerance) {
            continue;
        }
        let at = |c: u8| view.image.at(x, y, c) as f64;
        let color = if view.image.channels >= 3 {
            DVec3::new(at(0), at(1), at(2))
        } else {
            DVec3::splat(at(0))
        };
        sum += cosine * color;
        weight += cosine;
    }
    (weight > 0.0).then(|| sum / weight)
}

/// Gives every `None` the mean of its coloured neighbours, ring by ring; what no coloured
/// vertex reaches (a component nobody saw) becomes mid grey.
fn fill_from_neighbours(mut colors: Vec<Option<DVec3>>, faces: &[[u32; 3]]) -> Vec<DVec3> {
    loop {
        let mut sums = vec![(DVec3::ZERO, 0u32); colors.len()];
        for f in faces {
            for k in 0..3 {
                let (a, b) = (f[k] as usize, f[(k + 1) % 3] as usize);
                for (to, from) in [(a, b), (b, a)] {
                    if let (None, Some(c)) = (colors[to], colors[from]) {
                        sums[to].0 += c;
                        sums[to].1 += 1;
                    }
                }
            }
        }
        let mut changed = false;
        for (c, (sum, n)) in colors.iter_mut().zip(sums) {
            if c.is_none() && n > 0 {
                *c = Some(sum / n as f64);
                changed = true;
            }
        }
        if !changed {
            return colors.into_iter().map(|c| c.unwrap_or(DVec3::splat(0.5))).collect();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two unit spheres on the z axis, A at 0 and B at −3; camera 1 at z = 6 sees only A (red
    /// image), camera 2 at z = −9 sees only B (green image). Without the depth test B's cap
    /// facing camera 1 would turn red.
    #[test]
    fn occluded_vertices_take_no_colour_from_the_occluding_view() {
        let (p, f) = crate::synth::icosphere::icosphere(3);
        let n = p.len() as u32;
        let mut positions: Vec<[f32; 3]> = p.iter().map(|q| q.map(|c| c as f32)).collect();
        positions.extend(p.iter().map(|q| [q[0] as f32, q[1] as f32, q[2] as f32 - 3.0]));
        let mut faces = f.clone();
        faces.extend(f.iter().map(|t| t.map(|v| v + n)));
        let camera = |z: f64| {
            Camera::look_at(
                64,
                64,
                80.0,
                80.0,
                32.0,
                32.0,
                DVec3::new(0.0, 0.0, z),
                DVec3::new(0.0, 0.0, -1.5),
                DVec3::Y,
            )
            .unwrap()
        };
        let flat =
            |rgb: [f32; 3]| Image { width: 64, height: 64, channels: 3, data: rgb.repeat(64 * 64) };
        let (red, green, full) =
            (flat([1.0, 0.0, 0.0]), flat([0.0, 1.0, 0.0]), vec![1.0f32; 64 * 64]);
        let (c1, c2) = (camera(6.0), camera(-9.0));
        let views = [
            ColorSource { camera: &c1, image: &red, mask: &full },
            ColorSource { camera: &c2, image: &green, mask: &full },
        ];
        let mesh = ManifoldMesh::new(positions.clone(), faces).unwrap();
        let (colors, unseen) = vertex_colors(&mesh, &views, 0.05).unwrap();
        assert!(unseen > 0);
        for (v, c) in colors.iter().enumerate() {
            let expected = if (v as u32) < n { [255, 0, 0] } else { [0, 255, 0] };
            assert_eq!(*c, expected, "vertex {v} at {:?}", positions[v]);
        }
    }

    #[test]
    fn neighbours_fill_unseen_vertices() {
        // A strip of triangles 0-1-2-3-4: vertex 0 red, the others unseen.
        let faces = [[0, 1, 2], [1, 3, 2], [2, 3, 4]];
        let mut colors = vec![None; 6];
        colors[0] = Some(DVec3::X);
        let filled = fill_from_neighbours(colors, &faces);
        for c in &filled[..5] {
            assert_eq!(*c, DVec3::X);
        }
        assert_eq!(filled[5], DVec3::splat(0.5), "vertex 5 is in no face");
    }
}
