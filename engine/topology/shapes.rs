//! Reference surfaces of each kind the operations must handle (genus 0 and 1 come with the
//! icosphere of `synth` and [`torus`], an open disk is [`grid`]); tests and the bench use them.

use std::f64::consts::TAU;

/// A torus of major radius 1 and minor radius `0.4`, `major × minor` vertices (both ≥ 3),
/// counter-clockwise from outside. Euler characteristic 0.
pub fn torus(major: u32, minor: u32) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let mut positions = Vec::with_capacity((major * minor) as usize);
    for i in 0..major {
        let u = TAU * i as f64 / major as f64;
        for j in 0..minor {
            let v = TAU * j as f64 / minor as f64;
            let r = 1.0 + 0.4 * v.cos();
            positions.push([(r * u.cos()) as f32, (r * u.sin()) as f32, (0.4 * v.sin()) as f32]);
        }
    }
    let id = |i: u32, j: u32| (i % major) * minor + j % minor;
    (positions, quads(major, minor, id))
}

/// A flat `columns × rows` grid of unit cells in the z = 0 plane (both ≥ 1), counter-clockwise
/// seen from +z: an open disk with Euler characteristic 1.
pub fn grid(columns: u32, rows: u32) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let positions =
        (0..=columns).flat_map(|i| (0..=rows).map(move |j| [i as f32, j as f32, 0.0])).collect();
    let id = |i: u32, j: u32| i * (rows + 1) + j;
    (positions, quads(columns, rows, id))
}

/// Two triangles per cell `(i, j)` with corners from `id`, diagonals alternating so that no
/// vertex gets a very high valence.
fn quads(columns: u32, rows: u32, id: impl Fn(u32, u32) -> u32) -> Vec<[u32; 3]> {
    let mut faces = Vec::with_capacity((2 * columns * rows) as usize);
    for i in 0..columns {
        for j in 0..rows {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            if (i + j) % 2 == 0 {
                faces.extend([[a, b, c], [a, c, d]]);
            } else {
                faces.extend([[a, b, d], [b, c, d]]);
            }
        }
    }
    faces
}
