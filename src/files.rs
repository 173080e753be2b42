//! Files in and out, so that hostile input cannot exhaust memory and a failed write never loses
//! a file.
//!
//! Reads: [`read_input`] takes regular files only (not `/dev/zero`, a FIFO or a directory) and
//! at most a stated number of bytes; [`read_text`] also decodes UTF-8, drops a byte-order mark
//! and turns CR LF and lone CR line ends into LF, as exporters on every platform write them.
//!
//! Writes: [`replace`] writes a file under a temporary name beside its destination, syncs it
//! to disk and renames it into place, so a full disk, a crash or Ctrl-C leaves the previous
//! file intact. What is not a regular file is never replaced: a character device or a FIFO
//! that the output names (or a symbolic link to one) is written into as a stream, as
//! `cat > /dev/null` would; a block device or a socket is refused. [`check_outputs`] checks
//! every output path of a command before any work: the extension, a writable folder, no input
//! file of the scene, no two outputs the same file, and no block device or socket.

use crate::error::{Error, Result};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};

/// The largest scene file (TOML) read: 16 MiB.
pub const MAX_SCENE_FILE: u64 = 16 << 20;
/// The largest OBJ file read: 2 GiB (about 30 million triangles).
pub const MAX_MESH_FILE: u64 = 2 << 30;
/// The largest MTL file read: 64 MiB.
pub const MAX_MATERIAL_FILE: u64 = 64 << 20;

/// The bytes of the regular file at `path`, refusing anything else and anything over `limit`
/// bytes (`what` names the kind of file in the message: `a mesh (OBJ)`).
pub fn read_input(path: &Path, what: &str, limit: u64) -> Result<Vec<u8>> {
    let len = read_input_len(path, what)?;
    if len > limit {
        return Err(Error::io(path, too_large(what, len, limit)));
    }
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    // The length can change between the look and the read: never take more than the limit.
    let mut bytes = Vec::with_capacity(len as usize);
    file.take(limit + 1).read_to_end(&mut bytes).map_err(|e| Error::io(path, e))?;
    if bytes.len() as u64 > limit {
        return Err(Error::io(path, too_large(what, bytes.len() as u64, limit)));
    }
    Ok(bytes)
}

/// The length of the regular file at `path`, refusing anything else (for inputs that a
/// decoder reads itself).
pub fn read_input_len(path: &Path, what: &str) -> Result<u64> {
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    if !meta.is_file() {
        let kind = if meta.is_dir() { "a directory" } else { "not a regular file (a device, pipe or socket)" };
        return Err(Error::io(path, format!("is {kind}; only a regular file can be read as {what}")));
    }
    Ok(meta.len())
}

fn too_large(what: &str, len: u64, limit: u64) -> String {
    format!("{} is larger than the {} accepted for {what}", bytes(len), bytes(limit))
}

/// A byte count for messages: `512 B`, `3.0 MiB`, `1.5 GiB`.
#[must_use]
pub fn bytes(n: u64) -> String {
    const UNITS: [&str; 5] = ["B", "KiB", "MiB", "GiB", "TiB"];
    let mut v = n as f64;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < UNITS.len() {
        v /= 1024.0;
        u += 1;
    }
    if u == 0 {
        format!("{n} B")
    } else {
        format!("{v:.1} {}", UNITS[u])
    }
}

/// The text of the regular file at `path` (at most `limit` bytes): UTF-8 without a leading
/// byte-order mark, with every line ending as LF. Invalid UTF-8 is an error naming the line.
pub fn read_text(path: &Path, what: &str, limit: u64) -> Result<String> {
    let raw = read_input(path, what, limit)?;
    if raw.starts_with(&[0xFF, 0xFE]) || raw.starts_with(&[0xFE, 0xFF]) {
        return Err(Error::parse(path, 1, "the file is UTF-16; save it as UTF-8"));
    }
    let body = raw.strip_prefix(&[0xEF, 0xBB, 0xBF][..]).unwrap_or(&raw);
    let text = std::str::from_utf8(body).map_err(|e| {
        let line = body[..e.valid_up_to()].iter().filter(|&&b| b == b'\n').count() + 1;
        Error::parse(path, line, "not UTF-8 text")
    })?;
    Ok(normalise_line_ends(text))
}

