//! Node transforms that carry a graph's rest pose onto a posed copy of the same mesh: each node
//! the best rigid motion (least squares, Horn's quaternion method) of the vertices bound to it.
//! How a frame-0 graph starts from where the previous frames left the surface.

use super::graph::{DeformGraph, NODES_PER_VERTEX};
use super::reference::NodeTransforms;
use glam::{DMat3, DQuat, DVec3};

/// Per node k, the rotation R_k and translation t_k minimising
/// Σ_i w_ik ‖R_k (x_i − g_k) + g_k + t_k − y_i‖² over the vertices i bound to k (w_ik their
/// binding weights, x rest, y posed, g_k the node's rest position). Guarantees: a posed copy that
/// is a rigid motion of the rest pose gives that motion at every node exactly (up to rounding);
/// a node whose vertices are degenerate (collinear, one vertex) still gets a rotation that fits
/// them, and the best translation for it.
pub fn fit_nodes(rest: &[[f32; 3]], posed: &[[f32; 3]], graph: &DeformGraph) -> NodeTransforms {
    let nodes = graph.node_vertices.len();
    let mut sums = vec![(0.0f64, DVec3::ZERO, DVec3::ZERO); nodes];
    let point = |p: &[f32; 3]| DVec3::from(p.map(f64::from));
    for (i, (bound, weights)) in graph.bound_nodes.iter().zip(&graph.bound_weights).enumerate() {
        for s in (0..NODES_PER_VERTEX).filter(|&s| weights[s] > 0.0) {
            let (w, sum) = (weights[s] as f64, &mut sums[bound[s] as usize]);
            (sum.0, sum.1, sum.2) =
                (sum.0 + w, sum.1 + w * point(&rest[i]), sum.2 + w * point(&posed[i]));
        }
    }
    let centroids: Vec<(DVec3, DVec3)> = sums
        .iter()
        .map(|&(w, r, p)| if w > 0.0 { (r / w, p / w) } else { (DVec3::ZERO, DVec3::ZERO) })
        .collect();
    let mut covariance = vec![DMat3::ZERO; nodes];
    for (i, (bound, weights)) in graph.bound_nodes.iter().zip(&graph.bound_weights).enumerate() {
        for s in (0..NODES_PER_VERTEX).filter(|&s| weights[s] > 0.0) {
            let k = bound[s] as usize;
            let (a, b) = (point(&rest[i]) - centroids[k].0, point(&posed[i]) - centroids[k].1);
            // Column j holds Σ w a b_j: element (row i, column j) is S_ij = Σ w a_i b_j.
            covariance[k] += DMat3::from_cols(a * b.x, a * b.y, a * b.z) * weights[s] as f64;
        }
    }
    let mut out = NodeTransforms::identity(nodes);
    for k in 0..nodes {
        let rotation = best_rotation(&covariance[k]);
        let g = point(&rest[graph.node_vertices[k] as usize]);
        let (rest_centroid, posed_centroid) = centroids[k];
        out.rotations[k] = [rotation.w, rotation.x, rotation.y, rotation.z];
        out.translations[k] = (posed_centroid - rotation * (rest_centroid - g) - g).to_array();
    }
    out
}

