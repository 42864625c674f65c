//! A patch laid out: the box each pixel averages, the channels each pixel fills, and the
//! encoding of sampled screen values into universes.

use std::collections::BTreeMap;

use super::ofl::Slot;
use super::patch::{Fixture, MatrixOrder, Patch, Shape};

/// Channels in a DMX universe.
pub const UNIVERSE_CHANNELS: usize = 512;

/// The box of the image one pixel averages, in image coordinates (0–1, y down); the GPU reads
/// it as two `vec2<f32>`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PixelBox {
    /// Top left corner.
    pub min: [f32; 2],
    /// Bottom right corner.
    pub max: [f32; 2],
}

/// Where one pixel's bytes go.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelSlot {
    /// Index of its fixture in the patch.
    pub fixture: usize,
    /// Its universe.
    pub universe: u16,
    /// Its first channel, 0-based.
    pub offset: usize,
}

/// Every universe's 512 channels, by universe number: what one frame sends.
pub type Universes = BTreeMap<u16, [u8; UNIVERSE_CHANNELS]>;

/// A patch laid out on the image.
#[derive(Clone, Debug)]
pub struct Layout {
    /// The patch.
    pub patch: Patch,
    /// The box each pixel averages, in sampling order.
    pub boxes: Vec<PixelBox>,
    /// Where each pixel's bytes go, in the same order.
    pub slots: Vec<PixelSlot>,
}

impl Layout {
    /// Places every fixture's pixels and channels; refuses pixels that overlap in a universe
    /// or run past the last universe, naming the fixtures.
    pub fn new(patch: Patch) -> Result<Self, String> {
        let mut boxes = Vec::new();
        let mut slots = Vec::new();
        let mut owner: BTreeMap<(u16, usize), usize> = BTreeMap::new();
        for (index, fixture) in patch.fixtures.iter().enumerate() {
            let placed = pixel_boxes(&fixture.shape);
            if boxes.len() + placed.len() > super::patch::MAX_PIXELS {
                return Err(format!("more than {} pixels in one patch", super::patch::MAX_PIXELS));
            }
            let width = fixture.pixel_bytes();
            let (mut universe, mut offset) = (fixture.universe, usize::from(fixture.address) - 1);
            for pixel in placed {
                // A pixel never straddles two universes: it starts the next one (170 RGB pixels
                // to a universe).
                if offset + width > UNIVERSE_CHANNELS {
                    universe = universe
                        .checked_add(1)
                        .filter(|u| *u <= 32767)
                        .ok_or_else(|| format!("fixture '{}' runs past universe 32767", fixture.name))?;
                    offset = 0;
                }
                for channel in offset..offset + width {
                    if let Some(other) = owner.insert((universe, channel), index) {
                        let other = &patch.fixtures[other].name;
                        return Err(format!(
                            "fixtures '{other}' and '{}' both use universe {universe} channel {}",
                            fixture.name,
                            channel + 1
                        ));
                    }
                }
                boxes.push(pixel);
                slots.push(PixelSlot { fixture: index, universe, offset });
                offset += width;
            }
        }
        if patch.lamp_modes.len() != patch.lamps.len() {
            return Err("the lamps' profiles were not read (load the patch from its file)".into());
        }
        for (lamp, mode) in patch.lamps.iter().zip(&patch.lamp_modes) {
            let offset = usize::from(lamp.address) - 1;
            if offset + mode.slots.len() > UNIVERSE_CHANNELS {
                return Err(format!(
                    "lamp '{}': {} channels from {} run past channel 512",
                    lamp.name,
                    mode.slots.len(),
                    lamp.address
                ));
            }
            if let Some(channel) = lamp.drive.keys().find(|c| !mode.slots.contains(&Slot::Coarse((*c).clone()))) {
                return Err(format!("lamp '{}': {} has no channel '{channel}'", lamp.name, mode.name));
            }
            for channel in offset..offset + mode.slots.len() {
                if owner.insert((lamp.universe, channel), usize::MAX).is_some() {
                    return Err(format!(
                        "lamp '{}' uses universe {} channel {}, which another fixture uses",
                        lamp.name,
                        lamp.universe,
                        channel + 1
                    ));
                }
            }
        }
        let layout = Self { patch, boxes, slots };
        let universes = layout.universes();
        if universes.len() > super::patch::MAX_UNIVERSES {
            return Err(format!("more than {} universes in one patch", super::patch::MAX_UNIVERSES));
        }
        if layout.patch.sacn.is_some() && universes.first() == Some(&0) {
            return Err("sACN has no universe 0: start the fixtures at universe 1".into());
        }
        Ok(layout)
    }

