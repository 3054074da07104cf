//! The visual-hull field: at a world point, each view's signed distance to its silhouette
//! outline (pixels × depth / focal length, so scene units), and the hull keeps a point when it
//! is inside in every view but `tolerance` of them — the field is the (tolerance + 1)-th
//! smallest of the per-view values. Positive inside; continuous, so its zero set is found with
//! sub-voxel accuracy on any grid.

use super::distance::SignedDistance;
use crate::camera::Camera;
use glam::DVec3;

/// One view's camera and the signed distance of its (hole-filled) mask.
#[derive(Clone, Debug)]
pub struct ViewField {
    /// The view's camera.
    pub camera: Camera,
    /// Signed distance to the outline of the view's mask, in pixels.
    pub distance: SignedDistance,
}

impl ViewField {
    /// Signed distance in scene units at `p` (positive inside the silhouette cone); `behind`
    /// (a large negative number) for points at or behind the camera plane.
    #[inline]
    pub fn value(&self, p: DVec3, behind: f64) -> f64 {
        let c = self.camera.to_camera(p);
        if c.z.is_nan() || c.z <= 0.0 {
            return behind;
        }
        let (u, v) = (
            self.camera.fx * c.x / c.z + self.camera.cx,
            self.camera.fy * c.y / c.z + self.camera.cy,
        );
        self.distance.sample(u, v) * c.z / (self.camera.fx * self.camera.fy).sqrt()
    }
}

/// The combined field over all views.
#[derive(Clone, Debug)]
pub struct HullField {
    /// One term per view.
    pub views: Vec<ViewField>,
    /// Views allowed to disagree (say "outside") at a kept point.
    pub tolerance: usize,
    /// Value of a point behind a camera: minus this (a length far beyond the scene).
    pub far: f64,
}

impl HullField {
    /// The field at `p`, scene units, positive inside; `scratch` is reused between calls.
    #[inline]
    pub fn value(&self, p: DVec3, scratch: &mut Vec<f64>) -> f64 {
        scratch.clear();
        scratch.extend(self.views.iter().map(|v| v.value(p, -self.far)));
        let k = self.tolerance.min(scratch.len() - 1);
        if k == 0 {
            return scratch.iter().copied().fold(f64::INFINITY, f64::min);
        }
        *scratch.select_nth_unstable_by(k, f64::total_cmp).1
    }

    /// The field at every vertex of a regular grid (x fastest, then y, then z), computed on all
    /// cores.
    pub fn sample_grid(&self, grid: &GridFrame) -> Vec<f32> {
        let [nx, ny, nz] = grid.dims;
        let mut values = vec![0.0f32; nx * ny * nz];
        let threads = std::thread::available_parallelism().map_or(1, |n| n.get()).min(nz).max(1);
        let slab = nx * ny;
        std::thread::scope(|scope| {
            for (t, chunk) in values.chunks_mut(slab * nz.div_ceil(threads)).enumerate() {
                let first = t * nz.div_ceil(threads);
                scope.spawn(move || {
                    let mut scratch = Vec::with_capacity(self.views.len());
                    for (i, out) in chunk.iter_mut().enumerate() {
                        let index = first * slab + i;
                        let p = grid.point([index % nx, (index / nx) % ny, index / slab]);
                        *out = self.value(p, &mut scratch) as f32;
                    }
                });
            }
        });
        values
    }
}

/// Where a regular grid sits: the first vertex, the spacing (scene units) and the vertex counts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridFrame {
    /// Position of vertex (0, 0, 0), world units.
    pub origin: DVec3,
    /// Spacing between neighbouring vertices, world units.
    pub step: f64,
    /// Vertex counts along x, y and z.
    pub dims: [usize; 3],
}

impl GridFrame {
    /// The world position of grid vertex (i, j, k).
    #[inline]
    pub fn point(&self, [i, j, k]: [usize; 3]) -> DVec3 {
        self.origin + self.step * DVec3::new(i as f64, j as f64, k as f64)
    }

