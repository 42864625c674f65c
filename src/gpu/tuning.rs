//! Choices measured on the adapter that runs them: which of a parameter's options is fastest
//! where an option only changes how a node draws, not what it draws (the `rasterizer`, StarGlow's
//! `layout`). `indra tune` times each option and keeps the winners in a file per adapter in the
//! performer's configuration folder; a node whose parameter says `auto` takes the winner. The
//! file is keyed by the adapter's name, backend and driver and by indra's version, and one made
//! for another is not used: a driver update or a new indra is tuned again.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

/// Which choices a device uses for `auto`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum TuningSource {
    /// The built-in defaults (renders that must not depend on a measurement: goldens, farms).
    #[default]
    Defaults,
    /// The file `indra tune` saved for this adapter, if there is one.
    Saved,
    /// This file (a farm ships one to every node so all of them choose alike).
    File(PathBuf),
}

/// The adapter a tuning was measured on.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct AdapterKey {
    /// The adapter's name (`NVIDIA H200`, `llvmpipe (LLVM 19.1.7, 256 bits)`).
    pub adapter: String,
    /// The graphics API.
    pub backend: String,
    /// The driver and its version, as the adapter reports them.
    pub driver: String,
    /// The indra that measured it.
    pub indra: String,
}

impl AdapterKey {
    /// The key of `info` with this indra.
    pub fn of(info: &wgpu::AdapterInfo) -> Self {
        Self {
            adapter: info.name.clone(),
            backend: format!("{:?}", info.backend),
            driver: format!("{} {}", info.driver, info.driver_info).trim().to_string(),
            indra: env!("CARGO_PKG_VERSION").to_string(),
        }
    }

    /// The file name its tuning is saved under: the adapter and backend, in characters every file
    /// system takes (driver and version are checked inside the file).
    pub fn file_name(&self) -> String {
        let plain: String = format!("{}-{}", self.adapter, self.backend)
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() || c == '-' { c.to_ascii_lowercase() } else { '_' })
            .collect();
        format!("{}.ron", plain.trim_matches('_'))
    }
}

/// One measured choice: a technique's parameter, the option taken for `auto`, and the timings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TunedChoice {
    /// The technique (`tessellation`).
    pub technique: String,
    /// Its parameter (`rasterizer`).
    pub parameter: String,
    /// The option `auto` stands for on this adapter.
    pub chosen: String,
    /// The scene it was measured in, and at what size.
    pub scene: String,
    /// Output size of the measurement.
    pub size: (u32, u32),
    /// Each option and its median frame in milliseconds (GPU time where the adapter has
    /// timestamps, else wall time), in the order measured.
    pub figures: Vec<(String, f64)>,
}

/// What `auto` stands for on one adapter.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Tuning {
    /// The adapter it was measured on (`None`: the built-in defaults).
    pub key: Option<AdapterKey>,
    /// How the figures were taken: `GPU` or `wall`.
    pub clock: String,
    /// The choices.
    pub choices: Vec<TunedChoice>,
}

/// The most bytes a tuning file may have: a few choices, each a few lines.
const MAX_FILE_BYTES: u64 = 64 * 1024;

impl Tuning {
    /// The option `auto` stands for in `technique`'s `parameter`, if one was measured.
    pub fn choice(&self, technique: &str, parameter: &str) -> Option<&str> {
        let found = self.choices.iter().find(|c| c.technique == technique && c.parameter == parameter)?;
        Some(found.chosen.as_str())
    }

    /// One line for the panel and the log: what `auto` takes here.
    pub fn summary(&self) -> String {
        if self.key.is_none() {
            return "auto: built-in defaults (not tuned on this adapter: `indra tune`)".into();
        }
        let chosen: Vec<String> =
            self.choices.iter().map(|c| format!("{}.{} {}", c.technique, c.parameter, c.chosen)).collect();
        format!("auto, tuned here: {}", chosen.join(", "))
    }

    /// Where the tuning for `key` is saved: `tuning/` in the configuration folder.
    pub fn path_for(key: &AdapterKey) -> Option<PathBuf> {
        Some(crate::files::user_config()?.join("tuning").join(key.file_name()))
    }