    /// Moves fixture `index` by (`dx`, `dy`) of the picture; its channels stay.
    pub fn move_fixture(&mut self, index: usize, dx: f32, dy: f32) {
        let Some(fixture) = self.patch.fixtures.get_mut(index) else { return };
        fixture.shape.translate(dx, dy);
        self.boxes = self.patch.fixtures.iter().flat_map(|f| pixel_boxes(&f.shape)).collect();
    }

    /// The parameters the lamps' channels follow, in the order [`Layout::encode`] takes their
    /// positions: lamp by lamp, each lamp's channels by name.
    pub fn lamp_targets(&self) -> Vec<&str> {
        self.patch.lamps.iter().flat_map(|l| l.drive.values().map(String::as_str)).collect()
    }

    /// The universes the patch fills, in order.
    pub fn universes(&self) -> Vec<u16> {
        let mut list: Vec<u16> =
            self.slots.iter().map(|s| s.universe).chain(self.patch.lamps.iter().map(|l| l.universe)).collect();
        list.sort_unstable();
        list.dedup();
        list
    }

    /// All universes at 0 (a blackout).
    pub fn blackout(&self) -> Universes {
        self.universes().into_iter().map(|u| (u, [0; UNIVERSE_CHANNELS])).collect()
    }

    /// Encodes each pixel's sampled screen value (0–65535 per colour, as the GPU packs them)
    /// into the universes: gamma, brightness, white extraction, byte order and bit depth; and
    /// each lamp channel: the position (0–1) of the parameter driving it, in the order of
    /// [`Layout::lamp_targets`] (`None`, or none given: the profile's default).
    pub fn encode(&self, screen: &[[u16; 3]], lamps: &[Option<f32>]) -> Universes {
        let mut out = self.blackout();
        for (slot, value) in self.slots.iter().zip(screen) {
            let fixture = &self.patch.fixtures[slot.fixture];
            let channels = out.get_mut(&slot.universe).expect("every slot's universe is listed");
            write_pixel(fixture, *value, &mut channels[slot.offset..slot.offset + fixture.pixel_bytes()]);
        }
        let mut positions = lamps.iter();
        for (lamp, mode) in self.patch.lamps.iter().zip(&self.patch.lamp_modes) {
            let driven: BTreeMap<&str, f32> = lamp
                .drive
                .keys()
                .filter_map(|c| positions.next().copied().flatten().map(|p| (c.as_str(), p)))
                .collect();
            let channels = out.get_mut(&lamp.universe).expect("every lamp's universe is listed");
            let base = usize::from(lamp.address) - 1;
            let level =
                |name: &str| driven.get(name).or(mode.defaults.get(name)).copied().unwrap_or(0.0).clamp(0.0, 1.0);
            for (k, slot) in mode.slots.iter().enumerate() {
                let has_fine = |name: &String| mode.slots.contains(&Slot::Fine(name.clone()));
                channels[base + k] = match slot {
                    Slot::Coarse(name) if has_fine(name) => ((level(name) * 65535.0).round() as u16 >> 8) as u8,
                    Slot::Coarse(name) => (level(name) * 255.0).round() as u8,
                    Slot::Fine(name) => ((level(name) * 65535.0).round() as u16 & 0xff) as u8,
                    Slot::Unused => 0,
                };
            }
        }
        out
    }
}

