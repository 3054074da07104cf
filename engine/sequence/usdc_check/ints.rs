//! USD's coding of integer arrays (a crate file's integer tables and compressed int arrays):
//! the sizes openusd allocates for them, and their decoding, each read inside its block.

use super::decompress;

/// A compressed block of `count` coded integers of `width` bytes decompressed into the buffer
/// openusd allocates for it (already charged); refused when it holds less than their common
/// value and codes, where openusd slices past its buffer and panics.
pub fn coded_block(what: &str, block: &[u8], count: u64, width: u64) -> Result<Vec<u8>, String> {
    let data = decompress(what, block, coded_size(count))?;
    match count > 0 && (data.len() as u64) < width + count.div_ceil(4) {
        true => Err(format!("{what}: {count} coded integers in {} bytes", data.len())),
        false => Ok(data),
    }
}

/// The size of openusd's buffer for `count` coded 32-bit integers (its `encoded_buffer_size`):
/// the common value, two bits of code and four bytes per integer. u64::MAX when it overflows.
pub fn coded_size(count: u64) -> u64 {
    let size = count.checked_mul(4).and_then(|b| b.checked_add(count.div_ceil(4) + 4));
    if count == 0 {
        0
    } else {
        size.unwrap_or(u64::MAX)
    }
}

/// `count` integers in USD's integer coding: a common delta (i32), two bits of code per
/// integer (0: the common delta; 1, 2, 3: an i8, i16 or i32 delta among the bytes after the
/// codes), each integer the previous one plus its delta (wrapping, as openusd's do).
pub fn decode_ints(section: &str, data: &[u8], count: u64) -> Result<Vec<i32>, String> {
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
