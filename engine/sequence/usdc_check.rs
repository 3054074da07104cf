//! A structural check of a binary USD layer (a crate file, `PXR-USDC`) before openusd 0.6
//! parses it. openusd trusts the counts and offsets it reads: a damaged or hostile count makes
//! it allocate what the file does not hold (an out-of-memory abort cannot be caught), and a path
//! tree or a dictionary that loops makes it run or recurse for ever. [`CheckedResolver`] runs
//! [`check_layer`] on every layer a stage opens: the root layer, its sublayers, references,
//! payloads and value clips, and the layers inside a `.usdz` (all go through the resolver); a
//! text layer is only held to a nesting depth, since openusd's parser recurses once per level.
//!
//! A layer [`check`] accepts keeps openusd within these bounds:
//! - every section, compressed block, counted run and value lies inside the file, and every
//!   element count openusd allocates for is bounded by the bytes that hold the elements;
//! - what openusd builds on opening the layer (tokens, strings, fields, fieldsets, the paths'
//!   text, specs, and the buffers they are decompressed into) and the largest single value
//!   (expanded through time samples, dictionaries and list ops, however they share data)
//!   together take at most [`PER_FILE_BYTE`] bytes per file byte (8 MiB at least), in openusd's
//!   in-memory sizes rounded up; an LZ4 block decodes to at most what openusd allocates for it;
//! - the path tree reaches each of its entries once, values nest at most [`MAX_DEPTH`] deep and
//!   their offsets point forward, and walking every value takes one step per file byte at most.
//!
//! Not covered: the rest of a text layer (`.usda`: openusd's parser allocates by the text it has
//! read, not by counts), the zip container of a `.usdz` (the zip crate inflates a deflated entry to whatever
//! it holds), and what the reader builds from the values it samples (frames × points).

mod lz4;
mod nesting;

use super::gltf::accessor::Budget;
use openusd::ar::{Asset, AssetInfo, DefaultResolver, ResolvedPath, Resolver};
use openusd::usdc::MAGIC;
use std::collections::HashMap;
use std::io;
use std::time::SystemTime;

/// Bytes openusd may hold per byte of a crate file (beyond the budget's 8 MiB floor): the
/// allowance every reader keeps (tests/fuzz.rs holds them to it).
pub const PER_FILE_BYTE: usize = 64;
/// The deepest nesting of values accepted (dictionaries in dictionaries, time samples of
/// them): openusd recurses once per level.
pub const MAX_DEPTH: u32 = 32;
/// The deepest nesting of braces, brackets and parentheses a text layer may have: far above a
/// scene's (about one level per prim), far below the thousands at which openusd's parser
/// overflows an 8 MiB stack (it needs under 3 KiB a level, so 512 fit a thread's 2 MiB).
pub const MAX_TEXT_DEPTH: usize = 512;
/// What one element of a collection openusd builds may take beside its text: a `String`, path
/// or token (24 bytes), a `Value`, a hash-table slot.
const ITEM: u64 = 128;
/// The bits of a value rep that hold its offset (or its inlined value).
const PAYLOAD: u64 = (1 << 48) - 1;

/// openusd's file-system resolver, with every crate layer checked before openusd parses it.
#[derive(Default)]
pub struct CheckedResolver(DefaultResolver);

impl Resolver for CheckedResolver {
    fn create_identifier(&self, asset_path: &str, anchor: Option<&ResolvedPath>) -> String {
        self.0.create_identifier(asset_path, anchor)
    }

    fn resolve(&self, asset_path: &str) -> Option<ResolvedPath> {
        self.0.resolve(asset_path)
    }

    fn resolve_for_new_asset(&self, asset_path: &str) -> Option<ResolvedPath> {
        self.0.resolve_for_new_asset(asset_path)
    }

    /// The asset's bytes, refused (an `InvalidData` error naming the layer) when
    /// [`check_layer`] refuses them.
    fn open_asset(&self, resolved: &ResolvedPath) -> io::Result<Box<dyn Asset>> {
        let bytes = self.0.open_asset(resolved)?.read_all()?;
        let refused = |e| io::Error::new(io::ErrorKind::InvalidData, format!("{resolved}: {e}"));
        check_layer(&bytes).map_err(refused)?;
        Ok(Box::new(io::Cursor::new(bytes)))
    }

    fn get_extension<'a>(&self, asset_path: &'a str) -> &'a str {
        self.0.get_extension(asset_path)
    }

    fn get_asset_info(&self, asset_path: &str, resolved: &ResolvedPath) -> AssetInfo {
        self.0.get_asset_info(asset_path, resolved)
    }

    fn get_modification_timestamp(
        &self,
        asset_path: &str,
        resolved: &ResolvedPath,
    ) -> Option<SystemTime> {
        self.0.get_modification_timestamp(asset_path, resolved)
    }

    fn identity(&self) -> String {
        self.0.identity()
    }
}

/// Checks a layer's bytes: a crate file by [`check`], a text by its nesting depth (at most
/// [`MAX_TEXT_DEPTH`]). Other bytes pass: openusd reads no text that is not UTF-8.
pub fn check_layer(bytes: &[u8]) -> Result<(), String> {
    if bytes.starts_with(MAGIC) {
        return check(bytes);
    }
    let Ok(text) = std::str::from_utf8(bytes) else { return Ok(()) };
    match nesting::depth(text) {
        depth if depth > MAX_TEXT_DEPTH => Err(format!(
            "text nested {depth} deep, more than {MAX_TEXT_DEPTH} (openusd's parser recurses once per level)"
        )),
        _ => Ok(()),
    }
}

