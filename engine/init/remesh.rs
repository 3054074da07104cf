//! Isotropic remeshing towards a target edge length L, after Botsch & Kobbelt (2004), on the
//! topology module's operations (every change goes through their legality checks, so the
//! mesh stays a closed oriented manifold). Each round:
//! 1. split edges longer than 4/3 L at their midpoints;
//! 2. collapse edges shorter than 4/5 L to their midpoints, unless that makes an edge longer
//!    than 4/3 L;
//! 3. flip edges whose flip brings the four vertices' valences closer to 6;
//! 4. move each vertex half-way to its 1-ring centroid within its tangent plane and project it
//!    back onto the reference surface (the extracted hull surface). A move that would turn a
//!    face against its old normal is undone.

use crate::geometry::SurfaceBvh;
use crate::topology::{prev, vertex_normals, ManifoldMesh, NONE};
use glam::DVec3;

/// Counts of what the rounds did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct RemeshStats {
    /// Edges split.
    pub splits: usize,
    /// Edges collapsed.
    pub collapses: usize,
    /// Edges flipped.
    pub flips: usize,
}

/// Runs `rounds` rounds towards edge length `target` (scene units), projecting onto
/// `reference`. Tombstones stay; the caller compacts.
pub fn remesh(
    mesh: &mut ManifoldMesh,
    reference: &SurfaceBvh,
    target: f64,
    rounds: usize,
) -> RemeshStats {
    let (lo, hi) = (0.8 * target, 4.0 / 3.0 * target);
    let mut stats = RemeshStats::default();
    for _ in 0..rounds {
        stats.splits += split_long(mesh, hi);
        stats.collapses += collapse_short(mesh, lo, hi);
        stats.flips += flip_towards_valence_six(mesh);
        smooth_tangentially(mesh, reference);
    }
    stats
}

/// Each live edge once, as its vertex pair (half-edge indices go stale as faces are rewritten).
fn edge_pairs(mesh: &ManifoldMesh) -> Vec<(u32, u32)> {
    mesh.edges().map(|h| (mesh.origin(h), mesh.dest(h))).collect()
}

/// The live half-edge a → b (or b → a), if both ends are live and joined.
fn live_edge(mesh: &ManifoldMesh, (a, b): (u32, u32)) -> Option<u32> {
    (mesh.is_vertex_live(a) && mesh.is_vertex_live(b)).then(|| mesh.find_edge(a, b)).flatten()
}

fn split_long(mesh: &mut ManifoldMesh, hi: f64) -> usize {
    let mut count = 0;
    for pair in edge_pairs(mesh) {
        let (p, q) = (mesh.point(pair.0), mesh.point(pair.1));
        if p.distance(q) > hi {
            if let Some(h) = live_edge(mesh, pair) {
                count +=
                    usize::from(mesh.split_edge(h, (0.5 * (p + q)).as_vec3().to_array()).is_ok());
            }
        }
    }
    count
}

fn collapse_short(mesh: &mut ManifoldMesh, lo: f64, hi: f64) -> usize {
    let mut count = 0;
    for pair in edge_pairs(mesh) {
        let Some(h) = live_edge(mesh, pair) else { continue };
        let (p, q) = (mesh.point(pair.0), mesh.point(pair.1));
        if p.distance(q) >= lo {
            continue;
        }
        let m = 0.5 * (p + q);
        let neighbours = mesh.ring(pair.0).into_iter().chain(mesh.ring(pair.1));
        if neighbours.into_iter().any(|n| mesh.point(n).distance(m) > hi) {
            continue;
        }
        count += usize::from(mesh.collapse_edge(h, m.as_vec3().to_array()).is_ok());
    }
    count
}

fn flip_towards_valence_six(mesh: &mut ManifoldMesh) -> usize {
    let mut count = 0;
    for pair in edge_pairs(mesh) {
        let Some(h) = live_edge(mesh, pair) else { continue };
        let t = mesh.twin(h);
        if t == NONE {
            continue;
        }
        let corners = [mesh.origin(h), mesh.dest(h), mesh.origin(prev(h)), mesh.origin(prev(t))];
        let valence = corners.map(|v| mesh.valence(v) as i64);
        let deviation =
            |delta: [i64; 4]| (0..4).map(|k| (valence[k] + delta[k] - 6).pow(2)).sum::<i64>();
        if deviation([-1, -1, 1, 1]) < deviation([0; 4]) {
            count += usize::from(mesh.flip_edge(h).is_ok());
        }
    }
    count
}

