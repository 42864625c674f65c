//! One node's part of a checkpoint: named byte blobs (GPU buffers read back, CPU state), with
//! typed reads that check each blob's size against what the node expects.

use super::{Checkpoint, CheckpointError};

/// A node's state in a checkpoint, as named blobs.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NodeState {
    /// Whose state this is (the section prefix), for errors.
    owner: String,
    blobs: Vec<(String, Vec<u8>)>,
}

impl NodeState {
    /// An empty state for the node whose sections are named `owner/…`.
    pub fn new(owner: &str) -> Self {
        Self { owner: owner.to_string(), blobs: Vec::new() }
    }

    /// Whether the node saved nothing (it has no state of its own).
    pub fn is_empty(&self) -> bool {
        self.blobs.is_empty()
    }

    /// Adds a blob.
    pub fn put(&mut self, name: &str, bytes: Vec<u8>) {
        self.blobs.push((name.to_string(), bytes));
    }

    /// Adds plain values as their bytes.
    pub fn put_pod<T: bytemuck::Pod>(&mut self, name: &str, values: &[T]) {
        self.put(name, bytemuck::cast_slice(values).to_vec());
    }

    /// Adds a value that may be absent (an empty blob for none).
    pub fn put_option<T: bytemuck::Pod>(&mut self, name: &str, value: Option<T>) {
        self.put_pod(name, value.as_slice());
    }

    /// Adds one number.
    pub fn put_u64(&mut self, name: &str, value: u64) {
        self.put(name, value.to_le_bytes().to_vec());
    }

    /// The blob `name`.
    pub fn get(&self, name: &str) -> Result<&[u8], CheckpointError> {
        self.blobs
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, b)| b.as_slice())
            .ok_or_else(|| self.error(name, "missing (the checkpoint was made by a node of another kind)".into()))
    }

    /// The blob `name`, which must be `len` bytes long.
    pub fn get_exact(&self, name: &str, len: u64) -> Result<&[u8], CheckpointError> {
        let bytes = self.get(name)?;
        if bytes.len() as u64 != len {
            return Err(self.error(name, format!("holds {} bytes where this node has {len}", bytes.len())));
        }
        Ok(bytes)
    }

    /// The blob `name` as plain values (copied: blobs are not aligned).
    pub fn get_pod<T: bytemuck::Pod>(&self, name: &str) -> Result<Vec<T>, CheckpointError> {
        let bytes = self.get(name)?;
        if !bytes.len().is_multiple_of(size_of::<T>().max(1)) {
            return Err(self.error(name, format!("{} bytes is not a whole number of values", bytes.len())));
        }
        Ok(bytemuck::pod_collect_to_vec(bytes))
    }

    /// The value [`NodeState::put_option`] wrote as `name`.
    pub fn get_option<T: bytemuck::Pod>(&self, name: &str) -> Result<Option<T>, CheckpointError> {
        match self.get_pod::<T>(name)?[..] {
            [] => Ok(None),
            [value] => Ok(Some(value)),
            ref more => Err(self.error(name, format!("holds {} values where this node keeps one", more.len()))),
        }
    }

    /// The number `name`.
    pub fn get_u64(&self, name: &str) -> Result<u64, CheckpointError> {
        let bytes = self.get_exact(name, 8)?;
        Ok(u64::from_le_bytes(bytes.try_into().expect("8 bytes")))
    }

    /// An error about blob `name` of this node.
    pub fn error(&self, name: &str, why: String) -> CheckpointError {
        CheckpointError::Section { section: format!("{}/{name}", self.owner), why }
    }

    /// The blobs as checkpoint sections (`owner/name`).
    pub fn into_sections(self) -> impl Iterator<Item = (String, Vec<u8>)> {
        let owner = self.owner;
        self.blobs.into_iter().map(move |(name, bytes)| (format!("{owner}/{name}"), bytes))
    }

    /// The state of `owner` in `checkpoint` (empty when it saved none).
    pub fn from_checkpoint(owner: &str, checkpoint: &Checkpoint) -> Self {
        let prefix = format!("{owner}/");
        let blobs = checkpoint
            .sections
            .iter()
            .filter_map(|(n, b)| n.strip_prefix(&prefix).map(|rest| (rest.to_string(), b.clone())))
            .collect();
        Self { owner: owner.to_string(), blobs }
    }
}
