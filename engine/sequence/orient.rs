//! Which way is up in an export. A capture's world can have any axis up (Panoptic rigs are often
//! Z-up or −Y-up); glTF viewers expect +Y, Blender and most DCC scenes +Z. An [`Orientation`]
//! turns positions so that the capture's up points along the file's up axis. It is a proper
//! rotation by quarter turns, so winding is kept and every coordinate is copied or negated,
//! never rounded.

use super::MeshSequence;

/// Which axis is up in a written file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum UpAxis {
    /// +Y is up (glTF's convention).
    Y,
    /// +Z is up.
    Z,
}

impl UpAxis {
    /// The `upAxis` token of USD: `"Y"` or `"Z"`.
    pub fn name(self) -> &'static str {
        match self {
            UpAxis::Y => "Y",
            UpAxis::Z => "Z",
        }
    }

    /// The file's default up for a capture whose up is `source`: Z for a Z-up (or Z-down)
    /// capture, Y otherwise, so a capture already in one of the two conventions keeps its axes.
    pub fn following(source: SignedAxis) -> UpAxis {
        if source.axis == 2 {
            UpAxis::Z
        } else {
            UpAxis::Y
        }
    }

    fn as_signed(self) -> SignedAxis {
        SignedAxis { axis: if self == UpAxis::Y { 1 } else { 2 }, negative: false }
    }
}

/// A world axis with a direction: +X, −X, +Y, −Y, +Z or −Z.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SignedAxis {
    /// 0, 1, 2 for X, Y, Z.
    pub axis: usize,
    /// Points along −axis.
    pub negative: bool,
}

impl SignedAxis {
    /// The signed axis nearest `direction` (its largest component; +Y for zero or non-finite
    /// input, the convention of a Y-up file).
    pub fn nearest(direction: [f64; 3]) -> SignedAxis {
        let magnitude = |i: usize| direction[i].abs();
        let axis = (0..3).fold(1, |best, i| if magnitude(i) > magnitude(best) { i } else { best });
        // Phrased as "below zero" so that NaN reads as +.
        SignedAxis { axis, negative: direction[axis] < 0.0 }
    }

    /// Parses `+x`, `-z`, `y` (= `+y`) and so on, case-insensitive.
    pub fn parse(text: &str) -> Option<SignedAxis> {
        let lower = text.trim().to_ascii_lowercase();
        let (negative, name) = match lower.strip_prefix('-') {
            Some(rest) => (true, rest),
            None => (false, lower.strip_prefix('+').unwrap_or(&lower)),
        };
        let axis = ["x", "y", "z"].iter().position(|&n| n == name)?;
        Some(SignedAxis { axis, negative })
    }

    fn vector(self) -> [i32; 3] {
        let mut v = [0; 3];
        v[self.axis] = if self.negative { -1 } else { 1 };
        v
    }
}

impl std::fmt::Display for SignedAxis {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        let sign = if self.negative { '-' } else { '+' };
        write!(f, "{sign}{}", ["X", "Y", "Z"][self.axis])
    }
}

/// A quarter-turn rotation taking a capture's up to a file's up axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Orientation {
    /// The file's up axis.
    pub up: UpAxis,
    /// The capture's up it turns onto `up`.
    pub source: SignedAxis,
    /// Rotation matrix rows; entries −1, 0 or 1.
    rows: [[i32; 3]; 3],
}

impl Orientation {
    /// The rotation taking `source` onto `up`: the identity when they agree, a quarter turn about
    /// their cross product when they are perpendicular, a half turn about X (perpendicular to
    /// both, since `up` is Y or Z) when they are opposite.
    pub fn new(source: SignedAxis, up: UpAxis) -> Orientation {
        let (a, e) = (source.vector(), up.as_signed().vector());
        let k = cross(a, e);
        let rows = if a == e {
            identity()
        } else if k != [0; 3] {
            // Rodrigues at 90°: R v = k (k·v) + k × v, and R a = k × a = e.
            basis_columns(|v| add(scale(k, dot(k, v)), cross(k, v)))
        } else {
            // Half turn about an axis perpendicular to both: R v = 2 k (k·v) − v.
            let k = [1, 0, 0];
            basis_columns(|v| add(scale(k, 2 * dot(k, v)), scale(v, -1)))
        };
        Orientation { up, source, rows }
    }

    /// How to write a capture whose up is `source`: turned onto `requested` when given, otherwise
    /// onto +Y for glTF (`gltf`: its specification's up) and onto [`UpAxis::following`] for
    /// every other format.
    pub fn for_export(source: SignedAxis, requested: Option<UpAxis>, gltf: bool) -> Orientation {
        let fallback = if gltf { UpAxis::Y } else { UpAxis::following(source) };
        Orientation::new(source, requested.unwrap_or(fallback))
    }

    /// Positions as they are, in a file whose up is `up` (the capture's up is taken to be `up`).
    pub fn keep(up: UpAxis) -> Orientation {
        Orientation::new(up.as_signed(), up)
    }

