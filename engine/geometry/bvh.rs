//! A BVH over a triangle mesh (built by `obvhs`) with exact closest-point and ray queries.
//!
//! obvhs builds the tree; the traversals are ours because obvhs has no closest-point query and
//! its ray traversal runs in f32. Both walk `Bvh2::nodes` with an explicit stack: an inner node's
//! children sit at `first_index` and `first_index + 1`, a leaf holds the slots
//! `first_index..first_index + prim_count` of `primitive_indices`. Node boxes are the f32 bounds
//! of f32 corners, so distances to them are true lower bounds and the pruning never drops the
//! answer: results equal brute force over the same triangle routines.

use super::triangle::{closest_on_triangle, interpolate, ray_triangle};
use super::SurfaceError;
use crate::camera::Camera;
use glam::{DVec2, DVec3, Vec3A};
use obvhs::aabb::Aabb;
use obvhs::bvh2::builder::build_bvh2;
use obvhs::bvh2::Bvh2;
use obvhs::triangle::Triangle;
use obvhs::BvhBuildParams;
use std::time::Duration;

/// A point on the surface: face index, barycentric coordinates and the point itself.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// Index of the face the point lies on.
    pub face: u32,
    /// Weights of the face's three corners, in face order, summing to 1.
    pub barycentric: [f64; 3],
    /// The point, in the mesh's coordinates.
    pub position: DVec3,
    /// Distance from the query point (closest-point query) or ray parameter t (ray cast,
    /// in units of the ray direction's length).
    pub distance: f64,
}

/// A BVH over the triangles of one mesh, with the corners stored in BVH leaf order.
pub struct SurfaceBvh {
    bvh: Bvh2,
    /// Corners of the triangle in each `primitive_indices` slot.
    corners: Vec<[DVec3; 3]>,
}

impl SurfaceBvh {
    /// Builds the BVH over `faces` of `positions`.
    ///
    /// Errors: no faces, a face index out of range, a non-finite position.
    pub fn build(positions: &[[f32; 3]], faces: &[[u32; 3]]) -> Result<SurfaceBvh, SurfaceError> {
        let triangles = triangles(positions, faces)?;
        // No spatial splits: every leaf box then holds its whole triangle (see the module doc).
        let params = BvhBuildParams { pre_split: false, ..BvhBuildParams::medium_build() };
        let obvhs_tris: Vec<Triangle> = triangles
            .iter()
            .map(|t| Triangle {
                v0: Vec3A::from(t[0]),
                v1: Vec3A::from(t[1]),
                v2: Vec3A::from(t[2]),
            })
            .collect();
        let bvh = build_bvh2(&obvhs_tris, params, &mut Duration::default());
        let corners = bvh
            .primitive_indices
            .iter()
            .map(|&i| triangles[i as usize].map(|v| DVec3::from(v.map(f64::from))))
            .collect();
        Ok(SurfaceBvh { bvh, corners })
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.corners.len()
    }

    /// Never true: `build` refuses an empty mesh.
    pub fn is_empty(&self) -> bool {
        self.corners.is_empty()
    }

    /// The surface point closest to `p`. Among faces at the same distance, the first one the
    /// traversal meets wins. None only for a non-finite `p`.
    pub fn closest_point(&self, p: DVec3) -> Option<SurfacePoint> {
        if !p.is_finite() {
            return None;
        }
        let nodes = &self.bvh.nodes;
        let mut best_d2 = f64::INFINITY;
        let mut best = None;
        let mut stack: Vec<(u32, f64)> = Vec::with_capacity(64);
        stack.push((0, box_distance_squared(nodes[0].aabb(), p)));
        while let Some((index, d2)) = stack.pop() {
            if d2 >= best_d2 {
                continue;
            }
            let node = &nodes[index as usize];
            if node.prim_count > 0 {
                for slot in node.first_index..node.first_index + node.prim_count {
                    let [a, b, c] = self.corners[slot as usize];
                    let bary = closest_on_triangle(p, a, b, c);
                    let q = interpolate(bary, a, b, c);
                    let d2 = p.distance_squared(q);
                    if d2 < best_d2 {
                        best_d2 = d2;
                        best = Some((slot, bary, q));
                    }
                }
                continue;
            }
            let (l, r) = (node.first_index, node.first_index + 1);
            let dl = box_distance_squared(nodes[l as usize].aabb(), p);
            let dr = box_distance_squared(nodes[r as usize].aabb(), p);
            // Push the farther child first so the nearer one is searched first.
            let (near, far) = if dl <= dr { ((l, dl), (r, dr)) } else { ((r, dr), (l, dl)) };
            if far.1 < best_d2 {
                stack.push(far);
            }
            if near.1 < best_d2 {
                stack.push(near);
            }
        }
        best.map(|(slot, barycentric, position)| SurfacePoint {
            face: self.bvh.primitive_indices[slot as usize],
            barycentric,
            position,
            distance: best_d2.sqrt(),
        })
    }

