//! Keys of protocol v2 (`docs/protocol.md` §4): the network key every party of one
//! robot shares (or the all-zero *open* key), the per-session key derived from it at
//! Acquire, and the frame tag. The primitive is BLAKE3 in its keyed and key-derivation
//! modes (the `blake3` crate); nothing here is hand-rolled cryptography.
use std::fmt;
use std::path::Path;

use subtle::ConstantTimeEq;

use super::Mac;

/// Bytes of a key.
pub const KEY_LEN: usize = 32;
/// Bytes of the tag that ends every frame: BLAKE3 keyed hash, truncated.
pub const TAG_LEN: usize = 16;
/// Bytes of an Acquire / AcquireReply nonce.
pub const NONCE_LEN: usize = 16;

/// A random value a party contributes to a session key.
pub type Nonce = [u8; NONCE_LEN];

/// A 256-bit key. Its bytes never appear in `Debug` output or logs.
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct Key([u8; KEY_LEN]);

impl Key {
    /// The open network's key: anyone can compute it, so on an open network the
    /// session keys are only as secret as the nonces of the handshake (§4.4).
    pub const OPEN: Key = Key([0; KEY_LEN]);

    pub const fn from_bytes(bytes: [u8; KEY_LEN]) -> Self {
        Self(bytes)
    }

    /// A fresh key from the operating system's random source.
    pub fn random() -> Self {
        Self(rand::random())
    }

    pub fn is_open(&self) -> bool {
        *self == Self::OPEN
    }

    /// The 16-byte tag of `data` under this key.
    pub fn tag(&self, data: &[u8]) -> [u8; TAG_LEN] {
        let full = blake3::keyed_hash(&self.0, data);
        let mut tag = [0; TAG_LEN];
        tag.copy_from_slice(&full.as_bytes()[..TAG_LEN]);
        tag
    }

    /// Whether `tag` is the tag of `data`, compared in constant time.
    pub fn verify(&self, data: &[u8], tag: &[u8]) -> bool {
        tag.len() == TAG_LEN && bool::from(self.tag(data).ct_eq(tag))
    }

    /// The session key of `session` on the module `mac`, from both sides' nonces.
    /// Host and module compute it independently after Acquire; it never travels.
    pub fn session_key(&self, session: u32, mac: &Mac, host: &Nonce, module: &Nonce) -> Key {
        let mut h = blake3::Hasher::new_derive_key("snaked module protocol v2 session key");
        h.update(&self.0);
        h.update(&session.to_le_bytes());
        h.update(mac);
        h.update(host);
        h.update(module);
        Key(*h.finalize().as_bytes())
    }

    /// Parse 64 hexadecimal digits (surrounding whitespace allowed).
    pub fn from_hex(text: &str) -> Result<Self, KeyError> {
        let t = text.trim();
        if t.len() != 2 * KEY_LEN || !t.is_ascii() {
            return Err(KeyError::Format);
        }
        let mut out = [0; KEY_LEN];
        for (i, b) in out.iter_mut().enumerate() {
            *b = u8::from_str_radix(&t[2 * i..2 * i + 2], 16).map_err(|_| KeyError::Format)?;
        }
        Ok(Self(out))
    }

    /// 64 lower-case hexadecimal digits (what a key file holds).
    pub fn to_hex(&self) -> String {
        self.0.iter().map(|b| format!("{b:02x}")).collect()
    }

    /// Read a network key file: 64 hex digits, not readable by every user.
    pub fn load(path: &Path) -> Result<Self, KeyError> {
        use std::os::unix::fs::MetadataExt;
        let meta = std::fs::metadata(path).map_err(KeyError::Io)?;
        if meta.mode() & 0o004 != 0 {
            return Err(KeyError::WorldReadable(meta.mode() & 0o777));
        }
        let text = std::fs::read_to_string(path).map_err(KeyError::Io)?;
        let key = Self::from_hex(&text)?;
        if key.is_open() {
            return Err(KeyError::AllZero);
        }
        Ok(key)
    }
}

impl fmt::Debug for Key {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(if self.is_open() {
            "Key(open)"
        } else {
            "Key(..)"
        })
    }
}

#[derive(Debug, thiserror::Error)]
pub enum KeyError {
    #[error("{0}")]
    Io(std::io::Error),
    #[error("not a key: a key file holds 64 hexadecimal digits (32 random bytes)")]
    Format,
    #[error("readable by every user (mode {0:o}); make it 0600 or 0640")]
    WorldReadable(u32),
    #[error("the all-zero key is the open network's; write 32 random bytes")]
    AllZero,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tags_depend_on_key_and_every_byte() {
        let k = Key::from_bytes([7; KEY_LEN]);
        let t = k.tag(b"hello");
        assert!(k.verify(b"hello", &t));
        assert!(!k.verify(b"hellp", &t));
        assert!(!Key::OPEN.verify(b"hello", &t));
        assert!(!k.verify(b"hello", &t[..15]));
    }

    #[test]
    fn session_keys_differ_by_every_input() {
        let net = Key::from_bytes([1; KEY_LEN]);
        let base = net.session_key(5, &[1; 6], &[2; 16], &[3; 16]);
        assert_ne!(base, Key::OPEN.session_key(5, &[1; 6], &[2; 16], &[3; 16]));
        assert_ne!(base, net.session_key(6, &[1; 6], &[2; 16], &[3; 16]));
        assert_ne!(base, net.session_key(5, &[9; 6], &[2; 16], &[3; 16]));
        assert_ne!(base, net.session_key(5, &[1; 6], &[9; 16], &[3; 16]));
        assert_ne!(base, net.session_key(5, &[1; 6], &[2; 16], &[9; 16]));
    }

    #[test]
    fn hex_round_trip_and_refusals() {
        let k = Key::random();
        assert_eq!(Key::from_hex(&format!(" {}\n", k.to_hex())).unwrap(), k);
        assert!(matches!(Key::from_hex("abc"), Err(KeyError::Format)));
        assert!(matches!(
            Key::from_hex(&"zz".repeat(32)),
            Err(KeyError::Format)
        ));
        assert_eq!(format!("{:?}", Key::OPEN), "Key(open)");
        assert_eq!(format!("{k:?}"), "Key(..)");
    }
}
