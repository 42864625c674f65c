//! Names Windows reads differently from what they say, refused before the file system is asked:
//! - a network or device path (`\\server\share`, `//server/share`, `\\.\pipe\x`, `\\?\UNC\…`):
//!   merely looking one up makes Windows connect to the server and offer the user's credentials,
//!   so a name from the network must never reach a look-up; `\\?\C:\…` (a long local path) is
//!   fine;
//! - a drive-relative path (`C:scene.ron`, relative to that drive's own current folder);
//! - a colon past the drive (`a.png:hidden`, an alternate data stream of `a.png`);
//! - a reserved device name as any part (`CON`, `nul.png`, `COM1.ron`, `LPT¹`, `CONIN$`),
//!   whatever its case, extension or trailing spaces: it opens the device, in any folder;
//! - a part ending in a dot or a space, which Windows drops (`scene.ron.` is `scene.ron`), so
//!   one file would pass as another name's extension.
//!
//! Applied on Windows only (see [`super::FileRules`]); the rules are plain text, so they are
//! tested everywhere.

/// Device names Windows reserves in every folder (case-insensitive, before any extension).
const RESERVED: [&str; 6] = ["CON", "PRN", "AUX", "NUL", "CONIN$", "CONOUT$"];

/// Why Windows would read `name` as something other than a file inside the folders it names, or
/// `None` when it is a plain local path.
pub fn windows_problem(name: &str) -> Option<String> {
    let name = name.replace('/', "\\");
    let rest = if let Some(verbatim) = name.strip_prefix("\\\\?\\") {
        // `\\?\C:\…` is a local path past 260 characters; any other `\\?\` is a device or share.
        if !is_drive_root(verbatim) {
            return Some("a network or device path (\\\\…) is never opened".into());
        }
        &verbatim[2..]
    } else if name.starts_with("\\\\") {
        return Some("a network or device path (\\\\…) is never opened".into());
    } else if has_drive(&name) {
        if !name[2..].starts_with('\\') {
            return Some("a drive-relative path (C:name) is never opened; give C:\\…".into());
        }
        &name[2..]
    } else {
        &name[..]
    };
    if rest.contains(':') {
        return Some("a ':' past the drive names a hidden stream of a file; it is never opened".into());
    }
    for part in rest.split('\\').filter(|p| !p.is_empty() && *p != "." && *p != "..") {
        if part.ends_with('.') || part.ends_with(' ') {
            return Some(format!("'{part}' ends in a dot or space, which Windows drops"));
        }
        if is_reserved(part) {
            return Some(format!("'{part}' is a device name on Windows, never a file"));
        }
    }
    None
}

/// `C:` at the start.
fn has_drive(name: &str) -> bool {
    let b = name.as_bytes();
    b.len() >= 2 && b[0].is_ascii_alphabetic() && b[1] == b':'
}

/// `C:\` at the start (or `C:` alone).
fn is_drive_root(name: &str) -> bool {
    has_drive(name) && (name.len() == 2 || name[2..].starts_with('\\'))
}

/// Whether a path part names a device: its stem (before the first dot, trailing spaces dropped)
/// is a reserved name, or `COM`/`LPT` with one digit (superscripts 1–3 included).
fn is_reserved(part: &str) -> bool {
    let stem = part.split('.').next().unwrap_or(part).trim_end_matches(' ').to_ascii_uppercase();
    if RESERVED.contains(&stem.as_str()) {
        return true;
    }
    let Some(port) = stem.strip_prefix("COM").or_else(|| stem.strip_prefix("LPT")) else { return false };
    let mut digits = port.chars();
    matches!((digits.next(), digits.next()), (Some('0'..='9' | '¹' | '²' | '³'), None))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn network_device_and_stream_names_are_refused_and_local_paths_pass() {
        for name in [
            "\\\\attacker\\share\\a.png",
            "//attacker/share/a.png",
            "\\\\.\\pipe\\indra",
            "\\\\?\\UNC\\attacker\\share\\a.png",
            "\\\\?\\GLOBALROOT\\Device\\x",
            "C:scene.ron",
            "a.png:hidden",
            "C:\\show\\a.png:$DATA",
            "CON",
            "nul.png",
            "clips\\Com1.mov",
            "lpt²",
            "AUX  .ron",
            "conout$",
            "scene.ron.",
            "C:\\show\\clips \\a.mov",
        ] {
            assert!(windows_problem(name).is_some(), "{name} passed");
        }
        for name in [
            "scene.ron",
            "clips\\a.mov",
            "clips/a.mov",
            "..\\shared\\a.png",
            "C:\\Users\\vj\\show\\a.png",
            "\\\\?\\C:\\Users\\vj\\a very long path\\a.png",
            "console.png",
            "com10.ron",
            "nullify.wgsl",
            "LPT.ron",
            "./a.png",
        ] {
            assert_eq!(windows_problem(name), None, "{name}");
        }
    }
}