/// Checks the crate file `file` (see the module doc); the error names the section or the value
/// and the problem.
pub fn check(file: &[u8]) -> Result<(), String> {
    let version = version(file)?;
    let sections = sections(file)?;
    let budget = Budget::new(file.len(), PER_FILE_BYTE);
    let section = |name: &str| {
        let s = sections.iter().find(|s| s.name == name)?;
        Some(Cursor { name: format!("section {name}"), file, at: s.start, end: s.end })
    };
    let tokens = section("TOKENS").map_or(Ok(Vec::new()), |c| tokens(c, &budget))?;
    if let Some(mut c) = section("STRINGS") {
        let count = c.u64("the string count")?;
        c.take(count.checked_mul(4), || format!("{count} strings of 4 bytes"))?;
        charge(&budget, count.checked_mul(12), || format!("{}: {count} strings", c.name))?;
    }
    let fields = section("FIELDS").map_or(Ok(Vec::new()), |c| fields(c, &budget))?;
    if let Some(mut c) = section("FIELDSETS") {
        int_table(&mut c, 1, 16, &budget)?;
    }
    let longest_path = section("PATHS").map_or(Ok(0), |c| paths(c, &tokens, &budget))?;
    if let Some(mut c) = section("SPECS") {
        int_table(&mut c, 3, ITEM, &budget)?;
    }
    let longest_token = tokens.iter().map(|t| t.len() as u64).max().unwrap_or(0);
    let mut values = Values {
        file,
        version,
        longest_token,
        longest_path,
        sizes: HashMap::new(),
        steps: file.len() as u64,
    };
    values.check(&fields, &tokens, &budget)
}

/// The crate version (major, minor, patch as 0xMMmmpp), refusing a file too short for its
/// header or older than 0.4.0, whose sections openusd cannot read.
fn version(file: &[u8]) -> Result<u32, String> {
    let Some(&[major, minor, patch]) = file.get(8..11) else {
        return Err(format!("{} bytes: too short for a crate file's header", file.len()));
    };
    if (major, minor) < (0, 4) {
        return Err(format!(
            "crate version {major}.{minor}.{patch}: openusd reads 0.4.0 and later"
        ));
    }
    Ok(u32::from_be_bytes([0, major, minor, patch]))
}

/// One entry of the table of contents: a named byte range of the file.
struct Section {
    name: String,
    start: u64,
    end: u64,
}

/// The table of contents, at the offset the header gives: 1 to 63 sections (openusd refuses
/// others), each inside the file.
fn sections(file: &[u8]) -> Result<Vec<Section>, String> {
    let toc = file.get(16..24).map_or(u64::MAX, le_u64);
    let end = file.len() as u64;
    let mut c = Cursor { name: "the table of contents".into(), file, at: toc, end };
    let count = c.u64("the section count")?;
    if !(1..64).contains(&count) {
        return Err(format!("the table of contents lists {count} sections"));
    }
    (0..count)
        .map(|_| {
            let entry = c.take(Some(32), || "a section entry".into())?;
            let name = entry[..16].split(|&b| b == 0).next().unwrap_or_default();
            let name = String::from_utf8_lossy(name).into_owned();
            let (start, size) = (le_u64(&entry[16..24]), le_u64(&entry[24..32]));
            within(start, Some(size), end, || format!("section {name}: {size} bytes"))?;
            Ok(Section { name, start, end: start + size })
        })
        .collect()
}

/// Charges `bytes` (None: more than a u64 holds) to `budget`, `what` naming them.
fn charge(
    budget: &Budget,
    bytes: Option<u64>,
    what: impl FnOnce() -> String,
) -> Result<(), String> {
    budget.charge(bytes.and_then(|b| usize::try_from(b).ok()), 1, what).map(drop)
}

/// `len` bytes at `at` (None: more than a u64 holds) before `end`, or an error naming `what`.
fn within(
    at: u64,
    len: Option<u64>,
    end: u64,
    what: impl FnOnce() -> String,
) -> Result<(), String> {
    let left = end.saturating_sub(at);
    match len {
        Some(len) if len <= left && at <= end => Ok(()),
        _ => Err(format!("{} at byte {at}, but {left} bytes are left", what())),
    }
}

fn le_u64(bytes: &[u8]) -> u64 {
    bytes.iter().rev().fold(0, |word, &b| word << 8 | u64::from(b))
}

/// A section's bytes read in order, as openusd reads them, each read inside the section.
struct Cursor<'a> {
    /// "section TOKENS", for errors.
    name: String,
    file: &'a [u8],
    at: u64,
    end: u64,
}

