//! Checkpoints: a running scene's whole state at one frame boundary, in one file, so a render
//! can start at frame N without simulating the N steps before it (`indra bake`, then
//! `indra render --checkpoints`).
//!
//! The file is a header that pins what the state was made with (format, indra version, scene
//! and controls hashes, adapter and driver, frame, size, step, seed), then named sections (the
//! control layer's state, each node's buffers and CPU state), then a SHA-256 of everything
//! before it. Reading checks every length against the bytes that are there before it allocates,
//! and the checksum before it trusts a byte, so a damaged or hostile file is one clear error.
//! This module knows the format only; what goes in the sections is the scene's and each
//! technique's business (`scene::checkpoint`, `Technique::save_state`).

mod node_state;

use std::path::{Path, PathBuf};

use sha2::{Digest, Sha256};

pub use node_state::NodeState;

/// The version of the file layout and of what the sections hold; a checkpoint of another
/// version is refused.
pub const FORMAT: u32 = 1;

const MAGIC: &[u8; 16] = b"indra-checkpoint";
/// The largest checkpoint read: far above any bundled scene's at 4K (see docs/farm.md), far
/// below what would take a render node's memory.
pub const MAX_FILE: u64 = 4 << 30;
/// Most sections a checkpoint holds (a show of many clips has a few per node).
const MAX_SECTIONS: u32 = 1 << 16;
/// Longest header and section name, in bytes.
const MAX_HEADER: u32 = 1 << 16;
const MAX_NAME: u16 = 1024;

/// What a checkpoint was made with. A render from it must have been asked for the same scene,
/// controls, size, step and seed (else the frames would not be the ones asked for), and on the
/// same adapter and driver (else they are only close).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Header {
    /// [`FORMAT`] when written.
    pub format: u32,
    /// The indra version that wrote it.
    pub indra: String,
    /// The scene's or show's name.
    pub scene: String,
    /// SHA-256 (hex) of the validated scene, edits included.
    pub scene_hash: String,
    /// SHA-256 (hex) of the scheduled control events (a replay, an audio file's analysis).
    pub controls_hash: String,
    /// The adapter's name.
    pub adapter: String,
    /// The driver and its version.
    pub driver: String,
    /// The frame the state is at: the next step is this frame.
    pub frame: u64,
    /// The output size.
    pub size: (u32, u32),
    /// The fixed step in seconds, as its bits (exact).
    pub dt_bits: u32,
    /// The scene seed.
    pub seed: u64,
}

impl Header {
    /// Why a render asked for as `wanted` cannot start from this checkpoint, or `None`. A
    /// different adapter or driver is a reason unless `other_adapter` allows it.
    pub fn mismatch(&self, wanted: &Header, other_adapter: bool) -> Option<String> {
        let what = if self.format != wanted.format {
            format!("is format {} (this indra reads {})", self.format, wanted.format)
        } else if self.indra != wanted.indra {
            format!("was made by indra {} (this is {})", self.indra, wanted.indra)
        } else if self.scene_hash != wanted.scene_hash {
            format!("was made from another version of '{}' (the scene or its edits changed)", self.scene)
        } else if self.controls_hash != wanted.controls_hash {
            "was made with other control events (a different --replay or --audio)".into()
        } else if self.size != wanted.size {
            format!("is at {}x{}, the render at {}x{}", self.size.0, self.size.1, wanted.size.0, wanted.size.1)
        } else if self.dt_bits != wanted.dt_bits || self.seed != wanted.seed {
            "was made with another --dt or --seed".into()
        } else if !other_adapter && (self.adapter != wanted.adapter || self.driver != wanted.driver) {
            format!(
                "was made on {} ({}), this render runs on {} ({}): frames would be close, not identical; \
                 pass --accept-other-adapter to use it anyway",
                self.adapter, self.driver, wanted.adapter, wanted.driver
            )
        } else {
            return None;
        };
        Some(what)
    }
}

/// A checkpoint in memory: its header and its sections, by name.
#[derive(Clone, Debug, PartialEq)]
pub struct Checkpoint {
    /// What it was made with.
    pub header: Header,
    /// Named sections, in the order written.
    pub sections: Vec<(String, Vec<u8>)>,
}

/// Why a checkpoint could not be read, written or used.
#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    /// The file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The error.
        source: std::io::Error,
    },
    /// The file is not a checkpoint, or it is damaged.
    #[error("{} is not a usable checkpoint: {why}", path.display())]
    Damaged {
        /// The file.
        path: PathBuf,
        /// What is wrong, in a few words.
        why: String,
    },
    /// A section's content does not fit what reads it (a node of another shape).
    #[error("checkpoint section '{section}': {why}")]
    Section {
        /// The section.
        section: String,
        /// What is wrong.
        why: String,
    },
}

impl Checkpoint {
    /// The section called `name`.
    pub fn section(&self, name: &str) -> Option<&[u8]> {
        self.sections.iter().find(|(n, _)| n == name).map(|(_, b)| b.as_slice())
    }

