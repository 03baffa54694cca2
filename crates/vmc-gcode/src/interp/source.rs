//! The program's text as a seekable source: lines are read where execution is, not held.
//!
//! A [`LineSource`] reads one physical line at a byte offset (buffered: reading on from where
//! the last line ended, or jumping back into the bytes still buffered, costs no system call).
//! [`next_line`] applies the program rules of [`crate::syntax::parse_program`] from a
//! position: blank lines, comment-only lines and the opening `%` are skipped, the closing `%`
//! ends the text. Lines are split at `\n` with one trailing `\r` dropped (as `str::lines`);
//! bytes that are not UTF-8 become U+FFFD, line by line (a line break never falls inside a
//! character, so this equals decoding the whole text). A line's place is a [`Pos`]; an
//! O-word line's, with its keyword and name, an [`OEntry`] (what `program` holds of the text).

use std::io::{BufRead, BufReader, Read, Seek, SeekFrom};

use crate::syntax::{parse_line, GcodeError, Line, OKind, OName};

/// A program's bytes: a file, or an in-memory text (`std::io::Cursor`).
pub trait ProgramSource: Read + Seek + Send {}

impl<T: Read + Seek + Send> ProgramSource for T {}

/// A line's place: its file (0: the main program, k: the k-th subroutine file), the byte
/// offset where it starts, its 1-based physical line number. Ordered as the lines follow one
/// another: the main program, then the subroutine files' definitions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub(super) struct Pos {
    pub file: usize,
    pub offset: u64,
    pub line: usize,
}

/// One O-word line: where it is, where the line after it is, its keyword, name and column.
#[derive(Debug, Clone)]
pub(super) struct OEntry {
    pub pos: Pos,
    pub next: Pos,
    pub kind: OKind,
    pub name: OName,
    pub col: usize,
}

impl Reading {
    /// The places, in file `file`, of the line just read (at `offset`, numbered `line`) and
    /// of where this reading now is (the line after it).
    pub(super) fn places(&self, file: usize, offset: u64, line: usize) -> (Pos, Pos) {
        let here = Pos { file, offset, line };
        let next = Pos {
            file,
            offset: self.offset,
            line: self.line,
        };
        (here, next)
    }
}

/// Buffered line reader over a [`ProgramSource`], positioned by byte offsets.
pub(super) struct LineSource {
    reader: BufReader<Box<dyn ProgramSource>>,
    /// Offset of the reader's next byte.
    pos: u64,
    /// The last line read (bytes, line break included).
    buf: Vec<u8>,
}

impl std::fmt::Debug for LineSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LineSource")
            .field("pos", &self.pos)
            .finish()
    }
}

impl LineSource {
    /// A reader from the source's present position (offsets are the source's own).
    pub(super) fn new(mut source: Box<dyn ProgramSource>) -> std::io::Result<Self> {
        let pos = source.stream_position()?;
        Ok(Self {
            reader: BufReader::with_capacity(64 * 1024, source),
            pos,
            buf: Vec::new(),
        })
    }

    /// The offset the source was at when it was given (where its text starts).
    pub(super) fn start(&self) -> u64 {
        self.pos
    }

    /// Moves the reader to `offset`.
    fn seek_to(&mut self, offset: u64) -> std::io::Result<()> {
        if offset != self.pos {
            // Within the buffered bytes this moves in the buffer only.
            let delta = i64::try_from(offset).unwrap_or(i64::MAX)
                - i64::try_from(self.pos).unwrap_or(i64::MAX);
            match self.reader.seek_relative(delta) {
                Ok(()) => {}
                Err(_) => {
                    self.reader.seek(SeekFrom::Start(offset))?;
                }
            }
            self.pos = offset;
        }
        Ok(())
    }

