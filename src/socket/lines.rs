//! Reading newline-delimited lines with a length limit. An oversize line is
//! reported once, as soon as it passes the limit, and the rest of it is skipped
//! up to its newline, so the connection stays usable and memory stays bounded.
use tokio::io::{AsyncBufReadExt, AsyncRead, BufReader};

/// What `LineReader::next` found.
#[derive(Debug, PartialEq, Eq)]
pub(crate) enum Line {
    /// A line (without its newline or a trailing `\r`) is in `LineReader::line`.
    Complete,
    /// A line passed the limit; it is being discarded.
    TooLong,
    /// The peer closed its side.
    Eof,
}

pub(crate) struct LineReader<R> {
    inner: BufReader<R>,
    max_bytes: usize,
    buf: Vec<u8>,
    /// Skipping the rest of an oversize line.
    discarding: bool,
}

impl<R: AsyncRead + Unpin> LineReader<R> {
    pub(crate) fn new(inner: R, max_bytes: usize) -> Self {
        Self {
            inner: BufReader::new(inner),
            max_bytes,
            buf: Vec::new(),
            discarding: false,
        }
    }

    /// The line found by the last `next` that returned `Complete`.
    pub(crate) fn line(&self) -> &[u8] {
        self.buf.strip_suffix(b"\r").unwrap_or(&self.buf)
    }

    /// Read the next line. Cancel-safe between lines only; callers do not cancel it.
    pub(crate) async fn next(&mut self) -> std::io::Result<Line> {
        self.buf.clear();
        loop {
            let avail = self.inner.fill_buf().await?;
            if avail.is_empty() {
                // A last line without a newline still counts.
                let had_partial = !self.buf.is_empty() && !self.discarding;
                self.discarding = false;
                return Ok(if had_partial {
                    Line::Complete
                } else {
                    Line::Eof
                });
            }
            let newline = avail.iter().position(|&b| b == b'\n');
            let (chunk_len, used) = match newline {
                Some(i) => (i, i + 1),
                None => (avail.len(), avail.len()),
            };
            if self.discarding {
                self.inner.consume(used);
                if newline.is_some() {
                    self.discarding = false;
                }
                continue;
            }
            if self.buf.len() + chunk_len > self.max_bytes {
                self.buf.clear();
                self.discarding = newline.is_none();
                self.inner.consume(used);
                return Ok(Line::TooLong);
            }
            self.buf.extend_from_slice(&avail[..chunk_len]);
            self.inner.consume(used);
            if newline.is_some() {
                return Ok(Line::Complete);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    async fn collect(input: &[u8], max: usize) -> Vec<Result<String, Line>> {
        let mut r = LineReader::new(input, max);
        let mut out = Vec::new();
        loop {
            match r.next().await.unwrap() {
                Line::Complete => out.push(Ok(String::from_utf8(r.line().to_vec()).unwrap())),
                Line::Eof => return out,
                other => out.push(Err(other)),
            }
        }
    }

    fn run<F: std::future::Future>(f: F) -> F::Output {
        tokio::runtime::Builder::new_current_thread()
            .build()
            .unwrap()
            .block_on(f)
    }

    #[test]
    fn splits_lines_and_keeps_a_last_partial_one() {
        let got = run(collect(b"a\r\nbb\n\nccc", 8));
        assert_eq!(
            got,
            vec![
                Ok("a".into()),
                Ok("bb".into()),
                Ok("".into()),
                Ok("ccc".into())
            ]
        );
    }

    #[test]
    fn oversize_lines_are_reported_once_and_skipped() {
        let mut input = vec![b'x'; 50_000];
        input.extend_from_slice(b"\nok\n12345\n123456\n");
        let got = run(collect(&input, 5));
        assert_eq!(
            got,
            vec![
                Err(Line::TooLong),
                Ok("ok".into()),
                Ok("12345".into()),
                Err(Line::TooLong)
            ]
        );
    }
}
