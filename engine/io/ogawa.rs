//! Ogawa, the container inside Alembic files: a tree of groups and data blocks addressed by
//! byte offsets. The file starts with `Ogawa`, a frozen byte (0xFF once the writer closed the
//! file), the big-endian version 1 and the offset of the root group. A group is a child count
//! and that many 64-bit children; a child with its top bit set is a data block (a byte size,
//! then the bytes), otherwise a group. Offset 0 is the empty group, the top bit alone the empty
//! data block. Everything is little-endian.
//!
//! Every count, size and offset is checked against the file's size before anything is read or
//! allocated, so a hostile file gets an error naming the offset, never a panic or an allocation
//! beyond its size. What the blocks mean is the reader's business (`sequence::alembic`).

/// The top bit of a child: set for a data block.
const DATA_BIT: u64 = 1 << 63;

/// An Ogawa file held in memory.
pub struct Ogawa {
    bytes: Vec<u8>,
}

/// A group of the file: its children, each a group or a data block.
#[derive(Clone, Copy)]
pub struct Group<'a> {
    file: &'a Ogawa,
    /// Where the group starts (0 for the empty group).
    at: u64,
    /// The children's 8-byte words, checked to lie inside the file.
    children: &'a [u8],
}

impl Ogawa {
    /// The container of `bytes`, after checking the header: the magic, the frozen byte (a file
    /// whose writer did not finish has it 0) and the version.
    pub fn new(bytes: Vec<u8>) -> Result<Self, String> {
        if bytes.len() < 16 || &bytes[..5] != b"Ogawa" {
            return Err("not an Alembic (Ogawa) file: it does not start with \"Ogawa\" (an \
                 HDF5 Alembic file, from before 2013, is not read)"
                .into());
        }
        if bytes[5] != 0xFF {
            return Err("the Ogawa file was not closed by its writer (not frozen)".into());
        }
        let version = u16::from_be_bytes([bytes[6], bytes[7]]);
        if version != 1 {
            return Err(format!("Ogawa version {version}; only version 1 is read"));
        }
        Ok(Ogawa { bytes })
    }

    /// The file's size in bytes.
    pub fn len(&self) -> usize {
        self.bytes.len()
    }

    /// Whether the file is empty (never true for a file [`Ogawa::new`] accepted).
    pub fn is_empty(&self) -> bool {
        self.bytes.is_empty()
    }

    /// The root group, whose offset the header gives.
    pub fn root(&self) -> Result<Group<'_>, String> {
        let at = self.word(8)?;
        if at & DATA_BIT != 0 {
            return Err("the Ogawa header's root is a data block, not a group".into());
        }
        self.group(at)
    }

    /// The little-endian 64-bit word at byte `at`.
    fn word(&self, at: u64) -> Result<u64, String> {
        let bytes = self.span(at, 8).ok_or_else(|| past_end(at, 8, self.len()))?;
        Ok(u64::from_le_bytes(bytes.try_into().expect("8 bytes")))
    }

    /// The `len` bytes at `at`, when they lie inside the file.
    fn span(&self, at: u64, len: u64) -> Option<&[u8]> {
        let end = at.checked_add(len)?;
        let (at, end) = (usize::try_from(at).ok()?, usize::try_from(end).ok()?);
        self.bytes.get(at..end)
    }

    /// The group at byte `at` (0: the empty group). Its child count is checked against the
    /// bytes left in the file.
    fn group(&self, at: u64) -> Result<Group<'_>, String> {
        if at == 0 {
            return Ok(Group { file: self, at, children: &[] });
        }
        let count = self.word(at)?;
        let room = (self.len() as u64).saturating_sub(at + 8) / 8;
        if count > room {
            return Err(format!(
                "the Ogawa group at byte {at} claims {count} children; the file has room for \
                 {room}"
            ));
        }
        let children = self.span(at + 8, count * 8).expect("checked against the file's size");
        Ok(Group { file: self, at, children })
    }

    /// The data block at byte `at` (0: the empty block).
    fn data(&self, at: u64) -> Result<&[u8], String> {
        if at == 0 {
            return Ok(&[]);
        }
        let size = self.word(at)?;
        self.span(at + 8, size).ok_or_else(|| past_end(at + 8, size, self.len()))
    }
}

fn past_end(at: u64, len: u64, file: usize) -> String {
    format!("{len} bytes at byte {at} of the Ogawa file run past its end ({file} bytes)")
}

