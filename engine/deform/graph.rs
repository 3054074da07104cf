//! The embedded deformation graph of a frame (Sumner et al. 2007, with geodesic bindings):
//! nodes spread over the surface, each vertex bound to its nearest nodes along the mesh, nodes
//! linked when a vertex binds both. Plain arrays in and out; built on the CPU once per frame.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Nodes a vertex is bound to (the kernels' `NODES_PER_VERTEX`).
pub const NODES_PER_VERTEX: usize = 4;

/// A graph over `vertices` vertices.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DeformGraph {
    /// The vertex each node sits on.
    pub node_vertices: Vec<u32>,
    /// Per vertex: its nodes and their weights (sum 1; unused slots weigh 0).
    pub bound_nodes: Vec<[u32; NODES_PER_VERTEX]>,
    /// The weights of `bound_nodes`, slot for slot.
    pub bound_weights: Vec<[f32; NODES_PER_VERTEX]>,
    /// Node k's neighbours are `neighbours[start..start + count]`, `[start, count] =
    /// neighbour_ranges[k]`; the relation is symmetric.
    pub neighbour_ranges: Vec<[u32; 2]>,
    /// Every node's neighbour list, concatenated; indexed through `neighbour_ranges`.
    pub neighbours: Vec<u32>,
    /// Mean distance between linked nodes (scene units): the graph's length scale.
    pub node_spacing: f32,
}

/// Builds a graph of `nodes` nodes (fewer when the mesh has fewer vertices) over a mesh given
/// by its positions and symmetric vertex adjacency (`adjacency(i)` lists i's neighbours).
/// Guarantees: nodes are distinct vertices chosen by farthest-point sampling from vertex 0
/// (deterministic); every vertex reached from a node along edges is bound to its up to
/// `NODES_PER_VERTEX` geodesically nearest nodes (edge-path lengths), weighted
/// (1 − d / d_next)² as Sumner's, normalised; a vertex in a component without nodes binds
/// nothing (zero weights) and stays put.
pub fn build_graph<'a>(
    positions: &[[f32; 3]],
    adjacency: impl Fn(usize) -> &'a [u32],
    nodes: usize,
) -> DeformGraph {
    let node_vertices = farthest_points(positions, nodes);
    let nearest = nearest_nodes(positions, &adjacency, &node_vertices);
    let mut graph = DeformGraph { node_vertices, ..Default::default() };
    let mut links = vec![Vec::new(); graph.node_vertices.len()];
    for labels in &nearest {
        let (bound, weights) = weights_of(labels);
        for a in 0..NODES_PER_VERTEX {
            for b in 0..NODES_PER_VERTEX {
                if a != b && weights[a] > 0.0 && weights[b] > 0.0 {
                    links[bound[a] as usize].push(bound[b]);
                }
            }
        }
        graph.bound_nodes.push(bound);
        graph.bound_weights.push(weights);
    }
    let (mut length, mut count) = (0.0f64, 0usize);
    for (k, list) in links.iter_mut().enumerate() {
        list.sort_unstable();
        list.dedup();
        graph.neighbour_ranges.push([graph.neighbours.len() as u32, list.len() as u32]);
        graph.neighbours.extend_from_slice(list);
        let at = point(positions, graph.node_vertices[k]);
        for &j in list.iter() {
            length += (point(positions, graph.node_vertices[j as usize]) - at).length();
            count += 1;
        }
    }
    graph.node_spacing = if count > 0 { (length / count as f64) as f32 } else { 0.0 };
    graph
}

#[inline]
fn point(positions: &[[f32; 3]], v: u32) -> glam::DVec3 {
    glam::DVec3::from(positions[v as usize].map(f64::from))
}

/// `count` distinct vertices, each the farthest (Euclidean) from those before it.
fn farthest_points(positions: &[[f32; 3]], count: usize) -> Vec<u32> {
    let count = count.min(positions.len());
    let mut chosen = Vec::with_capacity(count);
    let mut distance = vec![f64::INFINITY; positions.len()];
    let mut next = 0u32;
    while chosen.len() < count {
        chosen.push(next);
        // −1 marks a chosen vertex: it stays below every distance, so none is chosen twice.
        distance[next as usize] = -1.0;
        let at = point(positions, next);
        let mut far = (-0.5, None);
        for (i, d) in distance.iter_mut().enumerate() {
            *d = d.min((point(positions, i as u32) - at).length_squared());
            if *d > far.0 {
                far = (*d, Some(i as u32));
            }
        }
        match far.1 {
            Some(v) => next = v,
            None => break,
        }
    }
    chosen
}

