//! The manifold mesh under every operation: invariants after each one on a sphere (genus 0), a
//! torus (genus 1) and an open disk; exact count changes; randomized sequences; refusals;
//! construction errors; the remap keeping rows by stored ids.

mod common;

use std::path::Path;
use tagsplat::mesh::TriMesh;
use tagsplat::rng::SplitMix64;
use tagsplat::synth::icosphere::icosphere;
use tagsplat::topology::shapes::{grid, torus};
use tagsplat::topology::{
    import, remap_rows, CollapseRefusal, FlipRefusal, ManifoldMesh, TopologyError, NEW_ROW, NONE,
};

fn sphere() -> ManifoldMesh {
    let (positions, faces) = icosphere(2);
    ManifoldMesh::new(positions.iter().map(|p| p.map(|c| c as f32)).collect(), faces).unwrap()
}

fn shapes() -> Vec<(&'static str, ManifoldMesh, i64)> {
    let (tp, tf) = torus(16, 9);
    let (gp, gf) = grid(8, 7);
    vec![
        ("sphere", sphere(), 2),
        ("torus", ManifoldMesh::new(tp, tf).unwrap(), 0),
        ("disk", ManifoldMesh::new(gp, gf).unwrap(), 1),
    ]
}

/// (vertices, edges, faces)
fn counts(m: &ManifoldMesh) -> [i64; 3] {
    [m.vertex_count() as i64, m.edge_count() as i64, m.face_count() as i64]
}

fn assert_sound(m: &ManifoldMesh, euler: i64, what: &str) {
    if let Some(problem) = m.problem() {
        panic!("{what}: {problem}");
    }
    assert_eq!(m.euler_characteristic(), euler, "{what}: Euler characteristic changed");
}

fn midpoint(m: &ManifoldMesh, h: u32) -> [f32; 3] {
    let (a, b) = (m.positions[m.origin(h) as usize], m.positions[m.dest(h) as usize]);
    [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])]
}

fn centroid(m: &ManifoldMesh, f: u32) -> [f32; 3] {
    let c = m.face(f).map(|v| m.positions[v as usize]);
    [0, 1, 2].map(|k| (c[0][k] + c[1][k] + c[2][k]) / 3.0)
}

fn interior_edge(m: &ManifoldMesh) -> u32 {
    m.edges()
        .find(|&h| {
            !m.is_boundary_edge(h)
                && !m.is_boundary_vertex(m.origin(h))
                && !m.is_boundary_vertex(m.dest(h))
        })
        .unwrap()
}

#[test]
fn reference_shapes_are_manifold_with_their_euler_characteristic() {
    for (name, m, euler) in shapes() {
        assert_sound(&m, euler, name);
        let boundary = m.vertices().filter(|&v| m.is_boundary_vertex(v)).count();
        assert_eq!(boundary, if name == "disk" { 2 * (8 + 7) } else { 0 }, "{name}");
        // Every vertex's 1-ring is the set of its edge partners.
        for v in m.vertices() {
            let mut ring = m.ring(v);
            let mut partners: Vec<u32> = m
                .edges()
                .filter_map(|h| {
                    if m.origin(h) == v {
                        Some(m.dest(h))
                    } else if m.dest(h) == v {
                        Some(m.origin(h))
                    } else {
                        None
                    }
                })
                .collect();
            ring.sort_unstable();
            partners.sort_unstable();
            assert_eq!(ring, partners, "{name}: ring of {v}");
        }
    }
}

#[test]
fn face_split_adds_one_vertex_three_edges_two_faces() {
    for (name, mut m, euler) in shapes() {
        let before = counts(&m);
        let f = m.faces().nth(5).unwrap();
        let old = m.face(f);
        let v = m.split_face(f, centroid(&m, f)).unwrap();
        assert_eq!(counts(&m), [before[0] + 1, before[1] + 3, before[2] + 2], "{name}");
        let mut ring = m.ring(v);
        ring.sort_unstable();
        let mut corners = old.to_vec();
        corners.sort_unstable();
        assert_eq!(ring, corners, "{name}: the new vertex joins the old corners");
        assert_sound(&m, euler, name);
    }
}

