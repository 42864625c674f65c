//! The NDI runtime, loaded when first asked for: `libndi.so.6` (or `libndi.so`) from
//! `NDI_RUNTIME_DIR_V6`, then the dynamic loader's own search and the standard install folders.
//! The runtime is proprietary and not ours to ship, so nothing links it: the SDK's dynamic-loading
//! entry point `NDIlib_v6_load` hands over its table of functions, and the few this crate calls
//! are read from that table at the positions the SDK's `NDIlib_v6` struct gives them.
//!
//! The structs below are the C layouts of the SDK's `Processing.NDI.*.h` (an ABI the SDK keeps
//! stable across v6); a test checks every table position against the symbol the library exports
//! under the same name.

use std::ffi::{CStr, c_char, c_void};
use std::sync::OnceLock;

/// The environment variable the NDI SDK names for its runtime's folder.
pub const RUNTIME_DIR_ENV: &str = "NDI_RUNTIME_DIR_V6";

/// Library names tried in each folder, newest ABI first.
#[cfg(not(windows))]
const LIBRARY_NAMES: &[&str] = &["libndi.so.6", "libndi.so"];
/// The runtime's name on Windows (64-bit), as NDI Tools and the NDI 6 Runtime install it.
#[cfg(windows)]
const LIBRARY_NAMES: &[&str] = &["Processing.NDI.Lib.x64.dll"];

/// Folders the NDI SDK and NDI Tools install the runtime to on Linux.
#[cfg(not(windows))]
const STANDARD_DIRS: &[&str] =
    &["/usr/local/lib", "/usr/lib", "/usr/lib/x86_64-linux-gnu", "/usr/lib/aarch64-linux-gnu"];
/// Folders the NDI 6 Runtime and NDI Tools install the runtime to on Windows.
#[cfg(windows)]
const STANDARD_DIRS: &[&str] = &["C:/Program Files/NDI/NDI 6 Runtime/v6", "C:/Program Files/NDI/NDI 6 Tools/Runtime"];

/// A source as the finder reports it and a receiver connects to it (`NDIlib_source_t`).
#[repr(C)]
#[derive(Clone, Copy)]
pub(super) struct RawSource {
    pub name: *const c_char,
    pub url_address: *const c_char,
}

/// `NDIlib_find_create_t`.
#[repr(C)]
pub(super) struct FindCreate {
    pub show_local_sources: bool,
    pub groups: *const c_char,
    pub extra_ips: *const c_char,
}

/// `NDIlib_send_create_t`.
#[repr(C)]
pub(super) struct SendCreate {
    pub name: *const c_char,
    pub groups: *const c_char,
    pub clock_video: bool,
    pub clock_audio: bool,
}

/// `NDIlib_recv_create_v3_t`.
#[repr(C)]
pub(super) struct RecvCreate {
    pub source: RawSource,
    pub color_format: i32,
    pub bandwidth: i32,
    pub allow_video_fields: bool,
    pub name: *const c_char,
}

/// `NDIlib_video_frame_v2_t`.
#[repr(C)]
pub(super) struct VideoFrame {
    pub xres: i32,
    pub yres: i32,
    pub fourcc: u32,
    pub frame_rate_n: i32,
    pub frame_rate_d: i32,
    pub picture_aspect_ratio: f32,
    pub frame_format_type: i32,
    /// 100 ns units.
    pub timecode: i64,
    pub data: *mut u8,
    pub line_stride: i32,
    pub metadata: *const c_char,
    /// 100 ns units since the UNIX epoch, stamped by the sending library.
    pub timestamp: i64,
}

impl VideoFrame {
    /// An empty frame for a receiver to fill.
    pub fn empty() -> Self {
        Self {
            xres: 0,
            yres: 0,
            fourcc: 0,
            frame_rate_n: 0,
            frame_rate_d: 0,
            picture_aspect_ratio: 0.0,
            frame_format_type: 0,
            timecode: 0,
            data: std::ptr::null_mut(),
            line_stride: 0,
            metadata: std::ptr::null(),
            timestamp: 0,
        }
    }
}

/// Four-character codes of the pixel layouts indra sends and takes.
pub(super) const fn fourcc(code: &[u8; 4]) -> u32 {
    u32::from_le_bytes(*code)
}
/// `NDIlib_frame_type_video`.
pub(super) const FRAME_VIDEO: i32 = 1;
/// `NDIlib_frame_type_error`: the connection was lost.
pub(super) const FRAME_ERROR: i32 = 4;
/// `NDIlib_frame_format_type_progressive`.
pub(super) const PROGRESSIVE: i32 = 1;
/// `NDIlib_recv_color_format_RGBX_RGBA`: every frame arrives as RGBX or RGBA rows.
pub(super) const COLOR_RGBX_RGBA: i32 = 2;
/// `NDIlib_recv_bandwidth_highest`.
pub(super) const BANDWIDTH_HIGHEST: i32 = 100;

