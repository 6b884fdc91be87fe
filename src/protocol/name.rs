//! Fixed-capacity UTF-8 names (module names and families) that are `Copy` and never allocate.
use std::fmt;

/// Longest name in bytes.
pub const NAME_CAPACITY: usize = 32;

#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Name {
    len: u8,
    bytes: [u8; NAME_CAPACITY],
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("name longer than {NAME_CAPACITY} bytes")]
pub struct NameTooLong;

impl Name {
    pub fn new(s: &str) -> Result<Self, NameTooLong> {
        let b = s.as_bytes();
        if b.len() > NAME_CAPACITY {
            return Err(NameTooLong);
        }
        let mut bytes = [0u8; NAME_CAPACITY];
        bytes[..b.len()].copy_from_slice(b);
        Ok(Name {
            len: b.len() as u8,
            bytes,
        })
    }

    /// Build from raw bytes received off the wire; `None` if too long or not UTF-8.
    pub fn from_bytes(b: &[u8]) -> Option<Self> {
        let s = std::str::from_utf8(b).ok()?;
        Name::new(s).ok()
    }

    pub fn as_str(&self) -> &str {
        // Constructed only from valid UTF-8 of `len` bytes.
        std::str::from_utf8(&self.bytes[..self.len as usize]).expect("Name holds valid UTF-8")
    }

    pub fn as_bytes(&self) -> &[u8] {
        &self.bytes[..self.len as usize]
    }
}

impl fmt::Debug for Name {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:?}", self.as_str())
    }
}

impl fmt::Display for Name {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}
