//! Files the application writes: checking outputs before any work, and writing atomically.
//!
//! Every file the tool writes goes through [`write_atomic`] (temporary file in the same folder,
//! then rename), and an existing file is never replaced unless the caller allows it (`--force`).
//! Outputs are checked with [`check_writable`] / [`prepare_output_folder`] before any
//! simulation starts, so a wrong path costs no minutes of work.

use std::io::Write;
use std::path::{Path, PathBuf};

use thiserror::Error;

/// Reading text inputs is the machine crate's (`vmc_machine::read`); the commands read and
/// write through this one module.
pub use vmc_machine::read::{one_line_toml_error, read_named, read_text, ReadError};

/// A file could not be written.
#[derive(Debug, Error)]
pub enum OutputError {
    /// The file exists and overwriting was not allowed.
    #[error("{0}: already exists (pass --force to overwrite)")]
    Exists(PathBuf),
    /// The path names a folder, not a file.
    #[error("{0}: is a folder; give a file name")]
    IsFolder(PathBuf),
    /// The file's folder does not exist.
    #[error("{path}: the folder {folder} does not exist")]
    NoFolder {
        /// The file.
        path: PathBuf,
        /// Its folder.
        folder: PathBuf,
    },
    /// The output folder could not be created.
    #[error("{}: cannot create output folder: {err}", path.display())]
    Folder {
        /// The folder.
        path: PathBuf,
        /// Why.
        err: std::io::Error,
    },
    /// An I/O failure.
    #[error("{path}: {err}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        err: std::io::Error,
    },
}

/// Checks up front, before any work, that `path` may be written: it is not a folder, its
/// folder exists, and the file does not exist unless `force`.
pub fn check_writable(path: &Path, force: bool) -> Result<(), OutputError> {
    if path.is_dir() {
        return Err(OutputError::IsFolder(path.to_path_buf()));
    }
    if let Some(folder) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        if !folder.is_dir() {
            return Err(OutputError::NoFolder {
                path: path.to_path_buf(),
                folder: folder.to_path_buf(),
            });
        }
    }
    if path.exists() && !force {
        return Err(OutputError::Exists(path.to_path_buf()));
    }
    Ok(())
}

/// Writes `contents` to `path` atomically (temporary file + rename). Refuses to replace an
/// existing file unless `force`.
pub fn write_atomic(path: &Path, contents: &[u8], force: bool) -> Result<(), OutputError> {
    write_atomic_with(path, force, |w| w.write_all(contents))
}

/// Writes `path` atomically with what `write` writes to it, through a buffer (for contents
/// produced piece by piece). Refuses to replace an existing file unless `force`.
pub fn write_atomic_with(
    path: &Path,
    force: bool,
    write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<(), OutputError> {
    check_writable(path, force)?;
    let io = |err| OutputError::Io {
        path: path.to_path_buf(),
        err,
    };
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default();
    let tmp = dir.join(format!(".{name}.tmp-{}", std::process::id()));
    let result = (|| {
        let mut f = std::io::BufWriter::new(std::fs::File::create(&tmp)?);
        write(&mut f)?;
        let f = f.into_inner().map_err(|e| e.into_error())?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(io)
}

/// Creates the output folder `dir` (with its parents) and checks that each of `names` may be
/// written in it (see [`check_writable`]); gives the files' paths in the order of `names`.
///
/// # Errors
/// The folder cannot be created, or a file may not be written.
pub fn prepare_output_folder(
    dir: &Path,
    names: &[String],
    force: bool,
) -> Result<Vec<PathBuf>, OutputError> {
    std::fs::create_dir_all(dir).map_err(|err| OutputError::Folder {
        path: dir.to_path_buf(),
        err,
    })?;
    let files: Vec<PathBuf> = names.iter().map(|n| dir.join(n)).collect();
    for f in &files {
        check_writable(f, force)?;
    }
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atomic_write_refuses_to_overwrite_without_force() {
        let dir = std::env::temp_dir().join(format!("vmc-report-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = dir.join("a.txt");
        let _ = std::fs::remove_file(&f);
        write_atomic(&f, b"one", false).unwrap();
        assert!(matches!(
            write_atomic(&f, b"two", false),
            Err(OutputError::Exists(_))
        ));
        assert_eq!(std::fs::read(&f).unwrap(), b"one");
        write_atomic(&f, b"two", true).unwrap();
        assert_eq!(std::fs::read(&f).unwrap(), b"two");
        // A folder as the file, even with --force, and a missing folder: refused up front.
        assert!(matches!(
            check_writable(&dir, true),
            Err(OutputError::IsFolder(_))
        ));
        let missing = dir.join("no-such-folder").join("m.json");
        assert_eq!(
            check_writable(&missing, true).unwrap_err().to_string(),
            format!(
                "{}: the folder {} does not exist",
                missing.display(),
                dir.join("no-such-folder").display()
            )
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
