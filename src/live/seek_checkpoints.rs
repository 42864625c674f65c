//! Checkpoints kept in memory by the seeks of a show chasing timecode, so that a jump deep into
//! a long show does not step from frame 0 each time: a seek stops on its way at every
//! `spacing`-th frame to keep the state there, and the next seek starts from the latest one at
//! or before where the code is. They hold the rehearsed timeline (a seek never carries live
//! moves), for one scene, size, step and seed at a time; a reload or a new size starts over.
//!
//! Bounded in bytes: when the next one would not fit, every other one goes and the spacing
//! doubles, so the store covers the whole show at a coarser grain rather than its start
//! finely.

use std::sync::{Arc, Mutex};

use crate::checkpoint::{Checkpoint, Header};

/// The most bytes kept (a 1024² cloth's state is about 50 MiB: ten of those).
pub const MAX_BYTES: u64 = 512 << 20;
/// Frames between checkpoints at first: 10 s at 60 steps a second.
pub const FIRST_SPACING: u64 = 600;

/// What checkpoints must share to serve one another's seeks.
#[derive(Clone, Debug, PartialEq)]
struct Key {
    scene_hash: String,
    size: (u32, u32),
    dt_bits: u32,
    seed: u64,
    adapter: String,
}

impl Key {
    fn of(header: &Header) -> Self {
        Key {
            scene_hash: header.scene_hash.clone(),
            size: header.size,
            dt_bits: header.dt_bits,
            seed: header.seed,
            adapter: format!("{} {}", header.adapter, header.driver),
        }
    }
}

#[derive(Debug)]
struct Store {
    key: Option<Key>,
    /// By frame, ascending.
    kept: Vec<Arc<Checkpoint>>,
    bytes: u64,
    spacing: u64,
    first_spacing: u64,
}

/// The checkpoints of a window's seeks, shared with their threads.
#[derive(Clone, Debug)]
pub struct SeekCheckpoints {
    store: Arc<Mutex<Store>>,
    max_bytes: u64,
}

impl Default for SeekCheckpoints {
    fn default() -> Self {
        Self::new(FIRST_SPACING, MAX_BYTES)
    }
}

/// The bytes a checkpoint holds.
fn bytes_of(checkpoint: &Checkpoint) -> u64 {
    checkpoint.sections.iter().map(|(name, bytes)| (name.len() + bytes.len()) as u64).sum()
}

impl SeekCheckpoints {
    /// A store that keeps a checkpoint every `spacing` frames at first, up to `max_bytes`.
    pub fn new(spacing: u64, max_bytes: u64) -> Self {
        let store = Store { key: None, kept: Vec::new(), bytes: 0, spacing, first_spacing: spacing.max(1) };
        SeekCheckpoints { store: Arc::new(Mutex::new(store)), max_bytes }
    }

    /// The latest checkpoint at or before `frame` for a seek pinned as `header` says (its frame
    /// aside).
    pub fn nearest(&self, header: &Header, frame: u64) -> Option<Arc<Checkpoint>> {
        let store = self.store.lock().ok()?;
        if store.key.as_ref() != Some(&Key::of(header)) {
            return None;
        }
        store.kept.iter().rev().find(|c| c.header.frame <= frame).cloned()
    }

    /// The next frame after `frame` at which a seek pinned as `header` says should stop to keep
    /// a checkpoint (one the store does not hold yet).
    pub fn next_stop(&self, header: &Header, frame: u64) -> u64 {
        let Ok(store) = self.store.lock() else { return u64::MAX };
        let spacing = if store.key.as_ref() == Some(&Key::of(header)) { store.spacing } else { store.first_spacing };
        let mut stop = (frame / spacing + 1) * spacing;
        while store.key.as_ref() == Some(&Key::of(header)) && store.kept.iter().any(|c| c.header.frame == stop) {
            stop += spacing;
        }
        stop
    }

