//! An NDI sender: RGBA frames out under a name other programs find (OBS, Resolume,
//! TouchDesigner, NDI Studio Monitor). Each frame carries its place on the show's clock as its
//! timecode (frame × 10⁷ / fps, NDI's 100 ns units), so a receiver can tell which frame it has.

use std::ffi::{CString, c_void};

use super::runtime::{NdiRuntime, PROGRESSIVE, SendCreate, VideoFrame, fourcc};

/// The longest sender name indra passes on (NDI shows names in menus).
const MAX_NAME: usize = 120;

/// A sender; dropping it withdraws the source.
pub struct NdiSender {
    runtime: &'static NdiRuntime,
    instance: *mut c_void,
    name: String,
    size: (u32, u32),
    /// fps as the fraction NDI carries (milli-frames per second over 1000).
    rate: (i32, i32),
    sent: u64,
}

// The instance is used from one thread at a time (the one that owns the sender).
unsafe impl Send for NdiSender {}

impl NdiSender {
    /// Announces a source called `name` for frames of `size` at `fps`. With `clock`, each send
    /// waits until its frame is due, so frames made faster than real time (a render) go out at
    /// `fps`; a live show, already on time, sends without it.
    pub fn start(name: &str, size: (u32, u32), fps: f64, clock: bool) -> Result<Self, String> {
        let name = name.trim();
        if name.is_empty() || name.len() > MAX_NAME || name.chars().any(char::is_control) {
            return Err(format!("'{name}' is no NDI name: give 1 to {MAX_NAME} printable characters"));
        }
        let runtime = NdiRuntime::get()?;
        let c_name = CString::new(name).map_err(|_| format!("'{name}' is no NDI name"))?;
        let settings =
            SendCreate { name: c_name.as_ptr(), groups: std::ptr::null(), clock_video: clock, clock_audio: false };
        // SAFETY: the settings and the name outlive the call; the SDK copies them.
        let instance = unsafe { runtime.send_create(&settings) };
        if instance.is_null() {
            return Err(format!("the NDI runtime could not create the sender '{name}'"));
        }
        let milli = (fps * 1000.0).round().clamp(1.0, f64::from(i32::MAX)) as i32;
        Ok(Self { runtime, instance, name: name.to_string(), size, rate: (milli, 1000), sent: 0 })
    }

    /// The name it announces.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Frames sent so far.
    pub fn sent(&self) -> u64 {
        self.sent
    }

    /// Sends one frame of tight RGBA rows, stamped as show frame `frame`; the SDK has copied
    /// (compressed) it when this returns.
    pub fn send(&mut self, rgba: &[u8], frame: u64) -> Result<(), String> {
        let (w, h) = self.size;
        if rgba.len() != (w as usize) * (h as usize) * 4 {
            return Err(format!("an NDI frame of {w}×{h} needs {} bytes, not {}", w * h * 4, rgba.len()));
        }
        let (n, d) = self.rate;
        let video = VideoFrame {
            xres: w as i32,
            yres: h as i32,
            // The output is opaque: X tells receivers there is no alpha to composite with.
            fourcc: fourcc(b"RGBX"),
            frame_rate_n: n,
            frame_rate_d: d,
            picture_aspect_ratio: 0.0,
            frame_format_type: PROGRESSIVE,
            timecode: timecode(frame, n, d),
            data: rgba.as_ptr().cast_mut(),
            line_stride: (w * 4) as i32,
            metadata: std::ptr::null(),
            timestamp: 0,
        };
        // SAFETY: the frame describes `rgba`, which lives through the synchronous send.
        unsafe { self.runtime.send_video(self.instance, &video) };
        self.sent += 1;
        Ok(())
    }
}

/// Frame `frame` at `n / d` frames per second in 100 ns units.
pub fn timecode(frame: u64, n: i32, d: i32) -> i64 {
    let ticks = u128::from(frame) * 10_000_000 * (d.max(1) as u128) / (n.max(1) as u128);
    ticks.min(i64::MAX as u128 - 1) as i64
}

impl Drop for NdiSender {
    fn drop(&mut self) {
        // SAFETY: the instance was created by `send_create` and is destroyed once.
        unsafe { self.runtime.send_destroy(self.instance) };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn timecodes_count_frames_in_100_ns_units() {
        assert_eq!(timecode(0, 60_000, 1000), 0);
        assert_eq!(timecode(60, 60_000, 1000), 10_000_000);
        assert_eq!(timecode(1, 30_000, 1000), 333_333);
        assert_eq!(timecode(u64::MAX, 1, 1000), i64::MAX - 1);
    }

    #[test]
    fn names_are_checked_before_the_runtime_is_looked_for() {
        for bad in ["", "   ", "a\nb", &"x".repeat(121)] {
            let e = NdiSender::start(bad, (16, 16), 60.0, false).err().expect("refused");
            assert!(e.contains("no NDI name"), "{e}");
        }
    }
}
