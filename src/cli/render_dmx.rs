//! `render --dmx-out`: each rendered frame's pixel map sent to the lights in real time, and
//! written to a file with `--dmx-record` (the bytes of frame N are the same on every render).

use std::io::Write;
use std::path::Path;
use std::time::{Duration, Instant};

use indra::dmx::{DmxOut, Layout, Patch, PixelMap};
use indra::offscreen::OffscreenRenderer;

/// A render's DMX output.
pub struct RenderDmx {
    layout: Layout,
    out: DmxOut,
    record: Option<std::io::BufWriter<std::fs::File>>,
    started: Instant,
    dt: Duration,
    sent: u64,
}

impl RenderDmx {
    /// Loads the patch, opens its sockets and the record file, and puts the pixel map into the
    /// renderer's frames.
    pub fn start(
        patch: &Path,
        record: Option<&Path>,
        renderer: &mut OffscreenRenderer,
        dt: f64,
    ) -> Result<Self, String> {
        let layout = Layout::new(Patch::load(patch)?).map_err(|e| format!("{}: {e}", patch.display()))?;
        if !layout.boxes.is_empty() {
            let map = PixelMap::new(&renderer.gpu().device, &layout.boxes).map_err(|e| e.to_string())?;
            renderer.set_pixel_map(map, layout.patch.image)?;
        }
        let record = record
            .map(|path| {
                std::fs::File::create(path)
                    .map(std::io::BufWriter::new)
                    .map_err(|e| format!("cannot write {}: {e}", path.display()))
            })
            .transpose()?;
        let out = DmxOut::start(layout.clone())?;
        Ok(Self { layout, out, record, started: Instant::now(), dt: Duration::from_secs_f64(dt), sent: 0 })
    }

    /// After each rendered frame: reads its pixels, records them, waits until the frame is
    /// due in real time and hands them to the sender.
    pub fn frame(&mut self, renderer: &mut OffscreenRenderer, frame: u64) -> Result<(), String> {
        let pixels = renderer.read_pixel_map().transpose().map_err(|e| e.to_string())?.unwrap_or_default();
        let instance = renderer.instance_mut();
        let lamps: Vec<Option<f32>> = self.layout.lamp_targets().iter().map(|t| instance.position_of(t)).collect();
        if let Some(file) = self.record.as_mut() {
            // Each universe: the frame (u64), the universe (u16), 512 channels; little-endian.
            for (universe, channels) in self.layout.encode(&pixels, &lamps) {
                let written = file
                    .write_all(&frame.to_le_bytes())
                    .and_then(|()| file.write_all(&universe.to_le_bytes()))
                    .and_then(|()| file.write_all(&channels));
                written.map_err(|e| format!("cannot write the DMX record: {e}"))?;
            }
        }
        let due = self.started + self.dt * self.sent as u32;
        if let Some(wait) = due.checked_duration_since(Instant::now()) {
            std::thread::sleep(wait);
        }
        self.out.offer(pixels, lamps);
        self.sent += 1;
        Ok(())
    }

    /// Flushes the record; the sender ends as the patch says (blackout or hold).
    pub fn finish(mut self) -> Result<u64, String> {
        if let Some(file) = self.record.as_mut() {
            file.flush().map_err(|e| format!("cannot write the DMX record: {e}"))?;
        }
        // The last frame is sent before the sender stops.
        std::thread::sleep(Duration::from_secs_f32(2.0 / self.layout.patch.rate));
        Ok(self.out.packets())
    }
}
