//! A closed unit sphere mesh by subdividing an octahedron: the surface the tracking benchmark
//! and tests query (no degenerate triangles, counter-clockwise from outside).

use std::collections::HashMap;

/// The octahedron subdivided `level` times (each triangle into four), vertices pushed onto the
/// unit sphere: 8·4^level faces, 4^level·4 + 2 vertices.
pub fn unit_sphere(level: u32) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let mut positions: Vec<[f64; 3]> = vec![
        [1.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, -1.0],
    ];
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 2, 4],
        [2, 1, 4],
        [1, 3, 4],
        [3, 0, 4],
        [2, 0, 5],
        [1, 2, 5],
        [3, 1, 5],
        [0, 3, 5],
    ];
    for _ in 0..level {
        let mut midpoints: HashMap<(u32, u32), u32> = HashMap::new();
        let mut midpoint = |a: u32, b: u32, positions: &mut Vec<[f64; 3]>| {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let (pa, pb) = (positions[a as usize], positions[b as usize]);
                let m = [0, 1, 2].map(|k| (pa[k] + pb[k]) * 0.5);
                let len = (m[0] * m[0] + m[1] * m[1] + m[2] * m[2]).sqrt();
                positions.push(m.map(|c| c / len));
                positions.len() as u32 - 1
            })
        };
        faces = faces
            .iter()
            .flat_map(|&[a, b, c]| {
                let (ab, bc, ca) = (
                    midpoint(a, b, &mut positions),
                    midpoint(b, c, &mut positions),
                    midpoint(c, a, &mut positions),
                );
                [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
            })
            .collect();
    }
    (positions.iter().map(|p| p.map(|c| c as f32)).collect(), faces)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_closure_and_orientation() {
        let (positions, faces) = unit_sphere(2);
        assert_eq!((positions.len(), faces.len()), (66, 128));
        // Closed: Euler characteristic 2. Outward: every face normal points away from the centre.
        assert_eq!(positions.len() as i64 - faces.len() as i64 * 3 / 2 + faces.len() as i64, 2);
        for f in &faces {
            let [a, b, c] = f.map(|i| glam::Vec3::from(positions[i as usize]));
            assert!((b - a).cross(c - a).dot(a + b + c) > 0.0);
        }
    }
}