/// `text` with CR LF and lone CR line ends turned into LF.
#[must_use]
pub fn normalise_line_ends(text: &str) -> String {
    if text.contains('\r') {
        text.replace("\r\n", "\n").replace('\r', "\n")
    } else {
        text.to_string()
    }
}

/// Writes `path` through `write`, which is given a temporary path beside it (same folder and
/// extension, so that writers choosing a format by extension still work). The temporary file is
/// synced and renamed over `path` only when `write` succeeded; otherwise it is removed and the
/// previous `path`, if any, is untouched.
/// A symbolic link is written through: its target is replaced, not the link. A target that is
/// not a regular file is never replaced (`write_into_special`).
pub fn replace(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    if let Some(kind) = special_target(path) {
        return write_into_special(path, kind, write);
    }
    let is_link = path.symlink_metadata().is_ok_and(|m| m.file_type().is_symlink());
    let dest = if is_link { path.canonicalize().unwrap_or_else(|_| path.to_path_buf()) } else { path.to_path_buf() };
    let tmp = temporary_beside(&dest);
    let result = write(&tmp).and_then(|()| {
        // Sync before the rename: a crash after it must not leave an empty file in place.
        let f = std::fs::OpenOptions::new().write(true).open(&tmp).map_err(|e| Error::output(path, e))?;
        f.sync_all().map_err(|e| Error::output(path, e))?;
        std::fs::rename(&tmp, &dest).map_err(|e| Error::output(path, e))?;
        // And the folder, so that the rename itself survives a crash (best effort: not every
        // platform can open a folder).
        if let Ok(dir) = std::fs::File::open(folder_of(&dest)) {
            let _ = dir.sync_all();
        }
        Ok(())
    });
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// What an existing output's final target (links followed) is, where it is not a regular file
/// or a directory.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Special {
    /// A character device (`/dev/null`, `/dev/full`, a terminal): written into.
    CharDevice,
    /// A named pipe: written into (the write waits for a reader, as `cat > fifo` does).
    Fifo,
    /// A block device: refused (its bytes are a disk's).
    BlockDevice,
    /// A socket: refused (it cannot be opened as a file).
    Socket,
}

/// The kind of `path`'s final target when it exists and is neither a regular file nor a
/// directory.
fn special_target(path: &Path) -> Option<Special> {
    let meta = std::fs::metadata(path).ok()?;
    if meta.is_file() || meta.is_dir() {
        return None;
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let t = meta.file_type();
        Some(if t.is_char_device() {
            Special::CharDevice
        } else if t.is_fifo() {
            Special::Fifo
        } else if t.is_block_device() {
            Special::BlockDevice
        } else {
            Special::Socket
        })
    }
    #[cfg(not(unix))]
    {
        Some(Special::BlockDevice)
    }
}

/// Why an output that names a block device or a socket is refused, or `None`.
fn refusal(path: &Path, kind: Special) -> Option<String> {
    let what = match kind {
        Special::BlockDevice => "a block device",
        Special::Socket => "a socket",
        Special::CharDevice | Special::Fifo => return None,
    };
    Some(format!("`{}` is {what}, not a regular file: it is neither replaced nor written into", path.display()))
}

/// Writes an output whose target is a character device or a FIFO into it, as a stream: `write`
/// writes a temporary file in the system's temporary folder (never beside a device in `/dev`),
/// whose bytes are then copied into the target opened for writing — never created, truncated,
/// renamed over or removed. A block device or a socket is refused.
fn write_into_special(path: &Path, kind: Special, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    if let Some(why) = refusal(path, kind) {
        return Err(Error::output(path, why));
    }
    let tmp = temporary_beside(&std::env::temp_dir().join(path.file_name().unwrap_or("output".as_ref())));
    let result = write(&tmp).and_then(|()| {
        let mut from = std::fs::File::open(&tmp).map_err(|e| Error::output(path, e))?;
        let mut to = std::fs::OpenOptions::new().write(true).open(path).map_err(|e| Error::output(path, e))?;
        std::io::copy(&mut from, &mut to).and_then(|_| to.flush()).map_err(|e| Error::output(path, e))?;
        Ok(())
    });
    let _ = std::fs::remove_file(&tmp);
    result
}

/// Writes `path` through a buffered writer, by way of [`replace`].
pub fn write_with(path: &Path, write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>) -> Result<()> {
    replace(path, |tmp| {
        let file = std::fs::File::create(tmp).map_err(|e| Error::output(path, e))?;
        let mut w = std::io::BufWriter::new(file);
        write(&mut w).and_then(|()| w.flush()).map_err(|e| Error::output(path, e))
    })
}

