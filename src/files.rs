//! Files the application writes: checking outputs before any work, and writing atomically.
//!
//! Every file the tool writes goes through [`write_atomic`] (temporary file in the same folder,
//! then link or rename), and an existing file is never replaced unless the caller allows it
//! (`--force`). Outputs are checked with [`check_writable`] / [`prepare_output_folder`] before
//! any simulation starts, so a wrong path costs no minutes of work.
//!
//! What may never happen, whatever the options:
//! - an input of the command is written over (the same file under any name: compared by
//!   device and inode, see `vmc_machine::read::is_input`), even with `--force`;
//! - a symbolic link, socket or folder is replaced: refused, even with `--force`;
//! - a device node or FIFO (`/dev/null`, a named pipe) is replaced by a regular file: with
//!   `--force` the contents are written through to it (not atomically), without it refused;
//! - two writers racing for a new name both succeed: without `--force` the final name is
//!   created exclusively (a hard link from the finished temporary file, which fails if the
//!   name exists), so the loser gets "already exists" and the winner's file stays.

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
    /// The path is one of the command's own inputs.
    #[error("{0}: is an input of this command; write the output to another file")]
    IsInput(PathBuf),
    /// The path is a symbolic link, socket or other file that is never replaced.
    #[error("{path}: is a {kind}, not a regular file; give the path of a regular file")]
    NotRegular {
        /// The file.
        path: PathBuf,
        /// What it is.
        kind: &'static str,
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
    let Ok(meta) = std::fs::symlink_metadata(path) else {
        return Ok(());
    };
    if vmc_machine::read::is_input(path) {
        return Err(OutputError::IsInput(path.to_path_buf()));
    }
    match target_kind(&meta) {
        Target::Regular | Target::Device if !force => Err(OutputError::Exists(path.to_path_buf())),
        Target::Regular | Target::Device => Ok(()),
        Target::Never(kind) => Err(OutputError::NotRegular {
            path: path.to_path_buf(),
            kind,
        }),
    }
}

/// What an existing output path is, for writing.
enum Target {
    /// A regular file: replaced atomically (with `--force`).
    Regular,
    /// A device node or FIFO: written through (with `--force`).
    Device,
    /// Never written: what it is.
    Never(&'static str),
}

fn target_kind(meta: &std::fs::Metadata) -> Target {
    let t = meta.file_type();
    if t.is_file() {
        return Target::Regular;
    }
    if t.is_symlink() {
        return Target::Never("symbolic link");
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_char_device() || t.is_block_device() || t.is_fifo() {
            return Target::Device;
        }
        if t.is_socket() {
            return Target::Never("socket");
        }
    }
    Target::Never("special file")
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
    let mut file = AtomicFile::create(path, force)?;
    write(&mut file).map_err(|err| OutputError::Io {
        path: path.to_path_buf(),
        err,
    })?;
    file.finish()
}

/// A file written as its contents are produced (a run's table, row by row): into a temporary
/// file in the target's folder, which [`AtomicFile::finish`] gives its name (see [`publish`]).
/// Dropped unfinished (an error, an interrupted run), the temporary file is removed: no
/// partial file is ever left under the final name. A device node or FIFO target (with
/// `--force`) is written through instead.
pub struct AtomicFile {
    path: PathBuf,
    force: bool,
    /// The temporary file (None: writing through to a device).
    tmp: Option<PathBuf>,
    out: Option<std::io::BufWriter<std::fs::File>>,
}

impl AtomicFile {
    /// Checks that `path` may be written ([`check_writable`]) and opens the temporary file.
    ///
    /// # Errors
    /// The checks', and the temporary file cannot be created.
    pub fn create(path: &Path, force: bool) -> Result<Self, OutputError> {
        check_writable(path, force)?;
        let io = |err| OutputError::Io {
            path: path.to_path_buf(),
            err,
        };
        if let Ok(meta) = std::fs::symlink_metadata(path) {
            if let Target::Device = target_kind(&meta) {
                // Never rename over a device or FIFO: write through it.
                let f = std::fs::OpenOptions::new()
                    .write(true)
                    .open(path)
                    .map_err(io)?;
                return Ok(Self {
                    path: path.to_path_buf(),
                    force,
                    tmp: None,
                    out: Some(std::io::BufWriter::new(f)),
                });
            }
        }
        let dir = path
            .parent()
            .filter(|d| !d.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().to_string())
            .unwrap_or_default();
        static WRITES: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let n = WRITES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let tmp = dir.join(format!(".{name}.tmp-{}-{n}", std::process::id()));
        let f = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)
            .map_err(io)?;
        Ok(Self {
            path: path.to_path_buf(),
            force,
            tmp: Some(tmp),
            out: Some(std::io::BufWriter::new(f)),
        })
    }

