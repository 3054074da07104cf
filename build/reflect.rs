//! Reflection of compiled SPIR-V: the interface a kernel's Rust side must match.
//!
//! The contract between a shader and the Rust code that dispatches it has two halves, and this
//! module reads both from the module glslang produced (compiled with debug info, so names
//! survive optimisation):
//! - the push-constant block: its size and each top-level member's name and byte offset. Rust
//!   push-constant structs assert, at compile time, that their size and field offsets equal
//!   these (`push_layout!` in engine/gpu/shader.rs), so a drifted struct fails `cargo build`;
//! - the storage buffers of descriptor set 0: each binding's number and name, the name being the
//!   block's member (`buffer KeysIn { uint keys_in[]; }` is `keys_in`). Aliases (several blocks
//!   at one binding) give one entry each. Pipelines size their descriptor layout from these, and
//!   dispatches pass buffers by these names (engine/gpu/pipeline.rs).
//!
//! Only what the engine's kernels use is understood; anything else in an interface (another
//! descriptor set, a non-block buffer, a type whose size is unknown) is an error, so the build
//! fails rather than emitting a contract that is silently wrong.

use std::collections::HashMap;

/// What a shader's Rust side must agree with.
#[derive(Debug, Default)]
pub struct Interface {
    /// Bytes of the push-constant block (end of its last member); 0 without one.
    pub push_size: u32,
    /// Top-level push-constant members: name and byte offset, in declaration order.
    pub push_members: Vec<(String, u32)>,
    /// Storage buffers of set 0: name and binding, sorted by binding.
    pub bindings: Vec<(String, u32)>,
}

const OP_MEMBER_NAME: u32 = 6;
const OP_TYPE_BOOL: u32 = 20;
const OP_TYPE_INT: u32 = 21;
const OP_TYPE_FLOAT: u32 = 22;
const OP_TYPE_VECTOR: u32 = 23;
const OP_TYPE_MATRIX: u32 = 24;
const OP_TYPE_ARRAY: u32 = 28;
const OP_TYPE_STRUCT: u32 = 30;
const OP_TYPE_POINTER: u32 = 32;
const OP_CONSTANT: u32 = 43;
const OP_VARIABLE: u32 = 59;
const OP_DECORATE: u32 = 71;
const OP_MEMBER_DECORATE: u32 = 72;

const DECORATION_ARRAY_STRIDE: u32 = 6;
const DECORATION_MATRIX_STRIDE: u32 = 7;
const DECORATION_BINDING: u32 = 33;
const DECORATION_DESCRIPTOR_SET: u32 = 34;
const DECORATION_OFFSET: u32 = 35;

const STORAGE_UNIFORM_CONSTANT: u32 = 0;
const STORAGE_UNIFORM: u32 = 2;
const STORAGE_PUSH_CONSTANT: u32 = 9;
const STORAGE_STORAGE_BUFFER: u32 = 12;

/// The facts of one module that the interface is computed from, indexed by result id.
#[derive(Default)]
struct Module {
    member_names: HashMap<(u32, u32), String>,
    /// Every instruction declaring a type, by result id: opcode and operands after the id.
    types: HashMap<u32, (u32, Vec<u32>)>,
    /// OpConstant values (32-bit), for array lengths.
    constants: HashMap<u32, u32>,
    decorations: HashMap<(u32, u32), u32>,
    member_offsets: HashMap<(u32, u32), u32>,
    matrix_strides: HashMap<(u32, u32), u32>,
    /// Global variables: id, pointer type, storage class.
    variables: Vec<(u32, u32, u32)>,
}

/// Reads the interface of `spirv` (a whole module, little-endian words).
pub fn reflect(spirv: &[u8]) -> Result<Interface, String> {
    let module = Module::parse(spirv)?;
    let mut interface = Interface::default();
    for &(variable, pointer, storage) in &module.variables {
        let pointee = *module.operands(pointer)?.get(1).ok_or("short OpTypePointer")?;
        match storage {
            STORAGE_PUSH_CONSTANT => {
                interface.push_size = module.size_of(pointee)?;
                interface.push_members = module.members(pointee)?;
            }
            STORAGE_STORAGE_BUFFER => {
                let set = module.decorations.get(&(variable, DECORATION_DESCRIPTOR_SET));
                let binding = module.decorations.get(&(variable, DECORATION_BINDING));
                let (Some(0), Some(&binding)) = (set, binding) else {
                    return Err(format!("buffer %{variable} is not in descriptor set 0"));
                };
                let name = module.member_name(pointee, 0)?;
                interface.bindings.push((name, binding));
            }
            // Pipelines bind storage buffers only.
            STORAGE_UNIFORM | STORAGE_UNIFORM_CONSTANT => {
                return Err(format!("%{variable}: uniform buffers and images are not supported"));
            }
            _ => {}
        }
    }
    interface.bindings.sort_by_key(|&(_, binding)| binding);
    Ok(interface)
}

