//! A unit icosphere: a closed, manifold, counter-clockwise (seen from outside) triangle mesh
//! with nearly equal edge lengths, the base of the procedural subject.

use std::collections::HashMap;

/// Icosahedron subdivided `levels` times (each level splits every triangle into four), vertices
/// on the unit sphere: 10·4^levels + 2 vertices, 20·4^levels faces.
pub fn icosphere(levels: u32) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut positions: Vec<[f64; 3]> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|&p| normalize(p))
    .collect();
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut midpoint: HashMap<(u32, u32), u32> = HashMap::new();
        let mut split = |a: u32, b: u32, positions: &mut Vec<[f64; 3]>| -> u32 {
            *midpoint.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let (p, q) = (positions[a as usize], positions[b as usize]);
                positions.push(normalize([p[0] + q[0], p[1] + q[1], p[2] + q[2]]));
                positions.len() as u32 - 1
            })
        };
        let mut next = Vec::with_capacity(faces.len() * 4);
        for &[a, b, c] in &faces {
            let ab = split(a, b, &mut positions);
            let bc = split(b, c, &mut positions);
            let ca = split(c, a, &mut positions);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        faces = next;
    }
    (positions, faces)
}

#[inline]
fn normalize(p: [f64; 3]) -> [f64; 3] {
    let l = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
    [p[0] / l, p[1] / l, p[2] / l]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_orientation_and_closure() {
        for levels in 0..3 {
            let (p, f) = icosphere(levels);
            assert_eq!(p.len(), 10 * 4usize.pow(levels) + 2);
            assert_eq!(f.len(), 20 * 4usize.pow(levels));
            // Outward: every face normal points away from the centre.
            for &[a, b, c] in &f {
                let (a, b, c) = (p[a as usize], p[b as usize], p[c as usize]);
                let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
                let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
                let n = [
                    u[1] * v[2] - u[2] * v[1],
                    u[2] * v[0] - u[0] * v[2],
                    u[0] * v[1] - u[1] * v[0],
                ];
                assert!(n[0] * a[0] + n[1] * a[1] + n[2] * a[2] > 0.0);
            }
            assert!(crate::synth::manifold::closed_manifold_problem(p.len(), &f).is_none());
        }
    }
}