    /// The tuning `source` names for the adapter `key`, and a sentence when a file was there but
    /// not used (made for another driver or indra, or unreadable). Defaults when there is none.
    pub fn load(source: &TuningSource, key: &AdapterKey) -> (Self, Option<String>) {
        let path = match source {
            TuningSource::Defaults => return (Self::default(), None),
            TuningSource::Saved => match Self::path_for(key) {
                Some(path) if path.exists() => path,
                _ => return (Self::default(), None),
            },
            TuningSource::File(path) => path.clone(),
        };
        match Self::read(&path) {
            Ok(tuning) if tuning.key.as_ref() == Some(key) => (tuning, None),
            Ok(tuning) => {
                let made = tuning.key.map_or("no adapter".into(), |k| {
                    format!("{} ({}, {}), indra {}", k.adapter, k.backend, k.driver, k.indra)
                });
                let note = format!(
                    "{} was tuned on {made}, not this adapter, driver and indra: `auto` takes the built-in defaults (run `indra tune` again)",
                    path.display()
                );
                (Self::default(), Some(note))
            }
            Err(e) => (Self::default(), Some(format!("{e}: `auto` takes the built-in defaults"))),
        }
    }

    /// The tuning in the file at `path`.
    pub fn read(path: &Path) -> Result<Self, String> {
        let bytes = crate::files::read_limited(path, MAX_FILE_BYTES).map_err(|e| e.to_string())?;
        let text = String::from_utf8(bytes).map_err(|_| format!("{}: not UTF-8", path.display()))?;
        ron::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))
    }

    /// Saves it at `path`, atomically.
    pub fn save(&self, path: &Path) -> Result<(), String> {
        let text = ron::ser::to_string_pretty(self, ron::ser::PrettyConfig::default()).map_err(|e| e.to_string())?;
        crate::atomic_file::write(path, text.as_bytes()).map_err(|e| format!("cannot save {}: {e}", path.display()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key() -> AdapterKey {
        AdapterKey {
            adapter: "NVIDIA H200".into(),
            backend: "Vulkan".into(),
            driver: "NVIDIA 570.1".into(),
            indra: "1.0.0".into(),
        }
    }

    fn tuned() -> Tuning {
        let choice = TunedChoice {
            technique: "tessellation".into(),
            parameter: "rasterizer".into(),
            chosen: "pipeline".into(),
            scene: "tessellation_fluid".into(),
            size: (1920, 1080),
            figures: vec![("compute".into(), 1.5), ("pipeline".into(), 0.5)],
        };
        Tuning { key: Some(key()), clock: "GPU".into(), choices: vec![choice] }
    }

    #[test]
    fn a_saved_tuning_is_used_only_for_the_adapter_driver_and_indra_it_was_made_on() {
        let dir = std::env::temp_dir().join(format!("indra-tuning-{}", std::process::id()));
        let path = dir.join(key().file_name());
        tuned().save(&path).unwrap();
        let file = TuningSource::File(path.clone());
        let (same, note) = Tuning::load(&file, &key());
        assert_eq!((same.choice("tessellation", "rasterizer"), note), (Some("pipeline"), None));
        assert_eq!(same.choice("poisson", "rasterizer"), None, "a technique not measured keeps its default");
        let newer = AdapterKey { driver: "NVIDIA 580.2".into(), ..key() };
        let (other, note) = Tuning::load(&file, &newer);
        assert_eq!(other, Tuning::default());
        assert!(note.unwrap().contains("run `indra tune` again"));
        std::fs::write(&path, "(key: Some(").unwrap();
        let (broken, note) = Tuning::load(&file, &key());
        assert_eq!(broken, Tuning::default());
        assert!(note.unwrap().contains(&path.display().to_string()));
        assert_eq!(Tuning::load(&TuningSource::Defaults, &key()).0, Tuning::default());
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn file_names_keep_to_plain_characters() {
        let llvmpipe = AdapterKey { adapter: "llvmpipe (LLVM 19.1.7, 256 bits)".into(), ..key() };
        assert_eq!(llvmpipe.file_name(), "llvmpipe__llvm_19_1_7__256_bits_-vulkan.ron");
        assert_eq!(key().file_name(), "nvidia_h200-vulkan.ron");
    }
}
