//! Reading input files (URDF, scene TOML) with limits: only regular files, at most
//! [`MAX_FILE_BYTES`], valid UTF-8. The file type is checked on the path's metadata before
//! opening, so a FIFO, a device (`/dev/zero`) or a directory is refused without blocking or
//! reading; the file is then opened non-blocking and checked again (it may have been replaced
//! meanwhile), and read through a cap (a file may grow, or report size 0 as `/proc` files do).
use std::io::Read;
use std::path::Path;

use crate::support::error::{Error, FileKind, Location};

/// Largest input file read: 128 MiB (a 150k-link URDF is about 50 MB).
pub const MAX_FILE_BYTES: u64 = 128 * 1024 * 1024;

/// Longest path shown in full in messages; longer ones are shortened in the middle.
const MAX_SHOWN_PATH: usize = 200;

/// `path` as shown in messages: shortened in the middle if longer than 200 characters.
pub fn display_path(path: &Path) -> String {
    let s = path.display().to_string();
    let n = s.chars().count();
    if n <= MAX_SHOWN_PATH {
        return s;
    }
    let head: String = s.chars().take(MAX_SHOWN_PATH / 2).collect();
    let tail: String = s.chars().skip(n - MAX_SHOWN_PATH / 2 + 10).collect();
    format!("{head}…{tail} (a path of {n} characters)")
}

fn kind_of(ft: &std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if ft.is_fifo() {
            return "a FIFO (named pipe)";
        }
        if ft.is_char_device() {
            return "a character device";
        }
        if ft.is_block_device() {
            return "a block device";
        }
        if ft.is_socket() {
            return "a socket";
        }
    }
    if ft.is_dir() {
        "a directory"
    } else if ft.is_symlink() {
        "a symbolic link"
    } else if ft.is_file() {
        "a regular file"
    } else {
        "a special file"
    }
}

fn expected(what: &str) -> String {
    format!(
        "expected a regular {what} file of at most {} MiB",
        MAX_FILE_BYTES >> 20
    )
}

/// Refuses anything but a regular file, naming what it is.
fn regular(meta: &std::fs::Metadata, what: &str) -> Result<(), String> {
    if meta.is_file() {
        Ok(())
    } else {
        Err(format!(
            "{}, got {}",
            expected(what),
            kind_of(&meta.file_type())
        ))
    }
}

#[cfg(unix)]
fn open_nonblocking(path: &Path) -> std::io::Result<std::fs::File> {
    use std::os::unix::fs::OpenOptionsExt;
    std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(path)
}

#[cfg(not(unix))]
fn open_nonblocking(path: &Path) -> std::io::Result<std::fs::File> {
    std::fs::File::open(path)
}

/// Reads `path` as UTF-8 text if it is a regular file of at most [`MAX_FILE_BYTES`]. The
/// error names the path (shortened by [`display_path`]) and says what was expected and what
/// was found; `kind` says which file it should have been ("URDF", "scene").
pub fn read_text(path: &Path, kind: FileKind) -> Result<String, Error> {
    let what = match kind {
        FileKind::Urdf => "URDF",
        FileKind::Scene => "scene",
    };
    read_text_named(path, kind, what)
}

/// [`read_text`] of a file whose errors are of `kind` but that messages call `what` (an
/// SRDF beside its URDF).
pub fn read_text_named(path: &Path, kind: FileKind, what: &str) -> Result<String, Error> {
    read_checked(path, what)
        .map_err(|message| Error::file(kind, Location::new(display_path(path), ""), message))
}

/// [`read_text`]'s work; the error is the message without the path.
fn read_checked(path: &Path, what: &str) -> Result<String, String> {
    let cannot = |e: std::io::Error| format!("cannot read the {what} file: {e}");
    let meta = std::fs::metadata(path).map_err(cannot)?;
    regular(&meta, what)?;
    if meta.len() > MAX_FILE_BYTES {
        return Err(format!(
            "{}, got a file of {} bytes",
            expected(what),
            meta.len()
        ));
    }
    let file = open_nonblocking(path).map_err(cannot)?;
    let meta = file.metadata().map_err(cannot)?;
    regular(&meta, what)?;
    let mut bytes = Vec::with_capacity(meta.len().min(MAX_FILE_BYTES) as usize);
    file.take(MAX_FILE_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(cannot)?;
    if bytes.len() as u64 > MAX_FILE_BYTES {
        return Err(format!(
            "{}, got a file that grew beyond that while being read",
            expected(what)
        ));
    }
    String::from_utf8(bytes).map_err(|e| {
        format!(
            "cannot read the {what} file: expected UTF-8 text, got an invalid byte at offset {}",
            e.utf8_error().valid_up_to()
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_directories_devices_and_long_paths() {
        let e = read_text(Path::new("/"), FileKind::Urdf)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("regular URDF file") && e.contains("a directory"),
            "{e}"
        );
        if Path::new("/dev/zero").exists() {
            let e = read_text(Path::new("/dev/zero"), FileKind::Scene)
                .unwrap_err()
                .to_string();
            assert!(e.contains("a character device"), "{e}");
        }
        let long = "x".repeat(100_000);
        let e = read_text(Path::new(&long), FileKind::Urdf)
            .unwrap_err()
            .to_string();
        assert!(e.contains("cannot read the URDF file"), "{e}");
        let shown = display_path(Path::new(&long));
        assert!(shown.len() < 300 && shown.contains("100000 characters"));
    }
}