/// Writes `bytes` to `path`, by way of [`replace`].
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    write_with(path, |w| w.write_all(bytes))
}

/// Writes an 8-bit RGB PNG of `width × height` pixels (`rgb` row-major), by way of [`replace`].
pub fn write_png(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<()> {
    write_with(path, |w| {
        let mut enc = png::Encoder::new(w, width, height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc.write_header().map_err(std::io::Error::other)?;
        writer.write_image_data(rgb).map_err(std::io::Error::other)?;
        writer.finish().map_err(std::io::Error::other)
    })
}

/// `.NAME.partial-PID-TIME-N.EXT` in `path`'s folder: unique to this process and call, and unlike
/// any file a killed earlier run with the same process id may have left.
fn temporary_beside(path: &Path) -> PathBuf {
    static COUNTER: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let n = COUNTER.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let t = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_nanos());
    let name = path.file_name().map_or("output".into(), |s| s.to_string_lossy().into_owned());
    let ext = path.extension().map_or(String::new(), |e| format!(".{}", e.to_string_lossy()));
    path.with_file_name(format!(".{name}.partial-{}-{t}-{n}{ext}", std::process::id()))
}

/// One output file of a command: the flag that names it, its path and the extension its format
/// needs (`exr`, `png`, `json`, …; compared without case).
#[derive(Clone, Copy, Debug)]
pub struct Output<'a> {
    /// The flag, as the user wrote it (`--png`).
    pub flag: &'a str,
    /// Where it goes.
    pub path: &'a Path,
    /// The format's extension, without the dot.
    pub ext: &'a str,
}

/// Checks every output of a command before any work is done: each has its format's extension,
/// is not a directory, lies in an existing folder where a file can be created, is none of
/// `inputs` (the scene's files, a reference image), and no two name the same file.
pub fn check_outputs(outputs: &[Output], inputs: &[PathBuf]) -> Result<()> {
    let inputs: Vec<(Identity, &PathBuf)> = inputs.iter().map(|p| (identity(p), p)).collect();
    let mut seen: Vec<(Identity, &Output)> = Vec::new();
    for out in outputs {
        let (flag, path) = (out.flag, out.path);
        match path.extension().and_then(|e| e.to_str()) {
            Some(e) if e.eq_ignore_ascii_case(out.ext) => {}
            given => {
                let hint = match given {
                    Some(e) if e.eq_ignore_ascii_case("png") => " (for a PNG preview add --png FILE.png)",
                    _ => "",
                };
                return Err(Error::setting(
                    flag,
                    format!(
                        "writes {} only, so `{}` must end in .{}{hint}",
                        out.ext.to_uppercase(),
                        path.display(),
                        out.ext.to_lowercase()
                    ),
                ));
            }
        }
        if path.is_dir() {
            return Err(Error::setting(flag, format!("`{}` is a directory; name a file in it", path.display())));
        }
        if let Some(why) = special_target(path).and_then(|kind| refusal(path, kind)) {
            return Err(Error::setting(flag, why));
        }
        check_folder(flag, path)?;
        let id = identity(path);
        if let Some((_, input)) = inputs.iter().find(|(i, _)| *i == id) {
            return Err(Error::setting(
                flag,
                format!("`{}` is an input ({}); writing it would destroy it", path.display(), input.display()),
            ));
        }
        if let Some((_, other)) = seen.iter().find(|(i, _)| *i == id) {
            return Err(Error::setting(
                flag,
                format!("`{}` is also the file of {}; give each output its own file", path.display(), other.flag),
            ));
        }
        seen.push((id, out));
    }
    Ok(())
}

/// The folder of `path` exists and a file can be created in it (a probe file is created and
/// removed: permission bits alone do not tell, e.g. on a read-only mount or as root).
fn check_folder(flag: &str, path: &Path) -> Result<()> {
    let dir = folder_of(path);
    if !dir.is_dir() {
        return Err(Error::setting(
            flag,
            format!("cannot write `{}`: the folder `{}` does not exist", path.display(), dir.display()),
        ));
    }
    let probe = temporary_beside(path);
    match std::fs::OpenOptions::new().write(true).create_new(true).open(&probe) {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) => Err(Error::setting(
            flag,
            format!("cannot write `{}`: the folder `{}` is not writable ({e})", path.display(), dir.display()),
        )),
    }
}