/// Positions in the SDK's `NDIlib_v6` table (each union of old and new names is one slot).
pub(super) mod slot {
    pub const INITIALIZE: usize = 0;
    pub const VERSION: usize = 2;
    pub const FIND_CREATE_V2: usize = 5;
    pub const FIND_DESTROY: usize = 6;
    pub const SEND_CREATE: usize = 8;
    pub const SEND_DESTROY: usize = 9;
    pub const RECV_DESTROY: usize = 23;
    pub const FIND_WAIT_FOR_SOURCES: usize = 42;
    pub const FIND_GET_CURRENT_SOURCES: usize = 43;
    pub const RECV_FREE_VIDEO_V2: usize = 47;
    pub const RECV_CAPTURE_V2: usize = 49;
    pub const SEND_SEND_VIDEO_V2: usize = 50;
    pub const RECV_CREATE_V3: usize = 84;
    /// One past the last slot read: the table must be at least this long (it has 134 in v6.3).
    pub const USED: usize = 85;
}

/// The loaded runtime: the library (kept loaded for the process's life) and its function table.
pub struct NdiRuntime {
    table: *const *const c_void,
    /// Where the library was found.
    pub path: String,
}

// The table is immutable after loading and the SDK's functions are thread-safe per instance.
unsafe impl Send for NdiRuntime {}
unsafe impl Sync for NdiRuntime {}

