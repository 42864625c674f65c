//! Fixture profiles in the Open Fixture Library's JSON format (open-fixture-library.org): a
//! fixture's channels, their default values and fine (16-bit) aliases, and its modes — the
//! channel order a mode puts on the wire. Capabilities (what a value of a channel does) are the
//! desk operator's concern and are not read; matrix fixtures (template channels) are refused.

use std::collections::BTreeMap;

use serde::Deserialize;

/// The largest profile read.
const MAX_PROFILE_BYTES: u64 = 1 << 20;

#[derive(Deserialize)]
#[serde(rename_all = "camelCase")]
struct ProfileFile {
    name: String,
    #[serde(default)]
    available_channels: BTreeMap<String, ChannelFile>,
    #[serde(default)]
    template_channels: Option<serde_json::Value>,
    modes: Vec<ModeFile>,
}

#[derive(Deserialize)]
#[serde(rename_all = "camelCase")]
struct ChannelFile {
    #[serde(default)]
    default_value: Option<serde_json::Value>,
    #[serde(default)]
    fine_channel_aliases: Vec<String>,
}

#[derive(Deserialize)]
struct ModeFile {
    name: String,
    channels: Vec<Option<serde_json::Value>>,
}

/// What one DMX channel of a mode carries.
#[derive(Clone, Debug, PartialEq)]
pub enum Slot {
    /// A channel's value (its coarse byte when it has a fine one).
    Coarse(String),
    /// The fine byte of the named channel.
    Fine(String),
    /// Nothing (`null` in the mode).
    Unused,
}

/// One mode of a profile: its channels in wire order and each channel's default (0–1).
#[derive(Clone, Debug, PartialEq)]
pub struct LampMode {
    /// The fixture's name and the mode's, for messages.
    pub name: String,
    /// The channels in wire order.
    pub slots: Vec<Slot>,
    /// Each named channel's default value, 0–1 of its range.
    pub defaults: BTreeMap<String, f32>,
}

/// Reads mode `mode` of the profile at `path`: one sentence for what is wrong.
pub fn load_mode(path: &std::path::Path, mode: &str) -> Result<LampMode, String> {
    let bytes = crate::files::read_limited(path, MAX_PROFILE_BYTES).map_err(|e| e.to_string())?;
    parse_mode(&bytes, mode).map_err(|e| format!("{}: {e}", path.display()))
}

/// Mode `mode` of a profile's JSON text.
pub fn parse_mode(json: &[u8], mode: &str) -> Result<LampMode, String> {
    let file: ProfileFile = serde_json::from_slice(json).map_err(|e| format!("not an OFL fixture: {e}"))?;
    if file.template_channels.is_some() {
        return Err(format!("'{}' is a matrix fixture (template channels): not supported", file.name));
    }
    let names: Vec<&str> = file.modes.iter().map(|m| m.name.as_str()).collect();
    let chosen = file
        .modes
        .iter()
        .find(|m| m.name == mode)
        .ok_or_else(|| format!("'{}' has no mode '{mode}' (its modes: {})", file.name, names.join(", ")))?;
    let fine_of: BTreeMap<&str, &str> = file
        .available_channels
        .iter()
        .flat_map(|(name, c)| c.fine_channel_aliases.iter().map(move |f| (f.as_str(), name.as_str())))
        .collect();
    let mut slots = Vec::with_capacity(chosen.channels.len());
    for entry in &chosen.channels {
        let slot = match entry {
            None | Some(serde_json::Value::Null) => Slot::Unused,
            Some(serde_json::Value::String(name)) if file.available_channels.contains_key(name) => {
                Slot::Coarse(name.clone())
            }
            Some(serde_json::Value::String(name)) => match fine_of.get(name.as_str()) {
                Some(coarse) => Slot::Fine((*coarse).to_string()),
                None => return Err(format!("mode '{mode}' names '{name}', which is no channel of the fixture")),
            },
            Some(other) => return Err(format!("mode '{mode}': {other} is not supported (matrix insert blocks)")),
        };
        slots.push(slot);
    }
    let mut defaults = BTreeMap::new();
    for (name, channel) in &file.available_channels {
        let full = if channel.fine_channel_aliases.is_empty() { 255.0 } else { 65535.0 };
        let value = match &channel.default_value {
            None => 0.0,
            Some(serde_json::Value::Number(n)) => n.as_f64().unwrap_or(0.0) as f32 / full,
            Some(serde_json::Value::String(s)) => {
                s.strip_suffix('%').and_then(|p| p.trim().parse::<f32>().ok()).map(|p| p / 100.0).ok_or_else(|| {
                    format!("channel '{name}': default value '{s}' is neither a number nor a percentage")
                })?
            }
            Some(other) => return Err(format!("channel '{name}': default value {other} is not a number")),
        };
        defaults.insert(name.clone(), value.clamp(0.0, 1.0));
    }
    Ok(LampMode { name: format!("{} ({mode})", file.name), slots, defaults })
}

#[cfg(test)]
mod tests {
    use super::*;

    const SPOT: &str = r#"{
        "name": "Spot", "categories": ["Moving Head"],
        "availableChannels": {
            "Pan": {"defaultValue": "50%", "fineChannelAliases": ["Pan fine"], "capability": {"type": "Pan"}},
            "Dimmer": {"capability": {"type": "Intensity"}},
            "Shutter": {"defaultValue": 255, "capability": {"type": "ShutterStrobe", "shutterEffect": "Open"}}
        },
        "modes": [{"name": "4ch", "channels": ["Pan", "Pan fine", "Dimmer", null]}, {"name": "2ch", "channels": ["Dimmer", "Shutter"]}]
    }"#;

    #[test]
    fn a_mode_lists_coarse_fine_and_unused_channels_with_their_defaults() {
        let mode = parse_mode(SPOT.as_bytes(), "4ch").unwrap();
        assert_eq!(
            mode.slots,
            vec![Slot::Coarse("Pan".into()), Slot::Fine("Pan".into()), Slot::Coarse("Dimmer".into()), Slot::Unused]
        );
        assert_eq!((mode.defaults["Pan"], mode.defaults["Dimmer"], mode.defaults["Shutter"]), (0.5, 0.0, 1.0));
    }

    #[test]
    fn an_unknown_mode_names_the_ones_there_are() {
        let error = parse_mode(SPOT.as_bytes(), "9ch").unwrap_err();
        assert!(error.contains("4ch, 2ch"), "{error}");
        assert!(parse_mode(b"{\"name\": 1}", "x").unwrap_err().starts_with("not an OFL fixture"));
    }
}