/// Writes one pixel's bytes.
fn write_pixel(fixture: &Fixture, screen: [u16; 3], bytes: &mut [u8]) {
    let level = |v: u16| (f32::from(v) / 65535.0).powf(fixture.gamma) * fixture.brightness;
    let mut colour = [level(screen[0]), level(screen[1]), level(screen[2]), 0.0];
    if fixture.format.order().len() == 4 {
        // The white LED takes what red, green and blue share.
        let white = colour[0].min(colour[1]).min(colour[2]);
        for c in &mut colour[..3] {
            *c -= white;
        }
        colour[3] = white;
    }
    let order = fixture.format.order();
    if fixture.bits == 16 {
        for (i, &c) in order.iter().enumerate() {
            let v = (colour[c].clamp(0.0, 1.0) * 65535.0).round() as u16;
            bytes[2 * i..2 * i + 2].copy_from_slice(&v.to_be_bytes());
        }
    } else {
        for (i, &c) in order.iter().enumerate() {
            bytes[i] = (colour[c].clamp(0.0, 1.0) * 255.0).round() as u8;
        }
    }
}

/// The boxes of a shape's pixels, in wiring order.
fn pixel_boxes(shape: &Shape) -> Vec<PixelBox> {
    let square = |(x, y): (f32, f32), side: f32| PixelBox {
        min: [x - side / 2.0, y - side / 2.0],
        max: [x + side / 2.0, y + side / 2.0],
    };
    match *shape {
        Shape::Strip { from, to, pixels, size } => {
            let steps = pixels.saturating_sub(1).max(1) as f32;
            let step = ((to.0 - from.0) / steps, (to.1 - from.1) / steps);
            let side = size.unwrap_or_else(|| step.0.hypot(step.1));
            (0..pixels).map(|k| square((from.0 + step.0 * k as f32, from.1 + step.1 * k as f32), side)).collect()
        }
        Shape::Matrix { at, size, columns, rows, order } => {
            let cell = (size.0 / columns as f32, size.1 / rows as f32);
            let cell_box = |column: u32, row: u32| {
                let min = [at.0 + cell.0 * column as f32, at.1 + cell.1 * row as f32];
                PixelBox { min, max: [min[0] + cell.0, min[1] + cell.1] }
            };
            let turn = |line: u32, k: u32, length: u32| if line % 2 == 1 { length - 1 - k } else { k };
            let mut boxes = Vec::with_capacity((columns * rows) as usize);
            match order {
                MatrixOrder::Rows | MatrixOrder::Serpentine => {
                    for row in 0..rows {
                        for k in 0..columns {
                            let column = if order == MatrixOrder::Serpentine { turn(row, k, columns) } else { k };
                            boxes.push(cell_box(column, row));
                        }
                    }
                }
                MatrixOrder::Columns | MatrixOrder::SerpentineColumns => {
                    for column in 0..columns {
                        for k in 0..rows {
                            let row = if order == MatrixOrder::SerpentineColumns { turn(column, k, rows) } else { k };
                            boxes.push(cell_box(column, row));
                        }
                    }
                }
            }
            boxes
        }
        Shape::Point { at, size } => vec![square(at, size)],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn patch(fixtures: &str) -> Patch {
        Patch::parse(&format!("(artnet: Some((to: [\"127.0.0.1\"])), fixtures: [{fixtures}])"), "test").unwrap()
    }

    #[test]
    fn a_strip_of_200_rgb_pixels_spans_two_universes_at_170_a_universe() {
        let layout = Layout::new(patch(
            "(name: \"tape\", shape: Strip(from: (0.0, 0.5), to: (1.0, 0.5), pixels: 200), universe: 3)",
        ))
        .unwrap();
        assert_eq!(layout.slots[169], PixelSlot { fixture: 0, universe: 3, offset: 507 });
        assert_eq!(layout.slots[170], PixelSlot { fixture: 0, universe: 4, offset: 0 });
        assert_eq!(layout.universes(), vec![3, 4]);
        // The ends are the first and last LEDs' centres.
        assert_eq!(layout.boxes[0].min[0] + layout.boxes[0].max[0], 0.0);
        assert!((layout.boxes[199].min[0] + layout.boxes[199].max[0] - 2.0).abs() < 1e-5);
    }

    #[test]
    fn a_serpentine_matrix_turns_at_each_row_end() {
        let layout = Layout::new(patch(
            "(name: \"wall\", shape: Matrix(at: (0.0, 0.0), size: (1.0, 1.0), columns: 3, rows: 2, order: Serpentine), universe: 1)",
        ))
        .unwrap();
        let columns: Vec<f32> = layout.boxes.iter().map(|b| b.min[0] * 3.0).map(f32::round).collect();
        assert_eq!(columns, vec![0.0, 1.0, 2.0, 2.0, 1.0, 0.0]);
    }

    #[test]
    fn overlapping_fixtures_are_refused_with_both_names() {
        let error = Layout::new(patch(
            "(name: \"a\", shape: Point(at: (0.5, 0.5)), universe: 1, address: 1), \
             (name: \"b\", shape: Point(at: (0.2, 0.5)), universe: 1, address: 3)",
        ))
        .unwrap_err();
        assert!(error.contains("'a' and 'b'") && error.contains("channel 3"), "{error}");
    }

    #[test]
    fn rgbw_takes_the_white_out_and_16_bits_send_coarse_then_fine() {
        let layout = Layout::new(patch(
            "(name: \"w\", shape: Point(at: (0.5, 0.5)), universe: 1, format: Grbw), \
             (name: \"fine\", shape: Point(at: (0.5, 0.5)), universe: 1, address: 10, bits: 16)",
        ))
        .unwrap();
        let universes = layout.encode(&[[65535, 32768, 32768], [65535, 0x1234, 0]], &[]);
        let u = &universes[&1];
        // G R B W: white takes the shared half, red keeps the rest.
        assert_eq!(&u[0..4], &[0, 127, 0, 128]);
        assert_eq!(&u[9..15], &[0xff, 0xff, 0x12, 0x34, 0, 0]);
    }

    #[test]
    fn gamma_and_brightness_shape_the_value() {
        let layout =
            Layout::new(patch("(name: \"g\", shape: Point(at: (0.5, 0.5)), universe: 1, gamma: 2.0, brightness: 0.5)"))
                .unwrap();
        let u = layout.encode(&[[32768, 65535, 0]], &[])[&1];
        assert_eq!(&u[0..3], &[32, 128, 0]);
    }

    #[test]
    fn a_moved_fixture_keeps_its_channels_and_a_saved_patch_reads_back_the_same() {
        let mut layout = Layout::new(patch(
            "(name: \"a\", shape: Strip(from: (0.1, 0.5), to: (0.3, 0.5), pixels: 3), universe: 1), \
             (name: \"b\", shape: Matrix(at: (0.5, 0.5), size: (0.2, 0.2), columns: 2, rows: 2), universe: 2, bits: 16)",
        ))
        .unwrap();
        let (slots, first) = (layout.slots.clone(), layout.boxes[3]);
        layout.move_fixture(1, 0.25, -0.5);
        assert_eq!(layout.slots, slots);
        assert!((layout.boxes[3].min[0] - first.min[0] - 0.25).abs() < 1e-6);
        assert!((layout.boxes[3].min[1] - first.min[1] + 0.5).abs() < 1e-6);
        assert_eq!(layout.patch.fixtures[1].shape.handle(), (0.85, 0.1));
        let again = Patch::parse(&layout.patch.to_ron(), "saved").unwrap();
        assert_eq!(again, layout.patch);
    }

    #[test]
    fn a_bad_patch_is_one_sentence_with_its_place() {
        let error = Patch::parse("(fixtures: [(name: \"x\", shape: Blob)])", "p.ron").unwrap_err();
        assert!(error.starts_with("p.ron:1:"), "{error}");
        let error = Patch::parse("(fixtures: [])", "p.ron").unwrap_err();
        assert!(error.contains("neither"), "{error}");
    }
}
