//! Marching tetrahedra: the zero set of a field sampled on a regular grid, as a triangle mesh.
//!
//! Each cube is cut into the six Kuhn tetrahedra around its main diagonal, which match across
//! shared faces; the zero set of the field's linear interpolant over that triangulation is a
//! closed 2-manifold wherever it stays off the grid's outer layer (`close_grid` makes sure).
//! Every tetrahedron edge holds at most one vertex, shared by all tetrahedra around it, so the
//! mesh is watertight, and each triangle is wound counter-clockwise seen from the negative
//! (outside) side. No ambiguous cases exist, unlike marching cubes.

use super::field::GridFrame;
use std::collections::HashMap;

/// The seven edge directions of the Kuhn triangulation, as offsets in {0, 1}³.
const DIRECTIONS: [[usize; 3]; 7] =
    [[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 0], [1, 0, 1], [0, 1, 1], [1, 1, 1]];

/// The six tetrahedra of a cube, as cube-corner bit masks (bit 0 = x, 1 = y, 2 = z): each path
/// 0 → one axis → two axes → 7.
const TETS: [[usize; 4]; 6] =
    [[0, 1, 3, 7], [0, 1, 5, 7], [0, 2, 3, 7], [0, 2, 6, 7], [0, 4, 5, 7], [0, 4, 6, 7]];

/// Forces the outermost layer of grid vertices outside (value ≤ 0) so the surface closes
/// inside the grid, and turns enclosed outside regions (cavities: negative vertices not
/// 6-connected to that layer) inside. Returns the number of vertices filled.
pub fn close_grid(values: &mut [f32], grid: &GridFrame) -> usize {
    let [nx, ny, nz] = grid.dims;
    let mut reached = vec![false; values.len()];
    let mut stack = Vec::new();
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                if i == 0 || j == 0 || k == 0 || i + 1 == nx || j + 1 == ny || k + 1 == nz {
                    let v = grid.index([i, j, k]);
                    values[v] = values[v].min(0.0);
                    reached[v] = true;
                    stack.push([i, j, k]);
                }
            }
        }
    }
    while let Some([i, j, k]) = stack.pop() {
        let neighbours = [
            [i.wrapping_sub(1), j, k],
            [i + 1, j, k],
            [i, j.wrapping_sub(1), k],
            [i, j + 1, k],
            [i, j, k.wrapping_sub(1)],
            [i, j, k + 1],
        ];
        for n in neighbours {
            if n[0] < nx && n[1] < ny && n[2] < nz {
                let v = grid.index(n);
                if !reached[v] && values[v] <= 0.0 {
                    reached[v] = true;
                    stack.push(n);
                }
            }
        }
    }
    let mut filled = 0;
    for (v, r) in values.iter_mut().zip(&reached) {
        if !r && *v <= 0.0 {
            *v = f32::MIN_POSITIVE.max(-*v);
            filled += 1;
        }
    }
    filled
}

/// The mesh of the zero set: positions in scene units, faces counter-clockwise seen from
/// outside (value ≤ 0 is outside, > 0 inside).
pub fn marching_tetrahedra(values: &[f32], grid: &GridFrame) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let [nx, ny, nz] = grid.dims;
    let mut positions = Vec::new();
    let mut faces = Vec::new();
    let mut vertex_of: HashMap<(usize, u8), u32> = HashMap::new();
    for k in 0..nz.saturating_sub(1) {
        for j in 0..ny.saturating_sub(1) {
            for i in 0..nx.saturating_sub(1) {
                let corner = |c: usize| [i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1)];
                let value = |c: usize| values[grid.index(corner(c))];
                let inside = (0..8).filter(|&c| value(c) > 0.0).count();
                if inside == 0 || inside == 8 {
                    continue;
                }
                for tet in TETS {
                    let mut edge_vertex = |a: usize, b: usize| -> u32 {
                        // Key: the lower corner of the edge and its direction.
                        let (lo, hi) = if a < b { (a, b) } else { (b, a) };
                        let delta = [
                            (hi & 1) - (lo & 1),
                            ((hi >> 1) & 1) - ((lo >> 1) & 1),
                            ((hi >> 2) & 1) - ((lo >> 2) & 1),
                        ];
                        let direction = DIRECTIONS
                            .iter()
                            .position(|&d| d == delta)
                            .expect("Kuhn edges go up in every axis")
                            as u8;
                        *vertex_of.entry((grid.index(corner(lo)), direction)).or_insert_with(|| {
                            let (fa, fb) = (value(a) as f64, value(b) as f64);
                            let t = (fa / (fa - fb)).clamp(1e-3, 1.0 - 1e-3);
                            let (pa, pb) = (grid.point(corner(a)), grid.point(corner(b)));
                            positions.push((pa + t * (pb - pa)).as_vec3().to_array());
                            positions.len() as u32 - 1
                        })
                    };
                    tet_triangles(
                        tet,
                        |c| value(c) > 0.0,
                        |c| grid.point(corner(c)),
                        &mut edge_vertex,
                        &mut faces,
                    );
                }
            }
        }
    }
    (positions, faces)
}

