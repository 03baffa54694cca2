//! Reading text inputs (machine, tool, plant and program files) with errors a person can act on.
//!
//! Every file the twin reads goes through [`read_text`]: bytes that are not UTF-8 are an error
//! naming their line and column (instead of the standard library's location-free message);
//! [`read_named`] adds the file and what it should hold. Each file read is remembered
//! ([`is_input`]) so that no output of the same process can be written over one of its inputs.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use thiserror::Error;

/// Reads a text file, without a leading UTF-8 byte-order mark; bytes that are not UTF-8 are an `InvalidData` error naming their line,
/// column and value (instead of the standard library's location-free message).
pub fn read_text(path: &Path) -> std::io::Result<String> {
    let mut bytes = std::fs::read(path)?;
    note_input(path);
    // A UTF-8 byte-order mark (as spreadsheet programs write) is not text: drop it.
    if bytes.starts_with(&[0xEF, 0xBB, 0xBF]) {
        bytes.drain(..3);
    }
    String::from_utf8(bytes).map_err(|e| {
        let bad_at = e.utf8_error().valid_up_to();
        let bytes = e.as_bytes();
        let before = &bytes[..bad_at];
        let line = 1 + before.iter().filter(|&&b| b == b'\n').count();
        let line_start = before
            .iter()
            .rposition(|&b| b == b'\n')
            .map_or(0, |i| i + 1);
        not_utf8(line, &before[line_start..], bytes[bad_at])
    })
}

/// The error of a byte `bad` that is not UTF-8, on line `line` after the valid bytes
/// `line_before` of that line.
fn not_utf8(line: usize, line_before: &[u8], bad: u8) -> std::io::Error {
    // Characters (not bytes) before the bad byte on its line; the prefix is valid UTF-8.
    let col = 1 + String::from_utf8_lossy(line_before).chars().count();
    std::io::Error::new(
        std::io::ErrorKind::InvalidData,
        format!("not UTF-8 text: line {line}, column {col}: byte 0x{bad:02X}"),
    )
}

/// [`read_text`] without holding the text: checks the file line by line (the same errors)
/// and returns it open at its text (after a byte-order mark), with a hash of its bytes (to
/// tell whether it changed between two openings).
pub fn open_text(path: &Path) -> std::io::Result<(std::fs::File, u64)> {
    use std::hash::Hasher;
    use std::io::{BufRead, Seek, SeekFrom};
    let mut reader = std::io::BufReader::new(std::fs::File::open(path)?);
    note_input(path);
    let bom = reader.fill_buf()?.starts_with(&[0xEF, 0xBB, 0xBF]);
    let start = if bom { 3 } else { 0 };
    reader.consume(start);
    let mut hasher = std::collections::hash_map::DefaultHasher::new();
    let (mut line, mut number) = (Vec::new(), 0);
    loop {
        line.clear();
        if reader.read_until(b'\n', &mut line)? == 0 {
            break;
        }
        number += 1;
        if let Err(e) = std::str::from_utf8(&line) {
            let bad_at = e.valid_up_to();
            return Err(not_utf8(number, &line[..bad_at], line[bad_at]));
        }
        hasher.write(&line);
    }
    let mut file = reader.into_inner();
    file.seek(SeekFrom::Start(start as u64))?;
    Ok((file, hasher.finish()))
}

/// The identity of a file: device and inode where the platform has them (so that two names of
/// one file, through links or `..`, are the same), else its canonical path.
#[derive(Debug, Clone, PartialEq, Eq)]
enum FileIdentity {
    #[cfg(unix)]
    Inode { dev: u64, ino: u64 },
    #[cfg_attr(unix, allow(dead_code))]
    Path(PathBuf),
}

fn identity(path: &Path) -> Option<FileIdentity> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        let m = std::fs::metadata(path).ok()?;
        Some(FileIdentity::Inode {
            dev: m.dev(),
            ino: m.ino(),
        })
    }
    #[cfg(not(unix))]
    {
        std::fs::canonicalize(path).ok().map(FileIdentity::Path)
    }
}

