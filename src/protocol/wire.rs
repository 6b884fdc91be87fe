//! Little-endian field writers and readers over a frame's bytes: the codec's only
//! byte-level code. Writing never fails (the codec sizes the buffer first); reading past
//! the end, or a non-zero reserved byte, is a malformed payload.
use super::codec::DecodeError;
use super::{NAME_CAPACITY, Name};

/// Writes into a buffer whose size `encode` has already checked.
pub(super) struct Writer<'a> {
    pub buf: &'a mut [u8],
    pub pos: usize,
}

impl Writer<'_> {
    pub fn bytes(&mut self, b: &[u8]) {
        self.buf[self.pos..self.pos + b.len()].copy_from_slice(b);
        self.pos += b.len();
    }
    pub fn u8(&mut self, v: u8) {
        self.bytes(&[v]);
    }
    pub fn u16(&mut self, v: u16) {
        self.bytes(&v.to_le_bytes());
    }
    pub fn u32(&mut self, v: u32) {
        self.bytes(&v.to_le_bytes());
    }
    pub fn u64(&mut self, v: u64) {
        self.bytes(&v.to_le_bytes());
    }
    /// Bit-exact, so NaN payloads survive.
    pub fn f32(&mut self, v: f32) {
        self.u32(v.to_bits());
    }
    /// Length byte, then the bytes.
    pub fn short_name(&mut self, n: &Name) {
        self.u8(n.as_bytes().len() as u8);
        self.bytes(n.as_bytes());
    }
    /// `NAME_CAPACITY` bytes, zero padded (the length travels separately).
    pub fn padded_name(&mut self, n: &Name) {
        let b = n.as_bytes();
        self.bytes(b);
        self.bytes(&[0; NAME_CAPACITY][b.len()..]);
    }
}

/// Reads a payload; running out of bytes is a malformed payload.
pub(super) struct Reader<'a> {
    pub buf: &'a [u8],
    pub pos: usize,
}

impl<'a> Reader<'a> {
    pub fn remaining(&self) -> usize {
        self.buf.len() - self.pos
    }
    pub fn take(&mut self, n: usize) -> Result<&'a [u8], DecodeError> {
        if n > self.remaining() {
            return Err(DecodeError::Malformed("payload ends inside a field"));
        }
        let s = &self.buf[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }
    pub fn array<const N: usize>(&mut self) -> Result<[u8; N], DecodeError> {
        Ok(self.take(N)?.try_into().expect("take returns N bytes"))
    }
    pub fn u8(&mut self) -> Result<u8, DecodeError> {
        Ok(self.take(1)?[0])
    }
    pub fn u16(&mut self) -> Result<u16, DecodeError> {
        self.array().map(u16::from_le_bytes)
    }
    pub fn u32(&mut self) -> Result<u32, DecodeError> {
        self.array().map(u32::from_le_bytes)
    }
    pub fn u64(&mut self) -> Result<u64, DecodeError> {
        self.array().map(u64::from_le_bytes)
    }
    pub fn f32(&mut self) -> Result<f32, DecodeError> {
        self.u32().map(f32::from_bits)
    }
    pub fn f32s<const N: usize>(&mut self) -> Result<[f32; N], DecodeError> {
        let mut out = [0.0; N];
        for v in &mut out {
            *v = self.f32()?;
        }
        Ok(out)
    }
    pub fn zero(&mut self, n: usize) -> Result<(), DecodeError> {
        if self.take(n)?.iter().any(|&b| b != 0) {
            return Err(DecodeError::Malformed("reserved bytes not zero"));
        }
        Ok(())
    }
    pub fn name(bytes: &[u8]) -> Result<Name, DecodeError> {
        let s = std::str::from_utf8(bytes).map_err(|_| DecodeError::Malformed("name not UTF-8"))?;
        Name::new(s).map_err(|_| DecodeError::Malformed("name too long"))
    }
    pub fn short_name(&mut self) -> Result<Name, DecodeError> {
        let len = self.u8()? as usize;
        if len > NAME_CAPACITY {
            return Err(DecodeError::Malformed("name too long"));
        }
        Self::name(self.take(len)?)
    }
    pub fn padded_name(&mut self, len: u8) -> Result<Name, DecodeError> {
        let field = self.take(NAME_CAPACITY)?;
        let len = len as usize;
        if len > NAME_CAPACITY {
            return Err(DecodeError::Malformed("name too long"));
        }
        if field[len..].iter().any(|&b| b != 0) {
            return Err(DecodeError::Malformed("name padding not zero"));
        }
        Self::name(&field[..len])
    }
}
