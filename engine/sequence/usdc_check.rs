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
//! - the path tree reaches each of its entries once and its elements are names or variant
//!   selections (openusd takes `/A}` for its own parent, and composing it never ends); values
//!   nest at most [`MAX_DEPTH`] deep, their offsets point forward, and walking every value
//!   takes one step per file byte at most;
//! - every token, string, path and lookup-table index lies inside its table, every integer
//!   block holds the codes its count needs, and no array rep is of a form openusd asserts
//!   against: openusd indexes and slices these unchecked, and a panic, caught or not, costs a
//!   backtrace when `RUST_BACKTRACE` is set (tens of megabytes).
//!
//! Not covered: the rest of a text layer (`.usda`: openusd's parser allocates by the text it has
//! read, not by counts), the zip container of a `.usdz` (the zip crate inflates a deflated entry
//! to whatever it holds), and what the reader builds from the values it samples (frames ×
//! points).

mod ints;
mod lz4;
mod nesting;
mod paths;
mod values;

use super::gltf::accessor::Budget;
use ints::{coded_block, coded_size};
use openusd::ar::{Asset, AssetInfo, DefaultResolver, ResolvedPath, Resolver};
use openusd::usdc::MAGIC;
use std::io;
use std::time::SystemTime;
use values::{Tables, Values};

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
            "text nested {depth} deep, more than {MAX_TEXT_DEPTH} \
             (openusd's parser recurses once per level)"
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
    let strings = section("STRINGS").map_or(Ok(0), |c| strings(c, tokens.len(), &budget))?;
    let fields = section("FIELDS").map_or(Ok(Vec::new()), |c| fields(c, &budget))?;
    if let Some(mut c) = section("FIELDSETS") {
        int_table(&mut c, 1, 16, &budget)?;
    }
    let (paths, longest_path) =
        section("PATHS").map_or(Ok((0, 0)), |c| paths::paths(c, &tokens, &budget))?;
    if let Some(mut c) = section("SPECS") {
        int_table(&mut c, 3, ITEM, &budget)?;
    }
    let longest_token = tokens.iter().map(|t| t.len() as u64).max().unwrap_or(0);
    let tables =
        Tables { tokens: tokens.len() as u64, strings, paths, longest_token, longest_path };
    Values::new(file, version, tables).check(&fields, &tokens, &budget)
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

/// The strings (STRINGS: a count, then each string's token index), each naming one of
/// `tokens` tokens; their count.
fn strings(mut c: Cursor, tokens: usize, budget: &Budget) -> Result<u64, String> {
    let count = c.u64("the string count")?;
    let indices = c.take(count.checked_mul(4), || format!("{count} strings of 4 bytes"))?;
    charge(budget, count.checked_mul(12), || format!("{}: {count} strings", c.name))?;
    match indices.chunks_exact(4).map(le_u64).enumerate().find(|&(_, t)| t >= tokens as u64) {
        Some((k, token)) => Err(format!("{}: string {k} names token {token} of {tokens}", c.name)),
        None => Ok(count),
    }
}

/// The fields (FIELDS: a count, a block of token indices, a block of value reps): each field's
/// token index and value rep.
fn fields(mut c: Cursor, budget: &Budget) -> Result<Vec<(u32, u64)>, String> {
    let (count, names) = int_table(&mut c, 1, 16, budget)?;
    let reps = c.block()?;
    let bytes = count.checked_mul(8);
    let buffers = bytes.and_then(|b| b.checked_add(reps.len() as u64));
    charge(budget, buffers, || format!("{}: {count} value reps", c.name))?;
    let names = ints::decode_ints(&c.name, &names[0], count)?;
    let reps = decompress(&c.name, reps, bytes.unwrap_or_default())?;
    // openusd asserts (in debug builds) that there is one rep per field.
    if reps.len() as u64 != count * 8 {
        return Err(format!("{}: {count} value reps in {} bytes", c.name, reps.len()));
    }
    Ok(names.iter().zip(reps.chunks_exact(8)).map(|(&n, rep)| (n as u32, le_u64(rep))).collect())
}

