//! Receiving an NDI source on a thread of its own: the finder looks for the named source, a
//! receiver takes its frames as RGBA rows and keeps the newest. A source that is not there yet is
//! waited for; one that stops sending leaves its last frame in place and one sentence, and is
//! shown again when it comes back (the SDK reconnects by itself).

use std::ffi::{CStr, CString, c_void};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use super::runtime::{
    BANDWIDTH_HIGHEST, COLOR_RGBX_RGBA, FRAME_ERROR, FRAME_VIDEO, FindCreate, NdiRuntime, RawSource, RecvCreate,
    VideoFrame, fourcc,
};

/// How long without a frame before a source counts as gone.
const SILENCE: Duration = Duration::from_secs(2);

/// The largest frame taken from the network (a side and RGBA bytes); larger ones are refused,
/// so a hostile sender cannot make indra allocate without bound.
const MAX_SIDE: u32 = 8192;

/// A source on the network: its full name (`MACHINE (stream)`) and address.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NdiSource {
    /// The name receivers select it by.
    pub name: String,
    /// Its address (`host:port`), where the runtime reports one.
    pub url: String,
}

/// Whether `wanted` (a full name, or the stream's part in the parentheses) names `source`.
pub fn names_source(wanted: &str, source: &str) -> bool {
    let wanted = wanted.trim();
    !wanted.is_empty() && (source == wanted || source.ends_with(&format!("({wanted})")))
}

/// Whether `wanted` is a source's address, `HOST:PORT` (as `--list-ndi` prints it), rather than
/// its name.
pub fn is_address(wanted: &str) -> bool {
    let Some((host, port)) = wanted.rsplit_once(':') else { return false };
    !host.is_empty()
        && host.chars().all(|c| c.is_ascii_alphanumeric() || ".-[]:".contains(c))
        && port.parse::<u16>().is_ok_and(|p| p > 0)
}

/// A finder for the life of a value.
struct Finder {
    runtime: &'static NdiRuntime,
    instance: *mut c_void,
}

impl Finder {
    fn new(runtime: &'static NdiRuntime) -> Result<Self, String> {
        let settings = FindCreate { show_local_sources: true, groups: std::ptr::null(), extra_ips: std::ptr::null() };
        // SAFETY: plain settings; null groups and extra IPs are the SDK's defaults (its config file).
        let instance = unsafe { runtime.find_create(&settings) };
        if instance.is_null() {
            return Err("the NDI runtime could not start looking for sources".into());
        }
        Ok(Self { runtime, instance })
    }

    /// Waits up to `timeout` for the list to change, then the sources seen so far.
    fn sources(&self, timeout: Duration) -> Vec<(NdiSource, RawSource)> {
        let mut count = 0u32;
        // SAFETY: a live finder; the returned array is valid until the next call on it, and the
        // strings are copied out before then.
        unsafe {
            self.runtime.find_wait(self.instance, timeout.as_millis().min(u128::from(u32::MAX)) as u32);
            let list = self.runtime.find_current(self.instance, &mut count);
            if list.is_null() {
                return Vec::new();
            }
            std::slice::from_raw_parts(list, count as usize)
                .iter()
                .map(|raw| {
                    let text = |p: *const std::ffi::c_char| {
                        if p.is_null() { String::new() } else { CStr::from_ptr(p).to_string_lossy().into_owned() }
                    };
                    (NdiSource { name: text(raw.name), url: text(raw.url_address) }, *raw)
                })
                .collect()
        }
    }
}

impl Drop for Finder {
    fn drop(&mut self) {
        // SAFETY: created by `find_create`, destroyed once.
        unsafe { self.runtime.find_destroy(self.instance) };
    }
}

/// The NDI sources seen within `wait` (the network announces them over a second or two).
pub fn list_sources(wait: Duration) -> Result<Vec<NdiSource>, String> {
    let finder = Finder::new(NdiRuntime::get()?)?;
    let until = Instant::now() + wait;
    let mut seen = Vec::new();
    while Instant::now() < until {
        seen = finder.sources(until.saturating_duration_since(Instant::now()).min(Duration::from_millis(250)));
    }
    let mut sources: Vec<NdiSource> = seen.into_iter().map(|(s, _)| s).collect();
    sources.sort_by(|a, b| a.name.cmp(&b.name));
    Ok(sources)
}

/// A frame taken from the network.
#[derive(Clone, Debug)]
pub struct NdiFrame {
    /// Counts frames from 1 in the order they came.
    pub number: u64,
    /// Width and height.
    pub size: (u32, u32),
    /// Tight RGBA rows.
    pub rgba: Arc<Vec<u8>>,
    /// The sender's timecode (100 ns units).
    pub timecode: i64,
}

#[derive(Default)]
struct FeedState {
    latest: Option<NdiFrame>,
    /// The full name of the source connected to.
    connected: Option<String>,
    /// Whether frames are coming now.
    live: bool,
    message: Option<String>,
    quit: bool,
}

/// A named NDI source read on its own thread; the newest frame wins.
pub struct NdiFeed {
    state: Arc<Mutex<FeedState>>,
}

