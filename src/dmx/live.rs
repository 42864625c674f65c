//! The lights of a live show: the pixel map in each frame, read back in the background and
//! handed to the sender — nothing on the render thread waits for the GPU or the network.

use crate::graph::FrameGraph;

use super::{DmxOut, Layout, Patch, PixelMap};

/// A patch playing in the window.
pub struct LiveLights {
    layout: Layout,
    path: std::path::PathBuf,
    /// None where the patch has no pixels (lamps only).
    map: Option<PixelMap>,
    /// The positions of the parameters the lamps follow, as the last step left them.
    lamps: Vec<Option<f32>>,
    out: DmxOut,
    image: usize,
    /// The patch file, for messages.
    pub origin: String,
    /// The panel draws the fixtures over the output.
    pub show_fixtures: bool,
    /// The panel lets the performer drag the fixtures.
    pub editing: bool,
    /// Fixtures moved since the patch was loaded or saved.
    pub moved: bool,
}

impl LiveLights {
    /// Loads `path`, builds the pixel map on `device` and opens the sockets.
    pub fn start(device: &wgpu::Device, path: &std::path::Path) -> Result<Self, String> {
        let origin = path.display().to_string();
        let layout = Layout::new(Patch::load(path)?).map_err(|e| format!("{origin}: {e}"))?;
        let map = if layout.boxes.is_empty() {
            None
        } else {
            Some(PixelMap::new(device, &layout.boxes).map_err(|e| e.to_string())?)
        };
        let image = layout.patch.image;
        let out = DmxOut::start(layout.clone())?;
        let path = path.to_path_buf();
        Ok(Self {
            layout,
            path,
            map,
            lamps: Vec::new(),
            out,
            image,
            origin,
            show_fixtures: false,
            editing: false,
            moved: false,
        })
    }

    /// The patch as it is now (fixtures moved by the panel included).
    pub fn patch(&self) -> &Patch {
        &self.layout.patch
    }

    /// Moves fixture `index` by (`dx`, `dy`) of the picture: the next frame samples it there.
    /// Its channels stay, so the sender needs nothing new.
    pub fn move_fixture(&mut self, queue: &wgpu::Queue, index: usize, dx: f32, dy: f32) {
        self.layout.move_fixture(index, dx, dy);
        if let Some(map) = &self.map {
            map.set_boxes(queue, &self.layout.boxes);
        }
        self.moved = true;
    }

    /// Saves the patch with the fixtures where they are now (atomically, over the file it came
    /// from; the file's comments are not kept). Returns the message for the performer.
    pub fn save(&mut self) -> Result<String, String> {
        crate::atomic_file::write(&self.path, self.layout.patch.to_ron().as_bytes())
            .map_err(|e| format!("cannot save {}: {e}", self.origin))?;
        self.moved = false;
        Ok(format!("saved the fixtures' places to {}", self.origin))
    }

    /// The parameters the lamps' channels follow ([`Layout::lamp_targets`]).
    pub fn lamp_targets(&self) -> Vec<&str> {
        self.layout.lamp_targets()
    }

    /// The positions (0–1) of [`LiveLights::lamp_targets`] after this frame's step.
    pub fn set_lamps(&mut self, positions: Vec<Option<f32>>) {
        self.lamps = positions;
    }

    /// Builds the pixel map again on a new device (after the old one was lost); the sender
    /// goes on.
    pub fn move_to(&mut self, device: &wgpu::Device) -> Result<(), String> {
        if self.map.is_some() {
            self.map = Some(PixelMap::new(device, &self.layout.boxes).map_err(|e| e.to_string())?);
        }
        Ok(())
    }

    /// Adds the pixel-map pass to the frame (no pass where the image is not drawn).
    pub fn add_pass<'r>(&'r self, graph: &mut FrameGraph<'r>) {
        let source = if self.image == 0 { graph.output() } else { graph.extra_output(self.image - 1) };
        if let (Some(map), Some(source)) = (&self.map, source) {
            map.add_pass(graph, source);
        }
    }

    /// After the frame's passes: copies the values out for reading back.
    pub fn after_encode(&mut self, encoder: &mut wgpu::CommandEncoder, frame: u64) {
        if let Some(map) = self.map.as_mut() {
            map.copy_out(encoder, frame);
        }
    }

    /// After the submit: maps the copy, and hands the newest values that came back to the
    /// sender.
    pub fn after_submit(&mut self, device: &wgpu::Device) {
        let Some(map) = self.map.as_mut() else {
            self.out.offer(Vec::new(), self.lamps.clone());
            return;
        };
        map.after_submit();
        if let Some((_, pixels)) = map.take_newest(device) {
            self.out.offer(pixels, self.lamps.clone());
        }
    }

    /// One line for the overlay: packets sent, polls answered, frames not read back.
    pub fn status(&self) -> String {
        format!(
            "DMX {}: {} packets, {} polls answered, {} frames skipped",
            self.origin,
            self.out.packets(),
            self.out.polls_answered(),
            self.map.as_ref().map_or(0, PixelMap::skipped)
        )
    }
}
