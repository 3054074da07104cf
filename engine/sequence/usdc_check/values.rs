//! The walk of a crate file's values as openusd reads them (its `CrateFile::value`): every
//! offset, count and nested value checked against the file, and the bytes openusd materialises
//! for each value summed, however values share their data.

use super::ints::{coded_block, coded_size, decode_ints};
use super::{charge, le_u64, within};
use super::{ITEM, MAX_DEPTH, PAYLOAD};
use crate::sequence::gltf::accessor::Budget;
use std::collections::HashMap;

/// How openusd reads an array value's elements.
#[derive(Clone, Copy)]
enum Array {
    /// Elements of this many bytes, never compressed.
    Plain(u64),
    /// Integers of this many bytes, compressed from crate version 0.5.0.
    Ints(u64),
    /// Floating-point values of this many bytes, compressed from crate version 0.6.0.
    Floats(u64),
    /// Token indices (4 bytes), each becoming a token's text.
    Tokens,
    /// A count and string indices (strings, asset paths, path expressions).
    Strings,
}

/// The bytes of one element of the gf types 13 to 30: Matrix2d, 3d, 4d, Quatd, f, h, then
/// Vec2d, f, h, i, Vec3 and Vec4 likewise.
const GF_BYTES: [u64; 18] = [32, 72, 128, 32, 16, 8, 16, 8, 4, 8, 24, 12, 6, 12, 32, 16, 8, 16];

/// How a value of crate type `ty` with the array bit is read, if that type has an array form.
fn array_kind(ty: u64) -> Option<Array> {
    Some(match ty {
        1 | 2 => Array::Plain(1),
        3 | 4 => Array::Ints(4),
        5 | 6 => Array::Ints(8),
        7 => Array::Floats(2),
        8 => Array::Floats(4),
        9 | 56 => Array::Floats(8),
        10 | 12 | 57 => Array::Strings,
        11 => Array::Tokens,
        13..=30 => Array::Plain(GF_BYTES[ty as usize - 13]),
        _ => return None,
    })
}

/// The tables of a crate file that values index: openusd looks the indices up unchecked.
#[derive(Clone, Copy)]
pub struct Tables {
    pub tokens: u64,
    pub strings: u64,
    pub paths: u64,
    pub longest_token: u64,
    pub longest_path: u64,
}

#[derive(Clone, Copy)]
enum Table {
    Tokens,
    Strings,
    Paths,
}

impl Tables {
    fn size(&self, table: Table) -> u64 {
        match table {
            Table::Tokens => self.tokens,
            Table::Strings => self.strings,
            Table::Paths => self.paths,
        }
    }

    /// The longest text an index into `table` names (a string is a token's text).
    fn longest(&self, table: Table) -> u64 {
        match table {
            Table::Paths => self.longest_path,
            Table::Tokens | Table::Strings => self.longest_token,
        }
    }
}

/// What a list op's items are.
#[derive(Clone, Copy)]
enum Item {
    /// Indices into a table.
    Indexed(Table),
    /// Integers of this many bytes.
    Pod(u64),
    Reference,
    Payload,
}

/// The fields' values walked as openusd reads them, each value rep once.
pub struct Values<'a> {
    file: &'a [u8],
    version: u32,
    tables: Tables,
    /// The expanded size of each value rep walked, and how many levels its values nest below it.
    sizes: HashMap<u64, (u64, u32)>,
    /// The deepest level reached below the value being walked.
    deepest: u32,
    /// Walk steps left: one per file byte, so that overlapping values cannot make it quadratic.
    steps: u64,
}

impl<'a> Values<'a> {
    /// A walk of the values of `file` (crate version `version`, 0xMMmmpp) indexing `tables`.
    pub fn new(file: &'a [u8], version: u32, tables: Tables) -> Self {
        let steps = file.len() as u64;
        Values { file, version, tables, sizes: HashMap::new(), deepest: 0, steps }
    }

