//! The show's output as a PipeWire video source (`run --pipewire-out NAME`): what OBS's
//! "Screen Capture (PipeWire)", browsers and `gst-launch-1.0 pipewiresrc` read on a modern Linux
//! desktop. GStreamer's `pipewiresink` makes the node, in a `gst-launch-1.0` process fed raw
//! RGBA frames like ffmpeg is for video — so indra links no PipeWire library and builds without
//! its headers; the machine needs `gstreamer1.0-tools` and `gstreamer1.0-pipewire` only when the
//! performer asks for PipeWire. In a live show it is a [`FrameOutlet`] of the readback ring: the
//! show never waits, frames it cannot take are dropped and counted.

use super::capture::FrameOutlet;
use super::frame_pipe::FramePipe;
use super::video::{VideoError, frame_rate};

/// The GStreamer launcher (`gst-launch-1.0`), or the program named in this variable.
pub const GST_LAUNCH_ENV: &str = "INDRA_GST_LAUNCH";

/// How long a launcher that cannot make the node (no daemon, no `pipewiresink`) takes to quit.
const START_CHECK: std::time::Duration = std::time::Duration::from_millis(400);

/// A PipeWire video source fed frames of one size.
pub struct PipeWireOut {
    pipe: FramePipe,
    name: String,
    size: (u32, u32),
    sent: u64,
}

/// Where the PipeWire daemon's socket should be: `$PIPEWIRE_RUNTIME_DIR` or `$XDG_RUNTIME_DIR`,
/// then `$PIPEWIRE_REMOTE` or `pipewire-0`.
fn daemon_socket() -> Option<std::path::PathBuf> {
    let dir = std::env::var_os("PIPEWIRE_RUNTIME_DIR").or_else(|| std::env::var_os("XDG_RUNTIME_DIR"))?;
    let name = std::env::var_os("PIPEWIRE_REMOTE").unwrap_or_else(|| "pipewire-0".into());
    Some(std::path::Path::new(&dir).join(name))
}

/// The launcher's pipeline: raw RGBA rows on standard input, timed at `fps`, converted to what
/// the consumer reads, into a PipeWire video source node called `name`; with `pace`, each frame
/// waits until it is due.
fn pipeline(name: &str, (w, h): (u32, u32), fps: f64, pace: bool) -> Vec<String> {
    let rate = frame_rate(fps);
    let rate = if rate.contains('/') { rate } else { format!("{rate}/1") };
    [
        "-q".into(),
        "fdsrc".into(),
        "fd=0".into(),
        format!("blocksize={}", w * h * 4),
        "!".into(),
        "rawvideoparse".into(),
        format!("width={w}"),
        format!("height={h}"),
        "format=rgba".into(),
        format!("framerate={rate}"),
        // The consumer picks the format it reads (OBS asks for BGRx); without a converter to
        // offer them, a PipeWire reader never links to the parser's fixed RGBA.
        "!".into(),
        "videoconvert".into(),
        "!".into(),
        "pipewiresink".into(),
        "mode=provide".into(),
        format!("client-name={name}"),
        format!("stream-properties=props,media.class=Video/Source,node.name={name},node.description={name}"),
        format!("sync={pace}"),
    ]
    .into()
}

impl PipeWireOut {
    /// Makes the PipeWire video source `name` (letters, digits, `-`, `_`, `.`; at most 64) for
    /// frames of `size` at `fps`; with `pace` (a render, faster than real time) each frame waits
    /// until it is due. A missing daemon or GStreamer is one sentence.
    pub fn start(name: &str, size: (u32, u32), fps: f64, pace: bool) -> Result<Self, String> {
        if !cfg!(target_os = "linux") {
            return Err("PipeWire out is Linux-only; on this system send the show with --ndi-out or --stream".into());
        }
        let name = name.trim();
        let plain = |c: char| c.is_ascii_alphanumeric() || "-_.".contains(c);
        if name.is_empty() || name.len() > 64 || !name.chars().all(plain) {
            return Err(format!("'{name}' is no PipeWire node name: use 1 to 64 letters, digits, '-', '_' or '.'"));
        }
        match daemon_socket() {
            Some(socket) if socket.exists() => {}
            Some(socket) => {
                return Err(format!(
                    "no PipeWire daemon is running (no socket at {}): start pipewire and wireplumber, or leave PipeWire out",
                    socket.display()
                ));
            }
            None => return Err("no PipeWire daemon can be reached: XDG_RUNTIME_DIR is not set".into()),
        }
        let program = std::env::var_os(GST_LAUNCH_ENV).unwrap_or_else(|| "gst-launch-1.0".into());
        let mut pipe = FramePipe::spawn(&program, &pipeline(name, size, fps, pace)).map_err(|e| {
            format!(
                "{} could not be run ({e}): install gstreamer1.0-tools and gstreamer1.0-pipewire",
                program.to_string_lossy()
            )
        })?;
        // A launcher without `pipewiresink`, or refused by the daemon, quits at once.
        let until = std::time::Instant::now() + START_CHECK;
        while std::time::Instant::now() < until {
            if pipe.has_ended() {
                return Err(pipe
                    .last_words("GStreamer could not make the PipeWire source (is gstreamer1.0-pipewire installed?)"));
            }
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        Ok(Self { pipe, name: name.to_string(), size, sent: 0 })
    }

    /// Sends one frame of tight RGBA rows.
    pub fn write(&mut self, rgba: &[u8]) -> Result<(), String> {
        let (w, h) = self.size;
        if rgba.len() != w as usize * h as usize * 4 {
            return Err(format!("a frame of {} bytes does not fit the PipeWire source's {w}×{h}", rgba.len()));
        }
        self.pipe.write(rgba).map_err(|e| format!("the PipeWire source '{}' stopped: {e}", self.name))?;
        self.sent += 1;
        Ok(())
    }

    /// Withdraws the node; returns the frames sent.
    pub fn finish(mut self) -> Result<u64, String> {
        self.pipe.finish().map_err(|e| format!("the PipeWire source '{}' ended badly: {e}", self.name))?;
        Ok(self.sent)
    }
}

impl FrameOutlet for PipeWireOut {
    /// A video source runs in real time: each frame goes once, however many steps it stood.
    fn take(&mut self, rgba: &[u8], _repeats: u32, _frame: u64) -> Result<(), VideoError> {
        self.write(rgba).map_err(VideoError::Settings)
    }

    fn close(self: Box<Self>) -> Result<u64, VideoError> {
        self.finish().map_err(VideoError::Settings)
    }

    fn destination(&self) -> std::path::PathBuf {
        format!("PipeWire '{}'", self.name).into()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_plain_and_checked_before_anything_starts() {
        for bad in ["", "a b", "x!y", "props,media.class=Audio/Sink", &"n".repeat(65)] {
            let e = PipeWireOut::start(bad, (16, 16), 60.0, false).err().expect("refused");
            assert!(e.contains("no PipeWire node name"), "{e}");
        }
    }

    #[test]
    fn the_pipeline_carries_size_rate_and_pacing() {
        let args = pipeline("indra", (64, 48), 1.0 / 0.0166667, true).join(" ");
        assert!(args.contains("blocksize=12288"), "{args}");
        assert!(args.contains("width=64 height=48 format=rgba framerate=60/1"), "{args}");
        assert!(args.contains("media.class=Video/Source,node.name=indra"), "{args}");
        assert!(args.ends_with("sync=true"), "{args}");
        assert!(pipeline("indra", (64, 48), 30000.0 / 1001.0, false).join(" ").contains("framerate=30000/1001"));
    }
}
