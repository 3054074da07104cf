//! Where the subject is: a box that surely holds the visual hull, found without any scene-size
//! constant. The rays through the silhouette centres meet (least squares) near the subject; a
//! box reaching from there to the farthest camera is carved conservatively on a coarse grid
//! (a cell survives when the rectangle its part beyond a near plane projects to touches the
//! silhouette in every view but the tolerated ones), and the survivors' box is carved again
//! until it stops shrinking.

use super::field::ViewField;
use glam::DVec3;

/// An axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Lower corner, world units.
    pub lo: DVec3,
    /// Upper corner, world units.
    pub hi: DVec3,
}

impl Aabb {
    /// Edge lengths along x, y and z (`hi - lo`).
    pub fn size(&self) -> DVec3 {
        self.hi - self.lo
    }

    /// Product of the edge lengths.
    pub fn volume(&self) -> f64 {
        self.size().x * self.size().y * self.size().z
    }
}

/// Why no box was found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BoundsProblem {
    /// The rays through the silhouette centres are (nearly) parallel or there are fewer than
    /// two of them.
    Parallel,
    /// No region of space projects into enough silhouettes.
    Disjoint,
}

/// Cells per axis of each conservative carving round.
const CELLS: usize = 32;

/// A box holding every point the hull keeps (with a margin of one coarse cell), or why none.
pub fn hull_bounds(views: &[ViewField], tolerance: usize) -> Result<Aabb, BoundsProblem> {
    let center = locate_subject(views).ok_or(BoundsProblem::Parallel)?;
    let reach = views.iter().map(|v| v.camera.center().distance(center)).fold(0.0, f64::max);
    let mut aabb = Aabb { lo: center - DVec3::splat(reach), hi: center + DVec3::splat(reach) };
    let tables: Vec<Coverage> = views.iter().map(Coverage::new).collect();
    let near: Vec<f64> = views.iter().map(|v| 0.01 * v.camera.center().distance(center)).collect();
    for _ in 0..12 {
        let next =
            carve_round(views, &tables, &near, tolerance, aabb).ok_or(BoundsProblem::Disjoint)?;
        let shrink = next.volume() / aabb.volume();
        aabb = next;
        if shrink > 0.8 {
            break;
        }
    }
    Ok(aabb)
}

/// Least-squares meeting point of the rays through each non-empty silhouette's centroid;
/// `None` when fewer than two such rays exist or they are nearly parallel.
pub fn locate_subject(views: &[ViewField]) -> Option<DVec3> {
    let rays = views.iter().filter_map(|v| {
        let d = &v.distance;
        let (mut sum, mut count) = ((0.0, 0.0), 0usize);
        for (p, _) in d.values.iter().enumerate().filter(|(_, &x)| x > 0.0) {
            sum.0 += (p % d.width) as f64 + 0.5;
            sum.1 += (p / d.width) as f64 + 0.5;
            count += 1;
        }
        (count > 0).then(|| v.camera.pixel_ray(sum.0 / count as f64, sum.1 / count as f64))
    });
    crate::camera::nearest_point_to_rays(rays)
}

/// A summed-area table of a view's silhouette (signed distance > 0).
struct Coverage {
    width: usize,
    height: usize,
    sums: Vec<u32>,
}

impl Coverage {
    fn new(view: &ViewField) -> Self {
        let d = &view.distance;
        let (w, h) = (d.width, d.height);
        let mut sums = vec![0u32; (w + 1) * (h + 1)];
        for y in 0..h {
            for x in 0..w {
                let inside = u32::from(d.values[y * w + x] > 0.0);
                sums[(y + 1) * (w + 1) + x + 1] =
                    inside + sums[y * (w + 1) + x + 1] + sums[(y + 1) * (w + 1) + x]
                        - sums[y * (w + 1) + x];
            }
        }
        Self { width: w, height: h, sums }
    }

    /// Whether any silhouette pixel centre lies in [u0, u1] × [v0, v1] (pixel coordinates).
    fn touches(&self, u0: f64, u1: f64, v0: f64, v1: f64) -> bool {
        let x0 = (u0 - 0.5).ceil().max(0.0);
        let y0 = (v0 - 0.5).ceil().max(0.0);
        let x1 = ((u1 - 0.5).floor() + 1.0).min(self.width as f64);
        let y1 = ((v1 - 0.5).floor() + 1.0).min(self.height as f64);
        if !(x0 < x1 && y0 < y1) {
            return false;
        }
        let (x0, y0, x1, y1) = (x0 as usize, y0 as usize, x1 as usize, y1 as usize);
        let w = self.width + 1;
        self.sums[y1 * w + x1] + self.sums[y0 * w + x0]
            > self.sums[y0 * w + x1] + self.sums[y1 * w + x0]
    }
}