    /// Linear index of vertex (i, j, k).
    #[inline]
    pub fn index(&self, [i, j, k]: [usize; 3]) -> usize {
        i + self.dims[0] * (j + self.dims[1] * k)
    }

    /// Number of vertices.
    pub fn len(&self) -> usize {
        self.dims.iter().product()
    }

    /// Whether the grid has no vertices.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A camera at `eye` looking at the origin, 64×64 px, 60° field of view.
    pub(crate) fn camera(eye: DVec3) -> Camera {
        let f = 32.0 / (30f64.to_radians()).tan();
        Camera::look_at(64, 64, f, f, 32.0, 32.0, eye, DVec3::ZERO, DVec3::Y).unwrap()
    }

    /// The exact silhouette of a sphere of radius r at the origin in `cam`: a mask with pixel
    /// centres inside the projected disk.
    pub(crate) fn sphere_view(cam: Camera, r: f64) -> ViewField {
        let mask: Vec<f32> = (0..64 * 64)
            .map(|p| {
                let (o, d) = cam.pixel_ray((p % 64) as f64 + 0.5, (p / 64) as f64 + 0.5);
                // Ray–sphere: closest approach of the ray to the centre.
                let t = -o.dot(d);
                ((o + t * d).length() < r) as u8 as f32
            })
            .collect();
        ViewField { distance: SignedDistance::from_mask(&mask, 64, 64), camera: cam }
    }

    #[test]
    fn sphere_hull_field_crosses_zero_near_the_sphere() {
        let r = 0.5;
        let views: Vec<ViewField> = [DVec3::X, DVec3::Y + 0.01 * DVec3::Z, DVec3::Z, -DVec3::X]
            .iter()
            .map(|&d| sphere_view(camera(3.0 * d), r))
            .collect();
        let field = HullField { views, tolerance: 0, far: 100.0 };
        let mut scratch = Vec::new();
        // Along the axis diagonal to all cameras the hull reaches past the sphere, but it never
        // cuts into it, and along a camera's image plane axis it is tight to about a pixel.
        let pixel = 3.0 / (32.0 / 30f64.to_radians().tan());
        assert!(field.value(DVec3::ZERO, &mut scratch) > 0.4);
        assert!(field.value(DVec3::new(0.0, 0.0, r - 2.0 * pixel), &mut scratch) > 0.0);
        assert!(field.value(DVec3::new(0.0, 0.0, r + 2.0 * pixel), &mut scratch) < 0.0);
        assert!(field.value(DVec3::new(3.0, 0.0, 0.0), &mut scratch) < 0.0);
        // Behind a camera: far outside.
        assert!(field.value(DVec3::new(4.0, 0.0, 0.0), &mut scratch) <= -100.0);
        // Two views: a point outside the +Z cone only is carved, unless one view may disagree.
        let two = HullField {
            views: vec![field.views[0].clone(), field.views[2].clone()],
            tolerance: 0,
            far: 100.0,
        };
        let outside_one = DVec3::new(0.6, 0.0, 0.0);
        assert!(two.value(outside_one, &mut scratch) < 0.0);
        assert!(HullField { tolerance: 1, ..two }.value(outside_one, &mut scratch) > 0.0);
    }

    #[test]
    fn grid_samples_match_point_values() {
        let views = vec![
            sphere_view(camera(3.0 * DVec3::X), 0.5),
            sphere_view(camera(3.0 * DVec3::Z), 0.5),
        ];
        let field = HullField { views, tolerance: 0, far: 100.0 };
        let grid = GridFrame { origin: DVec3::splat(-0.7), step: 0.1, dims: [15, 13, 11] };
        let values = field.sample_grid(&grid);
        let mut scratch = Vec::new();
        for ijk in [[0, 0, 0], [14, 12, 10], [7, 3, 9], [2, 11, 5]] {
            assert_eq!(values[grid.index(ijk)], field.value(grid.point(ijk), &mut scratch) as f32);
        }
    }
}