    /// Walks every field's value, charging the largest to `budget` (openusd holds one at a
    /// time beside its tables).
    pub fn check(
        &mut self,
        fields: &[(u32, u64)],
        tokens: &[String],
        budget: &Budget,
    ) -> Result<(), String> {
        let name = |k: usize| {
            let token = tokens.get(fields[k].0 as usize).map_or("?", String::as_str);
            format!("field {k} ({token})")
        };
        let mut largest = (0, 0);
        for (k, &(_, rep)) in fields.iter().enumerate() {
            let size = self.size(rep, 0).map_err(|e| format!("{}: {e}", name(k)))?;
            largest = largest.max((size, k));
        }
        charge(budget, Some(largest.0), || {
            format!("the value of {}, {} bytes,", name(largest.1), largest.0)
        })
    }

    /// The bytes openusd materialises reading value `rep` (rounded up), `depth` levels down.
    /// A value met again is not walked again, but its nesting still counts from the new depth.
    fn size(&mut self, rep: u64, depth: u32) -> Result<u64, String> {
        if let Some(&(size, height)) = self.sizes.get(&rep) {
            self.reach(depth + height)?;
            return Ok(size);
        }
        self.reach(depth)?;
        self.step()?;
        let outer = std::mem::replace(&mut self.deepest, depth);
        let size = self.expand(rep, depth)?;
        self.sizes.insert(rep, (size, self.deepest - depth));
        self.deepest = self.deepest.max(outer);
        Ok(size)
    }

    /// Notes that values nest down to `depth`, refusing more than [`MAX_DEPTH`].
    fn reach(&mut self, depth: u32) -> Result<(), String> {
        if depth > MAX_DEPTH {
            return Err(format!("values nest more than {MAX_DEPTH} deep"));
        }
        self.deepest = self.deepest.max(depth);
        Ok(())
    }

    fn step(&mut self) -> Result<(), String> {
        self.steps_of(1)
    }

    fn steps_of(&mut self, steps: u64) -> Result<(), String> {
        self.steps = self
            .steps
            .checked_sub(steps)
            .ok_or("walking the values takes more steps than the file has bytes (they overlap)")?;
        Ok(())
    }

    /// Checks the u32 indices of `count` records of `stride` bytes from `at`, one per table of
    /// `tables` at the start of each record.
    fn indices(
        &mut self,
        at: u64,
        count: u64,
        stride: u64,
        tables: &[Table],
    ) -> Result<(), String> {
        self.steps_of(count)?;
        for k in 0..count {
            for (j, &table) in tables.iter().enumerate() {
                let field = at + k * stride + 4 * j as u64;
                self.index(self.word(field, 4)?, Some(field), table)?;
            }
        }
        Ok(())
    }

    /// Refuses `index` (read at byte `at`, None: inlined in a rep) past the end of `table`.
    fn index(&self, index: u64, at: Option<u64>, table: Table) -> Result<(), String> {
        let size = self.tables.size(table);
        let name = ["tokens", "strings", "paths"][table as usize];
        let at = at.map_or("inlined".into(), |at| format!("at byte {at}"));
        match index < size {
            true => Ok(()),
            false => Err(format!("index {index} {at} past the {size} {name}")),
        }
    }

    /// Checks the index of a token, string or asset-path scalar, inlined in `rep` or at its
    /// offset (a token's a u64 there).
    fn scalar(&self, rep: u64) -> Result<(), String> {
        let (ty, at, inlined) = (rep >> 48 & 0xFF, rep & PAYLOAD, rep >> 62 & 1 == 1);
        let table = match (ty, inlined) {
            (11 | 53, _) | (12 | 57, true) => Table::Tokens,
            (10 | 12 | 57, _) => Table::Strings,
            _ => return Ok(()),
        };
        match inlined {
            true => self.index(at & u64::from(u32::MAX), None, table),
            false => {
                let width = if ty == 11 || ty == 53 { 8 } else { 4 };
                self.index(self.word(at, width)?, Some(at), table)
            }
        }
    }