impl std::fmt::Debug for Group<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "the Ogawa group at byte {} ({} children)", self.at, self.len())
    }
}

impl<'a> Group<'a> {
    /// Where the group starts: with the file, it names the group in errors and tells a group
    /// reached twice (a cycle) from a new one.
    pub fn offset(&self) -> u64 {
        self.at
    }

    /// How many children the group has.
    pub fn len(&self) -> usize {
        self.children.len() / 8
    }

    /// Whether the group has no children.
    pub fn is_empty(&self) -> bool {
        self.children.is_empty()
    }

    fn child(&self, i: usize) -> Result<u64, String> {
        let word = self.children.get(8 * i..8 * i + 8).ok_or_else(|| {
            format!(
                "the Ogawa group at byte {} has {} children, not {}",
                self.at,
                self.len(),
                i + 1
            )
        })?;
        Ok(u64::from_le_bytes(word.try_into().expect("8 bytes")))
    }

    /// Whether child `i` is a data block (false past the end).
    pub fn is_data(&self, i: usize) -> bool {
        self.child(i).is_ok_and(|c| c & DATA_BIT != 0)
    }

    /// Child `i` as a group; an error when it is a data block, the group itself or past the
    /// end. (Deeper cycles are the walker's to catch, by [`Group::offset`].)
    pub fn group(&self, i: usize) -> Result<Group<'a>, String> {
        let child = self.child(i)?;
        if child & DATA_BIT != 0 {
            return Err(format!(
                "child {i} of the Ogawa group at byte {} is data, not a group",
                self.at
            ));
        }
        if child != 0 && child == self.at {
            return Err(format!("the Ogawa group at byte {} contains itself", self.at));
        }
        self.file.group(child)
    }

    /// Child `i` as a data block's bytes; an error when it is a group or past the end.
    pub fn data(&self, i: usize) -> Result<&'a [u8], String> {
        let child = self.child(i)?;
        if child & DATA_BIT == 0 {
            return Err(format!(
                "child {i} of the Ogawa group at byte {} is a group, not data",
                self.at
            ));
        }
        self.file.data(child & !DATA_BIT)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file whose root group holds one data block (b"abc") and one empty group.
    fn small() -> Vec<u8> {
        let mut b = b"Ogawa\xff\x00\x01".to_vec();
        b.extend(32u64.to_le_bytes()); // the root group
        b.extend(3u64.to_le_bytes()); // data at 16: size 3, "abc", padding
        b.extend(b"abc\0\0\0\0\0");
        b.extend(2u64.to_le_bytes()); // root group at 32
        b.extend((16 | DATA_BIT).to_le_bytes());
        b.extend(0u64.to_le_bytes());
        b
    }

    #[test]
    fn reads_groups_and_data() {
        let file = Ogawa::new(small()).unwrap();
        let root = file.root().unwrap();
        assert_eq!(root.len(), 2);
        assert!(root.is_data(0) && !root.is_data(1) && !root.is_data(2));
        assert_eq!(root.data(0).unwrap(), b"abc");
        assert!(root.group(1).unwrap().is_empty());
        assert!(root.group(0).unwrap_err().contains("is data"));
        assert!(root.data(1).unwrap_err().contains("is a group"));
        assert!(root.data(2).unwrap_err().contains("has 2 children"));
    }

    #[test]
    fn refuses_bad_headers_counts_sizes_and_self_loops() {
        let fail = |b: Vec<u8>| Ogawa::new(b).and_then(|f| f.root().map(drop)).unwrap_err();
        let mut b = small();
        b[0] = b'X';
        assert!(fail(b).contains("not an Alembic"));
        let mut b = small();
        b[5] = 0;
        assert!(fail(b).contains("not frozen"));
        let mut b = small();
        b[32..40].copy_from_slice(&u64::MAX.to_le_bytes());
        assert!(fail(b).contains("claims"));
        let mut b = small();
        b[16..24].copy_from_slice(&(1u64 << 40).to_le_bytes());
        let file = Ogawa::new(b).unwrap();
        assert!(file.root().unwrap().data(0).unwrap_err().contains("past its end"));
        let mut b = small();
        b[48..56].copy_from_slice(&32u64.to_le_bytes());
        let file = Ogawa::new(b).unwrap();
        assert!(file.root().unwrap().group(1).unwrap_err().contains("contains itself"));
    }
}
