//! The file rules (`indra::files`) as a test of their own: CI's Windows job builds this one
//! target beside indra.exe and runs it under Wine, where the share, device and stream refusals
//! and the case-insensitive folders apply (a build of the library's unit tests for Windows took
//! most of that job's time).

use indra::files::{FileError, FileRules};
use std::path::PathBuf;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("indra-files-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("inside")).unwrap();
    dir
}

#[test]
fn names_resolve_beside_the_root_and_stay_inside_the_allowed_folders() {
    let dir = scratch("locate");
    let root = dir.join("inside");
    std::fs::write(root.join("a.ron"), "x").unwrap();
    std::fs::write(dir.join("outside.ron"), "x").unwrap();
    let rules = FileRules::new([root.clone()]);
    assert_eq!(rules.locate(Some(&root), "a.ron").unwrap(), root.join("a.ron").canonicalize().unwrap());
    for name in ["../outside.ron", dir.join("outside.ron").to_str().unwrap()] {
        assert!(matches!(rules.locate(Some(&root), name), Err(FileError::Refused(_))), "{name}");
    }
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink(dir.join("outside.ron"), root.join("link.ron")).unwrap();
        assert!(matches!(rules.locate(Some(&root), "link.ron"), Err(FileError::Refused(_))), "a link out");
    }
    assert!(matches!(rules.locate(Some(&root), "missing.ron"), Err(FileError::NotFound(_))));
    let wider = rules.allowing(dir.clone());
    assert!(wider.locate(Some(&root), "../outside.ron").is_ok());
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn saving_is_confined_to_the_allowed_folders_and_the_extension() {
    let dir = scratch("save");
    let root = dir.join("inside");
    std::fs::write(dir.join("victim.conf"), "keep").unwrap();
    let rules = FileRules::new([root.clone()]);
    assert!(rules.locate_for_saving(Some(&root), "wall.ron", "ron").is_ok());
    let victim = dir.join("victim.conf");
    for name in [victim.to_str().unwrap(), "../victim.ron", "wall.conf", "/etc/passwd"] {
        assert!(rules.locate_for_saving(Some(&root), name, "ron").is_err(), "{name}");
    }
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink(&victim, root.join("link.ron")).unwrap();
        assert!(rules.locate_for_saving(Some(&root), "link.ron", "ron").is_err(), "a link out");
    }
    assert_eq!(std::fs::read_to_string(&victim).unwrap(), "keep");
    std::fs::remove_dir_all(dir).unwrap();
}

/// Windows only (run under Wine in CI): a share, a device or a stream is refused before any
/// look-up, the allowed folders hold whatever case a name is given in, and the user's own
/// files go to %APPDATA%.
#[cfg(windows)]
#[test]
fn windows_shares_devices_and_streams_are_refused_and_case_does_not_matter() {
    let dir = scratch("windows");
    let root = dir.join("inside");
    std::fs::write(root.join("a.ron"), "x").unwrap();
    let rules = FileRules::new([root.clone()]);
    for name in
        ["\\\\127.0.0.1\\c$\\a.ron", "//127.0.0.1/c$/a.ron", "\\\\.\\pipe\\indra", "NUL.ron", "a.ron:x", "a.ron."]
    {
        let refused = rules.locate(Some(&root), name);
        assert!(
            matches!(&refused, Err(FileError::Refused(m)) if m.contains("never") || m.contains("drops")),
            "{name}: {refused:?}"
        );
        assert!(rules.locate_for_saving(Some(&root), name, "ron").is_err(), "{name}");
    }
    let upper = FileRules::new([PathBuf::from(root.to_str().unwrap().to_uppercase())]);
    assert!(upper.locate(Some(&root), "A.RON").is_ok(), "a name in another case is the same file");
    // Presets and learned mappings default to the user's roaming folder, not the install's.
    let app_data = PathBuf::from(std::env::var_os("APPDATA").expect("Windows sets APPDATA"));
    assert_eq!(indra::files::user_data("presets"), app_data.join("indra").join("presets"));
    let drive = root.to_str().unwrap()[..2].to_string();
    assert!(matches!(rules.locate(Some(&root), &format!("{drive}\\Windows\\win.ini")), Err(FileError::Refused(_))));
    std::fs::remove_dir_all(dir).unwrap();
}

#[cfg(unix)]
#[test]
fn pipes_devices_and_large_files_are_refused_without_blocking() {
    let dir = scratch("read");
    let fifo = dir.join("pipe");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    if made.is_ok_and(|s| s.success()) {
        assert!(matches!(indra::files::read_limited(&fifo, 1 << 20), Err(FileError::Refused(_))));
    }
    assert!(matches!(
        indra::files::read_limited(std::path::Path::new("/dev/zero"), 1 << 20),
        Err(FileError::Refused(_))
    ));
    assert!(matches!(indra::files::read_limited(&dir, 1 << 20), Err(FileError::Refused(_))));
    let big = dir.join("big");
    std::fs::write(&big, vec![7u8; 2000]).unwrap();
    assert!(matches!(indra::files::read_limited(&big, 1999), Err(FileError::Refused(_))));
    assert_eq!(indra::files::read_limited(&big, 2000).unwrap().len(), 2000);
    assert!(matches!(indra::files::read_limited(&dir.join("none"), 10), Err(FileError::NotFound(_))));
    std::fs::remove_dir_all(dir).unwrap();
}