    /// The file's bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let header = ron::to_string(&self.header).expect("a header serialises");
        let body: usize = self.sections.iter().map(|(n, b)| n.len() + b.len() + 10).sum();
        let mut out = Vec::with_capacity(MAGIC.len() + header.len() + body + 40);
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&(header.len() as u32).to_le_bytes());
        out.extend_from_slice(header.as_bytes());
        out.extend_from_slice(&(self.sections.len() as u32).to_le_bytes());
        for (name, bytes) in &self.sections {
            out.extend_from_slice(&(name.len() as u16).to_le_bytes());
            out.extend_from_slice(name.as_bytes());
            out.extend_from_slice(&(bytes.len() as u64).to_le_bytes());
            out.extend_from_slice(bytes);
        }
        let digest = Sha256::digest(&out);
        out.extend_from_slice(&digest);
        out
    }

    /// Writes the checkpoint to `path` atomically (a reader sees the old file or the new one).
    pub fn write(&self, path: &Path) -> Result<u64, CheckpointError> {
        let bytes = self.to_bytes();
        if bytes.len() as u64 > MAX_FILE {
            let why = format!("it would be {} bytes, more than a checkpoint may be ({MAX_FILE})", bytes.len());
            return Err(CheckpointError::Section { section: "(all)".into(), why });
        }
        crate::atomic_file::write(path, &bytes)
            .map_err(|source| CheckpointError::Io { path: path.to_path_buf(), source })?;
        Ok(bytes.len() as u64)
    }

    /// Reads the header of the checkpoint at `path` only (choosing a checkpoint reads no state).
    pub fn read_header(path: &Path) -> Result<Header, CheckpointError> {
        use std::io::Read;
        let io = |source| CheckpointError::Io { path: path.to_path_buf(), source };
        let mut file = std::fs::File::open(path).map_err(io)?;
        let mut start = [0u8; MAGIC.len() + 4];
        file.read_exact(&mut start).map_err(|_| damaged(path, "too short"))?;
        let len = header_length(path, &start)?;
        let mut header = vec![0u8; len];
        file.read_exact(&mut header).map_err(|_| damaged(path, "cut off in its header"))?;
        parse_header(path, &header)
    }

    /// Reads and checks the checkpoint at `path` (at most [`MAX_FILE`] bytes).
    pub fn read(path: &Path) -> Result<Self, CheckpointError> {
        use std::io::Read;
        let io = |source| CheckpointError::Io { path: path.to_path_buf(), source };
        let file = std::fs::File::open(path).map_err(io)?;
        let len = file.metadata().map_err(io)?.len();
        if len > MAX_FILE {
            return Err(damaged(path, &format!("it is {len} bytes, more than a checkpoint may be ({MAX_FILE})")));
        }
        let mut bytes = Vec::with_capacity(len as usize);
        file.take(MAX_FILE + 1).read_to_end(&mut bytes).map_err(io)?;
        Self::from_bytes(path, &bytes)
    }

    /// Parses a checkpoint's bytes (`path` names it in errors).
    pub fn from_bytes(path: &Path, bytes: &[u8]) -> Result<Self, CheckpointError> {
        if bytes.len() < MAGIC.len() + 4 + 4 + 32 {
            return Err(damaged(path, "too short"));
        }
        let (body, digest) = bytes.split_at(bytes.len() - 32);
        let mut reader = Reader { path, bytes: body, at: 0 };
        let start = reader.take(MAGIC.len() + 4)?;
        let header_len = header_length(path, start)?;
        // The checksum is checked once the file is known to be a checkpoint at all.
        if Sha256::digest(body).as_slice() != digest {
            return Err(damaged(path, "its checksum does not match (the file was cut short or changed)"));
        }
        let header = parse_header(path, reader.take(header_len)?)?;
        let count = reader.u32()?;
        if count > MAX_SECTIONS {
            return Err(damaged(path, &format!("it claims {count} sections")));
        }
        let mut sections = Vec::with_capacity(count.min(1024) as usize);
        for _ in 0..count {
            let name_len = u16::from_le_bytes(reader.take(2)?.try_into().expect("2 bytes"));
            if name_len > MAX_NAME {
                return Err(damaged(path, "a section name is too long"));
            }
            let name = std::str::from_utf8(reader.take(usize::from(name_len))?)
                .map_err(|_| damaged(path, "a section name is not UTF-8"))?
                .to_string();
            let len = u64::from_le_bytes(reader.take(8)?.try_into().expect("8 bytes"));
            let len = usize::try_from(len).map_err(|_| damaged(path, "a section is too large"))?;
            sections.push((name, reader.take(len)?.to_vec()));
        }
        if reader.at != body.len() {
            return Err(damaged(path, "bytes follow its last section"));
        }
        Ok(Self { header, sections })
    }
}

/// The header's length from the magic and length bytes, checked.
fn header_length(path: &Path, start: &[u8]) -> Result<usize, CheckpointError> {
    if &start[..MAGIC.len()] != MAGIC {
        return Err(damaged(path, "it does not start as an indra checkpoint does"));
    }
    let len = u32::from_le_bytes(start[MAGIC.len()..].try_into().expect("4 bytes"));
    if len > MAX_HEADER {
        return Err(damaged(path, "its header is too long"));
    }
    Ok(len as usize)
}

fn parse_header(path: &Path, bytes: &[u8]) -> Result<Header, CheckpointError> {
    let text = std::str::from_utf8(bytes).map_err(|_| damaged(path, "its header is not UTF-8"))?;
    ron::from_str(text).map_err(|e| damaged(path, &format!("its header does not parse ({e})")))
}

fn damaged(path: &Path, why: &str) -> CheckpointError {
    CheckpointError::Damaged { path: path.to_path_buf(), why: why.to_string() }
}

/// Reads a checkpoint's body, every length checked against what is left.
struct Reader<'a> {
    path: &'a Path,
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], CheckpointError> {
        let end =
            self.at.checked_add(n).filter(|&e| e <= self.bytes.len()).ok_or_else(|| damaged(self.path, "cut off"))?;
        let out = &self.bytes[self.at..end];
        self.at = end;
        Ok(out)
    }

    fn u32(&mut self) -> Result<u32, CheckpointError> {
        Ok(u32::from_le_bytes(self.take(4)?.try_into().expect("4 bytes")))
    }
}

/// SHA-256 of `bytes`, as lowercase hex (the manifest's and the header's hashes).
pub fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes).iter().map(|b| format!("{b:02x}")).collect()
}

#[cfg(test)]
mod tests;
