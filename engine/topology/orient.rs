//! Consistent orientation: flips faces so that neighbours run their shared edge in opposite
//! directions; closed components end up counter-clockwise seen from outside.

use super::TopologyError;
use std::collections::HashMap;

/// Orients `faces` in place and returns how many it flipped. Per connected component: faces
/// follow the first face of the component; then a closed component is turned outward (positive
/// signed volume) and an open one keeps the orientation of most of its input faces. Errors: an
/// edge with more than two faces, a non-orientable component (a Möbius strip).
pub fn orient_faces(
    positions: &[[f32; 3]],
    faces: &mut [[u32; 3]],
) -> Result<usize, TopologyError> {
    let edges = edge_faces(faces)?;
    let mut flip: Vec<Option<bool>> = vec![None; faces.len()];
    let mut flipped = 0;
    for seed in 0..faces.len() {
        if flip[seed].is_some() {
            continue;
        }
        let component = orient_component(faces, &edges, seed, &mut flip)?;
        let closed = component.iter().all(|&f| (0..3).all(|k| edges[&key(faces[f], k)].len() == 2));
        let turned = |f: usize| oriented(faces[f], flip[f] == Some(true));
        let reverse = if closed {
            component.iter().map(|&f| signed_volume(positions, turned(f))).sum::<f64>() < 0.0
        } else {
            2 * component.iter().filter(|&&f| flip[f] == Some(true)).count() > component.len()
        };
        for &f in &component {
            let change = (flip[f] == Some(true)) != reverse;
            if change {
                faces[f] = oriented(faces[f], true);
                flipped += 1;
            }
        }
    }
    Ok(flipped)
}

#[inline]
fn key(face: [u32; 3], k: usize) -> (u32, u32) {
    let (a, b) = (face[k], face[(k + 1) % 3]);
    (a.min(b), a.max(b))
}

#[inline]
fn oriented(face: [u32; 3], flip: bool) -> [u32; 3] {
    if flip {
        [face[0], face[2], face[1]]
    } else {
        face
    }
}

/// Whether `face` runs its edge from `a` to `b`.
#[inline]
fn runs(face: [u32; 3], a: u32, b: u32) -> bool {
    (0..3).any(|k| face[k] == a && face[(k + 1) % 3] == b)
}

fn edge_faces(faces: &[[u32; 3]]) -> Result<HashMap<(u32, u32), Vec<u32>>, TopologyError> {
    let mut edges: HashMap<(u32, u32), Vec<u32>> = HashMap::with_capacity(faces.len() * 3 / 2);
    for (f, face) in faces.iter().enumerate() {
        for k in 0..3 {
            let list = edges.entry(key(*face, k)).or_default();
            list.push(f as u32);
            if list.len() > 2 {
                let (a, b) = key(*face, k);
                return Err(TopologyError::NonManifoldEdge { a, b, faces: list.clone() });
            }
        }
    }
    Ok(edges)
}

/// Breadth-first over edge neighbours from `seed`, recording in `flip` whether each face must
/// be reversed to agree with the seed; returns the component.
fn orient_component(
    faces: &[[u32; 3]],
    edges: &HashMap<(u32, u32), Vec<u32>>,
    seed: usize,
    flip: &mut [Option<bool>],
) -> Result<Vec<usize>, TopologyError> {
    flip[seed] = Some(false);
    let mut component = vec![seed];
    let mut at = 0;
    while at < component.len() {
        let f = component[at];
        at += 1;
        let face = oriented(faces[f], flip[f] == Some(true));
        for k in 0..3 {
            let (a, b) = (face[k], face[(k + 1) % 3]);
            for &g in &edges[&key(face, k)] {
                let g = g as usize;
                if g == f {
                    continue;
                }
                let needs_flip = runs(faces[g], a, b);
                match flip[g] {
                    None => {
                        flip[g] = Some(needs_flip);
                        component.push(g);
                    }
                    Some(have) if have != needs_flip => {
                        return Err(TopologyError::NonOrientable { face: g as u32 })
                    }
                    Some(_) => {}
                }
            }
        }
    }
    Ok(component)
}

fn signed_volume(positions: &[[f32; 3]], face: [u32; 3]) -> f64 {
    let p = |v: u32| super::geometry::vec(positions[v as usize]);
    p(face[0]).dot(p(face[1]).cross(p(face[2])))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn octahedron() -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
        let positions = vec![
            [1.0, 0.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
        ];
        let faces = vec![
            [0, 2, 4],
            [2, 1, 4],
            [1, 3, 4],
            [3, 0, 4],
            [2, 0, 5],
            [1, 2, 5],
            [3, 1, 5],
            [0, 3, 5],
        ];
        (positions, faces)
    }

    #[test]
    fn scrambled_closed_mesh_is_turned_outward() {
        let (positions, good) = octahedron();
        let mut faces = good.clone();
        for f in [0, 3, 5] {
            faces[f] = oriented(faces[f], true);
        }
        faces.iter_mut().for_each(|f| *f = oriented(*f, true));
        assert_eq!(orient_faces(&positions, &mut faces).unwrap(), 5);
        assert_eq!(faces, good);
    }

    #[test]
    fn moebius_strip_is_refused() {
        // Six quads (12 triangles) around a loop, glued with a half twist.
        let n = 6u32;
        let positions: Vec<[f32; 3]> =
            (0..2 * n).map(|i| [i as f32, (i % 2) as f32, 0.0]).collect();
        let mut faces = Vec::new();
        for i in 0..n {
            let (a, b) = (2 * i, 2 * i + 1);
            let (c, d) = if i + 1 < n { (2 * i + 2, 2 * i + 3) } else { (1, 0) };
            faces.push([a, b, d]);
            faces.push([a, d, c]);
        }
        assert!(matches!(
            orient_faces(&positions, &mut faces),
            Err(TopologyError::NonOrientable { .. })
        ));
    }
}