/// The files this process has read (see [`note_input`]).
static INPUTS: Mutex<Vec<FileIdentity>> = Mutex::new(Vec::new());

/// Remembers `path` as an input of this process (done by [`read_text`]; call it for inputs
/// read another way, or before checking outputs up front). A path that does not exist is
/// ignored.
pub fn note_input(path: &Path) {
    if let Some(id) = identity(path) {
        let mut inputs = INPUTS.lock().unwrap_or_else(|p| p.into_inner());
        if !inputs.contains(&id) {
            inputs.push(id);
        }
    }
}

/// True if `path` names a file this process has read (the same file under any name), so
/// writing it would destroy an input.
pub fn is_input(path: &Path) -> bool {
    identity(path).is_some_and(|id| {
        INPUTS
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .contains(&id)
    })
}

/// Reads a text file, naming the file and what it holds in the error
/// (`FILE: cannot read WHAT: why`).
///
/// # Errors
/// [`ReadError`] when the file cannot be read or is not UTF-8.
pub fn read_named(path: &Path, what: &'static str) -> Result<String, ReadError> {
    read_text(path).map_err(|err| ReadError {
        path: path.to_path_buf(),
        what,
        err,
    })
}

/// A TOML parser's message on one line (it spans several, with a caret under the column).
pub fn one_line_toml_error(e: &toml::de::Error) -> String {
    e.to_string().trim_end().replace('\n', " ")
}

/// A file could not be read.
#[derive(Debug, Error)]
#[error("{}: cannot read {what}: {err}", path.display())]
pub struct ReadError {
    /// The file.
    pub path: PathBuf,
    /// What it should hold (e.g. `dataset`).
    pub what: &'static str,
    /// Why.
    pub err: std::io::Error,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_that_is_not_utf8_is_refused_with_its_line_and_column() {
        let dir = std::env::temp_dir().join(format!("vmc-files-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = dir.join("bad.ngc");
        std::fs::write(&f, b"G0 X1\nG1 X\xE92\n").unwrap();
        let e = read_named(&f, "program").unwrap_err().to_string();
        assert!(
            e.ends_with("cannot read program: not UTF-8 text: line 2, column 5: byte 0xE9"),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn an_opened_text_has_the_errors_of_a_read_one_and_starts_after_its_byte_order_mark() {
        use std::io::Read;
        let dir = std::env::temp_dir().join(format!("vmc-open-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (bad, good) = (dir.join("bad.ngc"), dir.join("good.ngc"));
        std::fs::write(&bad, b"G0 X1\nG1 \xC3\xA9 X\xE92\n").unwrap();
        let read = read_text(&bad).unwrap_err().to_string();
        assert_eq!(open_text(&bad).unwrap_err().to_string(), read);
        assert!(read.ends_with("line 2, column 7: byte 0xE9"), "{read}");
        std::fs::write(&good, b"\xEF\xBB\xBFG0 X1\n").unwrap();
        let (mut file, hash) = open_text(&good).unwrap();
        let mut text = String::new();
        file.read_to_string(&mut text).unwrap();
        assert_eq!(text, read_text(&good).unwrap());
        std::fs::write(&good, b"G0 X2\n").unwrap();
        assert_ne!(open_text(&good).unwrap().1, hash);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_file_read_is_an_input_under_any_of_its_names() {
        let dir = std::env::temp_dir().join(format!("vmc-inputs-test-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("sub")).unwrap();
        let f = dir.join("in.csv");
        std::fs::write(&f, "time_s\n0\n").unwrap();
        std::fs::write(dir.join("other.csv"), "x").unwrap();
        assert!(!is_input(&f));
        read_text(&dir.join("sub").join("..").join("in.csv")).unwrap();
        assert!(is_input(&f));
        assert!(!is_input(&dir.join("other.csv")));
        assert!(!is_input(&dir.join("missing.csv")));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
