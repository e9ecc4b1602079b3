//! The one reader of input files (issues 34 and 45): every file the project reads (a config,
//! a setup, measured data, a run manifest, a plan, a checkpoint, a DEM result or dump, a
//! front) is opened here. Only a regular file is read: a folder, a named pipe (FIFO), a
//! device (`/dev/zero`) or a socket is refused by name before it is opened for reading, and
//! the file is opened non-blocking, so a FIFO put in its place between the look and the open
//! cannot hang the reader either. A file larger than its kind's bound (declared in
//! `schema::FILES`) is refused by name before a byte is read, and at most the bound is ever
//! read, so a file that grows while it is read cannot exhaust the memory.

use std::fs::{File, FileType};
use std::io::Read as _;
use std::path::Path;

use anyhow::{bail, Context as _};

use crate::schema::FileLimit;

/// What a file that is not a regular file is, in words.
fn kind_of(t: &FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt as _;
        if t.is_fifo() {
            return "a named pipe (FIFO)";
        }
        if t.is_char_device() {
            return "a character device";
        }
        if t.is_block_device() {
            return "a block device";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    if t.is_dir() {
        "a folder"
    } else {
        "not a regular file"
    }
}

fn refuse_size(path: &Path, limit: &FileLimit) -> anyhow::Error {
    anyhow::anyhow!(
        "{} {} is larger than {} MiB, more than any real {} holds; refusing to read it",
        limit.what,
        path.display(),
        limit.max_bytes >> 20,
        limit.what
    )
}

/// Open `path` as an input file of kind `limit`: a regular file within its size bound.
fn open(path: &Path, limit: &FileLimit) -> anyhow::Result<File> {
    let cannot = || format!("cannot read {} {}", limit.what, path.display());
    // metadata follows a link: a link to a regular file is read, one to /dev/zero is not
    let meta = std::fs::metadata(path).with_context(cannot)?;
    if !meta.is_file() {
        bail!(
            "{} {} is {}, not a regular file; refusing to read it",
            limit.what,
            path.display(),
            kind_of(&meta.file_type())
        );
    }
    if meta.len() > limit.max_bytes {
        return Err(refuse_size(path, limit));
    }
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt as _;
        // a FIFO swapped in after the look must not block the open (reads of a regular file
        // are unaffected by the flag)
        options.custom_flags(libc::O_NONBLOCK);
    }
    let file = options.open(path).with_context(cannot)?;
    let meta = file.metadata().with_context(cannot)?;
    if !meta.is_file() {
        bail!(
            "{} {} is {}, not a regular file; refusing to read it",
            limit.what,
            path.display(),
            kind_of(&meta.file_type())
        );
    }
    Ok(file)
}

/// The bytes of `path`, a regular file of at most `limit.max_bytes`.
pub fn read_bytes(path: &Path, limit: &FileLimit) -> anyhow::Result<Vec<u8>> {
    let file = open(path, limit)?;
    let mut bytes = Vec::new();
    // one byte past the bound tells a file that grew after the look
    file.take(limit.max_bytes + 1)
        .read_to_end(&mut bytes)
        .with_context(|| format!("cannot read {} {}", limit.what, path.display()))?;
    if bytes.len() as u64 > limit.max_bytes {
        return Err(refuse_size(path, limit));
    }
    Ok(bytes)
}

/// The text of `path`: a regular file of at most `limit.max_bytes`, UTF-8.
pub fn read_text(path: &Path, limit: &FileLimit) -> anyhow::Result<String> {
    String::from_utf8(read_bytes(path, limit)?).map_err(|e| {
        anyhow::anyhow!(
            "{} {} is not UTF-8 text (byte {} is not); is it the right file?",
            limit.what,
            path.display(),
            e.utf8_error().valid_up_to()
        )
    })
}

/// `path` opened for a streaming reader (a large log read row by row): the same rules as
/// [`read_bytes`], and reading stops at the bound.
pub fn open_bounded(path: &Path, limit: &FileLimit) -> anyhow::Result<std::io::Take<File>> {
    Ok(open(path, limit)?.take(limit.max_bytes))
}

/// [`read_text`], or `None` where `path` does not exist (an optional file such as a run's
/// stroke time); every other failure is an error.
pub fn read_text_if_present(path: &Path, limit: &FileLimit) -> anyhow::Result<Option<String>> {
    match std::fs::symlink_metadata(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        _ => read_text(path, limit).map(Some),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SMALL: FileLimit = FileLimit { what: "config file", flags: &["--config"], max_bytes: 1 << 20 };

    #[test]
    fn a_device_is_refused_by_name_before_it_is_read() {
        if !Path::new("/dev/zero").exists() {
            return;
        }
        let e = read_text(Path::new("/dev/zero"), &SMALL).unwrap_err().to_string();
        assert!(e.contains("config file /dev/zero is a character device, not a regular file"), "{e}");
    }

    #[test]
    fn a_file_over_the_bound_is_refused_and_one_within_is_read() {
        let d = tempfile::tempdir().unwrap();
        let big = d.path().join("big.toml");
        std::fs::File::create(&big).unwrap().set_len((1 << 20) + 1).unwrap();
        assert!(read_text(&big, &SMALL).unwrap_err().to_string().contains("larger than 1 MiB"));
        let ok = d.path().join("ok.toml");
        std::fs::write(&ok, "env = \"earth\"\n").unwrap();
        assert_eq!(read_text(&ok, &SMALL).unwrap(), "env = \"earth\"\n");
        std::fs::write(&ok, [0xff, 0xfe, 0x00]).unwrap();
        assert!(read_text(&ok, &SMALL).unwrap_err().to_string().contains("not UTF-8"));
        assert!(read_text(d.path(), &SMALL).unwrap_err().to_string().contains("is a folder"));
        assert_eq!(read_text_if_present(&d.path().join("none"), &SMALL).unwrap(), None);
        assert!(read_text_if_present(d.path(), &SMALL).is_err());
    }

    /// A named pipe with no writer blocks a plain open for ever: it must be refused at once.
    #[cfg(unix)]
    #[test]
    fn a_named_pipe_is_refused_without_waiting_for_a_writer() {
        let d = tempfile::tempdir().unwrap();
        let fifo = d.path().join("fifo.toml");
        let ok = std::process::Command::new("mkfifo").arg(&fifo).status().is_ok_and(|s| s.success());
        if !ok {
            return;
        }
        let e = read_text(&fifo, &SMALL).unwrap_err().to_string();
        assert!(e.contains("is a named pipe (FIFO), not a regular file"), "{e}");
        // a link to it too
        let link = d.path().join("link.toml");
        std::os::unix::fs::symlink(&fifo, &link).unwrap();
        assert!(read_text(&link, &SMALL).unwrap_err().to_string().contains("named pipe"));
    }
}