impl<'a> Cursor<'a> {
    /// The next `len` bytes (None: more than a u64 holds); `what` names them in the error.
    fn take(
        &mut self,
        len: Option<u64>,
        what: impl FnOnce() -> String,
    ) -> Result<&'a [u8], String> {
        within(self.at, len, self.end, || format!("{}: {}", self.name, what()))?;
        let (start, len) = (self.at as usize, len.unwrap_or_default() as usize);
        self.at += len as u64;
        Ok(&self.file[start..start + len])
    }

    fn u64(&mut self, what: &str) -> Result<u64, String> {
        self.take(Some(8), || what.into()).map(le_u64)
    }

    /// A compressed block: its size, then its bytes.
    fn block(&mut self) -> Result<&'a [u8], String> {
        let size = self.u64("a compressed block's size")?;
        self.take(Some(size), || format!("a compressed block of {size} bytes"))
    }
}

/// The tokens (TOKENS: their count, the size of their text, a compressed block of NUL-ended
/// strings), charging the block, the buffer openusd decompresses it into and the strings.
fn tokens(mut c: Cursor, budget: &Budget) -> Result<Vec<String>, String> {
    c.u64("the token count")?;
    let size = c.u64("the tokens' size")?;
    let block = c.block()?;
    let buffers = size.checked_mul(2).and_then(|b| b.checked_add(block.len() as u64));
    charge(budget, buffers, || format!("{}: {size} bytes of tokens", c.name))?;
    let text = decompress(&c.name, block, size)?;
    let text = text.strip_suffix(&[0]).unwrap_or(&text);
    let tokens: Vec<String> =
        text.split(|&b| b == 0).map(|t| String::from_utf8_lossy(t).into_owned()).collect();
    charge(budget, Some(ITEM * tokens.len() as u64), || format!("{}: the tokens", c.name))?;
    Ok(tokens)
}

/// The fields (FIELDS: a count, a block of token indices, a block of value reps): each field's
/// token index and value rep.
fn fields(mut c: Cursor, budget: &Budget) -> Result<Vec<(u32, u64)>, String> {
    let (count, names) = int_table(&mut c, 1, 16, budget)?;
    let reps = c.block()?;
    let bytes = count.checked_mul(8);
    let buffers = bytes.and_then(|b| b.checked_add(reps.len() as u64));
    charge(budget, buffers, || format!("{}: {count} value reps", c.name))?;
    let names = decode_ints(&c.name, &decompress(&c.name, names[0], coded_size(count))?, count)?;
    let reps = decompress(&c.name, reps, bytes.unwrap_or_default())?;
    Ok(names.iter().zip(reps.chunks_exact(8)).map(|(&n, rep)| (n as u32, le_u64(rep))).collect())
}

/// A count and `blocks` integer blocks of that many integers each (FIELDSETS, SPECS, the
/// encoded paths), charging each block and `item` bytes per entry for what openusd builds.
fn int_table<'a>(
    c: &mut Cursor<'a>,
    blocks: usize,
    item: u64,
    budget: &Budget,
) -> Result<(u64, Vec<&'a [u8]>), String> {
    let count = c.u64("the entry count")?;
    charge(budget, count.checked_mul(item), || format!("{}: {count} entries", c.name))?;
    let blocks = (0..blocks)
        .map(|_| {
            let block = c.block()?;
            // The compressed bytes, the buffer openusd decodes from, and the integers decoded
            // (8 bytes each: openusd's vector may double once).
            let bytes = count.checked_mul(8).and_then(|b| b.checked_add(coded_size(count)));
            let bytes = bytes.and_then(|b| b.checked_add(block.len() as u64));
            charge(budget, bytes, || format!("{}: {count} integers", c.name))?;
            Ok(block)
        })
        .collect::<Result<_, String>>()?;
    Ok((count, blocks))
}

/// The size of openusd's buffer for `count` coded 32-bit integers (its `encoded_buffer_size`):
/// the common value, two bits of code and four bytes per integer. u64::MAX when it overflows.
fn coded_size(count: u64) -> u64 {
    let size = count.checked_mul(4).and_then(|b| b.checked_add(count.div_ceil(4) + 4));
    if count == 0 {
        0
    } else {
        size.unwrap_or(u64::MAX)
    }
}

/// A compressed block as openusd writes it (a chunk count, 0 for one LZ4 block, then the
/// block), decoded into at most `capacity` bytes (already charged).
fn decompress(section: &str, block: &[u8], capacity: u64) -> Result<Vec<u8>, String> {
    let capacity = usize::try_from(capacity).unwrap_or(usize::MAX);
    match block.split_first() {
        Some((0, lz4)) => lz4::decompress(lz4, capacity)
            .map_err(|e| format!("{section}: a compressed block: {e}")),
        Some((chunks, _)) => Err(format!(
            "{section}: a compressed block in {chunks} chunks, which openusd cannot read"
        )),
        None => Err(format!("{section}: an empty compressed block")),
    }
}