/// Per vertex, its `NODES_PER_VERTEX + 1` nearest nodes by edge-path length, nearest first
/// (the last one only sets the weights' falloff): one Dijkstra over (vertex, node) labels,
/// each vertex settling at most that many distinct nodes.
fn nearest_nodes<'a>(
    positions: &[[f32; 3]],
    adjacency: &impl Fn(usize) -> &'a [u32],
    nodes: &[u32],
) -> Vec<Vec<(u32, f64)>> {
    let keep = NODES_PER_VERTEX + 1;
    let mut labels: Vec<Vec<(u32, f64)>> = vec![Vec::new(); positions.len()];
    // Distances as ordered bits: non-negative f64s order as their bit patterns do.
    let mut queue: BinaryHeap<Reverse<(u64, u32, u32)>> =
        nodes.iter().enumerate().map(|(k, &v)| Reverse((0f64.to_bits(), v, k as u32))).collect();
    while let Some(Reverse((bits, v, k))) = queue.pop() {
        let here = &mut labels[v as usize];
        if here.len() >= keep || here.iter().any(|&(n, _)| n == k) {
            continue;
        }
        let d = f64::from_bits(bits);
        here.push((k, d));
        for &u in adjacency(v as usize) {
            let there = &labels[u as usize];
            if there.len() < keep && !there.iter().any(|&(n, _)| n == k) {
                let step = (point(positions, u) - point(positions, v)).length();
                queue.push(Reverse(((d + step).to_bits(), u, k)));
            }
        }
    }
    labels
}

/// Sumner's weights (1 − d_k / d_max)², normalised, d_max the distance of the next node
/// beyond the bound ones (or 1.5× the farthest bound one when there is none).
fn weights_of(labels: &[(u32, f64)]) -> ([u32; NODES_PER_VERTEX], [f32; NODES_PER_VERTEX]) {
    let (mut bound, mut weights) = ([0u32; NODES_PER_VERTEX], [0f32; NODES_PER_VERTEX]);
    let used = labels.len().min(NODES_PER_VERTEX);
    if used == 0 {
        return (bound, weights);
    }
    let d_max = labels.get(NODES_PER_VERTEX).map_or(1.5 * labels[used - 1].1, |l| l.1);
    let raw: Vec<f64> = labels[..used]
        .iter()
        .map(|&(_, d)| if d_max > 0.0 { (1.0 - d / d_max).max(0.0).powi(2) } else { 1.0 })
        .collect();
    let total: f64 = raw.iter().sum();
    for s in 0..used {
        bound[s] = labels[s].0;
        // A vertex whose nodes are all equidistant at d_max (total 0) weighs them equally.
        weights[s] = if total > 0.0 { raw[s] / total } else { 1.0 / used as f64 } as f32;
    }
    (bound, weights)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A strip of `n` vertices along x, each linked to its neighbours.
    fn strip(n: usize) -> (Vec<[f32; 3]>, Vec<Vec<u32>>) {
        let positions = (0..n).map(|i| [i as f32, 0.0, 0.0]).collect();
        let adjacency = (0..n)
            .map(|i| {
                [i.checked_sub(1), (i + 1 < n).then_some(i + 1)]
                    .into_iter()
                    .flatten()
                    .map(|j| j as u32)
                    .collect()
            })
            .collect();
        (positions, adjacency)
    }

    #[test]
    fn weights_sum_to_one_and_links_are_symmetric() {
        let (positions, adjacency) = strip(40);
        let graph = build_graph(&positions, |i| &adjacency[i], 8);
        assert_eq!(graph.node_vertices.len(), 8);
        assert_eq!(graph.node_vertices[..2], [0, 39]);
        for w in &graph.bound_weights {
            assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-6, "{w:?}");
        }
        for k in 0..8u32 {
            let [s, c] = graph.neighbour_ranges[k as usize];
            for &j in &graph.neighbours[s as usize..(s + c) as usize] {
                let [sj, cj] = graph.neighbour_ranges[j as usize];
                assert!(graph.neighbours[sj as usize..(sj + cj) as usize].contains(&k));
            }
        }
        assert!(graph.node_spacing > 0.0);
    }

    #[test]
    fn binding_follows_edges_not_space() {
        // Two strips side by side, 0.1 apart but not connected: no vertex binds across.
        let (mut positions, mut adjacency) = strip(20);
        let (other, other_adjacency) = strip(20);
        positions.extend(other.iter().map(|p| [p[0], 0.1, 0.0]));
        adjacency
            .extend(other_adjacency.into_iter().map(|l| l.into_iter().map(|j| j + 20).collect()));
        let graph = build_graph(&positions, |i| &adjacency[i], 6);
        let strip_of = |v: u32| v / 20;
        for (v, (nodes, weights)) in graph.bound_nodes.iter().zip(&graph.bound_weights).enumerate()
        {
            for (k, w) in nodes.iter().zip(weights) {
                if *w > 0.0 {
                    assert_eq!(
                        strip_of(graph.node_vertices[*k as usize]),
                        strip_of(v as u32),
                        "vertex {v}"
                    );
                }
            }
        }
    }

    #[test]
    fn empty_mesh_and_unreached_vertices() {
        let graph = build_graph(&[], |_| &[], 10);
        assert!(graph.node_vertices.is_empty() && graph.bound_nodes.is_empty());
        let positions = vec![[0.0; 3], [1.0, 0.0, 0.0]];
        let graph = build_graph(&positions, |_| &[], 1);
        assert_eq!(graph.bound_weights[1], [0.0; NODES_PER_VERTEX]);
        assert_eq!(graph.bound_weights[0][0], 1.0);
    }
}
