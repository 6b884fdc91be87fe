//! The TCP token (`control.tcp_token_file`): read by the daemon when it starts and by
//! the configuration's check, which must refuse what the daemon would.
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
}

/// The token: the file's first line, which must not be empty, from a file that not
/// every user can read.
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
        std::fs::write(&f, "abc\nignored\n").unwrap();
        std::fs::set_permissions(&f, std::fs::Permissions::from_mode(0o640)).unwrap();
        assert_eq!(read_token(&f).unwrap(), "abc");
        std::fs::set_permissions(&f, std::fs::Permissions::from_mode(0o644)).unwrap();
        assert!(matches!(
            read_token(&f),
            Err(TokenError::WorldReadable(0o644))
        ));
        std::fs::write(&f, "\n").unwrap();
        std::fs::set_permissions(&f, std::fs::Permissions::from_mode(0o600)).unwrap();
        assert!(matches!(read_token(&f), Err(TokenError::Empty)));
    }
}
