//! Decoding one LZ4 block (the LZ4 block format: sequences of a token, literals, and a match
//! copied from the output already written), into at most a given number of bytes.

/// The bytes `block` decodes to, refusing a block that would write more than `capacity` bytes,
/// copy from before the start of its output, or end inside a sequence. Allocates at most
/// `capacity` bytes.
pub fn decompress(block: &[u8], capacity: usize) -> Result<Vec<u8>, String> {
    let mut out = Vec::new();
    let mut at = 0;
    loop {
        let token = *block.get(at).ok_or("the block ends before its last literals")?;
        at += 1;
        let literals = length(block, &mut at, token >> 4)?;
        let end = at.checked_add(literals).filter(|&end| end <= block.len());
        let end = end.ok_or("literals run past the end of the block")?;
        grow(&mut out, literals, capacity)?;
        out.extend_from_slice(&block[at..end]);
        at = end;
        // The last sequence has literals only: the block ends after them.
        if at == block.len() {
            return Ok(out);
        }
        let offset = match block.get(at..at + 2) {
            Some(&[low, high]) => usize::from(u16::from_le_bytes([low, high])),
            _ => return Err("a match offset runs past the end of the block".into()),
        };
        at += 2;
        if offset == 0 || offset > out.len() {
            return Err(format!("a match at offset {offset} of {} bytes written", out.len()));
        }
        let copied = length(block, &mut at, token & 15)? + 4;
        grow(&mut out, copied, capacity)?;
        // Byte by byte: a match may overlap the bytes it writes (a run).
        for _ in 0..copied {
            out.push(out[out.len() - offset]);
        }
    }
}

/// A literal or match length: the token's nibble, and while it is saturated (15, then 255),
/// the bytes that follow.
fn length(block: &[u8], at: &mut usize, nibble: u8) -> Result<usize, String> {
    let mut length = usize::from(nibble);
    let mut more = nibble == 15;
    while more {
        let byte = *block.get(*at).ok_or("a length runs past the end of the block")?;
        *at += 1;
        length = length.saturating_add(usize::from(byte));
        more = byte == 255;
    }
    Ok(length)
}

/// Reserves room for `more` bytes in `out`, or refuses when that passes `capacity`.
fn grow(out: &mut Vec<u8>, more: usize, capacity: usize) -> Result<(), String> {
    match out.len().checked_add(more) {
        Some(len) if len <= capacity => {
            out.reserve(more);
            Ok(())
        }
        _ => Err(format!("it decodes to more than the {capacity} bytes claimed")),
    }
}

#[cfg(test)]
mod tests {
    use super::decompress;

    #[test]
    fn literals_then_an_overlapping_match_decode_to_a_run() {
        // "ab", then a match of 4 + 2 bytes at offset 2: "ab" repeated.
        let block = [0x22, b'a', b'b', 2, 0, 0x10, b'!'];
        assert_eq!(decompress(&block, 64).unwrap(), b"abababab!");
    }

    #[test]
    fn saturated_lengths_continue_into_the_next_bytes() {
        let mut block = vec![0xF0, 255, 5];
        block.extend([7u8; 15 + 255 + 5]);
        assert_eq!(decompress(&block, 1000).unwrap(), vec![7u8; 275]);
    }

    #[test]
    fn damaged_blocks_are_refused() {
        let cases: [(&[u8], &str); 5] = [
            (&[0x30, b'a'], "literals run past the end of the block"),
            (&[0x10, b'a', 5, 0, 0x00], "a match at offset 5 of 1 bytes written"),
            (&[0x10, b'a', 1], "a match offset runs past the end of the block"),
            (&[0x1F, b'a', 1, 0], "a length runs past the end of the block"),
            (&[0x40, 1, 2, 3, 4], "it decodes to more than the 3 bytes claimed"),
        ];
        for (block, expected) in cases {
            assert_eq!(decompress(block, 3).unwrap_err(), expected);
        }
    }
}
