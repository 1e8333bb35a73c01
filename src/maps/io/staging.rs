//! Atomic output: each file is written to a hidden temporary file beside its destination and renamed into place only
//! once every output is complete.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::error::SkinError;

/// A finished output file waiting in a temporary file beside its destination. [`commit_all`] (or
/// [`Staged::commit`]) renames it into place; dropping it un-committed deletes the temporary file and leaves the
/// destination untouched.
#[derive(Debug)]
pub struct Staged {
    temp: Option<tempfile::TempPath>,
    target: PathBuf,
    compression: Option<super::Compression>,
}

impl Staged {
    /// A finished temporary file (from [`create_temp`]) that is to become `target`.
    pub(super) fn from_temp(temp: tempfile::NamedTempFile, target: &Path) -> Staged {
        Staged { temp: Some(temp.into_temp_path()), target: target.to_path_buf(), compression: None }
    }

    /// The same file, recorded as an EXR written with `compression`.
    pub(super) fn with_compression(mut self, compression: super::Compression) -> Staged {
        self.compression = Some(compression);
        self
    }

    /// For an EXR, the compression it was written with (never [`super::Compression::Auto`]); `None` for other files.
    pub fn compression(&self) -> Option<super::Compression> {
        self.compression
    }

    /// The final path this file will be renamed to.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// The temporary file currently holding the data.
    pub fn temp_path(&self) -> Option<&Path> {
        self.temp.as_deref()
    }

    /// Rename this one file into place (replacing an existing file).
    pub fn commit(self) -> Result<(), SkinError> {
        commit_all(vec![self])
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if let Some(temp) = self.temp.take() {
            // Best effort: the file is in the destination directory, hidden by its leading dot.
            let _ = temp.close();
        }
    }
}

/// Rename every staged file into place, in order. Before the first rename every destination is checked (not a
/// directory, not named twice, its directory still exists); a check failure renames nothing and deletes all
/// temporary files. Each rename is atomic (same directory), so each destination holds either its old or its new
/// content; if a rename itself fails part-way (rare: e.g. the directory vanished), the files before it are already
/// replaced, and the remaining temporary files are deleted.
pub fn commit_all(staged: Vec<Staged>) -> Result<(), SkinError> {
    for (i, s) in staged.iter().enumerate() {
        if s.target.is_dir() {
            return Err(SkinError::io(&s.target, "cannot write output: expected a file path, found a directory"));
        }
        if staged[..i].iter().any(|earlier| earlier.target == s.target) {
            return Err(SkinError::io(&s.target, "cannot write output: the same file is written twice"));
        }
        if s.temp.as_ref().map_or(true, |t| !t.exists()) {
            return Err(SkinError::io(&s.target, "cannot write output: its temporary file has disappeared"));
        }
    }
    let mut dirs: Vec<PathBuf> = Vec::new();
    for mut s in staged {
        let Some(temp) = s.temp.take() else { continue };
        temp.persist(&s.target).map_err(|e| {
            SkinError::io_caused(&s.target, format!("cannot move the finished file into place: {}", e.error), e.error)
        })?;
        let dir = parent_dir(&s.target).to_path_buf();
        if !dirs.contains(&dir) {
            dirs.push(dir);
        }
    }
    // Make the renames durable (best effort; not supported everywhere).
    #[cfg(unix)]
    for dir in dirs {
        if let Ok(d) = std::fs::File::open(&dir) {
            let _ = d.sync_all();
        }
    }
    Ok(())
}

fn parent_dir(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// Create the temporary file beside `path`, after checking that the directory exists and `path` is not a directory.
pub(super) fn create_temp(path: &Path) -> Result<tempfile::NamedTempFile, SkinError> {
    let Some(name) = path.file_name() else {
        return Err(SkinError::io(path, "cannot write output: expected a file path, found none"));
    };
    let dir = parent_dir(path);
    if !dir.is_dir() {
        return Err(SkinError::io(
            path,
            format!("cannot write output: expected an existing directory {}; found none", dir.display()),
        ));
    }
    if path.is_dir() {
        return Err(SkinError::io(path, "cannot write output: expected a file path, found a directory"));
    }
    let prefix = format!(".{}.", name.to_string_lossy());
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix).suffix(".tmp");
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        // Like a plain File::create: 0666 minus the umask (tempfile's default would be 0600).
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    builder.tempfile_in(dir).map_err(|e| {
        let reason = format!("cannot write output: cannot create a temporary file in {}: {e}", dir.display());
        SkinError::io_caused(path, reason, e)
    })
}

