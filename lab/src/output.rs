//! Writing output files so that nothing is lost or clobbered.
//!
//! Every file the crate writes (CSV, JSON, SVG, Markdown, study directories) goes through
//! [`write_atomic`] or [`AtomicFile`]: the bytes go to a temporary file in the destination's
//! directory, which is renamed over the destination only once it is complete. A run killed
//! mid-write leaves the previous file intact (and at worst a stray `.NAME.gvi-tmp-PID` file),
//! never a truncated one. [`check_output_path`] and [`ensure_distinct`] validate destinations
//! before any computation, so a bad path costs nothing.

use crate::error::LabError;
use crate::error::Result;
use std::io::Write;
use std::path::{Component, Path, PathBuf};

mod plan;
pub use plan::Plan;

/// Pseudo-filesystems whose files are not outputs (writing there fails or does harm).
const FORBIDDEN_ROOTS: [&str; 2] = ["/proc", "/sys"];

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> LabError + '_ {
    move |source| LabError::Io {
        path: path.to_path_buf(),
        source,
    }
}

fn bad_output(path: &Path, reason: impl Into<String>) -> LabError {
    LabError::InvalidOutput {
        path: path.to_path_buf(),
        reason: reason.into(),
    }
}

/// The directory a path lives in (`.` for a bare file name).
fn parent_dir(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// Create the parent directory of `path` if it is missing, saying so on stderr.
pub fn ensure_parent(path: &Path) -> Result<()> {
    let dir = parent_dir(path);
    if !dir.exists() {
        std::fs::create_dir_all(dir).map_err(io_err(dir))?;
        eprintln!("created directory {}", dir.display());
    }
    Ok(())
}

/// Whether `path` exists and is something other than a regular file or directory (a
/// character device such as `/dev/null`, a FIFO): written in place, never replaced.
fn is_special(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir())
}

/// The absolute, symlink-resolved form of a path that may not exist yet, as the kernel will
/// see it once missing directories are created: components are taken left to right, every
/// existing prefix is canonicalised (symlinks resolved, so a later `..` goes to the real
/// parent) and `..` after a prefix that does not exist yet drops it lexically (`nope/../x` is
/// `x`, as it is once `nope` has been created).
pub fn resolve(path: &Path) -> PathBuf {
    let abs = if path.is_absolute() {
        path.to_path_buf()
    } else {
        std::env::current_dir().unwrap_or_default().join(path)
    };
    let mut out = PathBuf::new();
    for part in abs.components() {
        match part {
            Component::Prefix(_) | Component::RootDir => out.push(part),
            Component::CurDir => {}
            Component::ParentDir => {
                out.pop();
            }
            Component::Normal(name) => {
                out.push(name);
                if let Ok(c) = out.canonicalize() {
                    out = c;
                }
            }
        }
    }
    out
}

/// The longest file name an output may have: the atomic writer's temporary file is
/// `.NAME.gvi-tmp-PID`, 17 bytes longer at most (a PID has up to 7 digits), and a name has
/// at most 255 bytes on the usual filesystems.
pub const MAX_OUTPUT_NAME_BYTES: usize = 255 - TEMP_NAME_OVERHEAD;

/// Bytes the temporary name adds to a file name: `.`, `.gvi-tmp-` and up to 7 PID digits.
const TEMP_NAME_OVERHEAD: usize = 1 + ".gvi-tmp-".len() + 7;

/// Refuse a path with a directory name over 255 bytes or a file name over
/// [`MAX_OUTPUT_NAME_BYTES`] (`file` false for a directory: every component may have 255).
fn check_name_lengths(path: &Path, file: bool) -> Result<()> {
    let parts: Vec<&std::ffi::OsStr> = path
        .components()
        .filter_map(|c| match c {
            Component::Normal(n) => Some(n),
            _ => None,
        })
        .collect();
    for (i, name) in parts.iter().enumerate() {
        let len = name.as_encoded_bytes().len();
        let last = i + 1 == parts.len();
        let max = if file && last {
            MAX_OUTPUT_NAME_BYTES
        } else {
            255
        };
        if len > max {
            let why = if file && last {
                format!(
                    "the file name has {len} bytes; at most {max} are allowed (255, less the \
                     {TEMP_NAME_OVERHEAD} of the temporary name .NAME.gvi-tmp-PID it is written \
                     through)"
                )
            } else {
                format!("a directory name has {len} bytes; at most 255 are allowed")
            };
            return Err(bad_output(path, why));
        }
    }
    if path.as_os_str().as_encoded_bytes().len() + TEMP_NAME_OVERHEAD >= 4096 {
        return Err(bad_output(path, "the path is longer than 4096 bytes"));
    }
    Ok(())
}