#[test]
fn edge_split_adds_one_vertex_three_edges_two_faces_or_two_one_on_the_boundary() {
    for (name, mut m, euler) in shapes() {
        let before = counts(&m);
        let h = interior_edge(&m);
        let (a, b) = (m.origin(h), m.dest(h));
        let v = m.split_edge(h, midpoint(&m, h)).unwrap();
        assert_eq!(counts(&m), [before[0] + 1, before[1] + 3, before[2] + 2], "{name}");
        assert!(
            m.find_edge(a, b).is_none()
                && m.find_edge(a, v).is_some()
                && m.find_edge(v, b).is_some(),
            "{name}"
        );
        assert_eq!(m.valence(v), 4, "{name}");
        assert_sound(&m, euler, name);
        let boundary = m.edges().find(|&h| m.is_boundary_edge(h));
        if let Some(h) = boundary {
            let before = counts(&m);
            let v = m.split_edge(h, midpoint(&m, h)).unwrap();
            assert_eq!(
                counts(&m),
                [before[0] + 1, before[1] + 2, before[2] + 1],
                "{name} boundary"
            );
            assert!(m.is_boundary_vertex(v) && m.valence(v) == 3, "{name} boundary");
            assert_sound(&m, euler, name);
        }
    }
}

#[test]
fn edge_flip_keeps_counts_and_swaps_the_diagonal() {
    for (name, mut m, euler) in shapes() {
        let before = counts(&m);
        let h = m.edges().find(|&h| m.can_flip(h).is_ok()).unwrap();
        let (a, b) = (m.origin(h), m.dest(h));
        let (c, d) =
            (m.origin(tagsplat::topology::prev(h)), m.origin(tagsplat::topology::prev(m.twin(h))));
        m.flip_edge(h).unwrap();
        assert_eq!(counts(&m), before, "{name}");
        assert!(m.find_edge(a, b).is_none() && m.find_edge(c, d).is_some(), "{name}");
        assert_sound(&m, euler, name);
        let boundary = m.edges().find(|&h| m.is_boundary_edge(h));
        if let Some(h) = boundary {
            assert_eq!(m.flip_edge(h), Err(FlipRefusal::Boundary));
        }
    }
}

#[test]
fn edge_collapse_removes_one_vertex_three_edges_two_faces_or_two_one_on_the_boundary() {
    for (name, mut m, euler) in shapes() {
        let before = counts(&m);
        let h = interior_edge(&m);
        let (a, b) = (m.origin(h), m.dest(h));
        let mut expected_ring: Vec<u32> =
            m.ring(a).into_iter().chain(m.ring(b)).filter(|&v| v != a && v != b).collect();
        expected_ring.sort_unstable();
        expected_ring.dedup();
        assert_eq!(m.collapse_edge(h, midpoint(&m, h)), Ok(b), "{name}");
        assert_eq!(counts(&m), [before[0] - 1, before[1] - 3, before[2] - 2], "{name}");
        assert!(!m.is_vertex_live(a), "{name}");
        let mut ring = m.ring(b);
        ring.sort_unstable();
        assert_eq!(ring, expected_ring, "{name}: the kept vertex inherits both rings");
        assert_sound(&m, euler, name);
        let boundary = m
            .edges()
            .find(|&h| m.is_boundary_edge(h) && m.can_collapse(h, midpoint(&m, h)).is_ok());
        if let Some(h) = boundary {
            let before = counts(&m);
            m.collapse_edge(h, midpoint(&m, h)).unwrap();
            assert_eq!(
                counts(&m),
                [before[0] - 1, before[1] - 2, before[2] - 1],
                "{name} boundary"
            );
            assert_sound(&m, euler, name);
        }
    }
}

#[test]
fn tetrahedron_edges_are_refused() {
    let positions = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let faces = vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]];
    let m = ManifoldMesh::new(positions, faces).unwrap();
    assert_sound(&m, 2, "tetrahedron");
    for h in m.edges() {
        assert_eq!(m.can_collapse(h, midpoint(&m, h)), Err(CollapseRefusal::TooFewVertices));
    }
}