/// Whether the box `cell` may hold hull points at depth ≥ `near` in `view`: the part of the
/// cell in front of that plane (corners, and cell edges cut by it) projects to a rectangle that
/// touches the silhouette. Points nearer than `near` (a hundredth of the camera's distance to
/// the subject) are not the subject; testing them would let every cell crossing the camera
/// plane through, since those project everywhere.
fn cell_may_be_inside(view: &ViewField, coverage: &Coverage, cell: &Aabb, near: f64) -> bool {
    let corner = |c: usize| {
        let p = DVec3::new(
            if c & 1 == 0 { cell.lo.x } else { cell.hi.x },
            if c & 2 == 0 { cell.lo.y } else { cell.hi.y },
            if c & 4 == 0 { cell.lo.z } else { cell.hi.z },
        );
        view.camera.to_camera(p)
    };
    let corners: [DVec3; 8] = std::array::from_fn(corner);
    let mut front: Vec<DVec3> = corners.iter().copied().filter(|c| c.z >= near).collect();
    for a in 0..8 {
        for bit in [1, 2, 4] {
            let (p, q) = (corners[a], corners[a | bit]);
            if a & bit == 0 && (p.z >= near) != (q.z >= near) {
                front.push(p + (near - p.z) / (q.z - p.z) * (q - p));
            }
        }
    }
    if front.is_empty() {
        return false;
    }
    let cam = &view.camera;
    let (mut u0, mut u1, mut v0, mut v1) =
        (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for c in front {
        let (u, v) = (cam.fx * c.x / c.z + cam.cx, cam.fy * c.y / c.z + cam.cy);
        (u0, u1, v0, v1) = (u0.min(u), u1.max(u), v0.min(v), v1.max(v));
    }
    coverage.touches(u0, u1, v0, v1)
}

/// One conservative round on a CELLS³ grid over `aabb`: the box of surviving cells grown by
/// one cell (clipped to `aabb`), or `None` when nothing survives.
fn carve_round(
    views: &[ViewField],
    tables: &[Coverage],
    near: &[f64],
    tolerance: usize,
    aabb: Aabb,
) -> Option<Aabb> {
    let cell = aabb.size() / CELLS as f64;
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for k in 0..CELLS {
        for j in 0..CELLS {
            for i in 0..CELLS {
                let c_lo = aabb.lo + cell * DVec3::new(i as f64, j as f64, k as f64);
                let c = Aabb { lo: c_lo, hi: c_lo + cell };
                // Stops at the first view past the tolerance.
                let mut outside = 0;
                let kept = views.iter().zip(tables).zip(near).all(|((v, t), &n)| {
                    outside += usize::from(!cell_may_be_inside(v, t, &c, n));
                    outside <= tolerance
                });
                if kept {
                    lo = lo.min(c.lo);
                    hi = hi.max(c.hi);
                }
            }
        }
    }
    (lo.x <= hi.x).then(|| Aabb { lo: (lo - cell).max(aabb.lo), hi: (hi + cell).min(aabb.hi) })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::init::field::tests::{camera, sphere_view};

    fn check(eyes: &[DVec3], r: f64) -> Aabb {
        let views: Vec<ViewField> = eyes.iter().map(|&e| sphere_view(camera(e), r)).collect();
        let located = locate_subject(&views).unwrap();
        assert!(located.length() < 0.05, "the silhouette rays meet at the centre: {located}");
        let b = hull_bounds(&views, 0).unwrap();
        assert!(b.lo.max_element() < -r && b.hi.min_element() > r, "holds the sphere: {b:?}");
        b
    }

    #[test]
    fn box_holds_the_sphere_and_is_tight() {
        // A surround rig and a forward-facing one (cameras within 50° of each other).
        let surround = check(
            &[3.0 * DVec3::X, 3.0 * DVec3::Z, -3.0 * DVec3::X, DVec3::new(0.1, 3.0, 0.2)],
            0.5,
        );
        assert!(surround.size().max_element() < 1.6, "{surround:?}");
        let forward = [
            DVec3::new(0.0, 0.0, 3.0),
            DVec3::new(1.2, 0.3, 2.7),
            DVec3::new(-1.2, -0.3, 2.7),
            DVec3::new(0.3, 1.3, 2.6),
        ];
        let b = check(&forward, 0.5);
        // Depth is poorly constrained by a narrow rig, but the box still shrinks far below
        // the 6-unit start.
        assert!(b.size().max_element() < 3.0, "{b:?}");
    }

    #[test]
    fn parallel_and_disjoint_views_are_refused() {
        let one = sphere_view(camera(3.0 * DVec3::X), 0.5);
        assert_eq!(hull_bounds(&[one.clone(), one.clone()], 0), Err(BoundsProblem::Parallel));
        // The second camera looks at the origin, but its mask shows the sphere 18 rows (about
        // one unit) lower: its cone passes a unit from the first one's axis and they miss.
        let mut off = sphere_view(camera(3.0 * DVec3::Z), 0.5);
        let shift = 18 * off.distance.width;
        let shifted: Vec<f32> = (0..off.distance.values.len())
            .map(|p| if p >= shift { off.distance.values[p - shift] } else { -20.0 })
            .collect();
        off.distance.values = shifted;
        assert_eq!(hull_bounds(&[one.clone(), off.clone()], 0), Err(BoundsProblem::Disjoint));
        // One disagreeing view allowed: either cone alone is a hull.
        assert!(hull_bounds(&[one, off], 1).is_ok());
    }
}