/// `count` integers in USD's integer coding: a common delta (i32), two bits of code per
/// integer (0: the common delta; 1, 2, 3: an i8, i16 or i32 delta among the bytes after the
/// codes), each integer the previous one plus its delta (wrapping, as openusd's do).
fn decode_ints(section: &str, data: &[u8], count: u64) -> Result<Vec<i32>, String> {
    let short = || format!("{section}: {count} coded integers in {} bytes", data.len());
    if count == 0 {
        return Ok(Vec::new());
    }
    let codes_end = usize::try_from(count.div_ceil(4) + 4).map_err(|_| short())?;
    let codes = data.get(4..codes_end).ok_or_else(short)?;
    let word = |bytes: &[u8]| bytes.iter().rev().fold(0u32, |w, &b| w << 8 | u32::from(b));
    let common = word(&data[..4]) as i32;
    let mut deltas = &data[codes_end..];
    let mut value = 0i32;
    let mut ints = Vec::with_capacity(codes.len() * 4);
    for k in 0..count as usize {
        let width = [0, 1, 2, 4][usize::from(codes[k / 4] >> (2 * (k % 4)) & 3)];
        let delta = if width == 0 {
            common
        } else {
            let (bytes, rest) = deltas.split_at_checked(width).ok_or_else(short)?;
            deltas = rest;
            // Sign-extended from its width.
            (word(bytes) << (32 - 8 * width)) as i32 >> (32 - 8 * width)
        };
        value = value.wrapping_add(delta);
        ints.push(value);
    }
    Ok(ints)
}

/// The paths (PATHS: the number of paths, then a table of three blocks: each entry's path
/// index, token (negative for a property) and jump): charges the paths' text (three times:
/// openusd's paths, the parents its walk keeps, the specs' copies) and gives the longest.
fn paths(mut c: Cursor, tokens: &[String], budget: &Budget) -> Result<u64, String> {
    let slots = c.u64("the path count")?;
    charge(budget, slots.checked_mul(24), || format!("{}: {slots} paths", c.name))?;
    let (count, blocks) = int_table(&mut c, 3, 0, budget)?;
    let decoded = blocks
        .iter()
        .map(|block| decode_ints(&c.name, &decompress(&c.name, block, coded_size(count))?, count))
        .collect::<Result<Vec<_>, _>>()?;
    let lengths =
        path_lengths(&c.name, tokens, slots as usize, [&decoded[0], &decoded[1], &decoded[2]])?;
    let text = lengths.iter().sum::<u64>();
    charge(budget, text.checked_mul(3), || format!("{}: {text} bytes of path text", c.name))?;
    Ok(lengths.into_iter().max().unwrap_or(0))
}

/// Walks the path tree as openusd builds it (an entry's child is the entry after it when its
/// jump is positive or -1; its next sibling is `jump` entries on when the jump is 0 or more),
/// giving each path an upper bound of its text's length: its parent's, a separator and its
/// token. Refuses an entry reached twice (a tree that loops), and indices out of range.
fn path_lengths(
    section: &str,
    tokens: &[String],
    slots: usize,
    [index, element, jumps]: [&[i32]; 3],
) -> Result<Vec<u64>, String> {
    let mut lengths = vec![0u64; slots];
    let mut reached = vec![false; index.len()];
    let mut pending = if index.is_empty() { Vec::new() } else { vec![(0, None)] };
    while let Some((mut entry, mut parent)) = pending.pop() {
        loop {
            match reached.get(entry) {
                Some(false) => reached[entry] = true,
                Some(true) => return Err(format!("{section}: entry {entry} is reached twice")),
                None => {
                    return Err(format!(
                        "{section}: the tree runs past its {} entries",
                        index.len()
                    ))
                }
            }
            let slot = index[entry] as u32 as usize;
            let token = element[entry].unsigned_abs() as usize;
            let length = match (parent, tokens.get(token)) {
                (None, _) => 1,
                (Some(parent), Some(token)) => parent + 1 + token.len() as u64,
                (Some(_), None) => {
                    return Err(format!(
                        "{section}: entry {entry} names token {token} of {}",
                        tokens.len()
                    ))
                }
            };
            *lengths.get_mut(slot).ok_or_else(|| {
                format!("{section}: entry {entry} names path {slot} of {slots}")
            })? = length;
            let jump = jumps[entry];
            let (child, sibling) = (jump > 0 || jump == -1, jump >= 0);
            if child && sibling {
                pending.push((entry + jump as usize, parent));
            }
            if !child && !sibling {
                break;
            }
            if child {
                parent = Some(length);
            }
            entry += 1;
        }
    }
    Ok(lengths)
}

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

/// What a list op's items are.
#[derive(Clone, Copy)]
enum Item {
    /// String, token or path indices; the longest text they may name.
    Indexed(u64),
    /// Integers of this many bytes.
    Pod(u64),
    Reference,
    Payload,
}

/// The fields' values walked as openusd reads them, each value rep once.
struct Values<'a> {
    file: &'a [u8],
    version: u32,
    longest_token: u64,
    longest_path: u64,
    /// The expanded size of each value rep walked.
    sizes: HashMap<u64, u64>,
    /// Walk steps left: one per file byte, so that overlapping values cannot make it quadratic.
    steps: u64,
}