    /// The file's final path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Flushes, syncs and gives the file its name (removing the temporary file).
    ///
    /// # Errors
    /// Writing, syncing or publishing failed (the temporary file is removed).
    pub fn finish(mut self) -> Result<(), OutputError> {
        let io = |err| OutputError::Io {
            path: self.path.clone(),
            err,
        };
        let Some(out) = self.out.take() else {
            return Ok(());
        };
        let f = out.into_inner().map_err(|e| io(e.into_error()))?;
        let Some(tmp) = self.tmp.clone() else {
            return Ok(());
        };
        f.sync_all().map_err(io)?;
        let result = publish(&tmp, &self.path, self.force);
        let _ = std::fs::remove_file(&tmp);
        self.tmp = None;
        result
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        match self.out.as_mut() {
            Some(w) => w.write(buf),
            None => Err(std::io::Error::other("the file is finished")),
        }
    }

    fn flush(&mut self) -> std::io::Result<()> {
        match self.out.as_mut() {
            Some(w) => w.flush(),
            None => Ok(()),
        }
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        // Unfinished: nothing may be left that looks like a finished file.
        drop(self.out.take());
        if let Some(tmp) = self.tmp.take() {
            let _ = std::fs::remove_file(tmp);
        }
    }
}

/// Gives the finished temporary file `tmp` its final name `path` (the caller removes `tmp`
/// afterwards: after a hard link it still exists). Without `force` the name is
/// created exclusively: a hard link fails if the name exists (someone else won the race),
/// and where hard links are not supported the name is first claimed with an exclusive create.
/// With `force` an existing regular file is replaced by a rename, after checking again that
/// nothing else (a link, a device) took its place.
pub fn publish(tmp: &Path, path: &Path, force: bool) -> Result<(), OutputError> {
    let io = |err| OutputError::Io {
        path: path.to_path_buf(),
        err,
    };
    let exists = || OutputError::Exists(path.to_path_buf());
    if !force {
        return match std::fs::hard_link(tmp, path) {
            Ok(()) => Ok(()),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Err(exists()),
            Err(_) => {
                // No hard links here (some network and FAT file systems): claim the name.
                match std::fs::OpenOptions::new()
                    .write(true)
                    .create_new(true)
                    .open(path)
                {
                    Ok(_) => std::fs::rename(tmp, path).map_err(io),
                    Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Err(exists()),
                    Err(e) => Err(io(e)),
                }
            }
        };
    }
    check_writable(path, true)?;
    if let Ok(meta) = std::fs::symlink_metadata(path) {
        if !matches!(target_kind(&meta), Target::Regular) {
            return Err(OutputError::NotRegular {
                path: path.to_path_buf(),
                kind: "file that is not a regular file",
            });
        }
    }
    std::fs::rename(tmp, path).map_err(io)
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

    #[test]
    fn a_file_written_piece_by_piece_appears_only_when_finished() {
        let dir = std::env::temp_dir().join(format!("vmc-atomic-file-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = dir.join("rows.csv");
        let _ = std::fs::remove_file(&f);
        {
            let mut w = AtomicFile::create(&f, false).unwrap();
            w.write_all(b"a,b\n").unwrap();
            // Dropped unfinished (an error on the way): no file, no temporary left.
        }
        assert!(!f.exists());
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
        let mut w = AtomicFile::create(&f, false).unwrap();
        w.write_all(b"a,b\n").unwrap();
        assert!(!f.exists(), "visible before it is finished");
        w.write_all(b"1,2\n").unwrap();
        w.finish().unwrap();
        assert_eq!(std::fs::read(&f).unwrap(), b"a,b\n1,2\n");
        assert!(matches!(
            AtomicFile::create(&f, false),
            Err(OutputError::Exists(_))
        ));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
