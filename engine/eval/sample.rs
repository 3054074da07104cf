//! Area-uniform random points on a triangle mesh, as (face, barycentric) so the same samples
//! can be placed on any frame of a topology-consistent sequence.

use super::EvalError;
use crate::rng::SplitMix64;

/// A point on a mesh: face index and barycentric weights (b ≥ 0, Σb = 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceSample {
    /// Index of the face the point lies on.
    pub face: u32,
    /// Barycentric weights of the face's three corners, in face order.
    pub bary: [f64; 3],
}

/// Checks that every face index is in range and every position finite.
pub fn check_mesh(positions: &[[f32; 3]], faces: &[[u32; 3]]) -> Result<(), EvalError> {
    if positions.iter().flatten().any(|v| !v.is_finite()) {
        return Err(EvalError::NonFinite("mesh positions"));
    }
    for (face, f) in faces.iter().enumerate() {
        if let Some(&index) = f.iter().find(|&&i| i as usize >= positions.len()) {
            return Err(EvalError::FaceIndex { face, index, vertices: positions.len() });
        }
    }
    Ok(())
}

#[inline]
fn corner(positions: &[[f32; 3]], i: u32) -> [f64; 3] {
    positions[i as usize].map(f64::from)
}

/// Area of a triangle in squared scene units, in f64.
#[inline]
pub fn triangle_area(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
    let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    let n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
    0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt()
}

/// `n` points distributed uniformly by area over the mesh surface (faces picked with
/// probability proportional to area, barycentrics uniform on the triangle), deterministic for
/// `seed`. Zero-area faces are never picked; a mesh with no area is an error.
pub fn sample_surface(
    positions: &[[f32; 3]],
    faces: &[[u32; 3]],
    n: usize,
    seed: u64,
) -> Result<Vec<SurfaceSample>, EvalError> {
    check_mesh(positions, faces)?;
    let mut cumulative = Vec::with_capacity(faces.len());
    let mut total = 0.0f64;
    for f in faces {
        total += triangle_area(
            corner(positions, f[0]),
            corner(positions, f[1]),
            corner(positions, f[2]),
        );
        cumulative.push(total);
    }
    if total <= 0.0 || !total.is_finite() {
        return Err(EvalError::NoArea);
    }
    let mut rng = SplitMix64::new(seed);
    let samples = (0..n)
        .map(|_| {
            let u = rng.next_f64() * total;
            // First face whose cumulative area passes u: zero-area faces share their
            // predecessor's value and so are skipped.
            let face = cumulative.partition_point(|&c| c <= u).min(faces.len() - 1);
            let s = rng.next_f64().sqrt();
            let r = rng.next_f64();
            SurfaceSample { face: face as u32, bary: [1.0 - s, s * (1.0 - r), s * r] }
        })
        .collect();
    Ok(samples)
}

/// Positions of `samples` on a mesh with the faces they were drawn on (any frame of the
/// sequence). Faces and samples must come from [`sample_surface`] on the same face list.
pub fn surface_points(
    positions: &[[f32; 3]],
    faces: &[[u32; 3]],
    samples: &[SurfaceSample],
) -> Result<Vec<[f64; 3]>, EvalError> {
    check_mesh(positions, faces)?;
    samples
        .iter()
        .map(|s| {
            let f = faces
                .get(s.face as usize)
                .ok_or(EvalError::SampleFace { face: s.face, faces: faces.len() })?;
            let mut p = [0.0; 3];
            for (k, &b) in s.bary.iter().enumerate() {
                let v = corner(positions, f[k]);
                for d in 0..3 {
                    p[d] += b * v[d];
                }
            }
            Ok(p)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_follow_area_and_stay_inside() {
        // Two triangles, areas 1/2 and 3/2 (a 1×1 and a 3×1 right triangle) in the z = 0 plane.
        let p =
            [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [3.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
        let faces = [[0, 1, 2], [0, 3, 4], [1, 1, 2]];
        let s = sample_surface(&p, &faces, 20_000, 3).unwrap();
        assert!(s.iter().all(|s| s.face != 2), "a zero-area face was picked");
        let first = s.iter().filter(|s| s.face == 0).count() as f64 / s.len() as f64;
        assert!((first - 0.25).abs() < 0.015, "share of the small face {first}");
        for x in &s {
            assert!(
                x.bary.iter().all(|&b| b >= 0.0)
                    && (x.bary.iter().sum::<f64>() - 1.0).abs() < 1e-12
            );
        }
        // Uniform on the triangle: the mean of the samples is the centroid.
        let pts = surface_points(&p, &faces, &s).unwrap();
        let on0: Vec<_> =
            s.iter().zip(&pts).filter(|(s, _)| s.face == 0).map(|(_, p)| *p).collect();
        let mx = on0.iter().map(|p| p[0]).sum::<f64>() / on0.len() as f64;
        assert!((mx - 1.0 / 3.0).abs() < 0.02);
        assert_eq!(s, sample_surface(&p, &faces, 20_000, 3).unwrap());
    }

    #[test]
    fn bad_meshes() {
        assert!(matches!(
            sample_surface(&[[0.0; 3]; 3], &[[0, 1, 2]], 4, 0),
            Err(EvalError::NoArea)
        ));
        assert!(matches!(sample_surface(&[[0.0; 3]; 3], &[], 4, 0), Err(EvalError::NoArea)));
        assert!(matches!(
            sample_surface(&[[0.0; 3]; 3], &[[0, 1, 3]], 4, 0),
            Err(EvalError::FaceIndex { face: 0, index: 3, .. })
        ));
        assert!(matches!(
            sample_surface(&[[f32::NAN; 3]; 3], &[[0, 1, 2]], 4, 0),
            Err(EvalError::NonFinite(_))
        ));
    }
}