#[test]
fn collapse_that_would_pinch_two_sheets_is_refused() {
    // A degree-3 vertex inside a face of the sphere: collapsing an edge of that face would glue
    // the two remaining faces of the new vertex back to back.
    let mut m = sphere();
    let f = m.faces().next().unwrap();
    m.split_face(f, centroid(&m, f)).unwrap();
    let [a, b, _] = m.face(f);
    let h = m.find_edge(a, b).unwrap();
    assert_eq!(m.can_collapse(h, midpoint(&m, h)), Err(CollapseRefusal::LinkCondition));
    let t = m.twin(h);
    assert_eq!(m.can_collapse(t, midpoint(&m, t)), Err(CollapseRefusal::LinkCondition));
}

#[test]
fn boundary_collapses_that_would_pinch_or_dangle_are_refused() {
    // A 3×1 strip: the interior diagonal of each cell joins two boundary vertices.
    let (positions, faces) = grid(3, 1);
    let m = ManifoldMesh::new(positions, faces).unwrap();
    let diagonal = m.edges().find(|&h| !m.is_boundary_edge(h)).unwrap();
    assert_eq!(
        m.can_collapse(diagonal, midpoint(&m, diagonal)),
        Err(CollapseRefusal::BoundaryPinch)
    );
    // An ear's opposite edge joins two boundary vertices too.
    let (positions, faces) = grid(3, 3);
    let m = ManifoldMesh::new(positions, faces).unwrap();
    let corner = 3 * 4;
    assert_eq!(m.outgoing(corner).count(), 1);
    let opposite = tagsplat::topology::next(m.outgoing(corner).next().unwrap());
    assert_eq!(
        m.can_collapse(opposite, midpoint(&m, opposite)),
        Err(CollapseRefusal::BoundaryPinch)
    );
    // A lone triangle beside a grid: collapsing any of its edges would strand its third vertex.
    let (mut positions, mut faces) = grid(2, 2);
    let base = positions.len() as u32;
    positions.extend([[5.0, 0.0, 0.0], [6.0, 0.0, 0.0], [5.0, 1.0, 0.0]]);
    faces.push([base, base + 1, base + 2]);
    let m = ManifoldMesh::new(positions, faces).unwrap();
    let lone = m.outgoing(base).next().unwrap();
    assert_eq!(m.can_collapse(lone, midpoint(&m, lone)), Err(CollapseRefusal::DanglingVertex));
}

#[test]
fn collapse_that_would_flip_a_face_is_refused() {
    let (positions, faces) = grid(4, 4);
    let m = ManifoldMesh::new(positions, faces).unwrap();
    let h = interior_edge(&m);
    // Moving the kept vertex far past the opposite side folds the fan over.
    let (a, b) = (m.positions[m.origin(h) as usize], m.positions[m.dest(h) as usize]);
    let far = [0, 1, 2].map(|k| b[k] + 10.0 * (b[k] - a[k]));
    assert!(matches!(
        m.can_collapse(h, far),
        Err(CollapseRefusal::FlipsNormal { .. } | CollapseRefusal::Degenerate { .. })
    ));
    assert_eq!(m.can_collapse(h, midpoint(&m, h)), Ok(()));
}

