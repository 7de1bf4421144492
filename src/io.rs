//! Atomic file output: every file this crate (and its examples) writes — CSV, PNG, VTK,
//! checkpoints — is written in full to a uniquely named temporary file beside its target,
//! flushed to disk, and only then renamed over the target. A run killed mid-write leaves the
//! previous version (or no file) under the target's name, never a truncated one; at worst a
//! stray `.<name>.*.partial` file remains beside it.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use crate::error::{Error, Result};

/// An [`Error::Io`] for `path`.
pub(crate) fn io_error(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::Io { path: path.display().to_string(), message: e.to_string() }
}

/// Makes `path` appear complete or not at all: `write` creates the file at the temporary path
/// it is given (for writers that want a path, such as a plotting backend); the file is then
/// flushed to disk and renamed over `path`. The temporary file is removed if `write` fails.
///
/// Errors: [`Error::Io`] naming the path when the folder cannot hold the file or the rename
/// fails; `write`'s own error is passed on unchanged.
pub fn replace_atomically<E: From<Error>>(
    path: &Path,
    write: impl FnOnce(&Path) -> core::result::Result<(), E>,
) -> core::result::Result<(), E> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let extension =
        path.extension().map(|e| format!(".{}", e.to_string_lossy())).unwrap_or_default();
    // The target's extension last, so writers that pick a format by extension see the right one.
    let (prefix, suffix) = (format!(".{name}."), format!(".partial{extension}"));
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix).suffix(&suffix);
    // Ordinary file permissions (the process's umask applies), not a temporary file's 0600.
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
    let tmp = builder.tempfile_in(dir).map_err(|e| E::from(io_error(path, e)))?.into_temp_path();
    write(&tmp)?;
    File::open(&tmp).and_then(|f| f.sync_all()).map_err(|e| E::from(io_error(&tmp, e)))?;
    tmp.persist(path).map_err(|e| E::from(io_error(path, e.error)))?;
    Ok(())
}

/// Writes `path` atomically through a buffered writer (see [`replace_atomically`]).
///
/// ```
/// use std::io::Write;
/// let path = std::env::temp_dir().join("discrete_contact_io_doc.csv");
/// discrete_contact::io::write_atomically(&path, |w| writeln!(w, "t,x\n0,1"))?;
/// assert_eq!(std::fs::read_to_string(&path).unwrap(), "t,x\n0,1\n");
/// # Ok::<(), discrete_contact::Error>(())
/// ```
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> std::io::Result<()>,
) -> Result<()> {
    replace_atomically(path, |tmp: &Path| -> Result<()> {
        let mut w = BufWriter::new(File::create(tmp).map_err(|e| io_error(tmp, e))?);
        write(&mut w).and_then(|()| w.flush()).map_err(|e| io_error(tmp, e))
    })
}
