//! Cameras (Linux V4L2 devices) through ffmpeg's `v4l2` input, and a stand-in that runs the same
//! path without one (ffmpeg's `testsrc2`): a worker thread reads frames as they come and keeps
//! the newest. A camera that is missing, busy or unplugged is one sentence and a retry every few
//! seconds — an installation's camera may come back — never a crash.

use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use super::ffmpeg::RawPipe;

/// How long a lost camera waits before it is tried again.
const RETRY: Duration = Duration::from_secs(3);

/// A camera the machine has.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CameraInfo {
    /// Its device file (`/dev/video0`).
    pub device: PathBuf,
    /// The name its driver gives.
    pub name: String,
}

/// The V4L2 devices of this machine, by number (none where there is no `/sys/class/video4linux`).
pub fn list_cameras() -> Vec<CameraInfo> {
    let Ok(entries) = std::fs::read_dir("/sys/class/video4linux") else { return Vec::new() };
    let mut cameras: Vec<(u32, CameraInfo)> = entries
        .flatten()
        .filter_map(|entry| {
            let node = entry.file_name().to_string_lossy().into_owned();
            let number = node.strip_prefix("video")?.parse::<u32>().ok()?;
            let name = std::fs::read_to_string(entry.path().join("name")).unwrap_or_default().trim().to_string();
            Some((number, CameraInfo { device: PathBuf::from("/dev").join(&node), name }))
        })
        .collect();
    cameras.sort_by_key(|(n, _)| *n);
    cameras.into_iter().map(|(_, c)| c).collect()
}

/// Where frames come from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum CameraSource {
    /// A V4L2 device file.
    Device(PathBuf),
    /// ffmpeg's moving test pattern, through the same reader (no camera needed).
    TestPattern,
}

impl CameraSource {
    /// Reads a `device` parameter: `test`, a number (`0` is `/dev/video0`) or `/dev/videoN`.
    /// Nothing else is opened, so a message from the network cannot make ffmpeg read a file.
    pub fn parse(device: &str) -> Result<Self, String> {
        let device = device.trim();
        if device == "test" {
            return Ok(CameraSource::TestPattern);
        }
        let number = device.strip_prefix("/dev/video").unwrap_or(device);
        match number.parse::<u32>() {
            Ok(n) => Ok(CameraSource::Device(PathBuf::from(format!("/dev/video{n}")))),
            Err(_) => {
                Err(format!("'{device}' is no camera: name one as 0, /dev/video0 or test (`indra --list-cameras`)"))
            }
        }
    }

    /// ffmpeg's input arguments for `size` at `fps`.
    pub fn input_args(&self, size: (u32, u32), fps: u32) -> Vec<String> {
        let (w, h) = size;
        match self {
            CameraSource::TestPattern => {
                ["-f", "lavfi", "-i", &format!("testsrc2=size={w}x{h}:rate={fps}")].map(String::from).to_vec()
            }
            CameraSource::Device(path) => [
                "-f",
                "v4l2",
                "-framerate",
                &fps.to_string(),
                "-video_size",
                &format!("{w}x{h}"),
                "-i",
                &path.display().to_string(),
            ]
            .map(String::from)
            .to_vec(),
        }
    }
}

#[derive(Default)]
struct FeedState {
    /// The newest frame and its number.
    latest: Option<(u64, Arc<Vec<u8>>)>,
    /// Why there are no frames, once per cause.
    message: Option<String>,
    quit: bool,
}

/// A live source read on its own thread; the newest frame wins.
pub struct LiveFeed {
    state: Arc<Mutex<FeedState>>,
    size: (u32, u32),
}

impl LiveFeed {
    /// Starts reading `source` at `size` and `fps`.
    pub fn start(source: CameraSource, size: (u32, u32), fps: u32) -> Self {
        let state = Arc::new(Mutex::new(FeedState::default()));
        let shared = Arc::clone(&state);
        let spawned = std::thread::Builder::new().name("camera".into()).spawn(move || run(&shared, &source, size, fps));
        if let Err(e) = spawned {
            state.lock().unwrap_or_else(|e| e.into_inner()).message =
                Some(format!("cannot start the camera's thread: {e}"));
        }
        Self { state, size }
    }