/// Random splits, flips and collapses with a compaction every 97 steps, checking every
/// invariant after every operation and the remap against ids carried per vertex row.
#[test]
fn random_operation_sequences_keep_every_invariant() {
    for (seed, (name, mut m, euler)) in shapes().into_iter().enumerate() {
        let mut rng = SplitMix64::new(0x7090 + seed as u64);
        // ids[row] for every mesh row; `synced` holds the ids at the last compaction.
        let mut ids: Vec<u32> = (0..m.vertex_rows() as u32).collect();
        let mut synced = ids.clone();
        let mut next_id = ids.len() as u32;
        let mut done = [0usize; 4];
        for step in 0..3000 {
            let pick = |rng: &mut SplitMix64, n: usize| (rng.next_u64() % n as u64) as usize;
            let before = counts(&m);
            let op = pick(&mut rng, 4);
            let faces: Vec<u32> = m.faces().collect();
            let f = faces[pick(&mut rng, faces.len())];
            let h = 3 * f + pick(&mut rng, 3) as u32;
            let boundary = m.is_boundary_edge(h);
            let applied = match op {
                0 => m.split_face(f, centroid(&m, f)).is_ok_and(|_| {
                    assert_eq!(counts(&m), [before[0] + 1, before[1] + 3, before[2] + 2]);
                    true
                }),
                1 => m.split_edge(h, midpoint(&m, h)).is_ok_and(|_| {
                    let d = if boundary { [1, 2, 1] } else { [1, 3, 2] };
                    assert_eq!(counts(&m), [before[0] + d[0], before[1] + d[1], before[2] + d[2]]);
                    true
                }),
                2 => m.flip_edge(h).is_ok() && counts(&m) == before,
                _ => match m.collapse_edge(h, midpoint(&m, h)) {
                    Ok(_) => {
                        let d = if boundary { [1, 2, 1] } else { [1, 3, 2] };
                        assert_eq!(
                            counts(&m),
                            [before[0] - d[0], before[1] - d[1], before[2] - d[2]]
                        );
                        true
                    }
                    Err(_) => false,
                },
            };
            done[op] += applied as usize;
            while ids.len() < m.vertex_rows() {
                ids.push(next_id);
                next_id += 1;
            }
            assert_sound(&m, euler, &format!("{name} step {step} op {op}"));
            if step % 97 == 96 {
                let live: Vec<u32> = m.vertices().map(|v| ids[v as usize]).collect();
                let old_of_new = m.compact();
                let remapped = remap_rows(&synced, &old_of_new, |_| NONE);
                for (row, (&got, &want)) in remapped.iter().zip(&live).enumerate() {
                    let new = old_of_new[row] == NEW_ROW;
                    assert!(
                        if new { got == NONE && want >= synced.len() as u32 } else { got == want },
                        "{name}: row {row}"
                    );
                }
                assert_sound(&m, euler, &format!("{name} compaction at step {step}"));
                let (positions, faces, identity) = m.clone().into_arrays();
                assert_eq!(
                    (positions, faces, identity),
                    (m.positions.clone(), m.live_faces(), (0..m.vertex_count() as u32).collect())
                );
                ids = live;
                synced = ids.clone();
            }
        }
        assert!(done.iter().all(|&n| n > 100), "{name}: too few operations applied: {done:?}");
    }
}

#[test]
fn construction_errors_name_the_first_problem() {
    let quad =
        vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0], [0.5, 0.5, 1.0]];
    // Edge 0–1 with three faces.
    let fin = vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]];
    match ManifoldMesh::new(quad.clone(), fin) {
        Err(TopologyError::NonManifoldEdge { a: 0, b: 1, .. }) => {}
        other => panic!("expected edge 0–1, got {other:?}"),
    }
    // Two fans meeting at vertex 0 only (a bow tie).
    let bow = vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 0.0, 0.0],
        [-1.0, -1.0, 0.0],
    ];
    match ManifoldMesh::new(bow, vec![[0, 1, 2], [0, 3, 4]]) {
        Err(TopologyError::PinchedVertex { vertex: 0 }) => {}
        other => panic!("expected vertex 0, got {other:?}"),
    }
    assert!(matches!(
        ManifoldMesh::new(quad.clone(), vec![[0, 1, 2]]),
        Err(TopologyError::UnusedVertex { vertex: 3 })
    ));
    let mut nan = quad.clone();
    nan[2][1] = f32::NAN;
    assert!(matches!(
        ManifoldMesh::new(nan, vec![[0, 1, 2]]),
        Err(TopologyError::NonFinite { vertex: 2 })
    ));
    assert!(matches!(
        ManifoldMesh::new(quad.clone(), vec![[0, 1, 1]]),
        Err(TopologyError::DegenerateFace { face: 0, .. })
    ));
    assert!(matches!(
        ManifoldMesh::new(quad, vec![[0, 1, 9]]),
        Err(TopologyError::IndexOutOfRange { face: 0, .. })
    ));
}