/// A count and `blocks` integer blocks of that many integers each (FIELDSETS, SPECS, the
/// encoded paths), charging each block and `item` bytes per entry for what openusd builds; the
/// count and each block's bytes decompressed.
fn int_table(
    c: &mut Cursor,
    blocks: usize,
    item: u64,
    budget: &Budget,
) -> Result<(u64, Vec<Vec<u8>>), String> {
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
            coded_block(&c.name, block, count, 4)
        })
        .collect::<Result<_, String>>()?;
    Ok((count, blocks))
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
                ("STRINGS", [count(1), vec![0; 4]].concat()),
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
        assert_eq!(
            with(16, &u64::MAX.to_le_bytes()),
            "the table of contents: the section count at byte \
                18446744073709551615, but 0 bytes are left"
        );
        assert_eq!(
            with(toc as usize, &0u64.to_le_bytes()),
            "the table of contents lists 0 sections"
        );
        // The first section's size.
        assert_eq!(
            with(toc as usize + 8 + 24, &u64::MAX.to_le_bytes()),
            "section TOKENS: 18446744073709551615 bytes at byte 32, but 487 bytes are left"
        );
    }

    #[test]
    fn counts_and_blocks_past_their_section_are_refused() {
        let layer = Layer::default();
        let count = |n: u64| move |b: &mut Vec<u8>| b[..8].copy_from_slice(&n.to_le_bytes());
        assert_eq!(
            refusal(&edited(&layer, "STRINGS", count(u32::MAX.into()))),
            "section STRINGS: 4294967295 strings of 4 bytes at byte 77, but 4 bytes are left"
        );
        // FIELDS: the count, then its block of token indices (size, chunk count, LZ4).
        let size = |b: &mut Vec<u8>| b[8..16].copy_from_slice(&1000u64.to_le_bytes());
        assert_eq!(
            refusal(&edited(&layer, "FIELDS", size)),
            "section FIELDS: a compressed block of 1000 bytes at byte 97, but 29 bytes are left"
        );
        let chunks = |b: &mut Vec<u8>| b[16] = 2;
        assert_eq!(
            refusal(&edited(&layer, "FIELDS", chunks)),
            "section FIELDS: a compressed block in 2 chunks, which openusd cannot read"
        );
        let reps = |b: &mut Vec<u8>| b[..8].copy_from_slice(&2u64.to_le_bytes());
        assert_eq!(
            refusal(&edited(&layer, "FIELDS", reps)),
            "section FIELDS: 2 value reps in 8 bytes"
        );
        let truncated = |b: &mut Vec<u8>| b.truncate(20);
        assert_eq!(
            refusal(&edited(&layer, "FIELDS", truncated)),
            "section FIELDS: a compressed block of 11 bytes at byte 97, but 4 bytes are left"
        );
        // More fieldsets than their block codes: openusd would slice past its buffer.
        assert_eq!(
            refusal(&edited(&layer, "FIELDSETS", count(1000))),
            "section FIELDSETS: 1000 coded integers in 13 bytes"
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
        assert_eq!(
            refusal(&edited(&layer, "TOKENS", at(8, 1 << 32))),
            "section TOKENS: 4294967296 bytes of tokens would take more than the 8 \
                MiB this file's size allows"
        );
        // A claimed size smaller than the text: the block decodes to more.
        assert_eq!(
            refusal(&edited(&layer, "TOKENS", at(8, 3))),
            "section TOKENS: a compressed block: it decodes to more than the 3 bytes claimed"
        );
        assert_eq!(
            refusal(&edited(&layer, "PATHS", at(0, 1 << 40))),
            "section PATHS: 1099511627776 paths would take more than the 8 MiB \
                this file's size allows"
        );
        assert_eq!(
            refusal(&edited(&layer, "SPECS", at(0, 1 << 40))),
            "section SPECS: 1099511627776 entries would take more than the 8 MiB \
                this file's size allows"
        );
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
        let layer = Layer { tokens: vec!["", "a}", "default"], ..Layer::default() };
        assert_eq!(
            refusal(&layer.build()),
            "section PATHS: entry 1 names \"a}\", not a path element"
        );
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
            "field 0 (default): 1000000000 elements of 12 bytes at byte 40, but 487 bytes are left"
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
        assert_eq!(
            refusal(&overlapping.build()),
            "field 48 (default): walking the values takes more steps than the file \
                has bytes (they overlap)"
        );
        // An int array of ten million, all the common value 0: 2.5 MB of zeros, which LZ4
        // encodes as one literal, a match of the rest (about 10 kB of length bytes) and an
        // empty last sequence.
        let run = 2_500_004 - 1;
        let mut lz4 = vec![0, 0x1F, 0, 1, 0];
        let rest = run - 4 - 15;
        lz4.extend(std::iter::repeat_n(255, rest / 255));
        lz4.extend([(rest % 255) as u8, 0]);
        let coded = [words(&[10_000_000, lz4.len() as u64]), lz4].concat();
        let packed = 3 << 48 | 1 << 63 | 1 << 61 | HEAP;
        assert_eq!(
            value_refusal(packed, coded),
            "the value of field 0 (default), 122509814 bytes, would take more than the 8 MiB \
                this file's size allows"
        );
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

    #[test]
    fn shared_values_count_their_nesting_wherever_they_are_met() {
        // Dictionaries of one entry each (a count, a key, an offset of 8 to the value rep),
        // `levels` of them from byte `at`, the last one's value `last`.
        let chain = |at: u64, levels: u64, last: u64| -> Vec<u8> {
            let next = |k: u64| if k + 1 < levels { 31 << 48 | (at + 28 * (k + 1)) } else { last };
            let entry = |k: u64| [words(&[1]), vec![0; 4], words(&[8, next(k)])].concat();
            (0..levels).flat_map(entry).collect()
        };
        let first = 31 << 48 | HEAP;
        let second = 31 << 48 | (HEAP + 28 * 20);
        let heap = [chain(HEAP, 20, INLINE_INT), chain(HEAP + 28 * 20, 20, first)].concat();
        // Walked alone, each chain nests 20 deep; the second reaches the first at depth 20.
        let fields = vec![(2, first), (2, second)];
        assert_eq!(
            refusal(&Layer { fields, heap, ..Layer::default() }.build()),
            "field 1 (default): values nest more than 32 deep"
        );
    }

    #[test]
    fn indices_past_their_table_are_refused() {
        // A token array naming token 7 of 3.
        let tokens = 11 << 48 | 1 << 63 | HEAP;
        assert_eq!(
            value_refusal(tokens, [words(&[1]), 7u32.to_le_bytes().to_vec()].concat()),
            "field 0 (default): index 7 at byte 40 past the 3 tokens"
        );
        // An inlined token 9, a string at its offset naming string 4 of 1.
        assert_eq!(
            value_refusal(11 << 48 | 1 << 62 | 9, Vec::new()),
            "field 0 (default): index 9 inlined past the 3 tokens"
        );
        assert_eq!(
            value_refusal(10 << 48 | HEAP, 4u32.to_le_bytes().to_vec()),
            "field 0 (default): index 4 at byte 32 past the 1 strings"
        );
        // A payload (string and path indices, a layer offset) naming string 4 of 1.
        assert_eq!(
            value_refusal(47 << 48 | HEAP, [words(&[4]), vec![0; 16]].concat()),
            "field 0 (default): index 4 at byte 32 past the 1 strings"
        );
        let string = |b: &mut Vec<u8>| b[8..12].copy_from_slice(&5u32.to_le_bytes());
        assert_eq!(
            refusal(&edited(&Layer::default(), "STRINGS", string)),
            "section STRINGS: string 0 names token 5 of 3"
        );
        // A float array of 4 compressed as lookups into a table of 1 value, the last index 5.
        let table = [vec![b't'], 1u32.to_le_bytes().to_vec(), 1f32.to_le_bytes().to_vec()];
        let lookups = [words(&[4]), table.concat(), ints(&[0, 0, 0, 5])].concat();
        assert_eq!(
            value_refusal(8 << 48 | 1 << 63 | 1 << 61 | HEAP, lookups),
            "field 0 (default): a compressed array at byte 40: index 5 past its 1 values"
        );
        // A Vec3f array marked compressed, which openusd asserts against.
        assert_eq!(
            value_refusal(24 << 48 | 1 << 63 | 1 << 61 | HEAP, words(&[0])),
            "field 0 (default): an array at byte 32 marked inlined or compressed"
        );
    }
}