    /// Keeps `checkpoint` (a seek stopped at [`SeekCheckpoints::next_stop`]): another scene's
    /// are dropped first, and every other one goes (the spacing doubling) while it would not
    /// fit. One larger than a quarter of the store is not kept.
    pub fn keep(&self, checkpoint: Checkpoint) {
        let Ok(mut store) = self.store.lock() else { return };
        let bytes = bytes_of(&checkpoint);
        if bytes > self.max_bytes / 4 {
            return;
        }
        let key = Key::of(&checkpoint.header);
        if store.key.as_ref() != Some(&key) {
            (store.key, store.kept, store.bytes, store.spacing) = (Some(key), Vec::new(), 0, store.first_spacing);
        }
        while store.bytes + bytes > self.max_bytes {
            store.spacing *= 2;
            let spacing = store.spacing;
            store.kept.retain(|c| c.header.frame.is_multiple_of(spacing));
            store.bytes = store.kept.iter().map(|c| bytes_of(c)).sum();
        }
        if !checkpoint.header.frame.is_multiple_of(store.spacing) {
            return;
        }
        let at = store.kept.partition_point(|c| c.header.frame < checkpoint.header.frame);
        if store.kept.get(at).is_some_and(|c| c.header.frame == checkpoint.header.frame) {
            return;
        }
        store.bytes += bytes;
        store.kept.insert(at, Arc::new(checkpoint));
    }

    /// Drops every checkpoint (one could not be taken: the next seek starts from frame 0).
    pub fn forget(&self) {
        if let Ok(mut store) = self.store.lock() {
            (store.key, store.kept, store.bytes) = (None, Vec::new(), 0);
        }
    }

    /// The frames held, and their bytes (the status line, tests).
    pub fn held(&self) -> (Vec<u64>, u64) {
        self.store.lock().map(|s| (s.kept.iter().map(|c| c.header.frame).collect(), s.bytes)).unwrap_or_default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn checkpoint(scene: &str, frame: u64, bytes: usize) -> Checkpoint {
        let header = Header {
            format: crate::checkpoint::FORMAT,
            indra: "test".into(),
            scene: scene.into(),
            scene_hash: scene.into(),
            controls_hash: String::new(),
            adapter: "a".into(),
            driver: "d".into(),
            frame,
            size: (32, 32),
            dt_bits: 1,
            seed: 0,
        };
        Checkpoint { header, sections: vec![(String::new(), vec![0; bytes])] }
    }

    #[test]
    fn seeks_start_from_the_latest_checkpoint_before_them_and_the_store_thins_to_fit() {
        let store = SeekCheckpoints::new(10, 400);
        let header = checkpoint("a", 0, 0).header;
        assert_eq!(store.next_stop(&header, 0), 10);
        assert!(store.nearest(&header, 1000).is_none());
        for frame in [10, 20, 30, 40] {
            assert_eq!(store.next_stop(&header, frame - 10), frame);
            store.keep(checkpoint("a", frame, 100));
        }
        assert_eq!(store.held(), (vec![10, 20, 30, 40], 400));
        assert_eq!(store.nearest(&header, 35).unwrap().header.frame, 30);
        assert_eq!(store.nearest(&header, 9), None);
        // Full: the fifth thins them to every 20th frame, a grid it is not on.
        store.keep(checkpoint("a", 50, 100));
        assert_eq!(store.held().0, vec![20, 40]);
        assert_eq!(store.next_stop(&header, 40), 60);
        store.keep(checkpoint("a", 60, 100));
        assert_eq!(store.held(), (vec![20, 40, 60], 300));
        // Stops skip what is held.
        assert_eq!(store.next_stop(&header, 0), 80);
        // Too large for the store: not kept.
        store.keep(checkpoint("a", 80, 101));
        assert_eq!(store.held().0, vec![20, 40, 60]);
        // Another scene (a reload) starts over.
        let other = checkpoint("b", 0, 0).header;
        assert!(store.nearest(&other, 100).is_none());
        assert_eq!(store.next_stop(&other, 0), 10);
        store.keep(checkpoint("b", 10, 100));
        assert_eq!(store.held(), (vec![10], 100));
        assert!(store.nearest(&header, 100).is_none());
    }
}
