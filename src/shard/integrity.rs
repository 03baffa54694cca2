//! Integrity of a shard's result files: the shard lists each file it wrote in `shard.json` with
//! its size and 64-bit FNV-1a hash ([`super::fnv1a64`], offset basis 0xcbf29ce484222325, prime
//! 0x100000001b3, over the file's bytes); `merge` reads only listed files and refuses any whose
//! size or hash differ. FNV-1a is not a cryptographic hash: it catches a file edited, emptied,
//! truncated or replaced by mistake (and any change a person makes by hand), not a forgery
//! made to collide on purpose.

use std::path::Path;

use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};

use super::{fnv1a64, ShardManifest, MANIFEST_FILE, MANIFEST_FORMAT};
use crate::files;

/// One result file of a shard, as its shard wrote it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ResultFile {
    /// File name in the shard folder.
    pub name: String,
    /// Size, bytes.
    pub bytes: u64,
    /// FNV-1a 64 of its bytes, 16 hex digits.
    pub fnv1a64: String,
}

impl ResultFile {
    fn of(name: &str, bytes: &[u8]) -> Self {
        Self {
            name: name.to_string(),
            bytes: bytes.len() as u64,
            fnv1a64: format!("{:016x}", fnv1a64(bytes)),
        }
    }
}

/// Lists the result files `names` of `dir` in `manifest` (size and hash of what is on disk
/// now) and writes the manifest as `dir/shard.json`; the last file a shard writes.
///
/// # Errors
/// A result file that cannot be read; the manifest cannot be written.
pub fn write_manifest(
    dir: &Path,
    mut manifest: ShardManifest,
    names: &[String],
    force: bool,
) -> Result<std::path::PathBuf> {
    manifest.results = names
        .iter()
        .map(|n| {
            let bytes = std::fs::read(dir.join(n))
                .with_context(|| format!("{}: cannot read", dir.join(n).display()))?;
            Ok(ResultFile::of(n, &bytes))
        })
        .collect::<Result<_>>()?;
    let path = dir.join(MANIFEST_FILE);
    let json = serde_json::to_string_pretty(&manifest)?;
    files::write_atomic(&path, json.as_bytes(), force)?;
    Ok(path)
}

/// Checks the layout version of a shard's manifest and every result file it lists against its
/// size and hash.
///
/// # Errors
/// Another layout version, a listed file missing, or changed since its shard wrote it.
pub fn verify(dir: &Path, manifest: &ShardManifest) -> Result<()> {
    if manifest.format != MANIFEST_FORMAT {
        bail!(
            "{}: shard layout version {} (this version merges version {MANIFEST_FORMAT}, which \
             lists a checksum of each result file); run the shard again with this version",
            dir.join(MANIFEST_FILE).display(),
            manifest.format
        );
    }
    for f in &manifest.results {
        let path = dir.join(&f.name);
        if Path::new(&f.name).components().count() != 1 {
            bail!(
                "{}: result file name `{}` is not a plain file name",
                dir.join(MANIFEST_FILE).display(),
                f.name
            );
        }
        let bytes = std::fs::read(&path).with_context(|| {
            format!(
                "{}: cannot read (listed in {MANIFEST_FILE} of its shard)",
                path.display()
            )
        })?;
        let now = ResultFile::of(&f.name, &bytes);
        if now != *f {
            bail!(
                "{}: changed since its shard wrote it ({} bytes, FNV-1a {}; {MANIFEST_FILE} \
                 says {} bytes, FNV-1a {}); run that shard again",
                path.display(),
                now.bytes,
                now.fnv1a64,
                f.bytes,
                f.fnv1a64
            );
        }
    }
    Ok(())
}

/// True if the shard's manifest lists `name` among its checked result files.
pub fn lists(manifest: &ShardManifest, name: &str) -> bool {
    manifest.results.iter().any(|f| f.name == name)
}

/// Fails unless the manifest lists `name` (a file merge is about to read).
///
/// # Errors
/// `name` is not among the checked result files.
pub fn require(dir: &Path, manifest: &ShardManifest, name: &str) -> Result<()> {
    if !lists(manifest, name) {
        bail!(
            "{}: not listed among the result files of {} (its checksum is unknown); run that \
             shard again",
            dir.join(name).display(),
            dir.join(MANIFEST_FILE).display()
        );
    }
    Ok(())
}
