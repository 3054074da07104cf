//! Edge flips that raise the minimum angle without changing the vertex set.

use super::geometry::{area_vector, min_angle};
use super::mesh::{face_of, prev, ManifoldMesh, NONE};

/// Largest bend between the two faces of an edge that may still flip: cos 20°. Flipping across
/// a sharper crease would change the shape, not just the triangulation.
const FLIP_MIN_COS_BEND: f64 = 0.94;
/// A flip must raise the pair's minimum angle by this factor, so flips cannot cycle.
const FLIP_GAIN: f64 = 1.0 + 1e-3;

/// Flips edges of the faces `seeds` (and, after each flip, the four edges around it) while a
/// legal flip raises the smaller minimum angle of the two faces. Returns the number of flips.
/// Terminates: each flip strictly raises the minimum angle of its pair, and work is capped at
/// 32 × the seeds.
pub fn improve_angles(mesh: &mut ManifoldMesh, seeds: &[u32]) -> usize {
    let mut queue: Vec<u32> =
        seeds.iter().filter(|&&f| mesh.is_face_live(f)).flat_map(|&f| 3 * f..3 * f + 3).collect();
    let budget = 32 * queue.len();
    let mut flips = 0;
    let mut visits = 0;
    while let Some(h) = queue.pop() {
        visits += 1;
        if visits > budget {
            break;
        }
        if !mesh.is_face_live(face_of(h)) || !flip_helps(mesh, h) {
            continue;
        }
        let (f0, f1) = (face_of(h), face_of(mesh.twin(h)));
        if mesh.flip_edge(h).is_ok() {
            flips += 1;
            // The two rewritten faces' edges may now flip too.
            queue.extend((3 * f0..3 * f0 + 3).chain(3 * f1..3 * f1 + 3));
        }
    }
    flips
}

/// Whether flipping the interior edge of `h` raises the minimum angle of its two faces, and
/// the two faces are nearly coplanar.
fn flip_helps(mesh: &ManifoldMesh, h: u32) -> bool {
    let t = mesh.twin(h);
    if t == NONE {
        return false;
    }
    let [a, b, c, d] = [mesh.origin(h), mesh.dest(h), mesh.origin(prev(h)), mesh.origin(prev(t))]
        .map(|v| mesh.point(v));
    let (n0, n1) =
        (area_vector(a, b, c).normalize_or_zero(), area_vector(b, a, d).normalize_or_zero());
    if n0.dot(n1) < FLIP_MIN_COS_BEND {
        return false;
    }
    let before = min_angle(a, b, c).min(min_angle(b, a, d));
    let after = min_angle(a, d, c).min(min_angle(d, b, c));
    after > before * FLIP_GAIN
}