/// Check an output file path before any work: not a directory, not under `/proc` or `/sys`,
/// and its directory (or, if missing, the ancestor it would be created in) accepts a new file
/// (probed by creating and removing one).
pub fn check_output_path(path: &Path) -> Result<()> {
    if path.as_os_str().is_empty() {
        return Err(bad_output(path, "the path is empty"));
    }
    if path.is_dir() {
        return Err(bad_output(path, "it is a directory, not a file"));
    }
    if !is_special(path) {
        check_name_lengths(path, true)?;
    }
    let resolved = resolve(path);
    if FORBIDDEN_ROOTS.iter().any(|r| resolved.starts_with(r)) {
        return Err(bad_output(
            path,
            "it is in a kernel pseudo-filesystem (/proc, /sys), not a place for output",
        ));
    }
    if is_special(path) {
        // /dev/null, /dev/stdout, a FIFO: written in place; opening it is the check.
        return std::fs::OpenOptions::new()
            .write(true)
            .open(path)
            .map(|_| ())
            .map_err(io_err(path));
    }
    if std::fs::metadata(path).is_ok_and(|m| m.permissions().readonly()) {
        return Err(bad_output(path, "the file exists and is read-only"));
    }
    probe_dir(parent_dir(path))
}

/// Check an output directory before any work: not a file, not under `/proc` or `/sys`, and
/// writable (or, if missing, creatable: it is created when the first file is written, and
/// stderr says so).
pub fn check_output_dir(dir: &Path) -> Result<()> {
    if dir.exists() && !dir.is_dir() {
        return Err(bad_output(dir, "it is a file, not a directory"));
    }
    check_name_lengths(dir, false)?;
    let resolved = resolve(dir);
    if FORBIDDEN_ROOTS.iter().any(|r| resolved.starts_with(r)) {
        return Err(bad_output(
            dir,
            "it is in a kernel pseudo-filesystem (/proc, /sys), not a place for output",
        ));
    }
    probe_dir(dir)
}

/// Check that `dir`, or if it does not exist yet its deepest existing ancestor (where it
/// would be created), is a directory that accepts a new file: create and remove a probe file.
/// Nothing is left behind; missing directories are created when the output is written.
fn probe_dir(dir: &Path) -> Result<()> {
    let mut existing = dir;
    while !existing.exists() {
        existing = match existing.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
    }
    if !existing.is_dir() {
        return Err(bad_output(
            dir,
            format!("{} is not a directory", existing.display()),
        ));
    }
    let probe = existing.join(format!(".gvi-probe-{}", std::process::id()));
    std::fs::File::create(&probe)
        .map_err(|source| LabError::Io {
            path: existing.to_path_buf(),
            source,
        })
        .map(|_| {
            let _ = std::fs::remove_file(&probe);
        })
}

/// Refuse output paths that coincide with each other or with an input file (a scene): after
/// resolving symlinks, `..` and relative paths ([`resolve`]), every output must be distinct
/// from every other path. `outputs` and `inputs` are (role, path) pairs; the roles name the
/// flags in the message. The comparison of [`Plan::check`], without its per-path checks.
pub fn ensure_distinct(outputs: &[(&str, &Path)], inputs: &[(&str, &Path)]) -> Result<()> {
    let mut plan = Plan::new();
    for (role, path) in outputs {
        plan.output(*role, path);
    }
    for (role, path) in inputs {
        plan.input(*role, path);
    }
    plan.ensure_distinct()
}

/// Remove the temporary files `PREFIX<PID>` of this destination left by runs that were
/// killed (their process no longer exists), saying so on stderr. Only the tool's own pattern
/// for this very destination is touched; where processes cannot be checked (no `/proc`),
/// nothing is removed.
fn remove_stale_temps(dir: &Path, prefix: &str) {
    if !Path::new("/proc/self").exists() {
        return;
    }
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = name.to_str().and_then(|n| n.strip_prefix(prefix)) else {
            continue;
        };
        let dead = pid.parse::<u32>().is_ok_and(|pid| {
            pid != std::process::id() && !Path::new(&format!("/proc/{pid}")).exists()
        });
        if dead && std::fs::remove_file(entry.path()).is_ok() {
            eprintln!(
                "removed {}, the temporary file of a run that was killed",
                entry.path().display()
            );
        }
    }
}