    /// True when positions are written as they are.
    #[inline]
    pub fn is_identity(&self) -> bool {
        self.rows == identity()
    }

    /// `p` turned; exact (each output coordinate is one input coordinate or its negation).
    #[inline]
    pub fn apply<T: Copy + std::ops::Neg<Output = T>>(&self, p: [T; 3]) -> [T; 3] {
        self.rows.map(|row| {
            let i = row.iter().position(|&r| r != 0).unwrap_or(0);
            if row[i] < 0 {
                -p[i]
            } else {
                p[i]
            }
        })
    }

    /// `sequence` with every frame's positions turned (faces and colours as they are).
    pub fn sequence(&self, sequence: &MeshSequence) -> MeshSequence {
        MeshSequence {
            frames: sequence
                .frames
                .iter()
                .map(|f| f.iter().map(|&p| self.apply(p)).collect())
                .collect(),
            ..sequence.clone()
        }
    }

    /// A sentence for reports: the file's up and what was turned onto it.
    pub fn describe(&self) -> String {
        if self.is_identity() {
            format!("{} up (the capture's up {} kept)", self.up.name(), self.source)
        } else {
            format!(
                "{} up (the capture's up {} turned onto +{})",
                self.up.name(),
                self.source,
                self.up.name()
            )
        }
    }
}

fn identity() -> [[i32; 3]; 3] {
    [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
}

/// The matrix whose column j is `f(e_j)`, as rows.
fn basis_columns(f: impl Fn([i32; 3]) -> [i32; 3]) -> [[i32; 3]; 3] {
    let columns = identity().map(f);
    [0, 1, 2].map(|r| [columns[0][r], columns[1][r], columns[2][r]])
}

fn dot(a: [i32; 3], b: [i32; 3]) -> i32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: [i32; 3], b: [i32; 3]) -> [i32; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

fn scale(a: [i32; 3], s: i32) -> [i32; 3] {
    a.map(|x| x * s)
}

fn add(a: [i32; 3], b: [i32; 3]) -> [i32; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn det(m: [[i32; 3]; 3]) -> i32 {
        dot(m[0], cross(m[1], m[2]))
    }

    #[test]
    fn every_capture_up_lands_on_the_file_up_by_a_proper_rotation() {
        for axis in 0..3 {
            for negative in [false, true] {
                let source = SignedAxis { axis, negative };
                for up in [UpAxis::Y, UpAxis::Z] {
                    let o = Orientation::new(source, up);
                    assert_eq!(det(o.rows), 1, "{source} -> {up:?} must keep winding");
                    let turned = o.apply(source.vector().map(|x| x as f64));
                    assert_eq!(
                        turned,
                        up.as_signed().vector().map(|x| x as f64),
                        "{source} -> {up:?}"
                    );
                    assert_eq!(o.is_identity(), source == up.as_signed());
                }
            }
        }
    }

    #[test]
    fn z_up_to_y_up_is_the_usual_quarter_turn_and_exact() {
        let o = Orientation::new(SignedAxis { axis: 2, negative: false }, UpAxis::Y);
        // A Z-up capture's forward (+Y) becomes −Z, as Blender's glTF exporter does.
        assert_eq!(o.apply([0.1f32, 0.2, 0.3]), [0.1, 0.3, -0.2]);
        assert_eq!(o.apply([f32::MIN_POSITIVE, -0.0, 1e30]), [f32::MIN_POSITIVE, 1e30, 0.0]);
    }

    #[test]
    fn nearest_and_parse_name_the_axis() {
        assert_eq!(SignedAxis::nearest([0.1, -0.2, -0.9]).to_string(), "-Z");
        assert_eq!(SignedAxis::nearest([0.0; 3]).to_string(), "+Y");
        assert_eq!(SignedAxis::nearest([f64::NAN; 3]).to_string(), "+Y");
        assert_eq!(SignedAxis::parse("-z"), Some(SignedAxis { axis: 2, negative: true }));
        assert_eq!(SignedAxis::parse("Y"), Some(SignedAxis { axis: 1, negative: false }));
        assert_eq!(SignedAxis::parse("+x"), Some(SignedAxis { axis: 0, negative: false }));
        assert_eq!(SignedAxis::parse("up"), None);
        assert_eq!(UpAxis::following(SignedAxis::parse("-z").unwrap()), UpAxis::Z);
        assert_eq!(UpAxis::following(SignedAxis::parse("-y").unwrap()), UpAxis::Y);
        let z_up = SignedAxis::parse("z").unwrap();
        assert_eq!(Orientation::for_export(z_up, None, true).up, UpAxis::Y);
        assert!(Orientation::for_export(z_up, None, false).is_identity());
        assert_eq!(Orientation::for_export(z_up, Some(UpAxis::Y), false).up, UpAxis::Y);
    }
}