    /// Dispatches on the rep's type as openusd's `CrateFile::value` does.
    fn expand(&mut self, rep: u64, depth: u32) -> Result<u64, String> {
        let (ty, at, compressed) = (rep >> 48 & 0xFF, rep & PAYLOAD, rep >> 61 & 1 == 1);
        if let Some(kind) = array_kind(ty).filter(|_| rep >> 63 == 1) {
            return self.array(at, kind, compressed, rep >> 62 & 1 == 1);
        }
        self.scalar(rep)?;
        // Inlined: a scalar in the rep itself, an empty dictionary, or a form openusd refuses
        // (except a payload list op, which it reads at the offset anyway).
        if rep >> 62 & 1 == 1 && ty != 55 {
            return Ok(0);
        }
        within(at, Some(1), self.file.len() as u64, || "a value".into())?;
        let (token, path) = (self.tables.longest_token, self.tables.longest_path);
        Ok(match ty {
            41 => self.indexed(at, Table::Tokens)?.0,
            50 => self.indexed(at, Table::Strings)?.0,
            40 => self.indexed(at, Table::Paths)?.0,
            48 => self.array(at, Array::Floats(8), compressed, false)?,
            32 => self.list_op(at, Item::Indexed(Table::Tokens), depth)?,
            33 | 54 => self.list_op(at, Item::Indexed(Table::Strings), depth)?,
            34 => self.list_op(at, Item::Indexed(Table::Paths), depth)?,
            36 | 38 => self.list_op(at, Item::Pod(4), depth)?,
            37 | 39 => self.list_op(at, Item::Pod(8), depth)?,
            35 => self.list_op(at, Item::Reference, depth)?,
            55 => self.list_op(at, Item::Payload, depth)?,
            47 => self.payloads(at, 1)?.0,
            45 => self.pairs(at, Table::Strings)?.saturating_mul(ITEM + 2 * token),
            46 => self.time_samples(at, depth)?,
            31 => self.dictionary(at, depth)?.0,
            49 => self.counted(at, 16)?.0.saturating_mul(32),
            58 => self.pairs(at, Table::Paths)?.saturating_mul(ITEM + 2 * path),
            // A scalar at its offset: openusd reads a few bytes, and fails cleanly past the end.
            _ => 0,
        })
    }

    /// The little-endian word of `len` bytes (1 to 8) at `at`.
    fn word(&self, at: u64, len: u64) -> Result<u64, String> {
        within(at, Some(len), self.file.len() as u64, || format!("{len} bytes"))?;
        Ok(le_u64(&self.file[at as usize..(at + len) as usize]))
    }

    fn u64_at(&self, at: u64) -> Result<u64, String> {
        self.word(at, 8)
    }

    /// A count (u64) at `at` of elements of `elem` bytes that follow it inside the file; the
    /// count and where the elements end.
    fn counted(&self, at: u64, elem: u64) -> Result<(u64, u64), String> {
        let count = self.u64_at(at)?;
        self.run(at + 8, count, elem)?;
        Ok((count, at + 8 + count * elem))
    }

    /// `count` elements of `elem` bytes at `at`, inside the file; their bytes.
    fn run(&self, at: u64, count: u64, elem: u64) -> Result<u64, String> {
        let what = || format!("{count} elements of {elem} bytes");
        within(at, count.checked_mul(elem), self.file.len() as u64, what)?;
        Ok(count * elem)
    }

    /// Indices (a count, then u32s) into `table`; the size and the end.
    fn indexed(&mut self, at: u64, table: Table) -> Result<(u64, u64), String> {
        let (count, end) = self.counted(at, 4)?;
        self.indices(at + 8, count, 4, &[table])?;
        Ok((count.saturating_mul(4 + ITEM + self.tables.longest(table)), end))
    }

    /// Pairs of indices into `table` (a count, then two u32s each: a variant selection's
    /// names, a relocation's paths); their count.
    fn pairs(&mut self, at: u64, table: Table) -> Result<u64, String> {
        let (count, _) = self.counted(at, 8)?;
        self.indices(at + 8, count, 8, &[table, table])?;
        Ok(count)
    }

