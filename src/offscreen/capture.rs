//! Recording the live show to a video without ever making it wait: each shown frame is copied
//! into one of a few readback buffers (a ring), mapped asynchronously, and handed to an encoder
//! thread that feeds its [`FrameOutlet`] — ffmpeg for a file or a network stream, an NDI sender. When every buffer is still in flight, or the encoder is behind, the
//! frame is not recorded — and counted, so the performer is told how many were lost instead of
//! finding a stutter in the file later.
//!
//! The video runs on the show's fixed clock: a shown frame that advanced the clock by n steps is
//! written n times (0 steps: not at all), so the file lasts as long as the show did.

use std::collections::VecDeque;
use std::sync::Arc;
use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::mpsc::{Receiver, SyncSender, TrySendError};
use std::thread::JoinHandle;

use super::video::{VideoError, VideoSettings, VideoWriter};
use crate::gpu::Blit;

/// Readback buffers in flight by default: enough to cover a few frames of GPU latency.
pub const DEFAULT_IN_FLIGHT: usize = 4;

/// Frames that may wait for the encoder (each width × height × 4 bytes).
const ENCODER_QUEUE: usize = 8;

/// Map states a callback reports.
const WAITING: u8 = 0;
const MAPPED: u8 = 1;
const FAILED: u8 = 2;

/// What a recording has done so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CaptureCounts {
    /// Video frames asked for (shown frames × the steps each advanced).
    pub offered: u64,
    /// Video frames handed to the encoder.
    pub queued: u64,
    /// Video frames lost because every readback buffer was in flight.
    pub dropped_busy: u64,
    /// Video frames lost because the encoder was behind (or had failed).
    pub dropped_encoder: u64,
}

impl CaptureCounts {
    /// All frames lost.
    pub fn dropped(&self) -> u64 {
        self.dropped_busy + self.dropped_encoder
    }
}

/// How a finished recording went.
#[derive(Debug)]
pub struct CaptureReport {
    /// The video file.
    pub path: std::path::PathBuf,
    /// Frames in the file.
    pub written: u64,
    /// The counts at the end.
    pub counts: CaptureCounts,
}

impl std::fmt::Display for CaptureReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "recorded {} frame(s) to {}", self.written, self.path.display())?;
        let c = &self.counts;
        if c.dropped() > 0 {
            write!(
                f,
                "; {} frame(s) were not recorded ({} with the GPU readback busy, {} with the encoder behind)",
                c.dropped(),
                c.dropped_busy,
                c.dropped_encoder
            )?;
        }
        Ok(())
    }
}

/// Where a live recorder's frames go, on the recorder's own thread (so it may block).
pub trait FrameOutlet: Send + 'static {
    /// Takes one frame (tight RGBA rows, sRGB-encoded): show frame `frame`, held for `repeats`
    /// steps.
    fn take(&mut self, rgba: &[u8], repeats: u32, frame: u64) -> Result<(), VideoError>;
    /// Ends the output (closes the file, withdraws the source); returns the frames written.
    fn close(self: Box<Self>) -> Result<u64, VideoError>;
    /// Where the frames go, for the panel and reports: a file, a URL, `NDI 'name'`.
    fn destination(&self) -> std::path::PathBuf;
}

impl FrameOutlet for VideoWriter {
    /// A video runs on the show's clock: the frame is written once per step it was shown.
    fn take(&mut self, rgba: &[u8], repeats: u32, _frame: u64) -> Result<(), VideoError> {
        (0..repeats).try_for_each(|_| self.write(rgba))
    }

    fn close(self: Box<Self>) -> Result<u64, VideoError> {
        self.finish()
    }

    fn destination(&self) -> std::path::PathBuf {
        self.settings().path.clone()
    }
}

/// One readback buffer.
struct Slot {
    buffer: wgpu::Buffer,
    /// Set by the map callback.
    state: Arc<AtomicU8>,
}

/// A frame copied into a slot, waiting for its map.
struct Pending {
    slot: usize,
    repeats: u32,
    /// The show frame it is.
    frame: u64,
    mapping: bool,
}

/// A live recording.
pub struct LiveRecorder {
    target: wgpu::Texture,
    blit: Blit,
    size: (u32, u32),
    padded_row: u32,
    slots: Vec<Slot>,
    free: Vec<usize>,
    pending: VecDeque<Pending>,
    sender: Option<SyncSender<(Vec<u8>, u32, u64)>>,
    encoder: Option<JoinHandle<Result<u64, VideoError>>>,
    path: std::path::PathBuf,
    counts: CaptureCounts,
}

impl LiveRecorder {
    /// Starts ffmpeg and allocates `in_flight` readback buffers for frames of `settings.size`.
    pub fn start(device: &wgpu::Device, settings: VideoSettings, in_flight: usize) -> Result<Self, VideoError> {
        let size = settings.size;
        Self::start_outlet(device, size, Box::new(VideoWriter::start(settings)?), in_flight)
    }