#[test]
fn import_welds_seams_orients_and_names_the_file() {
    // The icosphere as a triangle soup (every face with its own corners), half the faces
    // reversed, plus an unused vertex.
    let (positions, faces) = icosphere(1);
    let mut soup = TriMesh::default();
    for (f, face) in faces.iter().enumerate() {
        let base = soup.positions.len() as u32;
        soup.positions.extend(face.iter().map(|&v| positions[v as usize].map(|c| c as f32)));
        soup.faces.push(if f % 2 == 0 {
            [base, base + 1, base + 2]
        } else {
            [base, base + 2, base + 1]
        });
    }
    soup.positions.push([5.0, 5.0, 5.0]);
    let path = Path::new("soup.ply");
    let imported = import(&soup, path, true).unwrap();
    assert_eq!(imported.mesh.vertex_count(), positions.len());
    assert_eq!(imported.report.welded_vertices, soup.positions.len() - positions.len() - 1);
    assert_eq!(imported.report.unused_vertices, 1);
    assert_eq!(imported.report.flipped_faces, faces.len() / 2);
    assert_sound(&imported.mesh, 2, "imported soup");
    // Outward: every face normal points away from the centre.
    for f in imported.mesh.faces() {
        let [a, b, c] =
            imported.mesh.face(f).map(|v| glam::Vec3::from(imported.mesh.positions[v as usize]));
        assert!((b - a).cross(c - a).dot(a + b + c) > 0.0);
    }
    // Each mesh row comes from a file row at the same position.
    for (row, &old) in imported.old_of_new.iter().enumerate() {
        assert_eq!(imported.mesh.positions[row], soup.positions[old as usize]);
    }
    // An open mesh where a closed one is needed, and a NaN, name the file.
    let (gp, gf) = grid(2, 2);
    let open = TriMesh { positions: gp, faces: gf, colors: None };
    let err = import(&open, path, true).unwrap_err().to_string();
    assert!(err.contains("soup.ply") && err.contains("open"), "{err}");
    assert!(import(&open, path, false).is_ok());
    let mut nan = open.clone();
    nan.positions[3][0] = f32::NAN;
    let err = import(&nan, path, false).unwrap_err().to_string();
    assert!(err.contains("soup.ply") && err.contains("vertex 3"), "{err}");
}

mod gaussians {
    use super::*;
    use tagsplat::splat::GaussianScene;
    use tagsplat::topology::{
        dc_colors, densify, face_scores, gaussian_normal, gaussians_from_mesh, improve_angles,
        prune, DensifyConfig, InitConfig, PruneConfig,
    };

