//! A child process that takes raw frames on its standard input — ffmpeg for video files and
//! streams, GStreamer for PipeWire — and whose last words on standard error say why it stopped.

use std::io::{Read, Write};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::thread::JoinHandle;

/// A running child fed frames.
pub(crate) struct FramePipe {
    child: Child,
    stdin: Option<ChildStdin>,
    /// Collects the child's standard error, so a failure can say what it said.
    stderr: Option<JoinHandle<String>>,
}

impl FramePipe {
    /// Starts `program` with `args`, its standard input piped and its output discarded.
    pub(crate) fn spawn(program: &std::ffi::OsStr, args: &[String]) -> std::io::Result<Self> {
        let mut child = Command::new(program)
            .args(args)
            .stdin(Stdio::piped())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()?;
        let stdin = child.stdin.take();
        let stderr = child.stderr.take().map(|mut pipe| {
            std::thread::spawn(move || {
                let mut text = String::new();
                let _ = pipe.read_to_string(&mut text);
                text
            })
        });
        Ok(Self { child, stdin, stderr })
    }

    /// Writes one frame; when the child has quit, says why, in its own words where it said any.
    pub(crate) fn write(&mut self, frame: &[u8]) -> Result<(), String> {
        let Some(stdin) = self.stdin.as_mut() else {
            return Err(self.last_words("it was already closed"));
        };
        if let Err(e) = stdin.write_all(frame) {
            self.stdin = None;
            let _ = self.child.wait();
            return Err(self.last_words(&format!("it stopped taking frames ({e})")));
        }
        Ok(())
    }

    /// Whether the child has ended (for a start-up check).
    pub(crate) fn has_ended(&mut self) -> bool {
        self.child.try_wait().is_ok_and(|status| status.is_some())
    }

    /// Closes the input and waits for the child to end.
    pub(crate) fn finish(&mut self) -> Result<(), String> {
        drop(self.stdin.take());
        match self.child.wait() {
            Ok(status) if status.success() => Ok(()),
            Ok(status) => Err(self.last_words(&format!("it ended with {status}"))),
            Err(e) => Err(self.last_words(&format!("cannot wait for it: {e}"))),
        }
    }

    /// `fallback`, followed by the child's last three lines on standard error, if any.
    pub(crate) fn last_words(&mut self, fallback: &str) -> String {
        let said = self.stderr.take().and_then(|t| t.join().ok()).unwrap_or_default();
        let lines: Vec<&str> = said.lines().filter(|l| !l.trim().is_empty()).collect();
        let tail = lines[lines.len().saturating_sub(3)..].join(" / ");
        if tail.is_empty() { fallback.to_string() } else { format!("{fallback}: {tail}") }
    }
}

impl Drop for FramePipe {
    /// A pipe dropped without `finish` is killed (its output is then incomplete).
    fn drop(&mut self) {
        if self.stdin.is_some() {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}