impl Values<'_> {
    /// Walks every field's value, charging the largest to `budget` (openusd holds one at a
    /// time beside its tables).
    fn check(
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
    fn size(&mut self, rep: u64, depth: u32) -> Result<u64, String> {
        if let Some(&size) = self.sizes.get(&rep) {
            return Ok(size);
        }
        if depth > MAX_DEPTH {
            return Err(format!("values nest more than {MAX_DEPTH} deep"));
        }
        self.step()?;
        let size = self.expand(rep, depth)?;
        self.sizes.insert(rep, size);
        Ok(size)
    }

    fn step(&mut self) -> Result<(), String> {
        self.steps = self
            .steps
            .checked_sub(1)
            .ok_or("walking the values takes more steps than the file has bytes (they overlap)")?;
        Ok(())
    }

    /// Dispatches on the rep's type as openusd's `CrateFile::value` does.
    fn expand(&mut self, rep: u64, depth: u32) -> Result<u64, String> {
        let (ty, at, compressed) = (rep >> 48 & 0xFF, rep & PAYLOAD, rep >> 61 & 1 == 1);
        if let Some(kind) = array_kind(ty).filter(|_| rep >> 63 == 1) {
            return self.array(at, kind, compressed);
        }
        // Inlined: a scalar in the rep itself, an empty dictionary, or a form openusd refuses
        // (except a payload list op, which it reads at the offset anyway).
        if rep >> 62 & 1 == 1 && ty != 55 {
            return Ok(0);
        }
        within(at, Some(1), self.file.len() as u64, || "a value".into())?;
        let (token, path) = (self.longest_token, self.longest_path);
        Ok(match ty {
            41 | 50 => self.indexed(at, token)?.0,
            40 => self.indexed(at, path)?.0,
            48 => self.array(at, Array::Floats(8), compressed)?,
            32 | 33 | 54 => self.list_op(at, Item::Indexed(token), depth)?,
            34 => self.list_op(at, Item::Indexed(path), depth)?,
            36 | 38 => self.list_op(at, Item::Pod(4), depth)?,
            37 | 39 => self.list_op(at, Item::Pod(8), depth)?,
            35 => self.list_op(at, Item::Reference, depth)?,
            55 => self.list_op(at, Item::Payload, depth)?,
            45 => self.counted(at, 8)?.0.saturating_mul(ITEM + 2 * token),
            46 => self.time_samples(at, depth)?,
            31 => self.dictionary(at, depth)?.0,
            49 => self.counted(at, 16)?.0.saturating_mul(32),
            58 => self.counted(at, 8)?.0.saturating_mul(ITEM + 2 * path),
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

    /// Indices (a count, then u32s) into text of at most `longest` bytes; the size and the end.
    fn indexed(&self, at: u64, longest: u64) -> Result<(u64, u64), String> {
        let (count, end) = self.counted(at, 4)?;
        Ok((count.saturating_mul(4 + ITEM + longest), end))
    }

    /// An array at `at` (0: empty), its head read as openusd's `unpack_array_len` does: a shape
    /// (u32) before crate version 0.5.0, then the count, a u32 before 0.7.0, else a u64.
    fn array(&mut self, at: u64, kind: Array, compressed: bool) -> Result<u64, String> {
        if at == 0 {
            return Ok(0);
        }
        if let Array::Strings = kind {
            return Ok(self.indexed(at, self.longest_token)?.0);
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
                self.coded(elements, count, width)
            }
            Array::Floats(width) if packed && self.version >= 0x600 => {
                self.floats(elements, count, width)
            }
            Array::Tokens => Ok(self
                .run(elements, count, 4)?
                .saturating_add(count.saturating_mul(ITEM + self.longest_token))),
            Array::Plain(width) | Array::Ints(width) | Array::Floats(width) => {
                Ok(2 * self.run(elements, count, width)?)
            }
            Array::Strings => Ok(0),
        }
    }

    /// `count` coded integers of `width` bytes in a compressed block at `at`: the block, the
    /// buffer openusd decodes from, and the integers (their vector may double once).
    fn coded(&self, at: u64, count: u64, width: u64) -> Result<u64, String> {
        let block = self.u64_at(at)?;
        self.run(at + 8, block, 1)?;
        Ok(block.saturating_add(coded_size(count)).saturating_add(count.saturating_mul(2 * width)))
    }

    /// A compressed floating-point array at `at`: a code, `i` for integers, `t` for a lookup
    /// table (a u32 count of values, the values) and coded indices into it.
    fn floats(&self, at: u64, count: u64, width: u64) -> Result<u64, String> {
        let values = count.saturating_mul(width);
        match self.word(at, 1)? as u8 {
            b'i' => Ok(self.coded(at + 1, count, 4)?.saturating_add(values)),
            b't' => {
                let table = self.run(at + 5, self.word(at + 1, 4)?, width)?;
                Ok(self.coded(at + 5 + table, count, 4)?.saturating_add(values + table))
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
                Item::Indexed(longest) => self.indexed(end, longest)?,
                Item::Pod(width) => self.counted(end, width).map(|(n, e)| (2 * n * width, e))?,
                Item::Payload => {
                    // A string and a path index, and a layer offset from crate version 0.8.0.
                    let width = if self.version >= 0x800 { 24 } else { 8 };
                    let (count, next) = self.counted(end, width)?;
                    (count.saturating_mul(ITEM + self.longest_token + self.longest_path), next)
                }
                Item::Reference => self.references(end, depth)?,
            };
            (size, end) = (size.saturating_add(bytes), next);
        }
        Ok(size)
    }

    /// A list of references at `at`: a count, then each one's string and path indices, layer
    /// offset (24 bytes in all) and a dictionary of custom data; the size and the end.
    fn references(&mut self, at: u64, depth: u32) -> Result<(u64, u64), String> {
        let (count, _) = self.counted(at, 32)?;
        let mut size = count.saturating_mul(ITEM + self.longest_token + self.longest_path);
        let mut end = at + 8;
        for _ in 0..count {
            self.step()?;
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
            self.step()?;
            let rep = self.forward(end + 4)?;
            let value = self.size(self.u64_at(rep)?, depth + 1)?;
            size = size.saturating_add(ITEM + self.longest_token).saturating_add(value);
            end = rep + 8;
        }
        Ok((size, end))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SEED: &[u8] = include_bytes!("../../tests/fuzz_corpus/usd_sequence/seed-anim.usdc");

    /// `bytes` as a compressed block: its size, one chunk, one LZ4 sequence of literals.
    fn block(bytes: &[u8]) -> Vec<u8> {
        let mut lz4 = vec![0, (bytes.len().min(15) as u8) << 4];
        if bytes.len() >= 15 {
            let rest = bytes.len() - 15;
            lz4.extend(std::iter::repeat_n(255, rest / 255));
            lz4.push((rest % 255) as u8);
        }
        lz4.extend(bytes);
        [(lz4.len() as u64).to_le_bytes().to_vec(), lz4].concat()
    }

    /// `ints` in USD's integer coding, every delta a full i32, as a compressed block.
    fn ints(ints: &[i32]) -> Vec<u8> {
        let mut codes = vec![0u8; ints.len().div_ceil(4)];
        (0..ints.len()).for_each(|k| codes[k / 4] |= 3 << (2 * (k % 4)));
        let deltas = (0..ints.len()).flat_map(|k| {
            let previous = if k == 0 { 0 } else { ints[k - 1] };
            ints[k].wrapping_sub(previous).to_le_bytes()
        });
        block(&[vec![0; 4], codes, deltas.collect()].concat())
    }

    fn words(words: &[u64]) -> Vec<u8> {
        words.iter().flat_map(|w| w.to_le_bytes()).collect()
    }

    /// An int 0 inlined in its rep.
    const INLINE_INT: u64 = 3 << 48 | 1 << 62;
    /// Where a layer's heap starts.
    const HEAP: u64 = 32;

    /// The parts of a small crate file (version 0.8.0).
    struct Layer {
        tokens: Vec<&'static str>,
        /// Field token indices and value reps, all in one fieldset.
        fields: Vec<(i32, u64)>,
        /// Value data, at byte [`HEAP`].
        heap: Vec<u8>,
        /// The paths' count, then their entries' path indices, tokens and jumps.
        paths: (u64, [Vec<i32>; 3]),
    }

    impl Default for Layer {
        /// The paths "/" and "/a", one field `default` holding an inlined int.
        fn default() -> Self {
            Layer {
                tokens: vec!["", "a", "default"],
                fields: vec![(2, INLINE_INT)],
                heap: Vec::new(),
                paths: (2, [vec![0, 1], vec![0, 1], vec![-1, -2]]),
            }
        }
    }

    impl Layer {
        /// The file's sections, in the order openusd reads them.
        fn sections(&self) -> Vec<(&'static str, Vec<u8>)> {
            let text: Vec<u8> =
                self.tokens.iter().flat_map(|t| [t.as_bytes(), b"\0"].concat()).collect();
            let count = |n: usize| (n as u64).to_le_bytes().to_vec();
            let (names, reps): (Vec<i32>, Vec<u64>) = self.fields.iter().copied().unzip();
            let mut fieldset: Vec<i32> = (0..names.len() as i32).collect();
            fieldset.push(-1);
            let (slots, [index, element, jumps]) = &self.paths;
            vec![
                ("TOKENS", [count(self.tokens.len()), count(text.len()), block(&text)].concat()),
                ("STRINGS", count(0)),
                ("FIELDS", [count(names.len()), ints(&names), block(&words(&reps))].concat()),
                ("FIELDSETS", [count(fieldset.len()), ints(&fieldset)].concat()),
                (
                    "PATHS",
                    [words(&[*slots, index.len() as u64]), ints(index), ints(element), ints(jumps)]
                        .concat(),
                ),
                ("SPECS", [count(2), ints(&[0, 1]), ints(&[0, 0]), ints(&[7, 6])].concat()),
            ]
        }

        /// The file: header, heap, sections, table of contents.
        fn build(&self) -> Vec<u8> {
            let mut file = [b"PXR-USDC".as_slice(), &[0, 8, 0, 0, 0, 0, 0, 0], &[0; 16]].concat();
            file.extend(&self.heap);
            let mut toc = words(&[6]);
            for (name, bytes) in self.sections() {
                let mut entry = [0u8; 16];
                entry[..name.len()].copy_from_slice(name.as_bytes());
                toc.extend(
                    [entry.to_vec(), words(&[file.len() as u64, bytes.len() as u64])].concat(),
                );
                file.extend(bytes);
            }
            let at = file.len() as u64;
            file[16..24].copy_from_slice(&at.to_le_bytes());
            file.extend(toc);
            file
        }
    }

    /// The layer `layer` with `edit` applied to the bytes of its section `name`, which may
    /// shorten them (the section then ends earlier) but not lengthen them.
    fn edited(layer: &Layer, name: &str, edit: impl Fn(&mut Vec<u8>)) -> Vec<u8> {
        let mut file = layer.build();
        let toc = le_u64(&file[16..24]) as usize + 8;
        let entry = (0..6).map(|k| toc + 32 * k);
        let entry = entry.clone().find(|&e| file[e..].starts_with(name.as_bytes())).unwrap();
        let (start, size) = (le_u64(&file[entry + 16..]) as usize, le_u64(&file[entry + 24..]));
        let mut bytes = file[start..start + size as usize].to_vec();
        edit(&mut bytes);
        file[start..start + bytes.len()].copy_from_slice(&bytes);
        file[entry + 24..entry + 32].copy_from_slice(&(bytes.len() as u64).to_le_bytes());
        file
    }

    fn refusal(file: &[u8]) -> String {
        check(file).unwrap_err()
    }

    #[test]
    fn the_seed_and_a_small_layer_are_accepted() {
        check(SEED).unwrap();
        check(&Layer::default().build()).unwrap();
    }

    #[test]
    fn a_damaged_header_or_table_of_contents_is_refused() {
        let file = Layer::default().build();
        let toc = le_u64(&file[16..24]);
        let with = |at: usize, bytes: &[u8]| {
            let mut f = file.clone();
            f[at..at + bytes.len()].copy_from_slice(bytes);
            refusal(&f)
        };
        assert_eq!(refusal(MAGIC), "8 bytes: too short for a crate file's header");
        assert_eq!(with(8, &[0, 3, 1]), "crate version 0.3.1: openusd reads 0.4.0 and later");
        assert_eq!(with(16, &u64::MAX.to_le_bytes()),
            "the table of contents: the section count at byte 18446744073709551615, but 0 bytes are left");
        assert_eq!(
            with(toc as usize, &0u64.to_le_bytes()),
            "the table of contents lists 0 sections"
        );
        // The first section's size.
        assert_eq!(
            with(toc as usize + 8 + 24, &u64::MAX.to_le_bytes()),
            "section TOKENS: 18446744073709551615 bytes at byte 32, but 483 bytes are left"
        );
    }

    #[test]
    fn counts_and_blocks_past_their_section_are_refused() {
        let layer = Layer::default();
        let count = |n: u64| move |b: &mut Vec<u8>| b[..8].copy_from_slice(&n.to_le_bytes());
        assert_eq!(
            refusal(&edited(&layer, "STRINGS", count(u32::MAX.into()))),
            "section STRINGS: 4294967295 strings of 4 bytes at byte 77, but 0 bytes are left"
        );
        // FIELDS: the count, then its block of token indices (size, chunk count, LZ4).
        let size = |b: &mut Vec<u8>| b[8..16].copy_from_slice(&1000u64.to_le_bytes());
        assert_eq!(
            refusal(&edited(&layer, "FIELDS", size)),
            "section FIELDS: a compressed block of 1000 bytes at byte 93, but 29 bytes are left"
        );
        let chunks = |b: &mut Vec<u8>| b[16] = 2;
        assert_eq!(
            refusal(&edited(&layer, "FIELDS", chunks)),
            "section FIELDS: a compressed block in 2 chunks, which openusd cannot read"
        );
        let truncated = |b: &mut Vec<u8>| b.truncate(20);
        assert_eq!(
            refusal(&edited(&layer, "FIELDS", truncated)),
            "section FIELDS: a compressed block of 11 bytes at byte 93, but 4 bytes are left"
        );
        // More encoded paths (the second count) than the blocks hold.
        let paths = |b: &mut Vec<u8>| b[8..16].copy_from_slice(&9u64.to_le_bytes());
        assert_eq!(
            refusal(&edited(&layer, "PATHS", paths)),
            "section PATHS: 9 coded integers in 13 bytes"
        );
    }

    #[test]
    fn claims_beyond_the_budget_are_refused_before_openusd_allocates() {
        let layer = Layer::default();
        let at = |offset: usize, n: u64| {
            move |b: &mut Vec<u8>| b[offset..offset + 8].copy_from_slice(&n.to_le_bytes())
        };
        // TOKENS: the count, the text's size.
        assert_eq!(refusal(&edited(&layer, "TOKENS", at(8, 1 << 32))),
            "section TOKENS: 4294967296 bytes of tokens would take more than the 8 MiB this file's size allows");
        // A claimed size smaller than the text: the block decodes to more.
        assert_eq!(
            refusal(&edited(&layer, "TOKENS", at(8, 3))),
            "section TOKENS: a compressed block: it decodes to more than the 3 bytes claimed"
        );
        assert_eq!(refusal(&edited(&layer, "PATHS", at(0, 1 << 40))),
            "section PATHS: 1099511627776 paths would take more than the 8 MiB this file's size allows");
        assert_eq!(refusal(&edited(&layer, "SPECS", at(0, 1 << 40))),
            "section SPECS: 1099511627776 entries would take more than the 8 MiB this file's size allows");
    }

    #[test]
    fn a_path_tree_that_loops_or_names_nothing_is_refused() {
        let tree = |index: [i32; 2], element: [i32; 2], jumps: [i32; 2]| {
            let paths = (2, [index.to_vec(), element.to_vec(), jumps.to_vec()]);
            refusal(&Layer { paths, ..Layer::default() }.build())
        };
        // The root's child and its sibling are both entry 1.
        assert_eq!(tree([0, 1], [0, 1], [1, -2]), "section PATHS: entry 1 is reached twice");
        // The last entry has a child.
        assert_eq!(
            tree([0, 1], [0, 1], [-1, -1]),
            "section PATHS: the tree runs past its 2 entries"
        );
        assert_eq!(tree([0, 5], [0, 1], [-1, -2]), "section PATHS: entry 1 names path 5 of 2");
        assert_eq!(tree([0, 1], [0, -9], [-1, -2]), "section PATHS: entry 1 names token 9 of 3");
    }

    /// The refusal of a layer whose one field has the value `rep` and whose heap is `heap`.
    fn value_refusal(rep: u64, heap: Vec<u8>) -> String {
        refusal(&Layer { fields: vec![(2, rep)], heap, ..Layer::default() }.build())
    }

    #[test]
    fn values_past_the_end_or_looping_are_refused() {
        let at = |ty: u64, array: u64| ty << 48 | array << 63 | HEAP;
        // A Vec3f array of a billion elements.
        assert_eq!(
            value_refusal(at(24, 1), words(&[1_000_000_000])),
            "field 0 (default): 1000000000 elements of 12 bytes at byte 40, but 483 bytes are left"
        );
        assert_eq!(
            value_refusal(24 << 48 | 1 << 63 | 1 << 40, Vec::new()),
            "field 0 (default): 8 bytes at byte 1099511627776, but 0 bytes are left"
        );
        // A dictionary of one entry whose value offset points back at its own key.
        let backwards = [words(&[1]), vec![0; 4], words(&[-12i64 as u64])].concat();
        assert_eq!(
            value_refusal(at(31, 0), backwards),
            "field 0 (default): an offset of -12 at byte 44 does not point forward inside the file"
        );
        // A dictionary whose one entry is the dictionary itself.
        let cycle = [words(&[1]), vec![0; 4], words(&[8, at(31, 0)])].concat();
        assert_eq!(
            value_refusal(at(31, 0), cycle),
            "field 0 (default): values nest more than 32 deep"
        );
    }

    #[test]
    fn overlapping_or_oversized_values_are_refused() {
        // Time samples read at any multiple of 8 bytes into a run of 64s: 64 samples each.
        let fields = (0..64).map(|k| (2, 46 << 48 | (HEAP + 8 * k))).collect();
        let overlapping = Layer { fields, heap: words(&[64; 200]), ..Layer::default() };
        assert_eq!(refusal(&overlapping.build()),
            "field 48 (default): walking the values takes more steps than the file has bytes (they overlap)");
        // An int array of ten million compressed into 16 bytes.
        let packed = 3 << 48 | 1 << 63 | 1 << 61 | HEAP;
        assert_eq!(value_refusal(packed, words(&[10_000_000, 8, 0])),
            "the value of field 0 (default), 122500012 bytes, would take more than the 8 MiB this file's size allows");
    }

    #[test]
    fn a_text_nested_too_deep_is_refused() {
        let nested = |depth: usize| format!("#usda 1.0\n{}", "(".repeat(depth));
        check_layer(nested(512).as_bytes()).unwrap();
        assert_eq!(
            check_layer(nested(513).as_bytes()).unwrap_err(),
            "text nested 513 deep, more than 512 (openusd's parser recurses once per level)"
        );
    }
}
#[cfg(test)]
#[test]
fn tmp_files_scratch() {
    for path in std::env::var("TMP_USDC").unwrap_or_default().split(':').filter(|p| !p.is_empty()) {
        let bytes = std::fs::read(path).unwrap();
        eprintln!("{path}: {:?}", check(&bytes));
        if std::env::var("TMP_DUMP").is_ok() {
            let sections = sections(&bytes).unwrap();
            let budget = Budget::new(bytes.len(), PER_FILE_BYTE);
            let sec = |n: &str| {
                let s = sections.iter().find(|s| s.name == n).unwrap();
                eprintln!("{n} {} {}", s.start, s.end);
                Cursor { name: n.into(), file: &bytes, at: s.start, end: s.end }
            };
            let tokens = tokens(sec("TOKENS"), &budget).unwrap();
            for (t, rep) in fields(sec("FIELDS"), &budget).unwrap() {
                eprintln!(
                    "{} ty {} arr {} inl {} comp {} at {}",
                    tokens[t as usize],
                    rep >> 48 & 0xff,
                    rep >> 63,
                    rep >> 62 & 1,
                    rep >> 61 & 1,
                    rep & PAYLOAD
                );
            }
        }
    }
    for path in std::env::var("TMP_USD").unwrap_or_default().split(':').filter(|p| !p.is_empty()) {
        let p = std::path::PathBuf::from(path);
        let r = std::thread::Builder::new()
            .stack_size(8 << 20)
            .spawn(move || {
                super::usd_read::read(&p, &Default::default())
                    .map(|s| (s.frames.len(), s.counts.len()))
            })
            .unwrap()
            .join();
        eprintln!("{path}: {:?}", r);
    }
    for path in std::env::var("TMP_RAW").unwrap_or_default().split(':').filter(|p| !p.is_empty()) {
        let p = path.to_owned();
        let r = std::thread::Builder::new()
            .stack_size(8 << 20)
            .spawn(move || {
                let stage = openusd::usd::Stage::open(&p).unwrap();
                let mut n = 0;
                stage.traverse(openusd::usd::PrimPredicate::DEFAULT, |_| n += 1).unwrap();
                n
            })
            .unwrap()
            .join();
        eprintln!("raw {path}: {:?}", r);
    }
}