    /// Starts a recorder whose frames of `size` go to `outlet`, with `in_flight` readback
    /// buffers.
    pub fn start_outlet(
        device: &wgpu::Device,
        size: (u32, u32),
        outlet: Box<dyn FrameOutlet>,
        in_flight: usize,
    ) -> Result<Self, VideoError> {
        let path = outlet.destination();
        let (sender, receiver) = std::sync::mpsc::sync_channel(ENCODER_QUEUE);
        let encoder = std::thread::Builder::new()
            .name("indra-video".into())
            .spawn(move || encode(outlet, receiver))
            .map_err(|e| VideoError::Settings(format!("cannot start the encoder thread: {e}")))?;
        let target = crate::gpu::display_target(device, "capture_target", size);
        let padded_row = (size.0 * 4).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let slots = (0..in_flight.max(1))
            .map(|_| Slot {
                buffer: device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("capture_readback"),
                    size: u64::from(padded_row) * u64::from(size.1),
                    usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                    mapped_at_creation: false,
                }),
                state: Arc::new(AtomicU8::new(WAITING)),
            })
            .collect::<Vec<_>>();
        Ok(Self {
            target,
            blit: Blit::new(device),
            size,
            padded_row,
            free: (0..slots.len()).rev().collect(),
            slots,
            pending: VecDeque::new(),
            sender: Some(sender),
            encoder: Some(encoder),
            path,
            counts: CaptureCounts::default(),
        })
    }

    /// The video file.
    pub fn path(&self) -> &std::path::Path {
        &self.path
    }

    /// The frame size.
    pub fn size(&self) -> (u32, u32) {
        self.size
    }

    /// The counts so far.
    pub fn counts(&self) -> CaptureCounts {
        self.counts
    }

    /// Records a copy of `source` (any float texture; sRGB-encoded like the window), show frame
    /// `frame`, into `encoder`, to be written `repeats` times. Never waits: with no free buffer the frame is
    /// counted as dropped. Call [`LiveRecorder::after_submit`] once the encoder is submitted.
    pub fn capture(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        source: &wgpu::TextureView,
        repeats: u32,
        frame: u64,
    ) {
        if repeats == 0 {
            return;
        }
        self.counts.offered += u64::from(repeats);
        let Some(slot) = self.free.pop() else {
            self.counts.dropped_busy += u64::from(repeats);
            return;
        };
        let target = self.target.create_view(&Default::default());
        self.blit.record_compute(device, encoder, source, &target, self.size);
        encoder.copy_texture_to_buffer(
            self.target.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &self.slots[slot].buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(self.padded_row),
                    rows_per_image: Some(self.size.1),
                },
            },
            self.target.size(),
        );
        self.pending.push_back(Pending { slot, repeats, frame, mapping: false });
    }

    /// Asks for the maps of the frames captured since the last call (their copies are submitted).
    pub fn after_submit(&mut self) {
        for p in self.pending.iter_mut().filter(|p| !p.mapping) {
            p.mapping = true;
            let slot = &self.slots[p.slot];
            slot.state.store(WAITING, Ordering::Release);
            let state = slot.state.clone();
            slot.buffer.slice(..).map_async(wgpu::MapMode::Read, move |r| {
                state.store(if r.is_ok() { MAPPED } else { FAILED }, Ordering::Release);
            });
        }
    }

    /// Hands the frames whose maps completed to the encoder, in order; never waits.
    pub fn poll(&mut self, device: &wgpu::Device) {
        let _ = device.poll(wgpu::PollType::Poll);
        while let Some(front) = self.pending.front() {
            let state = self.slots[front.slot].state.load(Ordering::Acquire);
            if !front.mapping || state == WAITING {
                break;
            }
            let Pending { slot, repeats, frame: number, .. } = self.pending.pop_front().expect("front exists");
            let buffer = &self.slots[slot].buffer;
            let frame = (state == MAPPED).then(|| buffer.slice(..).get_mapped_range().ok()).flatten().map(|mapped| {
                let tight = (self.size.0 * 4) as usize;
                let mut rgba = Vec::with_capacity(tight * self.size.1 as usize);
                for row in mapped.chunks(self.padded_row as usize) {
                    rgba.extend_from_slice(&row[..tight]);
                }
                rgba
            });
            if state == MAPPED {
                buffer.unmap();
            }
            self.free.push(slot);
            let sent = match (frame, &self.sender) {
                (Some(rgba), Some(sender)) => match sender.try_send((rgba, repeats, number)) {
                    Ok(()) => true,
                    Err(TrySendError::Full(_) | TrySendError::Disconnected(_)) => false,
                },
                _ => false,
            };
            if sent {
                self.counts.queued += u64::from(repeats);
            } else {
                self.counts.dropped_encoder += u64::from(repeats);
            }
        }
    }

    /// Waits for the frames in flight, closes the file and says how it went.
    pub fn finish(self, device: &wgpu::Device) -> Result<CaptureReport, VideoError> {
        self.finish_in_background(device).wait()
    }

    /// Reads back the frames still in flight (a few, already rendered), then leaves encoding
    /// them and closing the file to the encoder thread: the frame that stops a take never waits
    /// for ffmpeg.
    pub fn finish_in_background(mut self, device: &wgpu::Device) -> FinishingTake {
        while !self.pending.is_empty() {
            self.after_submit();
            let _ = device.poll(wgpu::PollType::wait_indefinitely());
            let before = self.pending.len();
            self.poll(device);
            if self.pending.len() == before {
                break;
            }
        }
        // Frames still pending here never mapped (a lost device): they are lost, and said so.
        for p in std::mem::take(&mut self.pending) {
            self.counts.dropped_busy += u64::from(p.repeats);
        }
        drop(self.sender.take());
        FinishingTake { path: self.path.clone(), counts: self.counts, encoder: self.encoder.take() }
    }
}