    /// An array at `at` (0: empty), its head read as openusd's `unpack_array_len` does: a shape
    /// (u32) before crate version 0.5.0, then the count, a u32 before 0.7.0, else a u64. An
    /// inlined rep, or a compressed one of a kind never compressed, is refused: openusd asserts
    /// against them.
    fn array(
        &mut self,
        at: u64,
        kind: Array,
        compressed: bool,
        inlined: bool,
    ) -> Result<u64, String> {
        if let Array::Strings = kind {
            return Ok(if at == 0 { 0 } else { self.indexed(at, Table::Strings)?.0 });
        }
        if inlined || compressed && matches!(kind, Array::Plain(_) | Array::Tokens) {
            return Err(format!("an array at byte {at} marked inlined or compressed"));
        }
        if at == 0 {
            return Ok(0);
        }
        let start = at + if self.version < 0x500 { 4 } else { 0 };
        let (count, elements) = match self.version < 0x700 {
            true => (self.word(start, 4)?, start + 4),
            false => (self.u64_at(start)?, start + 8),
        };
        // Compressed when the rep says so, the version has it, and there are 4 or more.
        let packed = compressed && count >= 4;
        match kind {
            Array::Ints(width) if packed && self.version >= 0x500 => {
                Ok(self.coded(elements, count, width)?.0)
            }
            Array::Floats(width) if packed && self.version >= 0x600 => {
                self.floats(elements, count, width)
            }
            Array::Tokens => {
                let bytes = self.run(elements, count, 4)?;
                self.indices(elements, count, 4, &[Table::Tokens])?;
                Ok(bytes.saturating_add(count.saturating_mul(ITEM + self.tables.longest_token)))
            }
            Array::Plain(width) | Array::Ints(width) | Array::Floats(width) => {
                Ok(2 * self.run(elements, count, width)?)
            }
            Array::Strings => Ok(0),
        }
    }

    /// `count` coded integers of `width` bytes in a compressed block at `at`: the block, the
    /// buffer openusd decodes from, and the integers (their vector may double once); and the
    /// block decompressed.
    fn coded(&self, at: u64, count: u64, width: u64) -> Result<(u64, Vec<u8>), String> {
        let size = self.u64_at(at)?;
        self.run(at + 8, size, 1)?;
        let block = &self.file[at as usize + 8..(at + 8 + size) as usize];
        let data = coded_block(&format!("a compressed array at byte {at}"), block, count, width)?;
        let bytes = coded_size(count).saturating_add(count.saturating_mul(2 * width));
        Ok((size.saturating_add(bytes), data))
    }

    /// A compressed floating-point array at `at`: a code, `i` for integers, `t` for a lookup
    /// table (a u32 count of values, the values) and coded indices into it, each inside it
    /// (openusd looks them up unchecked).
    fn floats(&self, at: u64, count: u64, width: u64) -> Result<u64, String> {
        let values = count.saturating_mul(width);
        match self.word(at, 1)? as u8 {
            b'i' => Ok(self.coded(at + 1, count, 4)?.0.saturating_add(values)),
            b't' => {
                let entries = self.word(at + 1, 4)?;
                let table = self.run(at + 5, entries, width)?;
                let (bytes, data) = self.coded(at + 5 + table, count, 4)?;
                let what = format!("a compressed array at byte {at}");
                let indices = decode_ints(&what, &data, count)?;
                match indices.iter().map(|&i| u64::from(i as u32)).find(|&i| i >= entries) {
                    Some(i) => Err(format!("{what}: index {i} past its {entries} values")),
                    None => Ok(bytes.saturating_add(values + table)),
                }
            }
            // openusd refuses another code before allocating.
            _ => Ok(0),
        }
    }