    /// The first surface point hit by the ray `origin + t·dir`, t ≥ 0 (either side of a face).
    /// `distance` is t. None for a miss or a non-finite or zero ray.
    pub fn ray_cast(&self, origin: DVec3, dir: DVec3) -> Option<SurfacePoint> {
        if !origin.is_finite() || !dir.is_finite() || dir == DVec3::ZERO {
            return None;
        }
        let inv_dir = dir.recip();
        let nodes = &self.bvh.nodes;
        let mut t_best = f64::INFINITY;
        let mut best = None;
        let mut stack: Vec<(u32, f64)> = Vec::with_capacity(64);
        if let Some(t) = box_entry(nodes[0].aabb(), origin, inv_dir) {
            stack.push((0, t));
        }
        while let Some((index, t_enter)) = stack.pop() {
            if t_enter > t_best {
                continue;
            }
            let node = &nodes[index as usize];
            if node.prim_count > 0 {
                for slot in node.first_index..node.first_index + node.prim_count {
                    let [a, b, c] = self.corners[slot as usize];
                    if let Some((t, bary)) = ray_triangle(origin, dir, t_best, a, b, c) {
                        t_best = t;
                        best = Some((slot, bary));
                    }
                }
                continue;
            }
            let (l, r) = (node.first_index, node.first_index + 1);
            let tl = box_entry(nodes[l as usize].aabb(), origin, inv_dir);
            let tr = box_entry(nodes[r as usize].aabb(), origin, inv_dir);
            let mut children = [(l, tl), (r, tr)];
            if tr.unwrap_or(f64::INFINITY) > tl.unwrap_or(f64::INFINITY) {
                children.swap(0, 1);
            }
            for (child, t) in children {
                if let Some(t) = t.filter(|&t| t <= t_best) {
                    stack.push((child, t));
                }
            }
        }
        best.map(|(slot, barycentric)| {
            let [a, b, c] = self.corners[slot as usize];
            SurfacePoint {
                face: self.bvh.primitive_indices[slot as usize],
                barycentric,
                position: interpolate(barycentric, a, b, c),
                distance: t_best,
            }
        })
    }

    /// Whether the surface blocks the sight line from `eye` to `p`: a hit nearer than
    /// `(1 − slack) · |p − eye|`, so the surface a point lies on does not hide it.
    pub fn hides(&self, eye: DVec3, p: DVec3, slack: f64) -> bool {
        let to_point = p - eye;
        let distance = to_point.length();
        // The ray direction is unit, so the hit's ray parameter is a distance.
        self.ray_cast(eye, to_point / distance)
            .is_some_and(|hit| hit.distance < distance * (1.0 - slack))
    }

    /// `p`'s pixel coordinates in `camera` (pixel (i, j)'s centre at (i + 0.5, j + 0.5)) when
    /// the camera sees it: in front of it, inside the image, and not hidden by this surface
    /// (`hides` with `slack`). None otherwise.
    pub fn sees(&self, camera: &Camera, p: DVec3, slack: f64) -> Option<DVec2> {
        let uv = camera.project(p)?;
        let (width, height) = (camera.width as f64, camera.height as f64);
        let inside = uv.x >= 0.0 && uv.y >= 0.0 && uv.x < width && uv.y < height;
        (inside && !self.hides(camera.center(), p, slack)).then_some(uv)
    }
}

/// The corners of every face, checked: at least one face, indices in range, finite positions.
pub fn triangles(
    positions: &[[f32; 3]],
    faces: &[[u32; 3]],
) -> Result<Vec<[[f32; 3]; 3]>, SurfaceError> {
    if faces.is_empty() {
        return Err(SurfaceError::EmptyMesh);
    }
    if let Some(vertex) = positions.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
        return Err(SurfaceError::NonFinitePosition { vertex });
    }
    faces
        .iter()
        .enumerate()
        .map(|(face, f)| {
            let corner = |k: usize| {
                positions.get(f[k] as usize).copied().ok_or(SurfaceError::IndexOutOfRange {
                    face,
                    index: f[k],
                    vertices: positions.len(),
                })
            };
            Ok([corner(0)?, corner(1)?, corner(2)?])
        })
        .collect()
}

/// Squared distance from `p` to the box (0 inside).
#[inline]
fn box_distance_squared(aabb: &Aabb, p: DVec3) -> f64 {
    let min = aabb.min.as_dvec3();
    let max = aabb.max.as_dvec3();
    let d = (min - p).max(p - max).max(DVec3::ZERO);
    d.length_squared()
}

/// Ray parameter at which the ray enters the closed box (0 when it starts inside), None for a
/// miss. Slab test; an axis the ray is parallel to only checks that the origin is in its slab.
#[inline]
fn box_entry(aabb: &Aabb, origin: DVec3, inv_dir: DVec3) -> Option<f64> {
    let (min, max) = (aabb.min.as_dvec3(), aabb.max.as_dvec3());
    let mut t_near = 0.0f64;
    let mut t_far = f64::INFINITY;
    for axis in 0..3 {
        if inv_dir[axis].is_infinite() {
            if origin[axis] < min[axis] || origin[axis] > max[axis] {
                return None;
            }
            continue;
        }
        let t0 = (min[axis] - origin[axis]) * inv_dir[axis];
        let t1 = (max[axis] - origin[axis]) * inv_dir[axis];
        t_near = t_near.max(t0.min(t1));
        t_far = t_far.min(t0.max(t1));
    }
    (t_near <= t_far).then_some(t_near)
}
