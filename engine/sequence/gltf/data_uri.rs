//! The bytes of a base64 `data:` URI (RFC 2397, RFC 4648), as glTF embeds buffers in a
//! `.gltf` file: `data:application/octet-stream;base64,AAAB...`.

/// The decoded bytes of `uri`; an error for a URI that is not base64 or holds a character
/// outside the base64 alphabet.
pub fn decode(uri: &str) -> Result<Vec<u8>, String> {
    let (header, payload) =
        uri.split_once(',').ok_or("a data: URI without a comma before its data")?;
    if !header.ends_with(";base64") {
        return Err(format!("data URI `{header}` is not base64"));
    }
    let mut out = Vec::with_capacity(payload.len() / 4 * 3);
    let (mut bits, mut held) = (0u32, 0u32);
    for (at, c) in payload.bytes().enumerate().filter(|&(_, c)| c != b'=') {
        let value = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            _ => return Err(format!("data URI: byte {at} of its data is not base64")),
        };
        bits = (bits << 6) | value as u32;
        held += 6;
        if held >= 8 {
            held -= 8;
            out.push((bits >> held) as u8);
            bits &= (1 << held) - 1;
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::decode;

    #[test]
    fn decodes_the_rfc_4648_examples_and_refuses_other_characters() {
        let uri = |data: &str| format!("data:application/octet-stream;base64,{data}");
        for (data, bytes) in
            [("", ""), ("Zg==", "f"), ("Zm8=", "fo"), ("Zm9v", "foo"), ("Zm9vYmFy", "foobar")]
        {
            assert_eq!(decode(&uri(data)).unwrap(), bytes.as_bytes());
        }
        assert!(decode(&uri("Zm9v!")).unwrap_err().contains("byte 4"));
        assert!(decode("data:text/plain,hi").unwrap_err().contains("not base64"));
    }
}