    /// A list op at `at`: a header byte whose bits 1 to 6 say which of its six lists follow.
    fn list_op(&mut self, at: u64, item: Item, depth: u32) -> Result<u64, String> {
        let lists = (self.file[at as usize] & 0x7E).count_ones();
        let (mut size, mut end) = (0u64, at + 1);
        for _ in 0..lists {
            let (bytes, next) = match item {
                Item::Indexed(table) => self.indexed(end, table)?,
                Item::Pod(width) => self.counted(end, width).map(|(n, e)| (2 * n * width, e))?,
                Item::Payload => {
                    let count = self.u64_at(end)?;
                    self.payloads(end + 8, count)?
                }
                Item::Reference => self.references(end, depth)?,
            };
            (size, end) = (size.saturating_add(bytes), next);
        }
        Ok(size)
    }

    /// `count` payloads at `at`, each a string and a path index, and a layer offset from crate
    /// version 0.8.0; their size and where they end.
    fn payloads(&mut self, at: u64, count: u64) -> Result<(u64, u64), String> {
        let width = if self.version >= 0x800 { 24 } else { 8 };
        let bytes = self.run(at, count, width)?;
        self.indices(at, count, width, &[Table::Strings, Table::Paths])?;
        let text = self.tables.longest_token + self.tables.longest_path;
        Ok((count.saturating_mul(ITEM + text), at + bytes))
    }

    /// A list of references at `at`: a count, then each one's string and path indices, layer
    /// offset (24 bytes in all) and a dictionary of custom data; the size and the end.
    fn references(&mut self, at: u64, depth: u32) -> Result<(u64, u64), String> {
        let (count, _) = self.counted(at, 32)?;
        let text = self.tables.longest_token + self.tables.longest_path;
        let mut size = count.saturating_mul(ITEM + text);
        let mut end = at + 8;
        for _ in 0..count {
            self.indices(end, 1, 8, &[Table::Strings, Table::Paths])?;
            let (data, next) = self.dictionary(end + 24, depth)?;
            (size, end) = (size.saturating_add(data), next);
        }
        Ok((size, end))
    }

    /// Where the offset at `at` leads (openusd's recursive offsets count from the offset
    /// itself): forward, past the offset, so that no walk loops.
    fn forward(&self, at: u64) -> Result<u64, String> {
        let offset = self.u64_at(at)? as i64;
        let to = u64::try_from(offset).ok().filter(|&o| o >= 8).and_then(|o| at.checked_add(o));
        match to.filter(|&to| to < self.file.len() as u64) {
            Some(to) => Ok(to),
            None => Err(format!(
                "an offset of {offset} at byte {at} does not point forward inside the file"
            )),
        }
    }

    /// Time samples at `at`: an offset to the times' value rep, and after it an offset to the
    /// count of samples and their value reps.
    fn time_samples(&mut self, at: u64, depth: u32) -> Result<u64, String> {
        let times = self.forward(at)?;
        let mut size = self.size(self.u64_at(times)?, depth + 1)?;
        let values = self.forward(times + 8)?;
        let (count, _) = self.counted(values, 8)?;
        for k in 0..count {
            self.step()?;
            let sample = self.size(self.u64_at(values + 8 + 8 * k)?, depth + 1)?;
            size = size.saturating_add(ITEM).saturating_add(sample);
        }
        Ok(size)
    }

    /// A dictionary at `at`: a count, then per entry a key (a u32 string index) and an offset
    /// to its value rep, which the next entry follows; the size and the end.
    fn dictionary(&mut self, at: u64, depth: u32) -> Result<(u64, u64), String> {
        // An entry takes 20 bytes at least.
        let (count, _) = self.counted(at, 20)?;
        let (mut size, mut end) = (0u64, at + 8);
        for _ in 0..count {
            self.indices(end, 1, 4, &[Table::Strings])?;
            let rep = self.forward(end + 4)?;
            let value = self.size(self.u64_at(rep)?, depth + 1)?;
            size = size.saturating_add(ITEM + self.tables.longest_token).saturating_add(value);
            end = rep + 8;
        }
        Ok((size, end))
    }
}