/// Write `bytes` to a temporary file beside `path` (flushed to disk); [`commit_all`] renames it into place.
/// The directory must exist.
pub fn stage_bytes(path: &Path, bytes: &[u8]) -> Result<Staged, SkinError> {
    let mut temp = create_temp(path)?;
    let fail = |e: std::io::Error| SkinError::io_caused(path, format!("cannot write output: {e}"), e);
    temp.write_all(bytes).map_err(fail)?;
    temp.as_file().sync_all().map_err(fail)?;
    Ok(Staged::from_temp(temp, path))
}

/// Write bytes atomically (temp file in the destination directory + rename); used for the JSON sidecar.
/// The directory must exist.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), SkinError> {
    stage_bytes(path, bytes)?.commit()
}

/// Check, before any work starts and without creating anything, that outputs can be written in `dir`: it is a
/// folder where a file can be created (a hidden temporary file, removed at once), or it is missing and its nearest
/// existing ancestor is such a folder (so [`create_output_dir`] can make it). The error names the folder and says
/// what is wrong, so a run fails in a second rather than after its whole computation; a failed run leaves no folder.
pub fn check_output_dir(dir: &Path) -> Result<(), SkinError> {
    let dir = if dir.as_os_str().is_empty() { Path::new(".") } else { dir };
    // The nearest existing ancestor (the folder itself if it exists); the operating system's error (a file in the
    // way: "not a directory") is kept as the source, with its code.
    let mut existing = dir;
    loop {
        match std::fs::metadata(existing) {
            Ok(meta) if meta.is_dir() => break,
            Ok(_) => {
                let reason = if existing == dir {
                    "cannot use it as the output folder: expected a folder, found a file".to_string()
                } else {
                    format!("cannot create the output folder: {} is a file, not a folder", existing.display())
                };
                return Err(SkinError::io(dir, reason));
            }
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                // A symbolic link whose target is missing cannot be created as a folder ("File exists").
                if let Ok(target) = std::fs::read_link(existing) {
                    return Err(SkinError::io(
                        dir,
                        format!(
                            "cannot create the output folder: {} is a symbolic link to {}, which does not exist                              (create its target, or give another folder)",
                            existing.display(),
                            target.display()
                        ),
                    ));
                }
                existing = match existing.parent() {
                    Some(p) if !p.as_os_str().is_empty() => p,
                    _ => Path::new("."),
                };
            }
            Err(e) => {
                let reason = format!(
                    "cannot create the output folder: {e} (expected a path whose existing part is folders; a file \
                     is in the way, or it cannot be reached)"
                );
                return Err(SkinError::io_caused(dir, reason, e));
            }
        }
    }
    tempfile::Builder::new().prefix(".spectral-skin-check.").suffix(".tmp").tempfile_in(existing).map(drop).map_err(
        |e| {
            let reason = if existing == dir {
                format!("cannot write in the output folder: {e} (expected a folder where files can be created)")
            } else {
                format!("cannot create the output folder in {}: {e}", existing.display())
            };
            SkinError::io_caused(dir, reason, e)
        },
    )
}

/// [`check_output_dir`], then create `dir` (and its parents) if missing: what a writer calls just before staging.
pub fn create_output_dir(dir: &Path) -> Result<(), SkinError> {
    check_output_dir(dir)?;
    let dir = if dir.as_os_str().is_empty() { Path::new(".") } else { dir };
    std::fs::create_dir_all(dir)
        .map_err(|e| SkinError::io_caused(dir, format!("cannot create the output folder: {e}"), e))
}

/// The folder that will hold `file` (`.` for a bare file name).
pub fn output_folder_of(file: &Path) -> &Path {
    parent_dir(file)
}
