//! The one atomic-write helper: the bytes go to a temporary file with a unique name in the
//! target's own directory (so the rename never crosses a filesystem), are fsynced, and the
//! file is renamed over the target; the directory is fsynced so the rename itself is
//! durable. A reader (or a crash, a SIGKILL, a pre-empted Slurm task) sees the old file or
//! the new one, never a torn one. Temporary files left by a killed writer are named
//! `.NAME.XXXXXX.sawtooth-tmp` and removed by [`clean_stale_temps`] once the folder is owned
//! (see `io::run_dir`). A missing folder on the way to the file is created; a device or pipe
//! (`/dev/stdout`) is written into directly, as it cannot be replaced; a link to a file is
//! followed.

use std::io::{BufWriter, Write};
use std::path::Path;

use anyhow::Context as _;

/// Suffix of every temporary file this helper creates.
pub const TMP_SUFFIX: &str = ".sawtooth-tmp";

/// Asked before every file is written: `io::run_dir` records a file written at the top of a
/// folder the process holds in that folder's marker first (a hook rather than a call, as
/// `run_dir` writes its marker through this module).
static BEFORE_WRITE: std::sync::OnceLock<fn(&Path) -> anyhow::Result<()>> = std::sync::OnceLock::new();

/// Install the question [`write_atomic`] asks before it writes (once per process).
pub fn set_before_write(hook: fn(&Path) -> anyhow::Result<()>) {
    let _ = BEFORE_WRITE.set(hook);
}

/// Refuse an output file that is one of the command's inputs (`synth --out my.toml --setup
/// my.toml` would replace the setup with the data it made), compared by resolved path so that
/// `./a.toml` and `a.toml` match. `out_flag` and each input's flag name the user's flags.
pub fn refuse_input_as_output(out: &Path, out_flag: &str, inputs: &[(&str, &Path)]) -> anyhow::Result<()> {
    let resolve = |p: &Path| -> Option<std::path::PathBuf> {
        if let Ok(c) = std::fs::canonicalize(p) {
            return Some(c);
        }
        // not there yet: its folder resolved, and its name
        let dir = match p.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        Some(std::fs::canonicalize(dir).ok()?.join(p.file_name()?))
    };
    let Some(target) = resolve(out) else { return Ok(()) };
    for (flag, input) in inputs {
        if resolve(input).as_deref() == Some(target.as_path()) {
            anyhow::bail!(
                "{out_flag} {} is the {flag} file: writing it would destroy the input; choose another {out_flag}",
                out.display()
            );
        }
    }
    Ok(())
}

/// Write `bytes` to `path` atomically.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    write_atomic_with(path, |w| Ok(w.write_all(bytes)?))
}

/// Write `path` atomically from a writer callback (e.g. a serde serialiser).
pub fn write_atomic_with(path: &Path, write: impl FnOnce(&mut dyn Write) -> anyhow::Result<()>) -> anyhow::Result<()> {
    // What is there already decides how to write. A folder is refused. A stream or device
    // (`--trajectories /dev/stdout`, a named pipe), and anything under /dev or /proc, is
    // written straight into: renaming a file over it would replace the device node or the
    // /dev/stdout link (as root) instead of writing to it. A link to a file is followed, so
    // the file is replaced and the link stays.
    if path == Path::new("/dev/stdout") {
        // through this process's own stdout, so that what else it prints follows in order
        // even when stdout is a file (a second open of /dev/stdout has its own offset)
        return write_buffered(path, &mut std::io::stdout().lock(), write);
    }
    let resolved;
    let mut path = path;
    if let Ok(meta) = std::fs::metadata(path) {
        if meta.is_dir() {
            anyhow::bail!("{} is a folder: name a file to write", path.display());
        }
        if !meta.is_file() || path.starts_with("/dev") || path.starts_with("/proc") {
            let mut stream = std::fs::OpenOptions::new()
                .write(true)
                .truncate(meta.is_file())
                .open(path)
                .with_context(|| format!("writing {}: opening it", path.display()))?;
            return write_buffered(path, &mut stream, write);
        }
        if std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink()) {
            resolved = std::fs::canonicalize(path).with_context(|| format!("writing {}", path.display()))?;
            path = &resolved;
        }
    }
    let name = path
        .file_name()
        .with_context(|| format!("{} has no file name", path.display()))?
        .to_string_lossy()
        .into_owned();
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if let Some(hook) = BEFORE_WRITE.get() {
        hook(path).with_context(|| format!("writing {}: recording it in its folder's marker", path.display()))?;
    }
    // a file named in a folder that is not there yet (`--trajectories out/traj.csv` in a
    // fresh checkout) gets the folder, as the user asked for the file in it
    std::fs::create_dir_all(dir)
        .with_context(|| format!("writing {}: creating its folder {}", path.display(), dir.display()))?;
    let mut builder = tempfile::Builder::new();
    // tempfile's default is 0600; results are read by others (a cluster group): 0666 less umask.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt as _;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    let mut tmp = builder
        .prefix(&format!(".{name}."))
        .suffix(TMP_SUFFIX)
        .tempfile_in(dir)
        .with_context(|| format!("writing {}: creating a temporary file in {}", path.display(), dir.display()))?;
    write_buffered(path, tmp.as_file_mut(), write)?;
    tmp.as_file().sync_all().with_context(|| format!("writing {}: fsync", path.display()))?;
    // On failure the temporary file is removed when `e.file` drops.
    tmp.persist(path)
        .map_err(|e| e.error)
        .with_context(|| format!("writing {}: renaming the temporary file over it", path.display()))?;
    // Make the rename durable; directories cannot be opened for this on Windows.
    #[cfg(unix)]
    if let Ok(d) = std::fs::File::open(dir) {
        let _ = d.sync_all();
    }
    Ok(())
}

