//! The lights of a live show: the pixel map in each frame, read back in the background and
//! handed to the sender — nothing on the render thread waits for the GPU or the network.

use crate::graph::FrameGraph;

use super::{DmxOut, Layout, Patch, PixelMap};

/// A patch playing in the window.
pub struct LiveLights {
    boxes: Vec<super::PixelBox>,
    map: PixelMap,
    out: DmxOut,
    image: usize,
    /// The patch file, for messages.
    pub origin: String,
}

impl LiveLights {
    /// Loads `path`, builds the pixel map on `device` and opens the sockets.
    pub fn start(device: &wgpu::Device, path: &std::path::Path) -> Result<Self, String> {
        let origin = path.display().to_string();
        let layout = Layout::new(Patch::load(path)?).map_err(|e| format!("{origin}: {e}"))?;
        let map = PixelMap::new(device, &layout.boxes).map_err(|e| e.to_string())?;
        let image = layout.patch.image;
        let boxes = layout.boxes.clone();
        Ok(Self { boxes, map, out: DmxOut::start(layout)?, image, origin })
    }

    /// Builds the pixel map again on a new device (after the old one was lost); the sender
    /// goes on.
    pub fn move_to(&mut self, device: &wgpu::Device) -> Result<(), String> {
        self.map = PixelMap::new(device, &self.boxes).map_err(|e| e.to_string())?;
        Ok(())
    }

    /// Adds the pixel-map pass to the frame (no pass where the image is not drawn).
    pub fn add_pass<'r>(&'r self, graph: &mut FrameGraph<'r>) {
        let source = if self.image == 0 { graph.output() } else { graph.extra_output(self.image - 1) };
        if let Some(source) = source {
            self.map.add_pass(graph, source);
        }
    }

    /// After the frame's passes: copies the values out for reading back.
    pub fn after_encode(&mut self, encoder: &mut wgpu::CommandEncoder, frame: u64) {
        self.map.copy_out(encoder, frame);
    }

    /// After the submit: maps the copy, and hands the newest values that came back to the
    /// sender.
    pub fn after_submit(&mut self, device: &wgpu::Device) {
        self.map.after_submit();
        if let Some((_, pixels)) = self.map.take_newest(device) {
            self.out.offer(pixels);
        }
    }

    /// One line for the overlay: packets sent, polls answered, frames not read back.
    pub fn status(&self) -> String {
        format!(
            "DMX {}: {} packets, {} polls answered, {} frames skipped",
            self.origin,
            self.out.packets(),
            self.out.polls_answered(),
            self.map.skipped()
        )
    }
}
