//! The patch file: which fixtures sit where on the image, in which universes, sent how.

use std::path::Path;

use serde::{Deserialize, Serialize};

/// The largest patch file read (a patch of thousands of fixtures is a few hundred kB).
pub const MAX_PATCH_BYTES: u64 = 4 << 20;
/// The most pixels one patch maps (a few LED walls; each costs 8 bytes of readback a frame and
/// one workgroup of the pixel-map pass, whose count a dispatch holds to 65 535).
pub const MAX_PIXELS: usize = 65_535;
/// The most universes one patch sends.
pub const MAX_UNIVERSES: usize = 1024;

/// A patch: fixtures placed on one of the show's images, and where their bytes go.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Patch {
    /// The image the fixtures sample: 0 the output, n the scene's n-th extra output.
    #[serde(default)]
    pub image: usize,
    /// Packets a second for each universe that changes (DMX's usual 44).
    #[serde(default = "default_rate")]
    pub rate: f32,
    /// Art-Net 4 out.
    #[serde(default)]
    pub artnet: Option<ArtNetOut>,
    /// sACN (E1.31) out.
    #[serde(default)]
    pub sacn: Option<SacnOut>,
    /// What the lights show when indra stops.
    #[serde(default)]
    pub on_stop: OnStop,
    /// The fixtures, in the order their pixels are sampled.
    #[serde(default)]
    pub fixtures: Vec<Fixture>,
    /// Fixtures with channels (moving heads, dimmers, strobes) from Open Fixture Library
    /// profiles, their channels driven by parameters.
    #[serde(default)]
    pub lamps: Vec<Lamp>,
    /// Each lamp's mode, read from its profile by [`Patch::load`].
    #[serde(skip)]
    pub lamp_modes: Vec<super::ofl::LampMode>,
}

/// A fixture with channels: a mode of an Open Fixture Library profile at an address, each
/// channel at its profile's default unless a parameter drives it.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Lamp {
    /// Its name in messages.
    pub name: String,
    /// The profile: an OFL fixture JSON file, beside the patch or under the project's folders.
    pub profile: String,
    /// The mode's name in the profile.
    pub mode: String,
    /// Its universe.
    pub universe: u16,
    /// Its first channel, 1–512 (the whole mode fits in the universe).
    #[serde(default = "first_channel")]
    pub address: u16,
    /// Channel name → the parameter that drives it (`node.param` or `node.param.x`), across the
    /// parameter's range; 16 bits where the mode has the channel's fine byte.
    #[serde(default)]
    pub drive: std::collections::BTreeMap<String, String>,
}

fn default_rate() -> f32 {
    44.0
}

fn yes() -> bool {
    true
}

/// Art-Net out: unicast to the nodes named (never broadcast unless a broadcast address is named).
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ArtNetOut {
    /// Nodes to send to: "IP" or "IP:PORT" (port 6454 by default).
    pub to: Vec<String>,
    /// The local address to send from and to answer ArtPoll on (port 6454), so that desks and
    /// nodes list indra; none: send from any address and answer no poll.
    #[serde(default)]
    pub bind: Option<String>,
    /// Send ArtSync after each frame's packets, so nodes output all universes at once.
    #[serde(default = "yes")]
    pub sync: bool,
}

/// sACN out: multicast per universe, or unicast to the receivers named.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SacnOut {
    /// Receivers to send to ("IP" or "IP:PORT"); empty: each universe's multicast group.
    #[serde(default)]
    pub to: Vec<String>,
    /// The local address to send from (default: any).
    #[serde(default)]
    pub bind: Option<String>,
    /// Priority 0–200 (receivers take the highest; 100 is the standard's default).
    #[serde(default = "default_priority")]
    pub priority: u8,
    /// A synchronisation universe: receivers hold each frame until its sync packet.
    #[serde(default)]
    pub sync_universe: Option<u16>,
    /// The source name receivers show.
    #[serde(default = "default_source_name")]
    pub name: String,
}

fn default_priority() -> u8 {
    100
}

fn default_source_name() -> String {
    "indra".into()
}

/// What the lights get when indra stops.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
pub enum OnStop {
    /// Every channel 0, then the streams end.
    #[default]
    Blackout,
    /// Nothing more is sent: nodes hold the last frame.
    Hold,
}

