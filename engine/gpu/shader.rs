//! Embedded shaders and their interface contracts.
//!
//! build.rs reflects every compiled module (build/reflect.rs) into a [`Shader`] in
//! `crate::shaders`. The Rust side of a kernel is checked against that reflection rather than
//! against comments:
//! - push constants at compile time: each push-constant struct states its contract in one
//!   [`push_layout!`] line, which fails `cargo build` naming the struct, the shader and the
//!   field when the struct's size or a field's offset differs from the shader's block;
//! - storage buffers at dispatch: [`Shader::binding_slots`] places each buffer at the binding
//!   its name has in the shader, and refuses unknown, repeated or missing names.

/// A compiled shader and the interface reflected from it.
#[derive(Debug)]
pub struct Shader {
    /// Source path under `shaders/`.
    pub path: &'static str,
    /// The SPIR-V module.
    pub spirv: &'static [u8],
    /// Bytes of the push-constant block: the end of its last member; 0 without one.
    pub push_size: usize,
    /// Top-level push-constant members: name and byte offset.
    pub push_members: &'static [(&'static str, usize)],
    /// Storage buffers of set 0: name and binding, by binding. Aliases (several blocks at one
    /// binding) have an entry each.
    pub bindings: &'static [(&'static str, u32)],
}

impl Shader {
    /// Whether the push-constant block has a member `name` at byte `offset`; `const`, so that
    /// `push_layout!` asserts it at compile time.
    pub const fn push_member_at(&self, name: &str, offset: usize) -> bool {
        let mut i = 0;
        while i < self.push_members.len() {
            let (member, at) = self.push_members[i];
            if str_eq(member, name) {
                return at == offset;
            }
            i += 1;
        }
        false
    }

    /// The binding numbers of the set-0 layout, ascending, aliases once.
    pub fn binding_numbers(&self) -> Vec<u32> {
        let mut numbers: Vec<u32> = self.bindings.iter().map(|&(_, b)| b).collect();
        numbers.dedup();
        numbers
    }

    /// The binding of each of `names`, in order: every binding of the shader named exactly
    /// once (by any of its aliases). The error names the shader and the binding.
    pub fn binding_slots(&self, names: &[&str]) -> Result<Vec<u32>, String> {
        let slots = names
            .iter()
            .map(|name| {
                let found = self.bindings.iter().find(|(n, _)| n == name);
                found.map(|&(_, b)| b).ok_or_else(|| {
                    let known: Vec<_> = self.bindings.iter().map(|(n, _)| *n).collect();
                    format!("{}: no binding named {name:?} (it has {known:?})", self.path)
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        for number in self.binding_numbers() {
            let given = slots.iter().filter(|&&s| s == number).count();
            if given != 1 {
                let names: Vec<_> =
                    self.bindings.iter().filter(|(_, b)| *b == number).map(|(n, _)| *n).collect();
                return Err(format!(
                    "{}: binding {number} {names:?} given {given} times, not once",
                    self.path
                ));
            }
        }
        Ok(slots)
    }
}

/// `a == b`, usable in `const` items.
const fn str_eq(a: &str, b: &str) -> bool {
    let (a, b) = (a.as_bytes(), b.as_bytes());
    if a.len() != b.len() {
        return false;
    }
    let mut i = 0;
    while i < a.len() {
        if a[i] != b[i] {
            return false;
        }
        i += 1;
    }
    true
}

/// States that push-constant struct `$ty` is the push-constant block of each listed shader
/// (constants of `crate::shaders`): same size, and each listed field at the offset of the block
/// member of the same name. The fields must name every member of the block. Checked at compile
/// time; a mismatch fails the build naming the struct, the shader and the field.
///
/// `push_layout!(ScanParams: [SORT_SCAN_REDUCE, SORT_SCAN_DOWNSWEEP], [len, has_block_offsets]);`
macro_rules! push_layout {
    ($ty:ty: [$($shader:ident),+ $(,)?], $fields:tt) => {
        $($crate::gpu::push_layout!(@shader $ty, $shader, $fields);)+
    };
    (@shader $ty:ty, $shader:ident, [$($field:ident),+ $(,)?]) => {
        const _: () = {
            let shader = &$crate::shaders::$shader;
            assert!(
                size_of::<$ty>() == shader.push_size,
                concat!(stringify!($ty), ": size differs from the push constants of ",
                    stringify!($shader)),
            );
            assert!(
                [$(stringify!($field)),+].len() == shader.push_members.len(),
                concat!(stringify!($ty), ": the fields listed are not the members of ",
                    stringify!($shader)),
            );
            $(assert!(
                shader.push_member_at(stringify!($field), std::mem::offset_of!($ty, $field)),
                concat!(stringify!($ty), ".", stringify!($field),
                    ": no member of that name at that offset in ", stringify!($shader)),
            );)+
        };
    };
}
pub(crate) use push_layout;

#[cfg(test)]
mod tests {
    use crate::shaders::{SORT_RADIX_HISTOGRAM, SORT_SCAN_DOWNSWEEP};

    #[test]
    fn reflection_reads_push_layout_and_bindings() {
        assert_eq!(SORT_SCAN_DOWNSWEEP.path, "sort/scan_downsweep.comp");
        assert_eq!(SORT_SCAN_DOWNSWEEP.push_size, 8);
        assert_eq!(SORT_SCAN_DOWNSWEEP.push_members, [("len", 0), ("has_block_offsets", 4)]);
        assert_eq!(SORT_SCAN_DOWNSWEEP.bindings, [("data", 0), ("block_offsets", 1)]);
        // Two blocks alias binding 0: both names are known, the layout has it once.
        assert_eq!(
            SORT_RADIX_HISTOGRAM.bindings,
            [("key_vectors", 0), ("key_words", 0), ("tile_counts", 1)]
        );
        assert_eq!(SORT_RADIX_HISTOGRAM.binding_numbers(), [0, 1]);
    }

    #[test]
    fn push_member_check_refuses_wrong_offset_or_name() {
        assert!(SORT_SCAN_DOWNSWEEP.push_member_at("has_block_offsets", 4));
        assert!(!SORT_SCAN_DOWNSWEEP.push_member_at("has_block_offsets", 0));
        assert!(!SORT_SCAN_DOWNSWEEP.push_member_at("length", 0));
    }

    #[test]
    fn bindings_resolve_by_name_in_any_order() {
        let slots = SORT_SCAN_DOWNSWEEP.binding_slots(&["block_offsets", "data"]);
        assert_eq!(slots, Ok(vec![1, 0]));
        assert_eq!(
            SORT_RADIX_HISTOGRAM.binding_slots(&["key_words", "tile_counts"]),
            Ok(vec![0, 1])
        );
    }

    #[test]
    fn binding_mismatch_names_shader_and_binding() {
        let unknown = SORT_SCAN_DOWNSWEEP.binding_slots(&["data", "offsets"]).unwrap_err();
        assert!(unknown.contains("sort/scan_downsweep.comp") && unknown.contains("\"offsets\""));
        let missing = SORT_SCAN_DOWNSWEEP.binding_slots(&["data"]).unwrap_err();
        assert!(missing.contains("binding 1 [\"block_offsets\"] given 0 times"), "{missing}");
        let aliased = SORT_RADIX_HISTOGRAM.binding_slots(&["key_words", "key_vectors"]);
        assert!(aliased.unwrap_err().contains("binding 0"));
    }
}