/// A file being written: bytes go to a temporary file next to the destination, renamed into
/// place by [`AtomicFile::commit`]. Dropped without a commit, the temporary file is removed
/// and the destination is untouched. Destinations that are devices or FIFOs (`/dev/null`,
/// `/dev/stdout`) are written in place.
pub struct AtomicFile {
    dest: PathBuf,
    temp: Option<PathBuf>,
    writer: std::io::BufWriter<std::fs::File>,
}

impl AtomicFile {
    /// Start writing `dest` (its directory is created if missing, and stderr says so).
    pub fn create(dest: &Path) -> Result<Self> {
        if is_special(dest) {
            let file = std::fs::OpenOptions::new()
                .write(true)
                .open(dest)
                .map_err(io_err(dest))?;
            return Ok(AtomicFile {
                dest: dest.to_path_buf(),
                temp: None,
                writer: std::io::BufWriter::with_capacity(1 << 16, file),
            });
        }
        ensure_parent(dest)?;
        let name = dest
            .file_name()
            .ok_or_else(|| bad_output(dest, "the path has no file name"))?;
        let prefix = format!(".{}.gvi-tmp-", name.to_string_lossy());
        remove_stale_temps(parent_dir(dest), &prefix);
        let temp = parent_dir(dest).join(format!("{prefix}{}", std::process::id()));
        let file = std::fs::File::create(&temp).map_err(io_err(&temp))?;
        Ok(AtomicFile {
            dest: dest.to_path_buf(),
            temp: Some(temp),
            writer: std::io::BufWriter::with_capacity(1 << 16, file),
        })
    }

    /// Flush, sync and rename the temporary file over the destination.
    pub fn commit(mut self) -> Result<()> {
        self.writer.flush().map_err(io_err(&self.dest))?;
        if let Some(temp) = self.temp.take() {
            let synced = self.writer.get_ref().sync_all();
            let renamed = synced.and_then(|_| std::fs::rename(&temp, &self.dest));
            if let Err(source) = renamed {
                let _ = std::fs::remove_file(&temp);
                return Err(LabError::Io {
                    path: self.dest.clone(),
                    source,
                });
            }
        }
        Ok(())
    }

    /// The destination path.
    pub fn path(&self) -> &Path {
        &self.dest
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.writer.write(buf)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.writer.flush()
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if let Some(temp) = self.temp.take() {
            let _ = std::fs::remove_file(temp);
        }
    }
}

/// Write `bytes` to `path` atomically (temporary file in the same directory, then rename),
/// creating the directory if missing (stderr says so).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let mut file = AtomicFile::create(path)?;
    file.write_all(bytes).map_err(io_err(path))?;
    file.commit()
}

/// Write a text file atomically ([`write_atomic`]).
pub fn write_file(path: &Path, text: &str) -> Result<()> {
    write_atomic(path, text.as_bytes())
}

/// Write text to stdout, returning a typed error instead of panicking as `print!` does: a
/// full device is an [`LabError::Io`] on `<stdout>`, a closed pipe one whose
/// [`LabError::is_broken_pipe`] is true.
pub fn print(text: &str) -> Result<()> {
    write_output(None, text)
}

/// Write text to a file atomically ([`write_atomic`]) or, with no path, to stdout.
pub fn write_output(path: Option<&Path>, text: &str) -> Result<()> {
    match path {
        Some(p) => write_atomic(p, text.as_bytes()),
        None => {
            let mut out = std::io::stdout().lock();
            out.write_all(text.as_bytes())
                .and_then(|_| out.flush())
                .map_err(io_err(Path::new("<stdout>")))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atomic_write_replaces_and_leaves_no_temp() {
        let dir = std::env::temp_dir().join(format!("gvi-output-{}", std::process::id()));
        let path = dir.join("sub/a.txt");
        write_atomic(&path, b"one").unwrap();
        write_atomic(&path, b"two").unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "two");
        let names: Vec<_> = std::fs::read_dir(dir.join("sub")).unwrap().collect();
        assert_eq!(names.len(), 1);
        // An uncommitted file leaves the destination untouched.
        {
            let mut f = AtomicFile::create(&path).unwrap();
            f.write_all(b"partial").unwrap();
        }
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "two");
        assert_eq!(std::fs::read_dir(dir.join("sub")).unwrap().count(), 1);
        assert!(check_output_path(&dir).is_err());
        assert!(check_output_path(Path::new("/proc/version")).is_err());
        let a = dir.join("x.csv");
        let b = dir.join("sub/../x.csv");
        assert!(ensure_distinct(&[("--output", &a), ("--plot", &b)], &[]).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