impl NdiFeed {
    /// Starts looking for `wanted` (see [`names_source`]) and taking its frames. A missing
    /// runtime is the feed's first message.
    pub fn start(wanted: &str) -> Self {
        let state = Arc::new(Mutex::new(FeedState::default()));
        let shared = Arc::clone(&state);
        let wanted = wanted.trim().to_string();
        let started = NdiRuntime::get().and_then(|runtime| {
            std::thread::Builder::new()
                .name("ndi-in".into())
                .spawn(move || receive(runtime, &shared, &wanted))
                .map(drop)
                .map_err(|e| format!("cannot start the NDI thread: {e}"))
        });
        if let Err(e) = started {
            lock(&state).message = Some(e);
        }
        Self { state }
    }

    /// The newest frame, if any came.
    pub fn latest(&self) -> Option<NdiFrame> {
        lock(&self.state).latest.clone()
    }

    /// The source's full name once connected, and whether its frames are coming now.
    pub fn connection(&self) -> (Option<String>, bool) {
        let s = lock(&self.state);
        (s.connected.clone(), s.live)
    }

    /// A new sentence about the source (gone, back, refused frames), once.
    pub fn take_message(&self) -> Option<String> {
        lock(&self.state).message.take()
    }
}

impl Drop for NdiFeed {
    fn drop(&mut self) {
        lock(&self.state).quit = true;
    }
}

fn lock(state: &Mutex<FeedState>) -> std::sync::MutexGuard<'_, FeedState> {
    state.lock().unwrap_or_else(|e| e.into_inner())
}

/// How a feed finds its source: an address (`HOST:PORT`) is connected to directly, without
/// discovery (a source across subnets, or a network without mDNS); a name is looked for.
enum Lookup {
    Address(CString),
    Discovery(Finder),
}

impl Lookup {
    fn new(runtime: &'static NdiRuntime, wanted: &str) -> Result<Self, String> {
        match is_address(wanted).then(|| CString::new(wanted).ok()).flatten() {
            Some(address) => Ok(Lookup::Address(address)),
            None => Finder::new(runtime).map(Lookup::Discovery),
        }
    }

    /// The source to connect to, if it is there (a name waits up to half a second for it). The
    /// raw source's strings stay valid until the next call.
    fn find(&self, wanted: &str) -> Option<(NdiSource, RawSource)> {
        match self {
            Lookup::Address(a) => {
                let source = NdiSource { name: wanted.to_string(), url: wanted.to_string() };
                Some((source, RawSource { name: a.as_ptr(), url_address: a.as_ptr() }))
            }
            Lookup::Discovery(finder) => {
                finder.sources(Duration::from_millis(500)).into_iter().find(|(s, _)| names_source(wanted, &s.name))
            }
        }
    }
}

/// A receiver for the life of a value.
struct Receiver {
    runtime: &'static NdiRuntime,
    instance: *mut c_void,
}

impl Drop for Receiver {
    fn drop(&mut self) {
        // SAFETY: created by `recv_create`, destroyed once.
        unsafe { self.runtime.recv_destroy(self.instance) };
    }
}

/// The feed's thread: find, connect, take frames until told to quit.
fn receive(runtime: &'static NdiRuntime, state: &Mutex<FeedState>, wanted: &str) {
    let quit = || lock(state).quit;
    let lookup = match Lookup::new(runtime, wanted) {
        Ok(lookup) => lookup,
        Err(e) => return lock(state).message = Some(e),
    };
    let receiver_name = CString::new("indra").expect("no NUL");
    let mut receiver: Option<Receiver> = None;
    let mut last_frame = Instant::now();
    let mut number = 0u64;
    while !quit() {
        let Some(recv) = &receiver else {
            if let Some((source, raw)) = lookup.find(wanted) {
                let settings = RecvCreate {
                    source: raw,
                    color_format: COLOR_RGBX_RGBA,
                    bandwidth: BANDWIDTH_HIGHEST,
                    allow_video_fields: false,
                    name: receiver_name.as_ptr(),
                };
                // SAFETY: the source's strings belong to the lookup and are valid until its next
                // call; the SDK copies them here.
                let instance = unsafe { runtime.recv_create(&settings) };
                if instance.is_null() {
                    lock(state).message = Some(format!("the NDI runtime could not receive '{}'", source.name));
                    std::thread::sleep(Duration::from_secs(1));
                    continue;
                }
                receiver = Some(Receiver { runtime, instance });
                last_frame = Instant::now();
                lock(state).connected = Some(source.name);
            }
            continue;
        };
        let mut video = VideoFrame::empty();
        // SAFETY: a live receiver; audio and metadata are not asked for.
        let kind =
            unsafe { runtime.recv_capture(recv.instance, &mut video, std::ptr::null_mut(), std::ptr::null_mut(), 200) };
        match kind {
            FRAME_VIDEO => {
                let copied = copy_frame(&video);
                // SAFETY: the frame was filled by this receiver's capture and is freed once.
                unsafe { runtime.recv_free_video(recv.instance, &video) };
                let mut s = lock(state);
                match copied {
                    Ok((size, rgba)) => {
                        number += 1;
                        last_frame = Instant::now();
                        if !s.live && number > 1 {
                            s.message = Some(format!("the NDI source '{wanted}' is sending again"));
                        }
                        s.live = true;
                        s.latest = Some(NdiFrame { number, size, rgba: Arc::new(rgba), timecode: video.timecode });
                    }
                    Err(e) if s.live || number == 0 => {
                        s.message = Some(e);
                        s.live = false;
                    }
                    Err(_) => {}
                }
            }
            FRAME_ERROR => last_frame = last_frame.min(Instant::now() - SILENCE),
            _ => {}
        }
        if last_frame.elapsed() >= SILENCE {
            let mut s = lock(state);
            if s.live {
                s.live = false;
                s.message = Some(match s.latest.is_some() {
                    true => format!("the NDI source '{wanted}' stopped sending; showing its last frame"),
                    false => format!("the NDI source '{wanted}' sends no video"),
                });
            }
        }
    }
}

