//! Area-weighted vertex normals (CONVENTIONS.md: faces counter-clockwise from outside).

use glam::DVec3;

/// Unit normal of every vertex: the normalised sum of its faces' cross products (twice their
/// area times their unit normal). A vertex no face uses, or whose faces cancel, gets zero.
pub fn vertex_normals(positions: &[[f32; 3]], faces: &[[u32; 3]]) -> Vec<DVec3> {
    let mut normals = vec![DVec3::ZERO; positions.len()];
    for f in faces {
        let [a, b, c] = f.map(|i| DVec3::from(positions[i as usize].map(f64::from)));
        let n = (b - a).cross(c - a);
        for &v in f {
            normals[v as usize] += n;
        }
    }
    normals.into_iter().map(|n| n.normalize_or_zero()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn icosphere_normals_point_outward() {
        let (p, f) = crate::synth::icosphere::icosphere(2);
        let positions: Vec<[f32; 3]> = p.iter().map(|q| q.map(|c| c as f32)).collect();
        for (n, q) in vertex_normals(&positions, &f).iter().zip(&p) {
            assert!(n.dot(DVec3::from(*q)) > 0.999);
        }
        assert_eq!(vertex_normals(&[[0.0; 3]], &[]), vec![DVec3::ZERO]);
    }
}