/// One fixture: a shape on the image, its pixels' format and its first channel.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Fixture {
    /// Its name in messages and the panel.
    pub name: String,
    /// Where its pixels sit on the image.
    pub shape: Shape,
    /// The universe its first pixel is in (Art-Net port-address, sACN universe).
    pub universe: u16,
    /// The first pixel's first channel, 1–512.
    #[serde(default = "first_channel")]
    pub address: u16,
    /// The order of the colour bytes each pixel sends.
    #[serde(default)]
    pub format: PixelFormat,
    /// 8 or 16 bits per colour (16: coarse byte, then fine).
    #[serde(default = "eight")]
    pub bits: u8,
    /// The screen value (0–1, as a monitor shows it) is raised to this power: 1 sends what
    /// the screen shows, 2.2 about the light the image means (LED tape is linear).
    #[serde(default = "one")]
    pub gamma: f32,
    /// Scales every value after the gamma (0–1).
    #[serde(default = "one")]
    pub brightness: f32,
}

fn first_channel() -> u16 {
    1
}

fn eight() -> u8 {
    8
}

fn one() -> f32 {
    1.0
}

/// Where a fixture's pixels sit, in image coordinates: (0, 0) the top left corner, (1, 1) the
/// bottom right.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub enum Shape {
    /// A line of `pixels` LEDs, the first at `from` and the last at `to`; each averages the
    /// square around it whose side is the step between LEDs (or `size`).
    Strip {
        /// The first LED.
        from: (f32, f32),
        /// The last LED.
        to: (f32, f32),
        /// How many LEDs.
        pixels: u32,
        /// The side of the square each LED averages (default: the step between LEDs).
        #[serde(default)]
        size: Option<f32>,
    },
    /// `columns` × `rows` LEDs filling the rectangle at `at` of `size`; each averages its cell.
    Matrix {
        /// The top left corner.
        at: (f32, f32),
        /// Width and height.
        size: (f32, f32),
        /// LEDs across.
        columns: u32,
        /// LEDs down.
        rows: u32,
        /// The order the LEDs are wired in, from the top left.
        #[serde(default)]
        order: MatrixOrder,
    },
    /// One LED (or a lamp) averaging the square of side `size` around `at` (0: one texel).
    Point {
        /// The centre.
        at: (f32, f32),
        /// The side of the square it averages.
        #[serde(default)]
        size: f32,
    },
}

/// The order a matrix's LEDs are wired in, starting at the top left.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
pub enum MatrixOrder {
    /// Row by row, each left to right.
    #[default]
    Rows,
    /// Row by row, turning at each end (left to right, then right to left, …).
    Serpentine,
    /// Column by column, each top to bottom.
    Columns,
    /// Column by column, turning at each end.
    SerpentineColumns,
}

/// The bytes of one pixel, in the order the LED chip reads them.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[allow(missing_docs)]
pub enum PixelFormat {
    #[default]
    Rgb,
    Rbg,
    Grb,
    Gbr,
    Brg,
    Bgr,
    /// Red, green, blue and a white LED: the white takes what the three have in common.
    Rgbw,
    /// Green, red, blue, white (SK6812 RGBW tape).
    Grbw,
}

impl Shape {
    /// Where the panel shows the shape's handle: a strip's middle, a matrix's centre, a point.
    pub fn handle(&self) -> (f32, f32) {
        match *self {
            Self::Strip { from, to, .. } => ((from.0 + to.0) / 2.0, (from.1 + to.1) / 2.0),
            Self::Matrix { at, size, .. } => (at.0 + size.0 / 2.0, at.1 + size.1 / 2.0),
            Self::Point { at, .. } => at,
        }
    }

    /// Moves the whole shape by (`dx`, `dy`) of the picture.
    pub fn translate(&mut self, dx: f32, dy: f32) {
        let by = |p: &mut (f32, f32)| *p = (p.0 + dx, p.1 + dy);
        match self {
            Self::Strip { from, to, .. } => {
                by(from);
                by(to);
            }
            Self::Matrix { at, .. } | Self::Point { at, .. } => by(at),
        }
    }
}

impl PixelFormat {
    /// Which colour each byte carries: 0 red, 1 green, 2 blue, 3 white.
    pub fn order(self) -> &'static [usize] {
        match self {
            Self::Rgb => &[0, 1, 2],
            Self::Rbg => &[0, 2, 1],
            Self::Grb => &[1, 0, 2],
            Self::Gbr => &[1, 2, 0],
            Self::Brg => &[2, 0, 1],
            Self::Bgr => &[2, 1, 0],
            Self::Rgbw => &[0, 1, 2, 3],
            Self::Grbw => &[1, 0, 2, 3],
        }
    }
}

