//! Reading an input file with a size bound (issue 34): `--config /dev/zero`, a named pipe
//! that never ends, or a file far larger than any real one of its kind is refused by name
//! after at most its bound in bytes, instead of being read until memory runs out. The bounds
//! are declared in `schema` (`schema::FILES`).

use std::io::Read as _;
use std::path::Path;

use anyhow::{bail, Context as _};

use crate::schema::FileLimit;

/// The text of `path`, refused when longer than `limit.max_bytes` or not UTF-8.
pub fn read_text(path: &Path, limit: &FileLimit) -> anyhow::Result<String> {
    let refuse = || {
        anyhow::anyhow!(
            "{} {} is larger than {} MiB, more than any real {} holds; refusing to read it",
            limit.what,
            path.display(),
            limit.max_bytes >> 20,
            limit.what
        )
    };
    let file = std::fs::File::open(path).with_context(|| format!("cannot read {} {}", limit.what, path.display()))?;
    // a regular file says its size: refuse it before reading a byte
    if let Ok(meta) = file.metadata() {
        if meta.is_dir() {
            bail!("{} {} is a folder, not a file", limit.what, path.display());
        }
        if meta.is_file() && meta.len() > limit.max_bytes {
            return Err(refuse());
        }
    }
    // a device or a pipe does not: read one byte past the bound to tell
    let mut bytes = Vec::new();
    file.take(limit.max_bytes + 1)
        .read_to_end(&mut bytes)
        .with_context(|| format!("cannot read {} {}", limit.what, path.display()))?;
    if bytes.len() as u64 > limit.max_bytes {
        return Err(refuse());
    }
    String::from_utf8(bytes).map_err(|e| {
        anyhow::anyhow!(
            "{} {} is not UTF-8 text (byte {} is not); is it the right file?",
            limit.what,
            path.display(),
            e.utf8_error().valid_up_to()
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const SMALL: FileLimit = FileLimit { what: "config file", flags: &["--config"], max_bytes: 1 << 20 };

    #[test]
    fn an_endless_device_is_refused_by_name_after_the_bound() {
        if !Path::new("/dev/zero").exists() {
            return;
        }
        let e = read_text(Path::new("/dev/zero"), &SMALL).unwrap_err().to_string();
        assert!(e.contains("config file /dev/zero is larger than 1 MiB"), "{e}");
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
    }
}
