//! Files that parameters name (warp files, height images, models, …): where they may be, and how
//! they are read and written, whoever named them — a scene, the panel, or a message from the
//! network.
//!
//! The rules, in one place so every file parameter follows them:
//! - A name is looked up beside the asset root (the folder holding `scenes/`), then as given. The
//!   file found must lie, links followed, inside an allowed folder: the asset root, the folder of
//!   a scene file the show was started with, or a folder given with `--allow-path` (`/` lifts the
//!   rule). One OSC message can then not make the show read `/etc/shadow` or a FIFO elsewhere.
//! - Only regular files are opened, without blocking (a named pipe or a device is refused before
//!   any read), and no more than the caller's byte limit is read.
//! - Saving writes only inside the allowed folders, a file with the caller's extension, atomically.
//! - Reading and decoding run on a worker thread ([`Loader`]); the render thread only polls.

mod loader;
mod windows_names;

pub use loader::{LoadWait, Loader};
use windows_names::windows_problem;

use std::borrow::Cow;
use std::io::Read;
use std::path::{Path, PathBuf};

/// Where the files that parameters name may be.
#[derive(Clone, Debug, Default)]
pub struct FileRules {
    /// Allowed folders, as given (resolved when a file is looked up: a folder may appear later).
    folders: Vec<PathBuf>,
}

/// Why a file could not be found or used.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum FileError {
    /// Nothing by that name in any place looked at.
    NotFound(String),
    /// Found, but not to be used (outside the allowed folders, not a regular file, too large…).
    Refused(String),
}

impl std::fmt::Display for FileError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FileError::NotFound(m) | FileError::Refused(m) => f.write_str(m),
        }
    }
}

impl FileRules {
    /// Rules allowing `folders` (the asset root among them, usually).
    pub fn new(folders: impl IntoIterator<Item = PathBuf>) -> Self {
        Self { folders: folders.into_iter().collect() }
    }

    /// These rules with `folder` allowed too.
    pub fn allowing(&self, folder: impl Into<PathBuf>) -> Self {
        let mut folders = self.folders.clone();
        folders.push(folder.into());
        Self { folders }
    }

    /// The file `name` means: beside `root` first, then as given (relative to the current folder
    /// or absolute), followed through links, if it is inside an allowed folder.
    pub fn locate(&self, root: Option<&Path>, name: &str) -> Result<PathBuf, FileError> {
        if name.is_empty() || name.contains('\0') {
            return Err(FileError::NotFound("no file named".into()));
        }
        refuse_windows_problem(name)?;
        let candidates = [root.map(|r| r.join(name)), Some(PathBuf::from(name))];
        let found = candidates.into_iter().flatten().find(|p| p.symlink_metadata().is_ok());
        let Some(found) = found else {
            let place = root.map_or(String::new(), |r| format!("beside {} and ", r.display()));
            return Err(FileError::NotFound(format!("no file '{name}' ({place}in the current folder)")));
        };
        let real = found.canonicalize().map_err(|e| FileError::Refused(format!("{}: {e}", found.display())))?;
        self.check_inside(&real, name)?;
        Ok(real)
    }

    /// Where to save `name` (a new or existing file with extension `ext`): beside `root` when
    /// relative, and inside an allowed folder.
    pub fn locate_for_saving(&self, root: Option<&Path>, name: &str, ext: &str) -> Result<PathBuf, FileError> {
        refuse_windows_problem(name)?;
        let given = Path::new(name);
        if given.extension().and_then(|e| e.to_str()) != Some(ext) {
            return Err(FileError::Refused(format!("'{name}' is not a .{ext} file; only .{ext} files are saved")));
        }
        let path = match root {
            Some(r) if given.is_relative() => r.join(given),
            _ => given.to_path_buf(),
        };
        let (Some(parent), Some(file_name)) = (path.parent(), path.file_name()) else {
            return Err(FileError::Refused(format!("'{name}' names no file")));
        };
        let parent = parent
            .canonicalize()
            .map_err(|e| FileError::NotFound(format!("no folder for '{name}' ({}: {e})", parent.display())))?;
        let target = parent.join(file_name);
        // An existing file is followed through links: the place written is where it really is.
        let real = match target.symlink_metadata() {
            Ok(meta) if meta.file_type().is_symlink() || meta.is_file() => {
                target.canonicalize().map_err(|e| FileError::Refused(format!("{}: {e}", target.display())))?
            }
            Ok(_) => return Err(FileError::Refused(format!("{} is not a regular file", target.display()))),
            Err(_) => target,
        };
        self.check_inside(&real, name)?;
        if real.extension().and_then(|e| e.to_str()) != Some(ext) {
            return Err(FileError::Refused(format!("'{name}' leads to {}, not a .{ext} file", real.display())));
        }
        Ok(real)
    }

    /// The bytes of the file `name` means (see [`FileRules::locate`]), at most `limit` of them;
    /// where no such file exists, `bundled`'s (a copy built into the binary), if given.
    pub fn read(
        &self,
        root: Option<&Path>,
        name: &str,
        limit: u64,
        bundled: Option<&'static [u8]>,
    ) -> Result<NamedBytes, FileError> {
        match (self.locate(root, name), bundled) {
            (Err(FileError::NotFound(_)), Some(bytes)) => {
                Ok(NamedBytes { path: None, origin: format!("bundled {name}"), bytes: Cow::Borrowed(bytes) })
            }
            (Err(e), _) => Err(e),
            (Ok(path), _) => {
                let bytes = read_limited(&path, limit)?;
                Ok(NamedBytes { origin: path.display().to_string(), path: Some(path), bytes: Cow::Owned(bytes) })
            }
        }
    }

