//! Controller profiles: which pads, buttons and faders of a controller do what, which message
//! lights each state, and the SysEx that puts the device in the mode indra drives. RON files:
//! bundled ones built into the binary (`controllers/`), the performer's beside them
//! (`--controller FILE`, or the user's `controllers/` folder).

use std::collections::BTreeSet;
use std::path::Path;

use serde::Deserialize;

/// The largest profile file read.
pub const MAX_PROFILE_BYTES: u64 = 256 << 10;

/// The profiles built into every binary: file name and text.
pub const BUNDLED: &[(&str, &str)] = &[
    ("apc40-mk2.ron", include_str!("../../../controllers/apc40-mk2.ron")),
    ("apc-mini-mk2.ron", include_str!("../../../controllers/apc-mini-mk2.ron")),
    ("launchpad-x.ron", include_str!("../../../controllers/launchpad-x.ron")),
    ("launchpad-mini-mk3.ron", include_str!("../../../controllers/launchpad-mini-mk3.ron")),
    ("generic-grid.ron", include_str!("../../../controllers/generic-grid.ron")),
];

/// One MIDI control: a note or a control change, on a channel 1–16.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Control {
    /// Note (channel, number): pressed is a note on, released a note off.
    Note(u8, u8),
    /// Control change (channel, number).
    Cc(u8, u8),
}

impl Control {
    /// The message that sets this control's light to `light` (same kind and number; the
    /// light's channel, which the vendors use for brightness and blinking).
    pub fn light_message(self, light: Light) -> [u8; 3] {
        let channel = light.channel.clamp(1, 16) - 1;
        match self {
            Control::Note(_, n) => [0x90 | channel, n, light.value],
            Control::Cc(_, n) => [0xB0 | channel, n, light.value],
        }
    }

    fn check(self) -> Result<(), String> {
        let (Control::Note(channel, number) | Control::Cc(channel, number)) = self;
        if !(1..=16).contains(&channel) || number > 127 {
            return Err(format!("{self:?}: channels are 1–16 and numbers 0–127"));
        }
        Ok(())
    }
}

/// A light: the channel and value of the message that sets it. In the vendors' protocols the
/// value (velocity) picks a colour of the device's palette and the channel its brightness or
/// behaviour.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq, Hash)]
pub struct Light {
    /// Channel 1–16.
    pub channel: u8,
    /// Value 0–127.
    pub value: u8,
}

impl Light {
    fn check(self, what: &str) -> Result<(), String> {
        if !(1..=16).contains(&self.channel) || self.value > 127 {
            return Err(format!("light '{what}': channel 1–16 and value 0–127"));
        }
        Ok(())
    }
}

/// The clip grid: columns are clips, rows are layers (the bottom row the bottom layer).
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Grid {
    /// Pads across.
    pub columns: u8,
    /// Pads down.
    pub rows: u8,
    /// The bottom left pad.
    pub bottom_left: Control,
    /// Number step from one pad to the one on its right.
    pub column_step: i16,
    /// Number step from one pad to the one above it.
    pub row_step: i16,
}

impl Grid {
    /// The pad at `column` (from the left) and `row` (from the bottom), if the grid has it.
    pub fn pad(&self, column: u8, row: u8) -> Option<Control> {
        if column >= self.columns || row >= self.rows {
            return None;
        }
        let (Control::Note(channel, first) | Control::Cc(channel, first)) = self.bottom_left;
        let number = i16::from(first) + i16::from(column) * self.column_step + i16::from(row) * self.row_step;
        let number = u8::try_from(number).ok().filter(|n| *n <= 127)?;
        Some(match self.bottom_left {
            Control::Note(..) => Control::Note(channel, number),
            Control::Cc(..) => Control::Cc(channel, number),
        })
    }

    /// Every pad with its column and row.
    pub fn pads(&self) -> impl Iterator<Item = (u8, u8, Control)> + '_ {
        (0..self.rows).flat_map(move |r| (0..self.columns).filter_map(move |c| Some((c, r, self.pad(c, r)?))))
    }
}

/// How each state of a clip pad lights.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Colours {
    /// No clip there.
    pub empty: Light,
    /// A clip, not playing.
    pub loaded: Light,
    /// The clip playing on its layer.
    pub playing: Light,
    /// A clip waiting for its beat or bar: indra alternates this and the pad's other state
    /// every half beat, in the show's tempo.
    pub queued: Light,
    /// A clip whose scene could not be loaded.
    pub broken: Light,
}