/// Tight RGBA rows of a received frame (RGBA, RGBX, BGRA or BGRX), or why it is refused.
fn copy_frame(video: &VideoFrame) -> Result<((u32, u32), Vec<u8>), String> {
    let (w, h) = (video.xres, video.yres);
    if w <= 0 || h <= 0 || w as u32 > MAX_SIDE || h as u32 > MAX_SIDE || video.data.is_null() {
        return Err(format!("an NDI frame of {w}×{h} was refused (at most {MAX_SIDE} on a side)"));
    }
    let (w, h) = (w as usize, h as usize);
    let stride = video.line_stride as usize;
    let swap = match video.fourcc {
        f if f == fourcc(b"RGBA") || f == fourcc(b"RGBX") => false,
        f if f == fourcc(b"BGRA") || f == fourcc(b"BGRX") => true,
        f => {
            let code = String::from_utf8_lossy(&f.to_le_bytes()).into_owned();
            return Err(format!("an NDI frame came as {code}, not the RGBA asked for"));
        }
    };
    if stride < w * 4 {
        return Err(format!("an NDI frame's rows ({stride} bytes) are shorter than {w} pixels"));
    }
    // SAFETY: the SDK hands `yres` rows of `line_stride` bytes at `data`.
    let data = unsafe { std::slice::from_raw_parts(video.data, stride * h) };
    let mut rgba = Vec::with_capacity(w * h * 4);
    for row in data.chunks_exact(stride) {
        rgba.extend_from_slice(&row[..w * 4]);
    }
    if swap {
        rgba.chunks_exact_mut(4).for_each(|p| p.swap(0, 2));
    }
    // RGBX carries no alpha: the picture is opaque.
    if video.fourcc == fourcc(b"RGBX") || video.fourcc == fourcc(b"BGRX") {
        rgba.chunks_exact_mut(4).for_each(|p| p[3] = 255);
    }
    Ok(((w as u32, h as u32), rgba))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sources_are_named_in_full_or_by_their_stream() {
        assert!(names_source("STAGE-PC (OBS)", "STAGE-PC (OBS)"));
        assert!(names_source("OBS", "STAGE-PC (OBS)"));
        assert!(names_source(" OBS ", "STAGE-PC (OBS)"));
        assert!(!names_source("BS", "STAGE-PC (OBS)"));
        assert!(!names_source("", "STAGE-PC (OBS)"));
        assert!(is_address("127.0.0.1:5961") && is_address("stage-pc.local:5961") && is_address("[::1]:5961"));
        assert!(!is_address("STAGE-PC (OBS)") && !is_address("OBS") && !is_address("host:0") && !is_address(":5961"));
    }

    #[test]
    fn frames_are_copied_to_tight_rgba_and_odd_ones_refused() {
        let mut data: Vec<u8> = (0..2 * 12).map(|i| i as u8).collect();
        let mut video = VideoFrame::empty();
        (video.xres, video.yres, video.line_stride, video.data) = (2, 2, 12, data.as_mut_ptr());
        video.fourcc = fourcc(b"BGRA");
        let ((w, h), rgba) = copy_frame(&video).unwrap();
        assert_eq!((w, h), (2, 2));
        assert_eq!(rgba, vec![2, 1, 0, 3, 6, 5, 4, 7, 14, 13, 12, 15, 18, 17, 16, 19]);
        video.fourcc = fourcc(b"RGBX");
        assert!(copy_frame(&video).unwrap().1.chunks(4).all(|p| p[3] == 255));
        video.fourcc = fourcc(b"UYVY");
        assert!(copy_frame(&video).unwrap_err().contains("UYVY"));
        video.fourcc = fourcc(b"RGBA");
        video.xres = 9000;
        assert!(copy_frame(&video).unwrap_err().contains("refused"));
        (video.xres, video.line_stride) = (4, 12);
        assert!(copy_frame(&video).unwrap_err().contains("shorter"));
    }
}
