//! A crate file's path tree (its PATHS section) walked as openusd builds it: every entry
//! reached once, its indices inside their tables, its elements names openusd can compose, and
//! the text of the paths it builds charged to the budget.

use super::ints::decode_ints;
use super::{charge, int_table, Cursor};
use crate::sequence::gltf::accessor::Budget;

/// The paths (PATHS: the number of paths, then a table of three blocks: each entry's path
/// index, token (negative for a property) and jump): charges the paths' text (three times:
/// openusd's paths, the parents its walk keeps, the specs' copies); the number of paths and
/// the longest one's length.
pub fn paths(mut c: Cursor, tokens: &[String], budget: &Budget) -> Result<(u64, u64), String> {
    let slots = c.u64("the path count")?;
    charge(budget, slots.checked_mul(24), || format!("{}: {slots} paths", c.name))?;
    let (count, blocks) = int_table(&mut c, 3, 0, budget)?;
    let decoded = blocks
        .iter()
        .map(|block| decode_ints(&c.name, block, count))
        .collect::<Result<Vec<_>, _>>()?;
    let lengths =
        path_lengths(&c.name, tokens, slots as usize, [&decoded[0], &decoded[1], &decoded[2]])?;
    let text = lengths.iter().fold(0u64, |sum, &length| sum.saturating_add(length));
    charge(budget, text.checked_mul(3), || format!("{}: {text} bytes of path text", c.name))?;
    Ok((slots, lengths.into_iter().max().unwrap_or(0)))
}

/// Walks the path tree as openusd builds it (an entry's child is the entry after it when its
/// jump is positive or -1; its next sibling is `jump` entries on when the jump is 0 or more),
/// giving each path an upper bound of its text's length. Refuses an entry reached twice (a
/// tree that loops), and indices out of range.
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
            if reached.get(entry) != Some(&false) {
                let problem = match entry < reached.len() {
                    true => format!("entry {entry} is reached twice"),
                    false => format!("the tree runs past its {} entries", reached.len()),
                };
                return Err(format!("{section}: {problem}"));
            }
            reached[entry] = true;
            let length = path_length(section, tokens, parent, entry, element[entry])?;
            let slot = index[entry] as u32 as usize;
            let named = || format!("{section}: entry {entry} names path {slot} of {slots}");
            *lengths.get_mut(slot).ok_or_else(named)? = length;
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

/// An upper bound of the length of entry `entry`'s path: 1 for the root (no parent), else its
/// parent's, a separator and its token's (negative for a property).
fn path_length(
    section: &str,
    tokens: &[String],
    parent: Option<u64>,
    entry: usize,
    token: i32,
) -> Result<u64, String> {
    let Some(parent) = parent else { return Ok(1) };
    let token = token.unsigned_abs() as usize;
    match tokens.get(token) {
        Some(text) if composable(text) => Ok(parent.saturating_add(1 + text.len() as u64)),
        Some(text) => Err(format!("{section}: entry {entry} names {text:?}, not a path element")),
        None => Err(format!("{section}: entry {entry} names token {token} of {}", tokens.len())),
    }
}

/// Whether `token` is a path element openusd can compose: a name without separators or
/// brackets, or a variant selection `{set=selection}`. (openusd takes a path that ends in `}`
/// without being a variant selection for its own parent, and recurses on it for ever.)
fn composable(token: &str) -> bool {
    let plain = |text: &str| !text.contains(['/', '{', '}', '[', ']', '<', '>']);
    match token.strip_prefix('{').and_then(|t| t.strip_suffix('}')) {
        Some(selection) => selection.contains('=') && plain(selection),
        None => plain(token) && !token.contains('.'),
    }
}