/// Emits the 0, 1 or 2 triangles of one tetrahedron. Winding comes from the triangle through
/// the edge midpoints (never degenerate): its normal must point from the inside corners to
/// the outside ones. The true triangle moves its corners along the same edges, which keeps
/// the combinatorial orientation, so neighbours always agree.
fn tet_triangles(
    tet: [usize; 4],
    inside: impl Fn(usize) -> bool,
    point: impl Fn(usize) -> glam::DVec3,
    edge_vertex: &mut impl FnMut(usize, usize) -> u32,
    faces: &mut Vec<[u32; 3]>,
) {
    let (ins, outs): (Vec<usize>, Vec<usize>) = tet.iter().partition(|&&c| inside(c));
    let edges: Vec<(usize, usize)> = match (ins.len(), outs.len()) {
        (1, 3) => vec![(ins[0], outs[0]), (ins[0], outs[1]), (ins[0], outs[2])],
        (3, 1) => vec![(ins[0], outs[0]), (ins[1], outs[0]), (ins[2], outs[0])],
        // A quad, in cyclic order: each consecutive pair of edges shares a corner.
        (2, 2) => vec![(ins[0], outs[0]), (ins[0], outs[1]), (ins[1], outs[1]), (ins[1], outs[0])],
        _ => return,
    };
    let mean = |cs: &[usize]| cs.iter().map(|&c| point(c)).sum::<glam::DVec3>() / cs.len() as f64;
    let outward = mean(&outs) - mean(&ins);
    let mid = |(a, b): (usize, usize)| 0.5 * (point(a) + point(b));
    let mut emit = |tri: [(usize, usize); 3]| {
        let [p, q, r] = tri.map(mid);
        let ids = tri.map(|(a, b)| edge_vertex(a, b));
        faces.push(if (q - p).cross(r - p).dot(outward) > 0.0 {
            ids
        } else {
            [ids[0], ids[2], ids[1]]
        });
    };
    emit([edges[0], edges[1], edges[2]]);
    if edges.len() == 4 {
        emit([edges[0], edges[2], edges[3]]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::manifold::closed_manifold_problem;
    use glam::DVec3;

    fn sampled(grid: &GridFrame, f: impl Fn(DVec3) -> f64) -> Vec<f32> {
        (0..grid.len())
            .map(|v| {
                f(grid.point([
                    v % grid.dims[0],
                    (v / grid.dims[0]) % grid.dims[1],
                    v / (grid.dims[0] * grid.dims[1]),
                ])) as f32
            })
            .collect()
    }

    #[test]
    fn sphere_is_closed_oriented_and_on_the_zero_set() {
        let grid = GridFrame { origin: DVec3::splat(-1.3), step: 0.1, dims: [27, 27, 27] };
        let r = 1.0;
        let mut values = sampled(&grid, |p| r - p.length());
        assert_eq!(close_grid(&mut values, &grid), 0);
        let (positions, faces) = marching_tetrahedra(&values, &grid);
        assert_eq!(closed_manifold_problem(positions.len(), &faces), None);
        // Vertices lie on the linear interpolant's zero: within the chord error of r.
        for p in &positions {
            let d = DVec3::from(p.map(f64::from)).length();
            assert!((d - r).abs() < 0.01, "{d}");
        }
        // Outward winding: the signed volume is positive and near the sphere's.
        let volume: f64 = faces
            .iter()
            .map(|f| {
                let [a, b, c] = f.map(|i| DVec3::from(positions[i as usize].map(f64::from)));
                a.dot(b.cross(c)) / 6.0
            })
            .sum();
        let exact = 4.0 / 3.0 * std::f64::consts::PI;
        assert!((volume - exact).abs() < 0.02 * exact, "{volume} vs {exact}");
    }

    #[test]
    fn touching_blobs_cavities_and_the_grid_border() {
        // Two spheres touching at a point (a generic PL level set is still a manifold), a shell
        // with a cavity (filled), and a slab running through the grid border (closed there).
        let grid = GridFrame { origin: DVec3::splat(-2.05), step: 0.1, dims: [42, 42, 42] };
        let blobs = |p: DVec3| {
            (0.8 - (p - DVec3::X * 0.8).length()).max(0.8 - (p + DVec3::X * 0.8).length())
        };
        let mut values = sampled(&grid, blobs);
        close_grid(&mut values, &grid);
        let (p, f) = marching_tetrahedra(&values, &grid);
        assert_eq!(closed_manifold_problem(p.len(), &f), None);

        let shell = |p: DVec3| (1.5 - p.length()).min(p.length() - 0.7);
        let mut values = sampled(&grid, shell);
        assert!(close_grid(&mut values, &grid) > 100, "the cavity is filled");
        let (p, f) = marching_tetrahedra(&values, &grid);
        assert_eq!(closed_manifold_problem(p.len(), &f), None);
        assert!(
            p.iter().all(|q| DVec3::from(q.map(f64::from)).length() > 1.4),
            "no inner surface is left"
        );

        let mut values = sampled(&grid, |p: DVec3| 0.5 - p.z.abs());
        close_grid(&mut values, &grid);
        let (p, f) = marching_tetrahedra(&values, &grid);
        assert_eq!(closed_manifold_problem(p.len(), &f), None);
    }
}
