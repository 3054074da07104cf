//! A glTF 2.0 file as a validated document and its buffers: a `.glb` container (JSON chunk,
//! BIN chunk) or a `.gltf` JSON file whose buffers are files beside it or `data:` URIs.
//! Every chunk length and buffer size is checked before it is trusted.

use super::accessor::{Accessors, Budget};
use super::data_uri;
use crate::sequence::glb::{CHUNK_BIN, CHUNK_JSON, MAGIC};
use std::path::Path;

/// A loaded file: the document (validated by the `gltf` crate: every index in range, every
/// enumeration known) and each buffer's bytes, held to its declared length.
pub struct Loaded {
    /// The document.
    pub document: gltf::Document,
    /// The bytes of buffer `i`, exactly `byteLength` of them.
    pub buffers: Vec<Vec<u8>>,
    /// Bytes read from disk in all (the file and its buffer files).
    pub file_bytes: usize,
}

/// What accessor reads may materialise per byte of the file: room for its data widened to
/// f64 (8 bytes per 1-byte component at most), and for morph targets and accessors without
/// data that take memory no byte stands for.
const BUDGET_PER_FILE_BYTE: usize = 64;

impl Loaded {
    /// The accessors of the file's buffers, within a budget its size justifies.
    pub fn accessors(&self) -> Accessors<'_> {
        Accessors::new(&self.buffers, Budget::new(self.file_bytes, BUDGET_PER_FILE_BYTE))
    }
}

/// Reads and validates `path` and its buffers. Errors are the problem, without the file name.
pub fn load(path: &Path) -> Result<Loaded, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read: {e}"))?;
    let (json, bin) = if bytes.starts_with(MAGIC) {
        let (json, bin) = read_container(&bytes)?;
        (json, Some(bin))
    } else {
        (&bytes[..], None)
    };
    let root = gltf::json::Root::from_slice(json)
        .map_err(|e| format!("not a valid glTF 2.0 file: {e}"))?;
    validate(&root)?;
    let document = gltf::Document::from_json_without_validation(root);
    let mut file_bytes = bytes.len();
    let mut buffers = Vec::new();
    for buffer in document.buffers() {
        let mut data = match buffer.source() {
            gltf::buffer::Source::Bin => bin.map(<[u8]>::to_vec).ok_or_else(|| {
                format!(
                    "buffer {} is the BIN chunk of a GLB, and this file is not one",
                    buffer.index()
                )
            })?,
            gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                data_uri::decode(uri).map_err(|e| format!("buffer {}: {e}", buffer.index()))?
            }
            gltf::buffer::Source::Uri(uri) => {
                let file = path.parent().unwrap_or(Path::new(".")).join(uri);
                let data = std::fs::read(&file)
                    .map_err(|e| format!("buffer {}: {}: {e}", buffer.index(), file.display()))?;
                file_bytes += data.len();
                data
            }
        };
        if data.len() < buffer.length() {
            return Err(format!(
                "buffer {} holds {} bytes, declares {}",
                buffer.index(),
                data.len(),
                buffer.length()
            ));
        }
        data.truncate(buffer.length());
        buffers.push(data);
    }
    Ok(Loaded { document, buffers, file_bytes })
}

/// The `gltf` crate's validation of `root` (every index in range, every enumeration known),
/// except its one departure from the specification: an accessor with neither a buffer view
/// nor sparse values is valid glTF (its values are zeros), as `write_glb` writes frame 0's
/// morph target.
///
/// The `gltf` crate's own checks index some arrays before checking the index (a primitive's
/// POSITION accessor): those indices are checked first, and a panic left there is still an
/// out-of-range index in the file.
fn validate(root: &gltf::json::Root) -> Result<(), String> {
    use gltf::json::validation::{Error, Validate};
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            if let Some(index) =
                primitive.attributes.values().find(|i| i.value() >= root.accessors.len())
            {
                return Err(format!(
                    "not a valid glTF 2.0 file: meshes[{m}].primitives[{p}] names accessor {}, the file has {}",
                    index.value(),
                    root.accessors.len()
                ));
            }
        }
    }
    let mut errors = Vec::new();
    let check = std::panic::AssertUnwindSafe(|| {
        root.validate(root, gltf::json::Path::new, &mut |path, error| {
            let path = path().to_string();
            let zeros = path.starts_with("accessors[") && path.ends_with("].bufferView");
            // The first error is the one reported; a damaged file can have millions.
            if !(zeros && matches!(error, Error::Missing)) && errors.is_empty() {
                errors.push(format!("{path}: {error}"));
            }
        })
    });
    if std::panic::catch_unwind(check).is_err() {
        return Err(
            "not a valid glTF 2.0 file: an index (of a mesh's accessor) is out of range".into()
        );
    }
    match errors.first() {
        None => Ok(()),
        Some(first) => Err(format!("not a valid glTF 2.0 file: {first}")),
    }
}

/// The JSON and BIN chunks of a GLB container (the BIN chunk empty when it has none).
fn read_container(bytes: &[u8]) -> Result<(&[u8], &[u8]), String> {
    let word =
        |at: usize| bytes.get(at..at + 4).map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]));
    if bytes.len() < 12 {
        return Err("not a GLB file (its header is cut off)".into());
    }
    if word(4) != Some(2) {
        return Err(format!("GLB version {}, only 2 is read", word(4).unwrap_or(0)));
    }
    let declared = word(8).unwrap_or(0) as usize;
    if declared != bytes.len() {
        return Err(format!(
            "truncated or padded: the header says {declared} bytes, the file has {}",
            bytes.len()
        ));
    }
    let (mut json, mut bin) = (None, &[][..]);
    let mut at = 12;
    while at < bytes.len() {
        let (Some(length), Some(kind)) = (word(at), word(at + 4)) else {
            return Err(format!("chunk header at byte {at} is cut off"));
        };
        let end = (length as usize).checked_add(at + 8);
        let data = end
            .and_then(|end| bytes.get(at + 8..end))
            .ok_or_else(|| format!("chunk at byte {at} runs past the end"))?;
        match kind {
            CHUNK_JSON if json.is_none() => json = Some(data),
            CHUNK_BIN if bin.is_empty() => bin = data,
            _ => {}
        }
        at += 8 + data.len();
    }
    Ok((json.ok_or("no JSON chunk")?, bin))
}