impl Patch {
    /// Reads and checks a patch file: one sentence with file:line:column for what is wrong.
    pub fn load(path: &Path) -> Result<Self, String> {
        let text = crate::files::read_text(path, MAX_PATCH_BYTES)?;
        let mut patch = Self::parse(&text, &path.display().to_string())?;
        let folder = path.parent().unwrap_or(Path::new("."));
        for lamp in &patch.lamps {
            let profile = folder.join(&lamp.profile);
            let profile = if profile.exists() { profile } else { Path::new(&lamp.profile).to_path_buf() };
            let mode = super::ofl::load_mode(&profile, &lamp.mode).map_err(|e| format!("lamp '{}': {e}", lamp.name))?;
            patch.lamp_modes.push(mode);
        }
        Ok(patch)
    }

    /// The patch as RON text (what the panel saves; comments of the file it came from are not
    /// kept).
    pub fn to_ron(&self) -> String {
        let config = ron::ser::PrettyConfig::default().struct_names(false);
        ron::ser::to_string_pretty(self, config).unwrap_or_default()
    }

    /// Parses and checks a patch's text; `origin` names it in messages.
    pub fn parse(text: &str, origin: &str) -> Result<Self, String> {
        let patch: Self = crate::files::parse_ron(text, origin)?;
        patch.check().map_err(|message| format!("{origin}: {message}"))?;
        Ok(patch)
    }

    /// Every rule a parsed patch must keep beyond its types.
    fn check(&self) -> Result<(), String> {
        if !(self.rate.is_finite() && (1.0..=250.0).contains(&self.rate)) {
            return Err(format!("rate {} must be 1–250 packets a second", self.rate));
        }
        if self.artnet.is_none() && self.sacn.is_none() {
            return Err("names neither `artnet` nor `sacn`: nothing would be sent".into());
        }
        if let Some(artnet) = &self.artnet
            && artnet.to.is_empty()
        {
            return Err("artnet.to is empty: name the nodes to send to".into());
        }
        if let Some(sacn) = &self.sacn {
            if sacn.priority > 200 {
                return Err(format!("sacn.priority {} is over 200", sacn.priority));
            }
            if sacn.sync_universe.is_some_and(|u| !(1..=63999).contains(&u)) {
                return Err("sacn.sync_universe must be 1–63999".into());
            }
        }
        if self.fixtures.is_empty() && self.lamps.is_empty() {
            return Err("has no fixtures and no lamps".into());
        }
        if let Some(lamp) = self.lamps.iter().find(|l| !(1..=512).contains(&l.address) || l.universe > 32767) {
            return Err(format!("lamp '{}': address must be 1–512 and universe 0–32767", lamp.name));
        }
        for fixture in &self.fixtures {
            fixture.check().map_err(|message| format!("fixture '{}': {message}", fixture.name))?;
        }
        Ok(())
    }
}

/// How DMX files are read: an optional field may be written without `Some(…)`.
pub fn ron_options() -> ron::Options {
    ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
}

impl Fixture {
    /// The rules of one fixture.
    fn check(&self) -> Result<(), String> {
        if !(1..=512).contains(&self.address) {
            return Err(format!("address {} must be 1–512", self.address));
        }
        if self.universe > 32767 {
            return Err(format!("universe {} is over 32767 (Art-Net's last)", self.universe));
        }
        if self.bits != 8 && self.bits != 16 {
            return Err(format!("bits {} must be 8 or 16", self.bits));
        }
        if !(self.gamma.is_finite() && (0.1..=5.0).contains(&self.gamma)) {
            return Err(format!("gamma {} must be 0.1–5", self.gamma));
        }
        if !(self.brightness.is_finite() && (0.0..=1.0).contains(&self.brightness)) {
            return Err(format!("brightness {} must be 0–1", self.brightness));
        }
        let finite = |p: (f32, f32)| p.0.is_finite() && p.1.is_finite();
        match &self.shape {
            Shape::Strip { from, to, pixels, size } => {
                if *pixels == 0 || !finite(*from) || !finite(*to) || size.is_some_and(|s| !s.is_finite() || s < 0.0) {
                    return Err("a strip needs pixels ≥ 1, finite ends and a size ≥ 0".into());
                }
            }
            Shape::Matrix { at, size, columns, rows, .. } => {
                if *columns == 0 || *rows == 0 || !finite(*at) || !finite(*size) || size.0 <= 0.0 || size.1 <= 0.0 {
                    return Err("a matrix needs columns and rows ≥ 1 and a size over 0".into());
                }
            }
            Shape::Point { at, size } => {
                if !finite(*at) || !size.is_finite() || *size < 0.0 {
                    return Err("a point needs a finite centre and a size ≥ 0".into());
                }
            }
        }
        Ok(())
    }

    /// Bytes per pixel on the wire.
    pub fn pixel_bytes(&self) -> usize {
        self.format.order().len() * usize::from(self.bits / 8)
    }
}