/// The folder a file path lies in (`.` for a bare name).
fn folder_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// What names one file, however it is written: the canonical path where the file exists (links
/// resolved), else the canonical folder joined with the name; and on Unix the device and inode
/// of a file that exists, so that hard links match too.
#[derive(Debug)]
struct Identity {
    path: PathBuf,
    inode: Option<(u64, u64)>,
}

impl PartialEq for Identity {
    fn eq(&self, o: &Identity) -> bool {
        self.path == o.path || (self.inode.is_some() && self.inode == o.inode)
    }
}

fn identity(path: &Path) -> Identity {
    #[cfg(unix)]
    let inode = std::fs::metadata(path).ok().map(|m| {
        use std::os::unix::fs::MetadataExt;
        (m.dev(), m.ino())
    });
    #[cfg(not(unix))]
    let inode = None;
    if let Ok(p) = path.canonicalize() {
        return Identity { path: p, inode };
    }
    let dir = folder_of(path);
    let dir = dir.canonicalize().unwrap_or(dir);
    let path = match path.file_name() {
        Some(name) => dir.join(name),
        None => dir,
    };
    Identity { path, inode }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("photonwave-files-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn a_failed_write_leaves_the_previous_file_and_no_temporary() {
        let d = scratch("failed");
        let p = d.join("out.json");
        std::fs::write(&p, "good").unwrap();
        // A writer that fails half-way, as a full disk does.
        let e = write_with(&p, |w| {
            w.write_all(b"half")?;
            Err(std::io::Error::new(std::io::ErrorKind::StorageFull, "No space left on device"))
        })
        .unwrap_err();
        assert!(e.to_string().contains("out.json") && e.to_string().contains("No space"), "{e}");
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "good");
        assert_eq!(std::fs::read_dir(&d).unwrap().count(), 1, "a temporary file was left behind");
        write_bytes(&p, b"new").unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "new");
        assert_eq!(std::fs::read_dir(&d).unwrap().count(), 1);
    }

    /// A link is written through (its target replaced), and an input reached through a hard
    /// link or a symbolic link is still recognised as the input.
    #[cfg(unix)]
    #[test]
    fn links_are_followed() {
        let d = scratch("links");
        let (target, link, hard) = (d.join("real.json"), d.join("link.json"), d.join("hard.json"));
        std::fs::write(&target, "old").unwrap();
        std::os::unix::fs::symlink(&target, &link).unwrap();
        std::fs::hard_link(&target, &hard).unwrap();
        for path in [&link, &hard] {
            let e = check_outputs(&[out("--stats", path, "json")], std::slice::from_ref(&target)).unwrap_err();
            assert!(e.to_string().contains("is an input"), "{e}");
        }
        write_bytes(&link, b"new").unwrap();
        assert!(link.symlink_metadata().unwrap().file_type().is_symlink());
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "new");
    }

    /// An output that is (or links to) a character device or a FIFO is written into, never
    /// replaced: private device nodes made with `mknod` (as root, which CI and many containers
    /// are; skipped, saying so, where `mknod` is refused), never the system's.
    #[cfg(unix)]
    #[test]
    fn devices_and_fifos_are_written_into_never_replaced() {
        use std::os::unix::fs::FileTypeExt;
        let d = scratch("special");
        let is_char = |p: &Path| std::fs::metadata(p).unwrap().file_type().is_char_device();
        let made = |name: &str, minor: &str| {
            let node = d.join(name);
            let ok = std::process::Command::new("mknod")
                .arg(&node)
                .args(["c", "1", minor])
                .status()
                .is_ok_and(|s| s.success());
            ok.then_some(node)
        };
        // Major 1, minor 3: a null device; minor 7: a full one (every write fails with ENOSPC).
        match (made("null", "3"), made("full", "7")) {
            (Some(null), Some(full)) => {
                let link = d.join("out.exr");
                std::os::unix::fs::symlink(&full, &link).unwrap();
                let e = write_bytes(&link, &[7u8; 100_000]).unwrap_err().to_string();
                assert!(e.contains("out.exr") && e.contains("No space"), "{e}");
                assert!(is_char(&full), "the full device was replaced");
                assert!(link.symlink_metadata().unwrap().file_type().is_symlink());
                write_bytes(&null, b"written into").unwrap();
                assert!(is_char(&null), "the null device was replaced");
                check_outputs(&[out("-o", &link, "exr")], &[]).unwrap();
            }
            _ => println!("mknod refused (not root?): the device half of this test is skipped"),
        }
        // A FIFO: the bytes reach its reader, and it stays a FIFO.
        let fifo = d.join("pipe.json");
        if std::process::Command::new("mkfifo").arg(&fifo).status().is_ok_and(|s| s.success()) {
            let reader = {
                let fifo = fifo.clone();
                std::thread::spawn(move || std::fs::read(&fifo).unwrap())
            };
            write_bytes(&fifo, b"{\"through\": \"the pipe\"}").unwrap();
            assert_eq!(reader.join().unwrap(), b"{\"through\": \"the pipe\"}");
            assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo());
        }
        // Nothing was left in the folder but what the test made.
        assert!(std::fs::read_dir(&d).unwrap().all(|e| !e.unwrap().file_name().to_string_lossy().contains("partial")));
    }

    #[test]
    fn text_loses_its_bom_and_carriage_returns() {
        let d = scratch("text");
        let p = d.join("a.obj");
        std::fs::write(&p, b"\xEF\xBB\xBFv 0 0 0\rv 1 0 0\r\nf 1 2 3\r").unwrap();
        assert_eq!(read_text(&p, "a mesh", 1000).unwrap(), "v 0 0 0\nv 1 0 0\nf 1 2 3\n");
        std::fs::write(&p, b"ok\n\xFF\xFE").unwrap();
        assert!(read_text(&p, "a mesh", 1000).unwrap_err().to_string().contains("a.obj:2:"));
        std::fs::write(&p, b"\xFF\xFEv\x00").unwrap();
        assert!(read_text(&p, "a mesh", 1000).unwrap_err().to_string().contains("UTF-16"));
    }

    #[test]
    fn devices_folders_and_large_files_are_refused() {
        let d = scratch("refuse");
        let e = read_input(Path::new("/dev/zero"), "a mesh", MAX_MESH_FILE).unwrap_err().to_string();
        assert!(e.contains("/dev/zero") && e.contains("not a regular file"), "{e}");
        assert!(read_input(&d, "a mesh", 10).unwrap_err().to_string().contains("directory"));
        let p = d.join("big.mtl");
        std::fs::write(&p, [b'#'; 2048]).unwrap();
        let e = read_input(&p, "a material file", 1024).unwrap_err().to_string();
        assert!(e.contains("2.0 KiB") && e.contains("1.0 KiB"), "{e}");
    }

    fn out<'a>(flag: &'a str, path: &'a Path, ext: &'a str) -> Output<'a> {
        Output { flag, path, ext }
    }

    #[test]
    fn outputs_are_checked_before_work() {
        let d = scratch("outputs");
        let scene = d.join("scene.toml");
        std::fs::write(&scene, "").unwrap();
        let exr = d.join("a.exr");
        let e = check_outputs(&[out("--stats", &scene, "json")], std::slice::from_ref(&scene)).unwrap_err().to_string();
        assert!(e.contains("--stats") && e.contains(".json"), "{e}");
        let json = d.join("scene.json");
        std::fs::write(&json, "{}").unwrap();
        let e = check_outputs(&[out("--stats", &json, "json")], std::slice::from_ref(&json)).unwrap_err().to_string();
        assert!(e.contains("is an input"), "{e}");
        // The same file named two ways.
        let again = d.join(".").join("a.exr");
        let e = check_outputs(&[out("-o", &exr, "exr"), out("--png", &again, "exr")], &[]).unwrap_err().to_string();
        assert!(e.contains("also the file of -o"), "{e}");
        let missing = d.join("nodir").join("x.exr");
        let e = check_outputs(&[out("-o", &missing, "exr")], &[]).unwrap_err().to_string();
        assert!(e.contains("does not exist") && e.contains("nodir"), "{e}");
        let under_file = scene.join("x.exr");
        assert!(check_outputs(&[out("-o", &under_file, "exr")], &[]).is_err());
        check_outputs(&[out("-o", &exr, "exr"), out("--stats", &json, "JSON")], &[scene]).unwrap();
        assert_eq!(std::fs::read_dir(&d).unwrap().count(), 2, "the writability probe was left behind");
    }
}