macro_rules! ndi_fn {
    ($(#[$doc:meta])* $name:ident, $slot:ident, fn($($arg:ident: $ty:ty),*) $(-> $ret:ty)?) => {
        $(#[$doc])*
        pub(super) unsafe fn $name(&self, $($arg: $ty),*) $(-> $ret)? {
            // SAFETY: the slot holds this function of the SDK's table (checked against the
            // library's own export of the same name in the tests).
            let f: unsafe extern "C" fn($($ty),*) $(-> $ret)? = unsafe { std::mem::transmute(self.entry(slot::$slot)) };
            unsafe { f($($arg),*) }
        }
    };
}

impl NdiRuntime {
    /// The runtime, loaded once; the same sentence every time it cannot be.
    pub fn get() -> Result<&'static NdiRuntime, String> {
        static RUNTIME: OnceLock<Result<NdiRuntime, String>> = OnceLock::new();
        RUNTIME.get_or_init(load).as_ref().map_err(Clone::clone)
    }

    /// The runtime's version string.
    pub fn version(&self) -> String {
        // SAFETY: `version` returns a static C string.
        unsafe { CStr::from_ptr(self.version_raw()) }.to_string_lossy().into_owned()
    }

    fn entry(&self, index: usize) -> *const c_void {
        // SAFETY: `load` checked the table is non-null and every slot up to `slot::USED` is set.
        unsafe { *self.table.add(index) }
    }

    ndi_fn!(initialize, INITIALIZE, fn() -> bool);
    ndi_fn!(version_raw, VERSION, fn() -> *const c_char);
    ndi_fn!(find_create, FIND_CREATE_V2, fn(settings: *const FindCreate) -> *mut c_void);
    ndi_fn!(find_destroy, FIND_DESTROY, fn(find: *mut c_void));
    ndi_fn!(
        /// Blocks up to `timeout_ms` for the list to change.
        find_wait, FIND_WAIT_FOR_SOURCES, fn(find: *mut c_void, timeout_ms: u32) -> bool
    );
    ndi_fn!(
        /// The sources seen so far; valid until the next call on `find`.
        find_current, FIND_GET_CURRENT_SOURCES, fn(find: *mut c_void, count: *mut u32) -> *const RawSource
    );
    ndi_fn!(send_create, SEND_CREATE, fn(settings: *const SendCreate) -> *mut c_void);
    ndi_fn!(send_destroy, SEND_DESTROY, fn(send: *mut c_void));
    ndi_fn!(
        /// Sends a frame; with `clock_video` it waits until the frame is due.
        send_video, SEND_SEND_VIDEO_V2, fn(send: *mut c_void, frame: *const VideoFrame)
    );
    ndi_fn!(recv_create, RECV_CREATE_V3, fn(settings: *const RecvCreate) -> *mut c_void);
    ndi_fn!(recv_destroy, RECV_DESTROY, fn(recv: *mut c_void));
    ndi_fn!(
        /// Waits up to `timeout_ms` for a frame; returns its type.
        recv_capture,
        RECV_CAPTURE_V2,
        fn(recv: *mut c_void, video: *mut VideoFrame, audio: *mut c_void, metadata: *mut c_void, timeout_ms: u32) -> i32
    );
    ndi_fn!(recv_free_video, RECV_FREE_VIDEO_V2, fn(recv: *mut c_void, video: *const VideoFrame));
}

/// Where the runtime may be, in the order tried.
fn candidates() -> Vec<String> {
    let mut paths = Vec::new();
    if let Some(dir) = std::env::var_os(RUNTIME_DIR_ENV).filter(|d| !d.is_empty()) {
        let dir = std::path::PathBuf::from(dir);
        paths.extend(LIBRARY_NAMES.iter().map(|n| dir.join(n).display().to_string()));
    }
    // Bare names go through the dynamic loader's search (LD_LIBRARY_PATH, ld.so.cache).
    paths.extend(LIBRARY_NAMES.iter().map(|n| (*n).to_string()));
    for dir in STANDARD_DIRS {
        paths.extend(LIBRARY_NAMES.iter().map(|n| format!("{dir}/{n}")));
    }
    paths
}

fn load() -> Result<NdiRuntime, String> {
    let not_found = || {
        format!(
            "no NDI runtime was found: install NDI Tools or the NDI SDK (https://ndi.video), or name the folder holding {} in {RUNTIME_DIR_ENV}",
            LIBRARY_NAMES[0]
        )
    };
    let (path, library) = candidates()
        .into_iter()
        .find_map(|path| {
            // SAFETY: loading runs the library's initialisers; libndi's are its own set-up.
            unsafe { libloading::Library::new(&path) }.ok().map(|lib| (path, lib))
        })
        .ok_or_else(not_found)?;
    type Load = unsafe extern "C" fn() -> *const *const c_void;
    // SAFETY: `NDIlib_v6_load` takes nothing and returns the SDK's static table.
    let table = unsafe {
        let load: libloading::Symbol<Load> = library
            .get(b"NDIlib_v6_load\0")
            .map_err(|_| format!("{path} is not an NDI 6 runtime (it has no NDIlib_v6_load): install NDI 6"))?;
        load()
    };
    if table.is_null() || (0..slot::USED).any(|i| unsafe { (*table.add(i)).is_null() }) {
        return Err(format!("{path} gave an incomplete NDI 6 table: install a current NDI 6 runtime"));
    }
    // The runtime stays loaded until the process ends: its threads and the table live on.
    std::mem::forget(library);
    let runtime = NdiRuntime { table, path };
    // SAFETY: `initialize` takes nothing; false means this CPU lacks what NDI needs (SSE4.2).
    if !unsafe { runtime.initialize() } {
        return Err("the NDI runtime does not support this CPU".into());
    }
    Ok(runtime)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every table position read is the function the library exports under that name, so a
    /// shifted slot cannot call the wrong function. Runs where a runtime is installed (CI
    /// installs cyndilib's); elsewhere it says so.
    #[test]
    fn table_slots_are_the_functions_of_their_names() {
        let runtime = match NdiRuntime::get() {
            Ok(r) => r,
            Err(e) if std::env::var_os("CI").is_none() => return eprintln!("skipped: {e}"),
            Err(e) => panic!("CI installs an NDI runtime: {e}"),
        };
        let library = unsafe { libloading::Library::new(&runtime.path) }.expect("loads again");
        let named = [
            (slot::INITIALIZE, "NDIlib_initialize"),
            (slot::VERSION, "NDIlib_version"),
            (slot::FIND_CREATE_V2, "NDIlib_find_create_v2"),
            (slot::FIND_DESTROY, "NDIlib_find_destroy"),
            (slot::SEND_CREATE, "NDIlib_send_create"),
            (slot::SEND_DESTROY, "NDIlib_send_destroy"),
            (slot::RECV_DESTROY, "NDIlib_recv_destroy"),
            (slot::FIND_WAIT_FOR_SOURCES, "NDIlib_find_wait_for_sources"),
            (slot::FIND_GET_CURRENT_SOURCES, "NDIlib_find_get_current_sources"),
            (slot::RECV_FREE_VIDEO_V2, "NDIlib_recv_free_video_v2"),
            (slot::RECV_CAPTURE_V2, "NDIlib_recv_capture_v2"),
            (slot::SEND_SEND_VIDEO_V2, "NDIlib_send_send_video_v2"),
            (slot::RECV_CREATE_V3, "NDIlib_recv_create_v3"),
        ];
        for (index, name) in named {
            let symbol: libloading::Symbol<*const c_void> =
                unsafe { library.get(format!("{name}\0").as_bytes()) }.unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(runtime.entry(index), *symbol, "slot {index} is not {name}");
        }
        assert!(runtime.version().contains("NDI"), "{}", runtime.version());
    }
}
