//! Keeps the largest connected piece of a mesh (by surface area) and drops the rest — stray
//! fragments carved out by noisy masks or by regions only a few cameras see.

/// Faces of the connected component (faces sharing a vertex) with the largest area, with the
/// vertices renumbered in first-use order; returns (positions, faces, components dropped).
pub fn largest_component(
    positions: &[[f32; 3]],
    faces: &[[u32; 3]],
) -> (Vec<[f32; 3]>, Vec<[u32; 3]>, usize) {
    let mut parent: Vec<u32> = (0..positions.len() as u32).collect();
    for f in faces {
        union(&mut parent, f[0], f[1]);
        union(&mut parent, f[1], f[2]);
    }
    let mut area = vec![0.0f64; positions.len()];
    for f in faces {
        let [a, b, c] = f.map(|i| glam::DVec3::from(positions[i as usize].map(f64::from)));
        area[find(&mut parent, f[0]) as usize] += 0.5 * (b - a).cross(c - a).length();
    }
    let mut roots: Vec<u32> = faces.iter().map(|f| find(&mut parent, f[0])).collect();
    roots.sort_unstable();
    roots.dedup();
    let Some(best) = (0..positions.len()).max_by(|&a, &b| area[a].total_cmp(&area[b])) else {
        return (Vec::new(), Vec::new(), 0);
    };
    let mut remap = vec![u32::MAX; positions.len()];
    let (mut kept_positions, mut kept_faces) = (Vec::new(), Vec::new());
    for f in faces {
        if find(&mut parent, f[0]) as usize != best {
            continue;
        }
        kept_faces.push(f.map(|v| {
            if remap[v as usize] == u32::MAX {
                remap[v as usize] = kept_positions.len() as u32;
                kept_positions.push(positions[v as usize]);
            }
            remap[v as usize]
        }));
    }
    (kept_positions, kept_faces, roots.len().saturating_sub(1))
}

fn find(parent: &mut [u32], mut v: u32) -> u32 {
    while parent[v as usize] != v {
        parent[v as usize] = parent[parent[v as usize] as usize];
        v = parent[v as usize];
    }
    v
}

fn union(parent: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        parent[ra.max(rb) as usize] = ra.min(rb);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_the_larger_tetrahedron() {
        let tetra = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]];
        let mut positions =
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        positions.extend([[5.0, 0.0, 0.0], [7.0, 0.0, 0.0], [5.0, 2.0, 0.0], [5.0, 0.0, 2.0]]);
        let mut faces: Vec<[u32; 3]> = tetra.to_vec();
        faces.extend(tetra.iter().map(|f| f.map(|v| v + 4)));
        let (p, f, dropped) = largest_component(&positions, &faces);
        assert_eq!(dropped, 1);
        assert_eq!(f.len(), 4);
        assert_eq!(p.len(), 4);
        assert!(p.iter().all(|q| q[0] >= 5.0), "the twice larger copy is kept");
        assert_eq!(crate::synth::manifold::closed_manifold_problem(p.len(), &f), None);
        assert_eq!(largest_component(&[], &[]).1.len(), 0);
    }
}