    /// The frame size.
    pub fn size(&self) -> (u32, u32) {
        self.size
    }

    /// The newest frame (RGBA rows) and its number, if any came.
    pub fn latest(&self) -> Option<(u64, Arc<Vec<u8>>)> {
        self.state.lock().unwrap_or_else(|e| e.into_inner()).latest.clone()
    }

    /// A new reason the camera gives no frames, once.
    pub fn take_message(&self) -> Option<String> {
        self.state.lock().unwrap_or_else(|e| e.into_inner()).message.take()
    }
}

impl Drop for LiveFeed {
    fn drop(&mut self) {
        self.state.lock().unwrap_or_else(|e| e.into_inner()).quit = true;
    }
}

fn run(state: &Mutex<FeedState>, source: &CameraSource, size: (u32, u32), fps: u32) {
    let quit = || state.lock().map_or(true, |s| s.quit);
    let mut last_message = String::new();
    let mut number = 0u64;
    while !quit() {
        let problem = match source {
            CameraSource::Device(path) if !path.exists() => {
                format!("no camera at {} (`indra --list-cameras` lists this machine's)", path.display())
            }
            _ => match RawPipe::start(&source.input_args(size, fps), size.0, size.1) {
                Err(e) => e,
                Ok(mut pipe) => loop {
                    match pipe.next_frame() {
                        Ok(frame) => {
                            number += 1;
                            let mut s = state.lock().unwrap_or_else(|e| e.into_inner());
                            if s.quit {
                                return;
                            }
                            s.latest = Some((number, Arc::new(frame)));
                            last_message.clear();
                        }
                        Err(e) => break format!("the camera stopped: {e}"),
                    }
                },
            },
        };
        if problem != last_message {
            state.lock().unwrap_or_else(|e| e.into_inner()).message =
                Some(format!("{problem}; trying again every {} s", RETRY.as_secs()));
            last_message = problem;
        }
        let until = std::time::Instant::now() + RETRY;
        while std::time::Instant::now() < until && !quit() {
            std::thread::sleep(Duration::from_millis(100));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn camera_names_are_numbers_device_files_or_the_test_pattern() {
        assert_eq!(CameraSource::parse("2").unwrap(), CameraSource::Device("/dev/video2".into()));
        assert_eq!(CameraSource::parse("/dev/video0").unwrap(), CameraSource::Device("/dev/video0".into()));
        assert_eq!(CameraSource::parse(" test ").unwrap(), CameraSource::TestPattern);
        for bad in ["/etc/shadow", "/dev/video0/../sda", "", "http://x"] {
            assert!(CameraSource::parse(bad).unwrap_err().contains("no camera"), "{bad}");
        }
    }

    #[test]
    fn a_camera_that_does_not_exist_is_one_sentence_and_no_frames() {
        let feed = LiveFeed::start(CameraSource::Device("/dev/video987".into()), (64, 48), 30);
        let deadline = std::time::Instant::now() + Duration::from_secs(10);
        let message = loop {
            if let Some(m) = feed.take_message() {
                break m;
            }
            assert!(std::time::Instant::now() < deadline, "no message");
            std::thread::sleep(Duration::from_millis(20));
        };
        assert!(message.starts_with("no camera at /dev/video987"), "{message}");
        assert_eq!(message.matches(". ").count(), 0, "one sentence: {message}");
        assert!(feed.latest().is_none());
    }

    #[test]
    fn the_stand_in_source_delivers_frames_through_the_camera_path() {
        let feed = LiveFeed::start(CameraSource::TestPattern, (64, 48), 30);
        let deadline = std::time::Instant::now() + Duration::from_secs(30);
        let (first, frame) = loop {
            if let Some(latest) = feed.latest() {
                break latest;
            }
            assert!(std::time::Instant::now() < deadline, "no frame: {:?}", feed.take_message());
            std::thread::sleep(Duration::from_millis(20));
        };
        assert_eq!(frame.len(), 64 * 48 * 4);
        assert!(frame.chunks(4).any(|p| p[0] != frame[0]), "a test pattern, not a flat frame");
        while feed.latest().is_some_and(|(n, _)| n == first) {
            assert!(std::time::Instant::now() < deadline, "frames stopped after the first");
            std::thread::sleep(Duration::from_millis(20));
        }
    }
}