/// The rotation R maximising Σ w bᵀ R a for the cross-covariance S = Σ w a bᵀ: the eigenvector
/// of Horn's symmetric 4×4 matrix with the largest eigenvalue, by power iteration on the matrix
/// shifted to be positive semidefinite (so the largest eigenvalue is also the largest in size).
fn best_rotation(s: &DMat3) -> DQuat {
    let e = |i: usize, j: usize| s.col(j)[i];
    let (sxx, sxy, sxz, syx, syy, syz, szx, szy, szz) =
        (e(0, 0), e(0, 1), e(0, 2), e(1, 0), e(1, 1), e(1, 2), e(2, 0), e(2, 1), e(2, 2));
    let n = [
        [sxx + syy + szz, syz - szy, szx - sxz, sxy - syx],
        [syz - szy, sxx - syy - szz, sxy + syx, szx + sxz],
        [szx - sxz, sxy + syx, -sxx + syy - szz, syz + szy],
        [sxy - syx, szx + sxz, syz + szy, -sxx - syy + szz],
    ];
    // Every eigenvalue of n lies within ± its Frobenius norm.
    let shift = n.iter().flatten().map(|v| v * v).sum::<f64>().sqrt();
    if shift.is_nan() || shift <= 0.0 {
        return DQuat::IDENTITY;
    }
    let mut q = [1.0, 0.0, 0.0, 0.0];
    for _ in 0..200 {
        let mut next = [0.0; 4];
        for (r, row) in n.iter().enumerate() {
            next[r] = shift * q[r] + (0..4).map(|c| row[c] * q[c]).sum::<f64>();
        }
        let length = next.iter().map(|v| v * v).sum::<f64>().sqrt();
        if length.is_nan() || length <= 0.0 {
            break;
        }
        q = next.map(|v| v / length);
    }
    DQuat::from_xyzw(q[1], q[2], q[3], q[0]).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::deform::build_graph;
    use crate::deform::reference::blend;

    /// A 6 × 6 × 6 grid's vertices, linked to their axis neighbours.
    fn grid() -> (Vec<[f32; 3]>, Vec<Vec<u32>>) {
        let index = |x: usize, y: usize, z: usize| (x * 36 + y * 6 + z) as u32;
        let mut positions = Vec::new();
        let mut adjacency = Vec::new();
        for x in 0..6 {
            for y in 0..6 {
                for z in 0..6 {
                    positions.push([x as f32 * 0.2, y as f32 * 0.2, z as f32 * 0.2]);
                    let mut near = Vec::new();
                    for (dx, dy, dz) in [(1, 0, 0), (0, 1, 0), (0, 0, 1)] {
                        let (a, b, c) = (x + dx, y + dy, z + dz);
                        if a < 6 && b < 6 && c < 6 {
                            near.push(index(a, b, c));
                        }
                        if x >= dx && y >= dy && z >= dz {
                            near.push(index(x - dx, y - dy, z - dz));
                        }
                    }
                    adjacency.push(near);
                }
            }
        }
        (positions, adjacency)
    }

    #[test]
    fn a_rigid_motion_is_recovered_at_every_node() {
        let (rest, adjacency) = grid();
        let graph = build_graph(&rest, |i| &adjacency[i], 20);
        let rotation = DQuat::from_axis_angle(DVec3::new(0.3, -1.0, 0.5).normalize(), 2.4);
        let shift = DVec3::new(0.7, -0.2, 1.5);
        let posed: Vec<[f32; 3]> = rest
            .iter()
            .map(|p| (rotation * DVec3::from(p.map(f64::from)) + shift).as_vec3().to_array())
            .collect();
        let nodes = fit_nodes(&rest, &posed, &graph);
        for k in 0..graph.node_vertices.len() {
            let q = DQuat::from_xyzw(
                nodes.rotations[k][1],
                nodes.rotations[k][2],
                nodes.rotations[k][3],
                nodes.rotations[k][0],
            );
            assert!(q.dot(rotation).abs() > 1.0 - 1e-9, "node {k}: {q:?} against {rotation:?}");
        }
        let rotations = vec![[1.0f32, 0.0, 0.0, 0.0]; rest.len()];
        let (blended, _) = blend((&rest, &rotations), &graph, &nodes);
        for (b, p) in blended.iter().zip(&posed) {
            assert!((0..3).all(|c| (b[c] - p[c] as f64).abs() < 1e-5), "{b:?} against {p:?}");
        }
    }

    #[test]
    fn the_rest_pose_gives_identity_and_a_collapsed_pose_stays_finite() {
        let (rest, adjacency) = grid();
        let graph = build_graph(&rest, |i| &adjacency[i], 10);
        let same = fit_nodes(&rest, &rest, &graph);
        assert!(same.rotations.iter().all(|q| (q[0].abs() - 1.0).abs() < 1e-9));
        assert!(same.translations.iter().flatten().all(|t| t.abs() < 1e-6));
        let collapsed = vec![[0.5f32, 0.5, 0.5]; rest.len()];
        let nodes = fit_nodes(&rest, &collapsed, &graph);
        assert!(nodes
            .rotations
            .iter()
            .flatten()
            .chain(nodes.translations.iter().flatten())
            .all(|v| v.is_finite()));
    }
}