    fn check_inside(&self, real: &Path, name: &str) -> Result<(), FileError> {
        let inside = self.folders.iter().filter_map(|f| f.canonicalize().ok()).any(|f| real.starts_with(&f));
        if inside {
            return Ok(());
        }
        let folders: Vec<String> = self.folders.iter().map(|f| f.display().to_string()).collect();
        Err(FileError::Refused(format!(
            "'{name}' is outside the folders the show may use ({}); start indra with --allow-path <folder> to open it",
            if folders.is_empty() { "none".to_string() } else { folders.join(", ") }
        )))
    }
}

/// On Windows, refuses a name it reads as something other than a local file (a share, a
/// device, a stream: see [`windows_problem`]) before anything looks it up.
fn refuse_windows_problem(name: &str) -> Result<(), FileError> {
    if !cfg!(windows) {
        return Ok(());
    }
    windows_problem(name).map_or(Ok(()), |why| Err(FileError::Refused(format!("'{name}': {why}"))))
}

/// Where the performer's own files live by default (presets, learned mappings): `name` in the
/// current folder, or on Windows in `%APPDATA%\indra` — a show started from the Start menu
/// runs in its install folder, which is not the user's to write.
pub fn user_data(name: &str) -> PathBuf {
    match std::env::var_os("APPDATA").filter(|d| cfg!(windows) && !d.is_empty()) {
        Some(app_data) => PathBuf::from(app_data).join("indra").join(name),
        None => PathBuf::from(name),
    }
}

/// The performer's configuration folder for indra, which settings made once for a machine are
/// kept in (the choices `indra tune` measured): `%APPDATA%\indra` on Windows,
/// `~/Library/Application Support/indra` on macOS, else `$XDG_CONFIG_HOME/indra` or
/// `~/.config/indra`. `None` where the environment names no home.
pub fn user_config() -> Option<PathBuf> {
    let var = |name: &str| std::env::var_os(name).filter(|v| !v.is_empty()).map(PathBuf::from);
    let folder = if cfg!(windows) {
        var("APPDATA")?
    } else if cfg!(target_os = "macos") {
        var("HOME")?.join("Library/Application Support")
    } else {
        var("XDG_CONFIG_HOME").or_else(|| var("HOME").map(|home| home.join(".config")))?
    };
    Some(folder.join("indra"))
}

/// A file's bytes and where they came from.
#[derive(Clone, Debug)]
pub struct NamedBytes {
    /// The file on disk, links followed (`None`: a copy built into the binary).
    pub path: Option<PathBuf>,
    /// Where the bytes came from, for messages: the path, or `bundled <name>`.
    pub origin: String,
    /// The bytes.
    pub bytes: Cow<'static, [u8]>,
}

/// The bytes of `path`, if it is a regular file of at most `limit` bytes. Opened without blocking
/// and checked after opening, so a FIFO or device swapped in after a look-up is still refused.
pub fn read_limited(path: &Path, limit: u64) -> Result<Vec<u8>, FileError> {
    let refused = |why: String| FileError::Refused(format!("{}: {why}", path.display()));
    let file = open_regular(path)?;
    let meta = file.metadata().map_err(|e| refused(e.to_string()))?;
    if meta.len() > limit {
        return Err(refused(format!("{} bytes, more than the {} allowed", meta.len(), limit)));
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    file.take(limit + 1).read_to_end(&mut bytes).map_err(|e| refused(e.to_string()))?;
    if bytes.len() as u64 > limit {
        return Err(refused(format!("grew past the {limit} bytes allowed while being read")));
    }
    Ok(bytes)
}

/// `path` opened for reading if it is a regular file (checked after opening, without blocking:
/// a FIFO or device swapped in after a look-up is refused). For files read in parts, such as
/// video clips; [`read_limited`] reads a whole one.
pub fn open_regular(path: &Path) -> Result<std::fs::File, FileError> {
    let refused = |why: String| FileError::Refused(format!("{}: {why}", path.display()));
    let file = open_nonblocking(path).map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound => FileError::NotFound(format!("{}: no such file", path.display())),
        _ => refused(e.to_string()),
    })?;
    let meta = file.metadata().map_err(|e| refused(e.to_string()))?;
    if !meta.is_file() {
        return Err(refused("not a regular file (a pipe, device or folder is never read)".into()));
    }
    Ok(file)
}

#[cfg(unix)]
fn open_nonblocking(path: &Path) -> std::io::Result<std::fs::File> {
    use std::os::unix::fs::OpenOptionsExt;
    std::fs::OpenOptions::new().read(true).custom_flags(libc::O_NONBLOCK | libc::O_NOCTTY).open(path)
}

#[cfg(not(unix))]
fn open_nonblocking(path: &Path) -> std::io::Result<std::fs::File> {
    std::fs::File::open(path)
}

/// Parses a settings file's RON text (an optional field may be written without `Some(…)`);
/// an error is one sentence placed at `origin:line:column`.
pub fn parse_ron<T: serde::de::DeserializeOwned>(text: &str, origin: &str) -> Result<T, String> {
    let options = ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME);
    options.from_str(text).map_err(|e| format!("{origin}:{}:{}: {}", e.span.start.line, e.span.start.col, e.code))
}

/// Reads a settings file of at most `limit` bytes as UTF-8 text.
pub fn read_text(path: &Path, limit: u64) -> Result<String, String> {
    let bytes = read_limited(path, limit).map_err(|e| e.to_string())?;
    String::from_utf8(bytes).map_err(|_| format!("{}: not UTF-8 text", path.display()))
}
