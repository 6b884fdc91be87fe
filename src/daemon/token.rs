//! The tokens (`control.tcp_token_file`, `foxglove.token_file`): read by the daemon when
//! it starts and by the configuration's check, which must refuse what the daemon would.
use std::os::unix::fs::MetadataExt;
use std::path::Path;

/// Why a token file cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum TokenError {
    #[error("{0}")]
    Io(#[from] std::io::Error),
    #[error("readable by every user (mode {0:o}); make it 0640 for the operators' group")]
    WorldReadable(u32),
    #[error("empty: its first line is the token")]
    Empty,
    #[error(
        "the token (the first line) has {0} characters: at least {MIN_TOKEN_CHARS} (e.g. \
         `openssl rand -hex 16`), so that it cannot be guessed"
    )]
    TooShort(usize),
}

/// The shortest token accepted, characters.
pub const MIN_TOKEN_CHARS: usize = 16;

/// The token: the file's first line (trimmed), at least [`MIN_TOKEN_CHARS`] long, from
/// a file that not every user can read.
pub fn read_token(path: &Path) -> Result<String, TokenError> {
    let meta = std::fs::metadata(path)?;
    if meta.mode() & 0o004 != 0 {
        return Err(TokenError::WorldReadable(meta.mode() & 0o777));
    }
    let text = std::fs::read_to_string(path)?;
    let token = text.lines().next().unwrap_or_default().trim().to_owned();
    if token.is_empty() {
        return Err(TokenError::Empty);
    }
    let n = token.chars().count();
    if n < MIN_TOKEN_CHARS {
        return Err(TokenError::TooShort(n));
    }
    Ok(token)
}

#[cfg(test)]
mod tests {
    use std::os::unix::fs::PermissionsExt;

    use super::*;

    #[test]
    fn a_token_file_every_user_can_read_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("token");
        std::fs::write(&f, "0123456789abcdef\nignored\n").unwrap();
        std::fs::set_permissions(&f, std::fs::Permissions::from_mode(0o640)).unwrap();
        assert_eq!(read_token(&f).unwrap(), "0123456789abcdef");
        std::fs::set_permissions(&f, std::fs::Permissions::from_mode(0o644)).unwrap();
        assert!(matches!(
            read_token(&f),
            Err(TokenError::WorldReadable(0o644))
        ));
        std::fs::write(&f, "\n").unwrap();
        std::fs::set_permissions(&f, std::fs::Permissions::from_mode(0o600)).unwrap();
        assert!(matches!(read_token(&f), Err(TokenError::Empty)));
    }

    #[test]
    fn a_short_token_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("token");
        std::fs::write(&f, " correct-horse \n").unwrap();
        std::fs::set_permissions(&f, std::fs::Permissions::from_mode(0o600)).unwrap();
        let e = read_token(&f).unwrap_err();
        assert!(matches!(e, TokenError::TooShort(13)), "{e}");
        assert!(e.to_string().contains("at least 16"), "{e}");
        std::fs::write(&f, "correct-horse-battery\n").unwrap();
        assert_eq!(read_token(&f).unwrap(), "correct-horse-battery");
    }
}