impl Module {
    fn parse(spirv: &[u8]) -> Result<Self, String> {
        if !spirv.len().is_multiple_of(4) || spirv.len() < 20 {
            return Err("SPIR-V is not a whole number of words".into());
        }
        let words: Vec<u32> =
            spirv.chunks_exact(4).map(|w| u32::from_le_bytes(w.try_into().unwrap())).collect();
        if words[0] != 0x0723_0203 {
            return Err("not little-endian SPIR-V".into());
        }
        let mut module = Self::default();
        let mut at = 5;
        while at < words.len() {
            let count = (words[at] >> 16) as usize;
            if count == 0 || at + count > words.len() {
                return Err(format!("truncated instruction at word {at}"));
            }
            module.add(words[at] & 0xffff, &words[at + 1..at + count]);
            at += count;
        }
        Ok(module)
    }

    /// Records one instruction (`opcode`, its operand words) if the interface needs it.
    fn add(&mut self, opcode: u32, ops: &[u32]) {
        match (opcode, ops) {
            (OP_MEMBER_NAME, [ty, member, name @ ..]) => {
                self.member_names.insert((*ty, *member), string(name));
            }
            (OP_TYPE_BOOL..=OP_TYPE_POINTER, [id, rest @ ..]) => {
                self.types.insert(*id, (opcode, rest.to_vec()));
            }
            (OP_CONSTANT, [_, id, value, ..]) => {
                self.constants.insert(*id, *value);
            }
            (OP_VARIABLE, [pointer, id, storage, ..]) => {
                self.variables.push((*id, *pointer, *storage))
            }
            (OP_DECORATE, [id, decoration, value, ..]) => {
                self.decorations.insert((*id, *decoration), *value);
            }
            (OP_MEMBER_DECORATE, [ty, member, DECORATION_OFFSET, offset, ..]) => {
                self.member_offsets.insert((*ty, *member), *offset);
            }
            (OP_MEMBER_DECORATE, [ty, member, DECORATION_MATRIX_STRIDE, stride, ..]) => {
                self.matrix_strides.insert((*ty, *member), *stride);
            }
            // Everything else, OpName included: the interface names members, not variables.
            _ => {}
        }
    }

    fn operands(&self, id: u32) -> Result<&[u32], String> {
        self.types.get(&id).map(|(_, ops)| ops.as_slice()).ok_or(format!("%{id} is not a type"))
    }

    fn member_name(&self, ty: u32, member: u32) -> Result<String, String> {
        match self.member_names.get(&(ty, member)) {
            Some(name) if !name.is_empty() => Ok(name.clone()),
            _ => Err(format!("struct %{ty} member {member} has no name (no debug info?)")),
        }
    }

    /// A struct's top-level members: name and offset.
    fn members(&self, ty: u32) -> Result<Vec<(String, u32)>, String> {
        (0..self.operands(ty)?.len() as u32)
            .map(|m| Ok((self.member_name(ty, m)?, self.offset(ty, m)?)))
            .collect()
    }

    fn offset(&self, ty: u32, member: u32) -> Result<u32, String> {
        self.member_offsets
            .get(&(ty, member))
            .copied()
            .ok_or(format!("struct %{ty} member {member} has no Offset"))
    }

    /// Bytes a value of type `ty` spans in an explicitly laid-out block; a struct ends at the
    /// end of its last member (its trailing padding is not part of what the shader reads).
    fn size_of(&self, ty: u32) -> Result<u32, String> {
        let (opcode, ops) = self.types.get(&ty).ok_or(format!("%{ty} is not a type"))?;
        let stride = |d| self.decorations.get(&(ty, d)).copied().ok_or(format!("%{ty}: no stride"));
        match (*opcode, ops.as_slice()) {
            (OP_TYPE_INT | OP_TYPE_FLOAT, [width, ..]) => Ok(width / 8),
            (OP_TYPE_VECTOR, [component, count]) => Ok(self.size_of(*component)? * count),
            (OP_TYPE_ARRAY, [_, length]) => {
                let length = self.constants.get(length).ok_or("array length not a constant")?;
                Ok(stride(DECORATION_ARRAY_STRIDE)? * length)
            }
            (OP_TYPE_STRUCT, members) => {
                let mut end = 0;
                for (m, &member_ty) in members.iter().enumerate() {
                    let start = self.offset(ty, m as u32)?;
                    end = end.max(start + self.member_size(ty, m as u32, member_ty)?);
                }
                Ok(end)
            }
            _ => Err(format!("%{ty}: unsupported type (opcode {opcode}) in a block")),
        }
    }

    /// Like [`Self::size_of`] for member `member` of struct `parent`, whose decorations give a
    /// matrix its column stride.
    fn member_size(&self, parent: u32, member: u32, ty: u32) -> Result<u32, String> {
        match self.types.get(&ty) {
            Some((OP_TYPE_MATRIX, ops)) => {
                let stride = self.matrix_strides.get(&(parent, member)).ok_or("no MatrixStride")?;
                Ok(stride * ops[1])
            }
            _ => self.size_of(ty),
        }
    }
}

/// A SPIR-V literal string: UTF-8, nul-terminated, packed little-endian into words.
fn string(words: &[u32]) -> String {
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
    let end = bytes.iter().position(|&b| b == 0).unwrap_or(bytes.len());
    String::from_utf8_lossy(&bytes[..end]).into_owned()
}
