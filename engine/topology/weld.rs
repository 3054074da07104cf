//! Welding: vertices closer than a tolerance become one (seams of UV-split exports).

use super::remap::NEW_ROW;
use std::collections::HashMap;

/// Result of [`weld`]: the kept positions, faces re-indexed (faces that lost a corner to the
/// weld dropped), `old_of_new` (each kept vertex's first old row) and the count of dropped faces.
#[derive(Clone, Debug)]
pub struct Welded {
    /// The kept positions, in order of first occurrence.
    pub positions: Vec<[f32; 3]>,
    /// The surviving faces, indexing `positions`.
    pub faces: Vec<[u32; 3]>,
    /// For each kept vertex, the input row it was taken from.
    pub old_of_new: Vec<u32>,
    /// Number of input faces dropped because two of their corners merged.
    pub dropped_faces: usize,
}

/// Merges every vertex into the first earlier vertex within `tolerance` (Euclidean), found
/// through a hash grid of cell `tolerance`; `tolerance <= 0` merges exact duplicates only.
/// Faces must index inside `positions`.
pub fn weld(positions: &[[f32; 3]], faces: &[[u32; 3]], tolerance: f32) -> Welded {
    // Exact mode keys on the bits (+0.0 folds -0.0 into 0.0) and looks in one cell only.
    let exact = tolerance.is_nan() || tolerance <= 0.0;
    let cell_of = |p: [f32; 3]| {
        p.map(|c| if exact { (c + 0.0).to_bits() as i64 } else { (c / tolerance).floor() as i64 })
    };
    let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
    let mut new_of_old = vec![NEW_ROW; positions.len()];
    let mut old_of_new = Vec::new();
    let mut kept = Vec::new();
    for (v, &p) in positions.iter().enumerate() {
        let c = cell_of(p);
        let near = neighbour_cells(c, exact).find_map(|n| {
            grid.get(&n)?
                .iter()
                .copied()
                .find(|&k| distance(kept[k as usize], p) <= tolerance.max(0.0))
        });
        new_of_old[v] = match near {
            Some(k) => k,
            None => {
                grid.entry(c).or_default().push(kept.len() as u32);
                kept.push(p);
                old_of_new.push(v as u32);
                kept.len() as u32 - 1
            }
        };
    }
    let remapped = faces.iter().map(|f| f.map(|v| new_of_old[v as usize]));
    let welded: Vec<[u32; 3]> =
        remapped.filter(|f| f[0] != f[1] && f[1] != f[2] && f[2] != f[0]).collect();
    Welded { positions: kept, dropped_faces: faces.len() - welded.len(), faces: welded, old_of_new }
}

#[inline]
fn distance(a: [f32; 3], b: [f32; 3]) -> f32 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

fn neighbour_cells(c: [i64; 3], exact: bool) -> impl Iterator<Item = [i64; 3]> {
    let offsets = if exact { 13..14 } else { 0..27 };
    offsets.map(move |i| [c[0] + i % 3 - 1, c[1] + (i / 3) % 3 - 1, c[2] + i / 9 - 1])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seam_duplicates_merge_and_collapsed_faces_drop() {
        // Two triangles of a quad exported with a seam: vertices 1/3 and 2/4 coincide.
        let positions = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 0.0, 1e-7],
            [0.0, 1.0, 0.0],
            [1.0, 1.0, 0.0],
        ];
        let faces = [[0, 1, 2], [3, 5, 4], [1, 3, 2]];
        let w = weld(&positions, &faces, 1e-5);
        assert_eq!(w.old_of_new, vec![0, 1, 2, 5]);
        assert_eq!(w.faces, vec![[0, 1, 2], [1, 3, 2]]);
        assert_eq!(w.dropped_faces, 1);
        let exact = weld(&positions, &faces, 0.0);
        assert_eq!(exact.old_of_new, vec![0, 1, 2, 3, 5]);
    }
}
