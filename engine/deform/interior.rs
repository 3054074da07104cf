//! Bindings through the body's interior, the visibility rule of skinning by bone heat
//! (Baran & Popović 2007): a vertex may bind a node it sees through the inside of the closed
//! surface, so skin between a leg and the belly follows the leg as a skinned character's does,
//! while the other leg, seen only through the air, stays out. Plain arrays in and out.

use crate::geometry::SurfaceBvh;
use glam::DVec3;

/// Per vertex, its `keep` nearest admissible nodes by straight-line distance, nearest first.
/// A node is admissible when `geodesic[v]` lists it (the nodes nearest along the surface, so a
/// vertex always keeps its own neighbourhood) or when the segment from the vertex to the node
/// leaves the vertex into the body (behind every face around it), arrives at the node from
/// inside (behind every face around the node) and crosses no face between. Guarantees: deterministic; a vertex whose geodesic list is empty and that sees no
/// node gets an empty list; without faces or with a face index out of range, the geodesic
/// lists come back re-ranked by straight-line distance.
pub fn interior_nearest_nodes(
    positions: &[[f32; 3]],
    faces: &[[u32; 3]],
    node_vertices: &[u32],
    geodesic: &[Vec<(u32, f64)>],
    keep: usize,
) -> Vec<Vec<(u32, f64)>> {
    let point = |v: u32| DVec3::from(positions[v as usize].map(f64::from));
    let bvh = SurfaceBvh::build(positions, faces).ok();
    let around = face_normals_around(positions, faces);
    // Strictly behind every face around `v`, looking along `dir`: the segment starts inside.
    let behind = |v: u32, dir: DVec3| around[v as usize].iter().all(|n| dir.dot(*n) < 0.0);
    (0..positions.len())
        .map(|v| {
            let at = point(v as u32);
            // Nearest first, so only the nodes up to the `keep`-th admitted are ray cast.
            let mut by_distance: Vec<(u32, f64)> = (0..node_vertices.len())
                .map(|k| (k as u32, (point(node_vertices[k]) - at).length()))
                .collect();
            by_distance.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
            let sees = |k: u32, length: f64| {
                let to = point(node_vertices[k as usize]) - at;
                bvh.as_ref().is_some_and(|bvh| {
                    length > 0.0
                        && behind(v as u32, to)
                        && behind(node_vertices[k as usize], -to)
                        && {
                            // Start a hair inside the segment and stop a hair before its end: the
                            // faces at either end do not count as crossings.
                            let (eps, dir) = (1e-4 * length, to / length);
                            bvh.ray_cast(at + eps * dir, dir)
                                .map_or(true, |hit| hit.distance > length - 2.0 * eps)
                        }
                })
            };
            by_distance
                .into_iter()
                .filter(|&(k, length)| geodesic[v].iter().any(|&(n, _)| n == k) || sees(k, length))
                .take(keep)
                .collect()
        })
        .collect()
}

/// Per vertex, the (unnormalised) normals of the valid faces around it.
fn face_normals_around(positions: &[[f32; 3]], faces: &[[u32; 3]]) -> Vec<Vec<DVec3>> {
    let mut around = vec![Vec::new(); positions.len()];
    for face in faces {
        if face.iter().any(|&i| i as usize >= positions.len()) {
            continue;
        }
        let [a, b, c] = face.map(|i| DVec3::from(positions[i as usize].map(f64::from)));
        let n = (b - a).cross(c - a);
        for &i in face {
            around[i as usize].push(n);
        }
    }
    around
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::sphere::unit_sphere;

    /// Two unit spheres 0.2 apart along x, the right one shifted off the axis a little so no
    /// test segment runs exactly along the edges of the left one's equator.
    fn two_spheres() -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
        let (positions, faces) = unit_sphere(2);
        let n = positions.len() as u32;
        let mut all: Vec<[f32; 3]> = positions.iter().map(|p| [p[0] - 1.1, p[1], p[2]]).collect();
        all.extend(positions.iter().map(|p| [p[0] + 1.1, p[1] + 0.13, p[2] + 0.07]));
        let mut faces2 = faces.clone();
        faces2.extend(faces.iter().map(|f| f.map(|i| i + n)));
        (all, faces2)
    }

    #[test]
    fn binds_through_the_body_not_through_the_air() {
        let (positions, faces) = two_spheres();
        let half = positions.len() / 2;
        let on = |x: f32| {
            (0..positions.len() as u32)
                .min_by(|&a, &b| {
                    let d = |v: u32| (positions[v as usize][0] - x).abs();
                    d(a).total_cmp(&d(b))
                })
                .unwrap()
        };
        // Nodes: the far and near poles of the left sphere, the near pole of the right one.
        let nodes = [on(-2.1), on(-0.1), on(0.1)];
        let none = vec![Vec::new(); positions.len()];
        let lists = interior_nearest_nodes(&positions, &faces, &nodes, &none, 3);
        let left_far = on(-2.1) as usize;
        // The left sphere's far pole sees both of its own nodes through the inside (the far
        // one at distance 0 is not a segment), never the right sphere's nearer-than-2 pole.
        let nodes_of = |v: usize| lists[v].iter().map(|&(k, _)| k).collect::<Vec<_>>();
        assert_eq!(nodes_of(left_far), [1], "{:?}", lists[left_far]);
        for (v, list) in lists.iter().enumerate() {
            let right = v >= half;
            for &(k, d) in list {
                assert_eq!(k == 2, right, "vertex {v} bound node {k}");
                let p = DVec3::from(positions[v].map(f64::from));
                let q = DVec3::from(positions[nodes[k as usize] as usize].map(f64::from));
                assert!((d - p.distance(q)).abs() < 1e-9);
            }
            for pair in list.windows(2) {
                assert!(pair[0].1 <= pair[1].1, "nearest first");
            }
        }
        // Every other left vertex sees both left poles through the inside, but the nodes
        // themselves and the 4 + 4 poles' neighbours, whose segment runs along an edge (in the
        // plane of the faces there, so not strictly behind them: the conservative side).
        let both = lists[..half].iter().filter(|l| l.len() == 2).count();
        assert_eq!(both, half - 10);
    }

    #[test]
    fn geodesic_neighbours_are_always_kept_and_bad_faces_fall_back() {
        let (positions, faces) = two_spheres();
        let nodes = [0u32, 1];
        // Vertex 2's geodesic list names node 1 even though no segment admits it here (faces
        // out of range: no BVH); the lists come back re-ranked by straight-line distance.
        let mut geodesic = vec![Vec::new(); positions.len()];
        geodesic[2] = vec![(1, 5.0), (0, 7.0)];
        let lists = interior_nearest_nodes(&positions, &[[0, 1, u32::MAX]], &nodes, &geodesic, 5);
        let d = |a: u32, b: u32| {
            DVec3::from(positions[a as usize].map(f64::from))
                .distance(DVec3::from(positions[b as usize].map(f64::from)))
        };
        let mut expected = vec![(0, d(2, 0)), (1, d(2, 1))];
        expected.sort_by(|a, b| a.1.total_cmp(&b.1));
        assert_eq!(lists[2], expected);
        assert!(lists[3].is_empty());
        let with_faces = interior_nearest_nodes(&positions, &faces, &nodes, &geodesic, 5);
        assert_eq!(with_faces.len(), positions.len());
    }
}