/// What a button does.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
pub enum Action {
    /// The next cue.
    Go,
    /// The previous cue.
    Back,
    /// Tap tempo (lit on each beat's first quarter).
    Tap,
    /// The grid shows the clips one page to the left (lit where there are).
    PageLeft,
    /// The grid shows the clips one page to the right (lit where there are).
    PageRight,
    /// The grid shows the layers one page up (lit where there are).
    PageUp,
    /// The grid shows the layers one page down (lit where there are).
    PageDown,
    /// Triggers column n (1 = the grid's leftmost on the current page) on every layer.
    Column(u8),
    /// Stops row n's layer (1 = the grid's bottom row on the current page).
    Stop(u8),
    /// Toggles the bypass of effect k (from 1) of layer n (from 1); lit while it is on.
    BypassLayer(u8, u8),
    /// Toggles the bypass of the master's effect k (from 1); lit while it is on.
    BypassMaster(u8),
    /// Steps layer n's blend mode to the next.
    Blend(u8),
}

/// A button.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Button {
    /// Its note or control change.
    pub control: Control,
    /// What it does.
    pub action: Action,
    /// Its light when what it shows is on (none: it has no light).
    #[serde(default)]
    pub on: Option<Light>,
    /// Its light when off.
    #[serde(default)]
    pub off: Option<Light>,
    /// It acts only while the profile's `shift` is held (and the button without shift acts
    /// only while it is not). Lights show the unshifted action.
    #[serde(default)]
    pub shifted: bool,
}

/// What a fader moves.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
pub enum FaderTarget {
    /// Layer n's opacity (from 1, the bottom layer).
    Layer(u8),
    /// The master level.
    Master,
}

/// A fader (a control change, 0–127 across the parameter's range).
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Fader {
    /// Its control change.
    pub control: Control,
    /// What it moves.
    pub target: FaderTarget,
}

/// What a non-motorised fader does when it is moved away from where the parameter is.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
pub enum Takeover {
    /// Nothing, until the fader passes the parameter's value; it takes over from there (no
    /// jump on stage).
    #[default]
    Pickup,
    /// The parameter jumps to the fader.
    Jump,
}

/// A controller profile.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Profile {
    /// The controller's name.
    pub name: String,
    /// The profile serves MIDI ports whose name contains one of these (any case).
    pub ports: Vec<String>,
    /// SysEx sent once each time the output port connects (the vendor's mode switch).
    #[serde(default)]
    pub hello: Vec<u8>,
    /// The button that shifts others to their second action, if the device has one.
    #[serde(default)]
    pub shift: Option<Control>,
    /// The clip grid.
    pub grid: Grid,
    /// How pads light.
    pub colours: Colours,
    /// Buttons.
    #[serde(default)]
    pub buttons: Vec<Button>,
    /// Faders.
    #[serde(default)]
    pub faders: Vec<Fader>,
    /// Fader takeover.
    #[serde(default)]
    pub takeover: Takeover,
    /// Light messages a second at most (a USB MIDI device takes a few thousand; DIN MIDI
    /// about 1000).
    #[serde(default = "default_rate")]
    pub rate: u32,
}

fn default_rate() -> u32 {
    1000
}

impl Profile {
    /// Parses and checks a profile's text; `origin` names it in messages.
    pub fn parse(text: &str, origin: &str) -> Result<Self, String> {
        let profile: Self = crate::files::parse_ron(text, origin)?;
        profile.check().map_err(|message| format!("{origin}: {message}"))?;
        Ok(profile)
    }

    /// Reads a profile file.
    pub fn load(path: &Path) -> Result<Self, String> {
        let text = crate::files::read_text(path, MAX_PROFILE_BYTES)?;
        Self::parse(&text, &path.display().to_string())
    }

    /// Whether this profile serves the port named `port`.
    pub fn serves(&self, port: &str) -> bool {
        let port = port.to_lowercase();
        self.ports.iter().any(|p| port.contains(&p.to_lowercase()))
    }