/// Tangential relaxation with projection; moves that fold a face are undone (repeatedly,
/// since undoing one vertex can leave a neighbour's face folded against the old shape).
fn smooth_tangentially(mesh: &mut ManifoldMesh, reference: &SurfaceBvh) {
    let faces = mesh.live_faces();
    let normals: Vec<DVec3> =
        vertex_normals(mesh).iter().map(|n| DVec3::from(n.map(f64::from))).collect();
    let old: Vec<DVec3> = (0..mesh.vertex_rows() as u32).map(|v| mesh.point(v)).collect();
    let mut new = old.clone();
    for v in mesh.vertices() {
        let ring = mesh.ring(v);
        let centroid = ring.iter().map(|&n| old[n as usize]).sum::<DVec3>() / ring.len() as f64;
        let (p, n) = (old[v as usize], normals[v as usize]);
        let step = 0.5 * (centroid - p);
        let moved = p + step - n * n.dot(step);
        if let Some(s) = reference.closest_point(moved) {
            new[v as usize] = s.position;
        }
    }
    let area = |x: &[DVec3], f: &[u32; 3]| {
        (x[f[1] as usize] - x[f[0] as usize]).cross(x[f[2] as usize] - x[f[0] as usize])
    };
    for _ in 0..8 {
        let mut undone = false;
        for f in &faces {
            if area(&new, f).dot(area(&old, f)) <= 0.0 {
                for &v in f {
                    undone |= new[v as usize] != old[v as usize];
                    new[v as usize] = old[v as usize];
                }
            }
        }
        if !undone {
            break;
        }
    }
    for v in mesh.vertices().collect::<Vec<_>>() {
        mesh.positions[v as usize] = new[v as usize].as_vec3().to_array();
    }
}

/// Edge length that gives about `vertices` vertices on a closed surface of area `area`: an
/// equilateral mesh has twice as many faces as vertices, each of area √3/4 L².
pub fn edge_for_vertices(area: f64, vertices: usize) -> f64 {
    (2.0 * area / (3f64.sqrt() * vertices as f64)).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::icosphere::icosphere;

    fn sphere(levels: u32) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
        let (p, f) = icosphere(levels);
        (p.iter().map(|q| q.map(|c| c as f32)).collect(), f)
    }

    #[test]
    fn sphere_remeshes_to_the_target_length_and_stays_on_it() {
        let (p, f) = sphere(4);
        let reference = SurfaceBvh::build(&p, &f).unwrap();
        // From a fine sphere (edge ≈ 0.076) to a target of 0.2.
        let mut mesh = ManifoldMesh::new(p, f).unwrap();
        let target = 0.2;
        let stats = remesh(&mut mesh, &reference, target, 6);
        assert!(stats.collapses > 0);
        assert_eq!(mesh.problem(), None);
        assert_eq!(mesh.euler_characteristic(), 2);
        let expected = 4.0 * std::f64::consts::PI / (3f64.sqrt() / 2.0 * target * target);
        let n = mesh.vertex_count() as f64;
        assert!((n / expected - 1.0).abs() < 0.3, "{n} vertices, expected about {expected}");
        let lengths: Vec<f64> = mesh
            .edges()
            .map(|h| mesh.point(mesh.origin(h)).distance(mesh.point(mesh.dest(h))))
            .collect();
        let mean = lengths.iter().sum::<f64>() / lengths.len() as f64;
        assert!((mean / target - 1.0).abs() < 0.2, "mean edge {mean}");
        for v in mesh.vertices() {
            assert!((mesh.point(v).length() - 1.0).abs() < 0.01, "vertices stay on the reference");
        }
        // Valence near 6 for most vertices.
        let regular = mesh.vertices().filter(|&v| (5..=7).contains(&mesh.valence(v))).count();
        assert!(regular as f64 > 0.9 * n);
    }

    #[test]
    fn edge_length_for_a_count() {
        // The icosphere of level 4 (2562 vertices) has edges ≈ 0.0757 on the unit sphere.
        let l = edge_for_vertices(4.0 * std::f64::consts::PI, 2562);
        assert!((l - 0.0757).abs() < 0.005, "{l}");
    }
}
