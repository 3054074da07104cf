//! A check the generator runs on every subject before it writes anything.

use std::collections::HashMap;

/// `None` when the faces form a closed, consistently oriented 2-manifold: every directed edge
/// appears exactly once and its reverse exactly once, every vertex is used, and every vertex
/// link is a single cycle (no pinched vertices). Otherwise the first problem found.
pub fn closed_manifold_problem(vertex_count: usize, faces: &[[u32; 3]]) -> Option<String> {
    let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
    for (f, face) in faces.iter().enumerate() {
        if face.iter().any(|&v| v as usize >= vertex_count) {
            return Some(format!("face {f} indexes past the {vertex_count} vertices"));
        }
        if face[0] == face[1] || face[1] == face[2] || face[2] == face[0] {
            return Some(format!("face {f} {face:?} repeats a vertex"));
        }
        for k in 0..3 {
            if directed.insert((face[k], face[(k + 1) % 3]), f).is_some() {
                return Some(format!(
                    "edge {}→{} is used twice in the same direction (face {f})",
                    face[k],
                    face[(k + 1) % 3]
                ));
            }
        }
    }
    if let Some((a, b)) = directed.keys().find(|(a, b)| !directed.contains_key(&(*b, *a))) {
        return Some(format!("edge {a}–{b} has only one face (the surface is open)"));
    }
    // Vertex links: around vertex v, each face (v, a, b) maps a → b; a disk is one cycle.
    let mut link: Vec<HashMap<u32, u32>> = vec![HashMap::new(); vertex_count];
    for face in faces {
        for k in 0..3 {
            link[face[k] as usize].insert(face[(k + 1) % 3], face[(k + 2) % 3]);
        }
    }
    for (v, next) in link.iter().enumerate() {
        let Some(&start) = next.keys().next() else {
            return Some(format!("vertex {v} is used by no face"));
        };
        let (mut at, mut steps) = (start, 0);
        loop {
            at = next[&at]; // present: every edge has its reverse
            steps += 1;
            if at == start {
                break;
            }
        }
        if steps != next.len() {
            return Some(format!("vertex {v} is pinched (its faces form more than one fan)"));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn detects_open_flipped_and_pinched() {
        let tetra = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]];
        assert_eq!(closed_manifold_problem(4, &tetra), None);
        assert!(closed_manifold_problem(4, &tetra[..3]).unwrap().contains("open"));
        let flipped = [[0, 1, 2], [0, 1, 3], [1, 2, 3], [0, 3, 2]];
        assert!(closed_manifold_problem(4, &flipped).unwrap().contains("same direction"));
        assert!(closed_manifold_problem(5, &tetra).unwrap().contains("vertex 4"));
        // Two tetrahedra sharing vertex 0 only: closed, but 0 is pinched.
        let two = [
            [0, 2, 1],
            [0, 1, 3],
            [1, 2, 3],
            [0, 3, 2],
            [0, 5, 4],
            [0, 4, 6],
            [4, 5, 6],
            [0, 6, 5],
        ];
        assert!(closed_manifold_problem(7, &two).unwrap().contains("pinched"));
    }
}