    /// The physical line starting at `offset` (without its line break) and the offset after
    /// it; `None` at the end of the text.
    fn read_at(
        &mut self,
        offset: u64,
    ) -> std::io::Result<Option<(std::borrow::Cow<'_, str>, u64)>> {
        self.seek_to(offset)?;
        self.buf.clear();
        let n = self.reader.read_until(b'\n', &mut self.buf)?;
        if n == 0 {
            return Ok(None);
        }
        self.pos += n as u64;
        let mut text = self.buf.as_slice();
        if let Some(t) = text.strip_suffix(b"\n") {
            text = t.strip_suffix(b"\r").unwrap_or(t);
        }
        Ok(Some((String::from_utf8_lossy(text), self.pos)))
    }
}

/// Where reading is: the offset and 1-based physical number of the next line, and whether
/// the program's content has begun (a `%` line then closes it).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Reading {
    pub offset: u64,
    pub line: usize,
    pub seen_content: bool,
}

/// What [`next_line`] found.
#[derive(Debug)]
pub(super) enum Next {
    /// A line that does something, starting at this offset.
    Line(u64, Line),
    /// The end of the text: `end` or the source's end, or a closing `%` (the reading then
    /// stays at it).
    End,
}

/// Reads from `at` the next line that does something, not beyond offset `end`. On a syntax
/// error (or a source that cannot be read) the reading stays at the offending line.
pub(super) fn next_line(
    src: &mut LineSource,
    at: &mut Reading,
    end: u64,
) -> Result<Next, GcodeError> {
    loop {
        if at.offset >= end {
            return Ok(Next::End);
        }
        let (start, number) = (at.offset, at.line);
        let read = src
            .read_at(start)
            .map_err(|e| GcodeError::invalid(number, 1, format!("cannot read the program: {e}")))?;
        let Some((text, next)) = read else {
            return Ok(Next::End);
        };
        let trimmed = text.trim();
        if trimmed == "%" && at.seen_content {
            // Closing `%`: LinuxCNC ignores everything after it.
            return Ok(Next::End);
        }
        let parsed = match trimmed.is_empty() || trimmed == "%" {
            true => None,
            false => parse_line(number, &text)?,
        };
        if !trimmed.is_empty() {
            at.seen_content = true;
        }
        at.offset = next;
        at.line += 1;
        if let Some(l) = parsed {
            return Ok(Next::Line(start, l));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lines_of(text: &str) -> Vec<(u64, usize)> {
        let mut src =
            LineSource::new(Box::new(std::io::Cursor::new(text.as_bytes().to_vec()))).unwrap();
        let mut at = Reading {
            offset: 0,
            line: 1,
            seen_content: false,
        };
        let mut out = Vec::new();
        while let Next::Line(offset, l) = next_line(&mut src, &mut at, u64::MAX).unwrap() {
            out.push((offset, l.line));
        }
        out
    }

    #[test]
    fn lines_are_found_as_parse_program_finds_them() {
        let text = "\n%\r\nG0 X1\r\n(c)\n\nG1 X2\n%\nG1 X3\n";
        let mine: Vec<usize> = lines_of(text).iter().map(|l| l.1).collect();
        let reference: Vec<usize> = crate::syntax::parse_program(text)
            .map(|l| l.unwrap().line)
            .collect();
        assert_eq!(mine, reference);
        assert_eq!(lines_of(text)[0].0, 4);
    }

    #[test]
    fn a_jump_back_into_the_buffer_reads_the_same_line_again() {
        let text = "G0 X1\nG0 X2\nG0 X3";
        let mut src =
            LineSource::new(Box::new(std::io::Cursor::new(text.as_bytes().to_vec()))).unwrap();
        let first = src.read_at(6).unwrap().unwrap().0.into_owned();
        src.read_at(12).unwrap();
        assert_eq!(src.read_at(6).unwrap().unwrap().0, first);
        assert_eq!(src.read_at(12).unwrap().unwrap(), ("G0 X3".into(), 17));
        assert!(src.read_at(17).unwrap().is_none());
    }
}
