//! Polygons to triangles, the same way for every reader: a fan from each polygon's first vertex.

/// Triangles of the polygons `counts` (vertices per polygon) over `indices` (their vertex
/// indices, concatenated): polygon `p` = (v0, v1, … vk) gives (v0, vi, vi+1) for i = 1 … k−1,
/// keeping its winding. Also returns, per triangle, the polygon it came from.
///
/// Guarantees: every index is below `vertices`; the counts add up to `indices.len()`. Errors
/// (naming the polygon): a polygon of fewer than 3 vertices, an index out of range, counts that
/// do not add up.
pub fn fan_triangulate(
    counts: &[u32],
    indices: &[u32],
    vertices: usize,
) -> Result<(Vec<[u32; 3]>, Vec<u32>), String> {
    let total: u64 = counts.iter().map(|&c| u64::from(c)).sum();
    if total != indices.len() as u64 {
        return Err(format!(
            "the polygon sizes add up to {total} corners, the index list has {}",
            indices.len()
        ));
    }
    let triangles = counts.iter().map(|&c| c.saturating_sub(2) as usize).sum();
    let (mut faces, mut polygon_of) =
        (Vec::with_capacity(triangles), Vec::with_capacity(triangles));
    let mut start = 0;
    for (p, &count) in counts.iter().enumerate() {
        let polygon = &indices[start..start + count as usize];
        start += count as usize;
        if polygon.len() < 3 {
            return Err(format!("polygon {p} has {} vertices", polygon.len()));
        }
        if let Some(&v) = polygon.iter().find(|&&v| v as usize >= vertices) {
            return Err(format!("polygon {p} indexes vertex {v}, past the {vertices} vertices"));
        }
        faces.extend(polygon.windows(2).skip(1).map(|w| [polygon[0], w[0], w[1]]));
        polygon_of.extend(std::iter::repeat_n(p as u32, polygon.len() - 2));
    }
    Ok((faces, polygon_of))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fans_a_quad_and_a_pentagon_keeping_winding() {
        let (faces, of) =
            fan_triangulate(&[4, 3, 5], &[0, 1, 2, 3, 2, 1, 4, 0, 1, 2, 3, 4], 5).unwrap();
        assert_eq!(faces, [[0, 1, 2], [0, 2, 3], [2, 1, 4], [0, 1, 2], [0, 2, 3], [0, 3, 4]]);
        assert_eq!(of, [0, 0, 1, 2, 2, 2]);
    }

    #[test]
    fn refuses_degenerate_polygons_bad_indices_and_bad_counts() {
        assert!(fan_triangulate(&[2], &[0, 1], 3).unwrap_err().contains("polygon 0 has 2"));
        assert!(fan_triangulate(&[3], &[0, 1, 7], 3).unwrap_err().contains("vertex 7"));
        assert!(fan_triangulate(&[3, 3], &[0, 1, 2], 3).unwrap_err().contains("add up to 6"));
        assert!(fan_triangulate(&[u32::MAX; 4], &[0, 1, 2], 3).is_err());
    }
}
