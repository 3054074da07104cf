//! Where the subject is: a box that surely holds the visual hull, found without any scene-size
//! constant. The rays through the silhouette centres meet (least squares) near the subject; a
//! box reaching from there to the farthest camera is carved conservatively on a coarse grid
//! (a cell survives when its projected rectangle touches the silhouette in every view but the
//! tolerated ones), and the survivors' box is carved again until it stops shrinking.

use super::field::ViewField;
use glam::{DMat3, DVec3};

/// An axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub lo: DVec3,
    pub hi: DVec3,
}

impl Aabb {
    pub fn size(&self) -> DVec3 {
        self.hi - self.lo
    }

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
    for _ in 0..12 {
        let next = carve_round(views, &tables, tolerance, aabb).ok_or(BoundsProblem::Disjoint)?;
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
    let (mut a, mut b, mut rays) = (DMat3::ZERO, DVec3::ZERO, 0);
    for v in views {
        let d = &v.distance;
        let (mut sum, mut count) = ((0.0, 0.0), 0usize);
        for (p, _) in d.values.iter().enumerate().filter(|(_, &x)| x > 0.0) {
            sum.0 += (p % d.width) as f64 + 0.5;
            sum.1 += (p / d.width) as f64 + 0.5;
            count += 1;
        }
        if count == 0 {
            continue;
        }
        let (o, dir) = v.camera.pixel_ray(sum.0 / count as f64, sum.1 / count as f64);
        // Σ (I − d dᵀ)(x − o) = 0: the point nearest every ray.
        let m = DMat3::IDENTITY - DMat3::from_cols(dir * dir.x, dir * dir.y, dir * dir.z);
        a += m;
        b += m * o;
        rays += 1;
    }
    // det(A) ~ sin² of the angle between rays; 1e-4 relative keeps angles above about 1°.
    let scale = (a.x_axis.x + a.y_axis.y + a.z_axis.z) / 3.0;
    (rays >= 2 && a.determinant() > 1e-4 * scale.powi(3)).then(|| a.inverse() * b)
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
                sums[(y + 1) * (w + 1) + x + 1] = inside + sums[y * (w + 1) + x + 1] + sums[(y + 1) * (w + 1) + x] - sums[y * (w + 1) + x];
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
        self.sums[y1 * w + x1] + self.sums[y0 * w + x0] > self.sums[y0 * w + x1] + self.sums[y1 * w + x0]
    }
}

/// Whether the box `cell` may hold hull points as seen by `view`: some corner at or behind the
/// camera plane (undecided), or its projected rectangle touches the silhouette.
fn cell_may_be_inside(view: &ViewField, coverage: &Coverage, cell: &Aabb) -> bool {
    let (mut u0, mut u1, mut v0, mut v1) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for corner in 0..8 {
        let p = DVec3::new(
            if corner & 1 == 0 { cell.lo.x } else { cell.hi.x },
            if corner & 2 == 0 { cell.lo.y } else { cell.hi.y },
            if corner & 4 == 0 { cell.lo.z } else { cell.hi.z },
        );
        let Some(q) = view.camera.project(p) else {
            return true;
        };
        (u0, u1, v0, v1) = (u0.min(q.x), u1.max(q.x), v0.min(q.y), v1.max(q.y));
    }
    coverage.touches(u0, u1, v0, v1)
}

/// One conservative round on a CELLS³ grid over `aabb`: the box of surviving cells grown by
/// one cell (clipped to `aabb`), or `None` when nothing survives.
fn carve_round(views: &[ViewField], tables: &[Coverage], tolerance: usize, aabb: Aabb) -> Option<Aabb> {
    let cell = aabb.size() / CELLS as f64;
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for k in 0..CELLS {
        for j in 0..CELLS {
            for i in 0..CELLS {
                let c_lo = aabb.lo + cell * DVec3::new(i as f64, j as f64, k as f64);
                let c = Aabb { lo: c_lo, hi: c_lo + cell };
                // Stops at the first view past the tolerance.
                let mut outside = 0;
                let kept = views.iter().zip(tables).all(|(v, t)| {
                    outside += usize::from(!cell_may_be_inside(v, t, &c));
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