    fn min_angle_of(m: &ManifoldMesh) -> f64 {
        m.faces()
            .map(|f| {
                let [a, b, c] = m.face(f).map(|v| m.point(v));
                let angle =
                    |p: glam::DVec3, q: glam::DVec3, r: glam::DVec3| (q - p).angle_between(r - p);
                angle(a, b, c).min(angle(b, c, a)).min(angle(c, a, b))
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// A scene whose opacity logits hold the row ids, so rows can be followed.
    fn tagged_scene(m: &ManifoldMesh) -> GaussianScene {
        let colors: Vec<[f32; 3]> =
            (0..m.vertex_rows()).map(|i| [(i % 7) as f32 / 7.0, 0.5, 0.25]).collect();
        let mut scene =
            gaussians_from_mesh(m, &colors, &InitConfig { sh_degree: 1, ..Default::default() });
        scene.opacity_logits = (0..scene.len()).map(|i| i as f32).collect();
        scene
    }

    #[test]
    fn gaussians_lie_in_the_sphere_with_neighbour_scales_and_vertex_colours() {
        let m = sphere();
        let colors: Vec<[f32; 3]> =
            (0..m.vertex_rows()).map(|i| [i as f32 / 200.0, 0.2, 0.9]).collect();
        let config = InitConfig::default();
        let scene = gaussians_from_mesh(&m, &colors, &config);
        scene.check().unwrap();
        for v in m.vertices() {
            let i = v as usize;
            // On the unit sphere the area-weighted normal is close to the radial direction.
            let radial = m.point(v).normalize();
            assert!(gaussian_normal(scene.rotations[i]).dot(radial) > 0.995, "vertex {v}");
            let ring = m.ring(v);
            let mean = ring.iter().map(|&r| (m.point(r) - m.point(v)).length()).sum::<f64>()
                / ring.len() as f64;
            let s = scene.log_scales[i];
            assert!((s[0] as f64 - (0.5 * mean).ln()).abs() < 1e-5 && s[0] == s[1]);
            assert!((s[2] as f64 - (0.05 * mean).ln()).abs() < 1e-5);
            let opacity = 1.0 / (1.0 + (-scene.opacity_logits[i]).exp());
            assert!((opacity - 0.95).abs() < 1e-5);
            let dc = dc_colors(&scene)[i];
            assert!(dc.iter().zip(colors[i]).all(|(a, b)| (a - b).abs() < 1e-5), "{dc:?}");
        }
    }

    #[test]
    fn densify_splits_the_chosen_faces_averages_parents_and_keeps_rows() {
        for (name, mut m, euler) in shapes() {
            let mut scene = tagged_scene(&m);
            let n = m.vertex_count();
            let mut scores = vec![0.0f32; m.vertex_rows()];
            for v in (0..n).step_by(5) {
                scores[v] = 1.0;
            }
            let faces = face_scores(&m, &scores);
            let config = DensifyConfig { threshold: 0.3, large_scale: 10.0, ..Default::default() };
            // New rows come in decreasing score order (ties by face index).
            let mut chosen: Vec<u32> = m.faces().filter(|&f| faces[f as usize] > 0.3).collect();
            chosen.sort_by(|&a, &b| faces[b as usize].total_cmp(&faces[a as usize]));
            let chosen: Vec<[u32; 3]> = chosen.into_iter().map(|f| m.face(f)).collect();
            let report = densify(&mut m, &mut scene, &faces, &config).unwrap();
            assert_sound(&m, euler, name);
            assert_eq!(report.split_faces + report.refused_splits, chosen.len(), "{name}");
            assert_eq!(m.vertex_count(), n + report.split_faces, "{name}");
            assert_eq!(scene.len(), m.vertex_count());
            assert_eq!(scene.positions, m.positions, "{name}: Gaussians sit on their vertices");
            let mut new_rows = 0;
            for (row, &old) in report.old_of_new.iter().enumerate() {
                if old == NEW_ROW {
                    // A new Gaussian averages three parents: its id is the mean of theirs.
                    let parents = chosen[new_rows];
                    let expected = parents.iter().map(|&p| p as f32).sum::<f32>() / 3.0;
                    assert!(
                        (scene.opacity_logits[row] - expected).abs() < 1e-3,
                        "{name} row {row}"
                    );
                    let q = scene.rotations[row];
                    assert!((q.iter().map(|c| c * c).sum::<f32>() - 1.0).abs() < 1e-5);
                    new_rows += 1;
                } else {
                    assert_eq!(scene.opacity_logits[row], old as f32, "{name} row {row}");
                }
            }
            assert_eq!(new_rows, report.split_faces);
        }
    }

    #[test]
    fn flips_after_repeated_splits_keep_angles_up() {
        let split_all = |m: &mut ManifoldMesh, rounds: usize, flip: bool| {
            for _ in 0..rounds {
                let faces: Vec<u32> = m.faces().collect();
                let mut touched = Vec::new();
                for f in faces {
                    let before = m.face_rows() as u32;
                    let c = m.face(f).map(|v| m.positions[v as usize]);
                    let centroid = [0, 1, 2].map(|k| (c[0][k] + c[1][k] + c[2][k]) / 3.0);
                    if m.split_face(f, centroid).is_ok() {
                        touched.extend([f, before, before + 1]);
                    }
                }
                if flip {
                    assert!(improve_angles(m, &touched) > 0);
                }
            }
        };
        let (mut plain, mut flipped) = (sphere(), sphere());
        split_all(&mut plain, 2, false);
        split_all(&mut flipped, 2, true);
        assert_sound(&flipped, 2, "flipped");
        assert_eq!(plain.vertex_count(), flipped.vertex_count());
        let (a, b) = (min_angle_of(&plain).to_degrees(), min_angle_of(&flipped).to_degrees());
        assert!(b > 2.0 * a, "min angle {a:.2}° without flips, {b:.2}° with");
    }

    #[test]
    fn large_new_gaussians_and_their_corners_are_halved() {
        let mut m = sphere();
        let mut scene = tagged_scene(&m);
        let f = m.faces().next().unwrap();
        let corners = m.face(f);
        let before: Vec<[f32; 3]> = corners.iter().map(|&c| scene.log_scales[c as usize]).collect();
        let mut scores = vec![0.0; m.face_rows()];
        scores[f as usize] = 1.0;
        let report = densify(
            &mut m,
            &mut scene,
            &scores,
            &DensifyConfig { threshold: 0.5, large_scale: 1e-4, ..Default::default() },
        )
        .unwrap();
        assert_eq!((report.split_faces, report.halved), (1, 4));
        for (k, &c) in corners.iter().enumerate() {
            let row = report.old_of_new.iter().position(|&o| o == c).unwrap();
            for (now, was) in scene.log_scales[row].iter().zip(before[k]) {
                assert!((now - (was - std::f32::consts::LN_2)).abs() < 1e-6);
            }
        }
    }

    #[test]
    fn prune_merges_picked_gaussians_into_their_cheapest_neighbour() {
        for (name, mut m, euler) in shapes() {
            let mut scene = tagged_scene(&m);
            let n = scene.len();
            // Ids in the SH DC red channel (opacity is the criterion here).
            let stride = scene.coefficients() * 3;
            for i in 0..n {
                scene.sh[i * stride] = i as f32;
                scene.opacity_logits[i] = if i % 9 == 4 { -10.0 } else { 3.0 };
            }
            let picked: Vec<usize> = (0..n).filter(|i| i % 9 == 4).collect();
            let config = PruneConfig { w_a: 0.0, ..Default::default() };
            let report = prune(&mut m, &mut scene, &config).unwrap();
            assert_sound(&m, euler, name);
            assert_eq!(report.candidates, picked.len());
            assert_eq!(report.pruned + report.kept_no_legal_edge, picked.len(), "{name}");
            assert!(report.pruned > picked.len() / 2, "{name}: {report:?}");
            assert_eq!(scene.len(), n - report.pruned);
            for (row, &old) in report.old_of_new.iter().enumerate() {
                assert_ne!(old, NEW_ROW);
                assert_eq!(
                    scene.sh[row * stride],
                    old as f32,
                    "{name}: row {row} keeps its own parameters"
                );
                assert_eq!(scene.positions[row], m.positions[row]);
            }
            let survivors_picked = report.old_of_new.iter().filter(|&&o| o % 9 == 4).count();
            assert_eq!(survivors_picked, report.kept_no_legal_edge, "{name}");
        }
    }

    #[test]
    fn prune_counts_gaussians_without_a_legal_edge() {
        // An octahedron: after one merge 5 vertices remain, so the second is refused.
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
        let mut m = ManifoldMesh::new(positions, faces).unwrap();
        let mut scene = tagged_scene(&m);
        scene.opacity_logits = vec![-10.0, -10.0, 3.0, 3.0, 3.0, 3.0];
        let report =
            prune(&mut m, &mut scene, &PruneConfig { max_scale: 10.0, ..Default::default() })
                .unwrap();
        assert_eq!((report.candidates, report.pruned, report.kept_no_legal_edge), (2, 1, 1));
        assert_eq!(m.vertex_count(), 5);
        assert_sound(&m, 2, "octahedron");
    }
}

/// The training loop's view of one densify + prune round: every per-vertex array it keeps
/// (Adam moments, gradient statistics) follows the scene through the returned remaps.
#[test]
fn optimizer_moments_and_statistics_follow_the_gaussians() {
    use tagsplat::topology::{
        densify, gaussians_from_mesh, prune, DensifyConfig, InitConfig, PruneConfig,
    };
    let mut m = sphere();
    let mut scene =
        gaussians_from_mesh(&m, &[], &InitConfig { sh_degree: 0, ..Default::default() });
    let n = scene.len();
    // Ids in the DC term; moments = 10 × id (3 floats per row); statistics = id.
    for i in 0..n {
        scene.sh[3 * i] = i as f32;
    }
    let mut moments: Vec<f32> = (0..n).flat_map(|i| [10.0 * i as f32; 3]).collect();
    let mut stats: Vec<f32> = (0..n).map(|i| i as f32).collect();
    let scores: Vec<f32> = (0..m.face_rows()).map(|f| (f % 4 == 0) as u32 as f32).collect();
    let d = densify(
        &mut m,
        &mut scene,
        &scores,
        &DensifyConfig { threshold: 0.5, large_scale: 10.0, ..Default::default() },
    )
    .unwrap();
    moments = tagsplat::topology::remap_strided(&moments, 3, &d.old_of_new, |_, row| row.fill(0.0));
    stats = remap_rows(&stats, &d.old_of_new, |_| 0.0);
    for (i, l) in scene.opacity_logits.iter_mut().enumerate() {
        *l = if i % 7 == 3 { -10.0 } else { 3.0 };
    }
    let p =
        prune(&mut m, &mut scene, &PruneConfig { max_scale: 10.0, ..Default::default() }).unwrap();
    moments = tagsplat::topology::remap_strided(&moments, 3, &p.old_of_new, |_, _| {
        unreachable!("pruning adds no rows")
    });
    stats = remap_rows(&stats, &p.old_of_new, |_| unreachable!("pruning adds no rows"));
    assert!(d.split_faces > 50 && p.pruned > 20, "{} splits, {} merges", d.split_faces, p.pruned);
    assert_eq!((moments.len(), stats.len()), (3 * scene.len(), scene.len()));
    let mut fresh = 0;
    for row in 0..scene.len() {
        let kept_since_start = tagsplat::topology::compose(&d.old_of_new, &p.old_of_new)[row];
        if kept_since_start == NEW_ROW {
            fresh += 1;
            assert_eq!(
                (moments[3 * row], stats[row]),
                (0.0, 0.0),
                "row {row}: new Gaussians start with zero moments"
            );
        } else {
            let id = scene.sh[3 * row];
            assert_eq!(id, kept_since_start as f32, "row {row}");
            assert_eq!((moments[3 * row], stats[row]), (10.0 * id, id), "row {row}");
        }
    }
    assert!(fresh > 0);
}

#[test]
fn densify_and_prune_refuse_mismatched_inputs() {
    use tagsplat::topology::{
        densify, gaussians_from_mesh, prune, DensifyConfig, InitConfig, PruneConfig,
    };
    let mut m = sphere();
    let mut scene =
        gaussians_from_mesh(&m, &[], &InitConfig { sh_degree: 0, ..Default::default() });
    let short = vec![1.0; m.face_rows() - 1];
    let err =
        densify(&mut m, &mut scene, &short, &DensifyConfig::default()).unwrap_err().to_string();
    assert!(err.contains("face scores"), "{err}");
    scene.positions.pop();
    let err = prune(&mut m, &mut scene, &PruneConfig::default()).unwrap_err().to_string();
    assert!(err.contains("Gaussians for"), "{err}");
    let mut scene =
        gaussians_from_mesh(&m, &[], &InitConfig { sh_degree: 0, ..Default::default() });
    let h = m.edges().next().unwrap();
    let mid = [0, 1, 2]
        .map(|k| 0.5 * (m.positions[m.origin(h) as usize][k] + m.positions[m.dest(h) as usize][k]));
    m.collapse_edge(h, mid).unwrap();
    let err = prune(&mut m, &mut scene, &PruneConfig::default()).unwrap_err().to_string();
    assert!(err.contains("compact"), "{err}");
}

#[test]
fn collapsing_a_thin_tube_across_is_refused_and_leaves_the_mesh_untouched() {
    // A torus whose tube has a triangular cross-section: collapsing an edge of a cross-section
    // ring would press the tube flat, two sheets glued along an edge.
    let minor = 3;
    let (p, f) = torus(8, minor);
    let mut m = ManifoldMesh::new(p, f).unwrap();
    let before = counts(&m);
    let across: Vec<u32> =
        m.edges().filter(|&h| m.origin(h) / minor == m.dest(h) / minor).collect();
    assert_eq!(across.len(), 8 * 3);
    for h in across {
        assert_eq!(m.collapse_edge(h, midpoint(&m, h)), Err(CollapseRefusal::LinkCondition));
    }
    assert_eq!(counts(&m), before);
    assert_sound(&m, 0, "thin torus");
}
