//! The node hierarchy of a glTF file: each node's parent (a node with two parents, or a
//! cycle, is an error: glTF requires a forest), local transforms (a matrix, or translation,
//! rotation and scale), and global transforms as products of local ones from the root down.

use glam::{DMat4, DQuat, DVec3};

/// A node's local transform: its matrix, or T · R · S.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Local {
    /// A `matrix` node (never animated: glTF forbids animating one).
    Matrix(DMat4),
    /// Translation, rotation (x, y, z, w; normalised when the matrix is built), scale.
    Trs {
        /// Translation.
        t: [f64; 3],
        /// Rotation quaternion (x, y, z, w).
        r: [f64; 4],
        /// Scale.
        s: [f64; 3],
    },
}

impl Local {
    /// A node's local transform as the file gives it.
    pub fn of(node: &gltf::Node) -> Local {
        match node.transform() {
            gltf::scene::Transform::Matrix { matrix } => {
                Local::Matrix(glam::Mat4::from_cols_array_2d(&matrix).as_dmat4())
            }
            gltf::scene::Transform::Decomposed { translation, rotation, scale } => Local::Trs {
                t: translation.map(f64::from),
                r: rotation.map(f64::from),
                s: scale.map(f64::from),
            },
        }
    }

    /// The transform as a matrix.
    pub fn matrix(&self) -> DMat4 {
        match *self {
            Local::Matrix(m) => m,
            Local::Trs { t, r, s } => DMat4::from_scale_rotation_translation(
                DVec3::from(s),
                DQuat::from_array(r).normalize(),
                DVec3::from(t),
            ),
        }
    }
}

/// Each node's parent, and an order that puts every parent before its children.
#[derive(Clone, Debug)]
pub struct Hierarchy {
    parents: Vec<Option<usize>>,
    order: Vec<usize>,
}

impl Hierarchy {
    /// The hierarchy of `document`'s nodes, checked to be a forest.
    pub fn new(document: &gltf::Document) -> Result<Self, String> {
        let name = |i: usize| node_name(&document.nodes().nth(i).expect("in range"));
        let mut parents = vec![None; document.nodes().len()];
        for node in document.nodes() {
            for child in node.children() {
                if let Some(other) = parents[child.index()].replace(node.index()) {
                    return Err(format!(
                        "node {} has two parents, {} and {} (glTF requires a tree)",
                        name(child.index()),
                        name(other),
                        name(node.index())
                    ));
                }
            }
        }
        let mut order = Vec::with_capacity(parents.len());
        let mut placed = vec![false; parents.len()];
        for start in 0..parents.len() {
            // The chain of unplaced ancestors, root-most last; a chain longer than the node
            // count has gone round a cycle.
            let mut chain = vec![start];
            let mut at = start;
            while let Some(p) = parents[at].filter(|&p| !placed[p]) {
                if chain.len() > parents.len() || p == start {
                    return Err(format!("the node hierarchy has a cycle through node {}", name(p)));
                }
                chain.push(p);
                at = p;
            }
            for &n in chain.iter().rev() {
                if !placed[n] {
                    placed[n] = true;
                    order.push(n);
                }
            }
        }
        Ok(Self { parents, order })
    }

    /// The parent of `node`.
    pub fn parent(&self, node: usize) -> Option<usize> {
        self.parents[node]
    }

    /// Global transforms of every node for `locals` (one per node).
    pub fn globals(&self, locals: &[Local]) -> Vec<DMat4> {
        let mut globals = vec![DMat4::IDENTITY; locals.len()];
        for &n in &self.order {
            let local = locals[n].matrix();
            globals[n] = match self.parents[n] {
                Some(p) => globals[p] * local,
                None => local,
            };
        }
        globals
    }
}

/// A node as messages name it: `name` (#index), or #index when it has no name.
pub fn node_name(node: &gltf::Node) -> String {
    match node.name() {
        Some(name) => format!("`{name}` (#{})", node.index()),
        None => format!("#{}", node.index()),
    }
}
