//! The effect library: what a chain can take — every ISF filter with one image input (bundled
//! and in the performer's `shaders/isf/`), every WGSL effect, and every technique that takes one
//! image — for the
//! panel's picker and the browser's menu. Read once on a worker thread (every ISF header), so
//! no frame waits for it.

use std::sync::OnceLock;
use std::sync::atomic::{AtomicBool, Ordering};

use crate::assets::{AssetKind, Assets};
use crate::techniques::isf::{IsfFiles, header};

static NAMES: OnceLock<Vec<String>> = OnceLock::new();
static STARTED: AtomicBool = AtomicBool::new(false);

/// Starts reading the library from `assets` (once; later calls do nothing).
pub fn start(assets: &Assets) {
    if NAMES.get().is_some() || STARTED.swap(true, Ordering::Relaxed) {
        return;
    }
    let assets = assets.clone();
    let read = move || {
        let _ = NAMES.set(read_library(&assets));
    };
    if std::thread::Builder::new().name("indra-effect-library".into()).spawn(read).is_err() {
        STARTED.store(false, Ordering::Relaxed);
    }
}

/// The library, once read (`None` before [`start`] and while it reads).
pub fn names() -> Option<&'static [String]> {
    NAMES.get().map(Vec::as_slice)
}

/// Every ISF filter with one image input, every WGSL effect (`shaders/effect_*.wgsl`), then every
/// technique that takes one image.
pub fn read_library(assets: &Assets) -> Vec<String> {
    let filter = |name: &String| {
        let Ok(files) = IsfFiles::read(assets, name) else { return false };
        header::Header::parse(&files.fs.1)
            .is_ok_and(|h| h.role() == header::Role::Filter && h.image_inputs().len() == 1)
    };
    let mut names: Vec<String> = crate::techniques::isf::shader_names(assets).into_iter().filter(filter).collect();
    let wgsl = assets.names(AssetKind::Shader).into_iter().filter(|n| n.starts_with("effect_") && n.ends_with(".wgsl"));
    names.extend(wgsl);
    let techniques = crate::techniques::REGISTRY.iter().filter(|t| t.inputs.len() == 1 && t.declare.is_none());
    names.extend(techniques.map(|t| t.name.to_string()));
    names
}