/// A take being closed off the render thread: the encoder thread writes its last frames and
/// ffmpeg finishes the file; the render thread only asks whether that thread has ended.
pub struct FinishingTake {
    path: std::path::PathBuf,
    counts: CaptureCounts,
    encoder: Option<JoinHandle<Result<u64, VideoError>>>,
}

impl FinishingTake {
    /// How the take went, once the file is complete (`None` while ffmpeg is still writing).
    pub fn poll(&mut self) -> Option<Result<CaptureReport, VideoError>> {
        if self.encoder.as_ref().is_some_and(|e| !e.is_finished()) {
            return None;
        }
        Some(self.report())
    }

    /// Waits until the file is complete (the show is ending, or a take made off-screen).
    pub fn wait(mut self) -> Result<CaptureReport, VideoError> {
        self.report()
    }

    /// Joins the encoder thread (at once when it has ended) and says how the take went.
    fn report(&mut self) -> Result<CaptureReport, VideoError> {
        match self.encoder.take().map(JoinHandle::join) {
            Some(Ok(written)) => Ok(CaptureReport { path: self.path.clone(), written: written?, counts: self.counts }),
            _ => Err(VideoError::Settings("the encoder thread stopped unexpectedly".into())),
        }
    }
}

/// The file a new take goes to: `name` (a bare file name, as OSC may send one: no folders, so
/// the network cannot write elsewhere) in `base`'s folder, or `base` itself; never over an
/// existing file — `show.mp4` is followed by `show-2.mp4`, `show-3.mp4`, …
pub fn take_path(base: &std::path::Path, name: Option<&str>) -> Result<std::path::PathBuf, String> {
    let wanted = match name.map(str::trim) {
        None | Some("") => base.to_path_buf(),
        Some(n) if n.contains(['/', '\\']) || n.starts_with('.') || n.len() > 120 => {
            return Err(format!("'{n}' is not a plain file name; recordings go to {}", folder_of(base).display()));
        }
        Some(n) => {
            let named = folder_of(base).join(n);
            if named.extension().is_none() {
                named.with_extension(base.extension().unwrap_or("mp4".as_ref()))
            } else {
                named
            }
        }
    };
    if !wanted.exists() {
        return Ok(wanted);
    }
    let stem = wanted.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let ext = wanted.extension().map(|e| format!(".{}", e.to_string_lossy())).unwrap_or_default();
    (2..10_000)
        .map(|n| wanted.with_file_name(format!("{stem}-{n}{ext}")))
        .find(|p| !p.exists())
        .ok_or_else(|| format!("no free name for a new take beside {}", wanted.display()))
}

fn folder_of(path: &std::path::Path) -> std::path::PathBuf {
    path.parent().filter(|p| !p.as_os_str().is_empty()).map_or_else(|| ".".into(), std::path::Path::to_path_buf)
}

/// The encoder thread: hands each frame to the outlet, then closes it. After an error it keeps
/// draining (so the show's sends never block) and returns the error at the end.
fn encode(mut outlet: Box<dyn FrameOutlet>, frames: Receiver<(Vec<u8>, u32, u64)>) -> Result<u64, VideoError> {
    let mut failure = None;
    for (rgba, repeats, frame) in frames {
        if failure.is_none() {
            failure = outlet.take(&rgba, repeats, frame).err();
        }
    }
    match failure {
        Some(e) => Err(e),
        None => outlet.close(),
    }
}

#[cfg(test)]
mod tests {
    use super::take_path;

    #[test]
    fn takes_never_overwrite_and_network_names_stay_in_the_folder() {
        let dir = std::env::temp_dir().join(format!("indra-takes-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let base = dir.join("show.mp4");
        let _ = std::fs::remove_file(&base);
        assert_eq!(take_path(&base, None).unwrap(), base);
        std::fs::write(&base, b"x").unwrap();
        assert_eq!(take_path(&base, None).unwrap(), dir.join("show-2.mp4"));
        assert_eq!(take_path(&base, Some("encore")).unwrap(), dir.join("encore.mp4"));
        assert_eq!(take_path(&base, Some("encore.mov")).unwrap(), dir.join("encore.mov"));
        for bad in ["../etc/x.mp4", "/tmp/x.mp4", ".hidden.mp4", "a\\b.mp4"] {
            assert!(take_path(&base, Some(bad)).is_err(), "{bad}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