/// `write` through a buffer into `out`, flushed; errors name `path`.
fn write_buffered(
    path: &Path,
    out: &mut dyn Write,
    write: impl FnOnce(&mut dyn Write) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let mut w = BufWriter::new(out);
    write(&mut w).with_context(|| format!("writing {}", path.display()))?;
    w.flush().with_context(|| format!("writing {}", path.display()))
}

/// True for the names of temporary files a killed atomic write can leave behind: this
/// helper's, and those of the helpers it replaced (`.NAME.tmpPID`, `.NAME.PID.tmp`, `NAME.tmp`).
pub fn is_temp_name(name: &str) -> bool {
    if name.starts_with('.') && name.ends_with(TMP_SUFFIX) {
        return true;
    }
    if let Some(i) = name.rfind(".tmp") {
        let tail = &name[i + 4..];
        return tail.chars().all(|c| c.is_ascii_digit()) && (name.starts_with('.') || tail.is_empty());
    }
    false
}

/// Remove stale temporary files from `dir` (not recursive). Only call this while owning
/// `dir` (holding its `run_dir` lock): another writer's temporary file is not stale.
/// Returns how many were removed.
pub fn clean_stale_temps(dir: &Path) -> anyhow::Result<usize> {
    let mut n = 0;
    let entries = match std::fs::read_dir(dir) {
        Ok(e) => e,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(0),
        Err(e) => return Err(e).with_context(|| format!("listing {}", dir.display())),
    };
    for e in entries {
        let e = e.with_context(|| format!("listing {}", dir.display()))?;
        let name = e.file_name().to_string_lossy().into_owned();
        if is_temp_name(&name) && e.file_type().is_ok_and(|t| t.is_file()) {
            std::fs::remove_file(e.path())
                .with_context(|| format!("removing stale temporary file {}", e.path().display()))?;
            n += 1;
        }
    }
    Ok(n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_replaces_and_leaves_no_temporary_file() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("a.csv");
        write_atomic(&p, b"one\n").unwrap();
        write_atomic(&p, b"two\n").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"two\n");
        assert_eq!(std::fs::read_dir(d.path()).unwrap().count(), 1);
        #[cfg(unix)]
        {
            // the same permissions as File::create (0666 less the umask), not tempfile's 0600
            use std::os::unix::fs::PermissionsExt as _;
            let probe = d.path().join("probe");
            std::fs::File::create(&probe).unwrap();
            let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
            assert_eq!(mode(&p), mode(&probe));
        }
    }

    /// A device or pipe named as the output is written into, not replaced by a file (as
    /// root the rename would succeed and swap the device node for a regular file); a folder
    /// is refused by name; a link to a file is followed.
    #[cfg(unix)]
    #[test]
    fn devices_are_written_into_and_folders_refused() {
        use std::os::unix::fs::FileTypeExt as _;
        write_atomic(Path::new("/dev/null"), b"discarded").unwrap();
        assert!(std::fs::metadata("/dev/null").unwrap().file_type().is_char_device());
        // a device that refuses the bytes is an error naming it (where the system has one)
        if std::fs::metadata("/dev/full").is_ok_and(|m| m.file_type().is_char_device()) {
            let full = write_atomic(Path::new("/dev/full"), &[b'x'; 1 << 16]);
            assert!(format!("{:#}", full.unwrap_err()).contains("/dev/full"));
            assert!(std::fs::metadata("/dev/full").unwrap().file_type().is_char_device());
        }
        let d = tempfile::tempdir().unwrap();
        let err = write_atomic(d.path(), b"x").unwrap_err();
        assert!(format!("{err:#}").contains("is a folder: name a file to write"), "{err:#}");
        // a link to a file: the file is replaced, the link stays a link
        let (file, link) = (d.path().join("data.csv"), d.path().join("latest.csv"));
        std::fs::write(&file, "old").unwrap();
        std::os::unix::fs::symlink(&file, &link).unwrap();
        write_atomic(&link, b"new").unwrap();
        assert!(std::fs::symlink_metadata(&link).unwrap().file_type().is_symlink());
        assert_eq!(std::fs::read_to_string(&file).unwrap(), "new");
    }

    #[test]
    fn a_failed_write_keeps_the_old_file_and_no_temporary() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("a.csv");
        write_atomic(&p, b"old\n").unwrap();
        let r = write_atomic_with(&p, |w| {
            w.write_all(b"half")?;
            anyhow::bail!("serialiser failed")
        });
        assert!(r.is_err());
        assert_eq!(std::fs::read(&p).unwrap(), b"old\n");
        assert_eq!(std::fs::read_dir(d.path()).unwrap().count(), 1);
    }

    #[test]
    fn stale_temporaries_are_recognised_and_removed() {
        let d = tempfile::tempdir().unwrap();
        for n in [
            ".a.csv.x1y2z3.sawtooth-tmp",
            ".checkpoint.json.tmp123",
            ".plot.svg.77.tmp",
            "run.tmp",
            "keep.csv",
            "tmpfile",
            ".hidden",
        ] {
            std::fs::write(d.path().join(n), b"x").unwrap();
        }
        assert_eq!(clean_stale_temps(d.path()).unwrap(), 4);
        let mut left: Vec<String> = std::fs::read_dir(d.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        left.sort();
        assert_eq!(left, [".hidden", "keep.csv", "tmpfile"]);
    }
}