    /// Every rule a parsed profile keeps beyond its types.
    fn check(&self) -> Result<(), String> {
        if self.ports.iter().all(|p| p.trim().is_empty()) {
            return Err("`ports` names no port".into());
        }
        if let Some((&first, rest)) = self.hello.split_first() {
            let body_ok = rest.split_last().is_some_and(|(&last, body)| last == 0xF7 && body.iter().all(|b| *b < 0x80));
            if first != 0xF0 || !body_ok {
                return Err("`hello` must be one SysEx message: F0, 7-bit bytes, F7".into());
            }
        }
        if !(1..=16).contains(&self.grid.columns) || !(1..=16).contains(&self.grid.rows) {
            return Err("the grid has 1–16 columns and 1–16 rows".into());
        }
        if !(1..=10_000).contains(&self.rate) {
            return Err(format!("rate {} must be 1–10000 messages a second", self.rate));
        }
        let c = &self.colours;
        for (what, light) in [
            ("empty", c.empty),
            ("loaded", c.loaded),
            ("playing", c.playing),
            ("queued", c.queued),
            ("broken", c.broken),
        ] {
            light.check(what)?;
        }
        if let Some(shift) = self.shift {
            shift.check()?;
            if self.buttons.iter().any(|b| b.control == shift) {
                return Err(format!("shift {shift:?} is also a button"));
            }
        }
        if self.buttons.iter().any(|b| b.shifted) && self.shift.is_none() {
            return Err("a button is `shifted` but the profile names no `shift`".into());
        }
        let mut used = BTreeSet::new();
        let mut claim = |control: Control, shifted: bool, what: String| {
            control.check()?;
            if !used.insert((control, shifted)) {
                return Err(format!("{control:?} ({what}) is used twice"));
            }
            Ok(())
        };
        let pads = usize::from(self.grid.columns) * usize::from(self.grid.rows);
        if self.grid.pads().count() != pads {
            return Err("a pad of the grid falls outside 0–127".into());
        }
        for (column, row, pad) in self.grid.pads() {
            claim(pad, false, format!("pad {},{}", column + 1, row + 1))?;
        }
        for b in &self.buttons {
            claim(b.control, b.shifted, format!("{:?}", b.action))?;
            for light in b.on.iter().chain(&b.off) {
                light.check(&format!("{:?}", b.action))?;
            }
        }
        for f in &self.faders {
            if !matches!(f.control, Control::Cc(..)) {
                return Err(format!("fader {:?} must be a control change", f.target));
            }
            claim(f.control, false, format!("fader {:?}", f.target))?;
        }
        Ok(())
    }
}

/// Every bundled profile, parsed (they are checked by the tests: a bad one is a build's bug).
pub fn bundled() -> Vec<Profile> {
    BUNDLED.iter().filter_map(|(name, text)| Profile::parse(text, name).map_err(|e| log::error!("{e}")).ok()).collect()
}

/// The profiles a performer asks for: `choice` a bundled profile's name or file name, or a
/// file; `None` every bundled profile and those in `user_dir` (auto-detected by port name).
pub fn choose(choice: Option<&str>, user_dir: &Path) -> Result<Vec<Profile>, String> {
    let Some(choice) = choice else {
        let mut profiles = bundled();
        let mut files: Vec<_> = std::fs::read_dir(user_dir)
            .map(|d| d.flatten().map(|e| e.path()).filter(|p| p.extension().is_some_and(|e| e == "ron")).collect())
            .unwrap_or_default();
        files.sort();
        for file in files {
            match Profile::load(&file) {
                // A user's profile replaces the bundled one of its name, and is tried first.
                Ok(p) => {
                    profiles.retain(|b| b.name != p.name);
                    profiles.insert(0, p);
                }
                Err(e) => log::warn!("controller profile skipped: {e}"),
            }
        }
        return Ok(profiles);
    };
    let wanted = choice.to_lowercase();
    let named = BUNDLED.iter().find(|(file, text)| {
        file.trim_end_matches(".ron") == wanted
            || *file == wanted
            || Profile::parse(text, file).is_ok_and(|p| p.name.to_lowercase() == wanted)
    });
    match named {
        Some((file, text)) => Profile::parse(text, file).map(|p| vec![p]),
        None if Path::new(choice).is_file() => Profile::load(Path::new(choice)).map(|p| vec![p]),
        None => {
            let names: Vec<&str> = BUNDLED.iter().map(|(f, _)| f.trim_end_matches(".ron")).collect();
            Err(format!("no controller profile '{choice}': name a file or one of {}", names.join(", ")))
        }
    }
}
