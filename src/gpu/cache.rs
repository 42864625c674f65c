//! Bind groups (or any GPU object made from resources) cached by a key of what they bind —
//! resource ids, slots, buffer roles — and evicted once unused for a number of frames. Steady
//! frames create nothing; after a resize the groups that held the old pool textures age out
//! instead of keeping those textures alive.

use std::collections::HashMap;
use std::hash::Hash;

/// Frames an entry may go unused before it is dropped.
pub const DEFAULT_MAX_AGE: u64 = 120;

/// Values by key, each remembering the frame it was last used in.
pub struct BindGroupCache<K, V = wgpu::BindGroup> {
    entries: HashMap<K, (V, u64)>,
    frame: u64,
    max_age: u64,
}

impl<K: Hash + Eq, V> BindGroupCache<K, V> {
    /// An empty cache dropping entries unused for more than `max_age` frames.
    pub fn new(max_age: u64) -> Self {
        Self { entries: HashMap::new(), frame: 0, max_age }
    }

    /// Starts a frame: drops what the last `max_age` frames did not use. Call once per frame,
    /// before any lookup.
    pub fn begin_frame(&mut self) {
        self.frame += 1;
        let (frame, max_age) = (self.frame, self.max_age);
        self.entries.retain(|_, (_, used)| frame - *used <= max_age);
    }

    /// The entry for `key`, made by `create` if there is none; marks it used this frame.
    pub fn get_or_create(&mut self, key: K, create: impl FnOnce() -> V) -> &V {
        let frame = self.frame;
        let entry = self.entries.entry(key).or_insert_with(|| (create(), frame));
        entry.1 = frame;
        &entry.0
    }

    /// The entry for `key`, if one was made (no mark).
    pub fn get(&self, key: &K) -> Option<&V> {
        self.entries.get(key).map(|(v, _)| v)
    }

    /// Number of entries.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }
}

/// `cache[&key]`: the entry made for `key` earlier this frame.
///
/// # Panics
/// If none was made: bind groups are made while a frame is planned, before passes bind them.
impl<K: Hash + Eq, V> std::ops::Index<&K> for BindGroupCache<K, V> {
    type Output = V;

    fn index(&self, key: &K) -> &V {
        self.get(key).expect("a bind group is made (get_or_create) before a pass binds it")
    }
}

impl<K: Hash + Eq, V> Default for BindGroupCache<K, V> {
    fn default() -> Self {
        Self::new(DEFAULT_MAX_AGE)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steady_frames_create_nothing_and_unused_entries_age_out() {
        let mut cache: BindGroupCache<u64, u32> = BindGroupCache::new(2);
        let mut made = 0;
        for _ in 0..10 {
            cache.begin_frame();
            cache.get_or_create(7, || {
                made += 1;
                7
            });
        }
        assert_eq!(made, 1, "a key used every frame is made once");
        cache.get_or_create(8, || 8); // used once, in frame 10
        for frame in 11..=13 {
            cache.begin_frame();
            cache.get_or_create(7, || 7);
            assert_eq!(cache.get(&8).is_some(), frame - 10 <= 2, "frame {frame}");
        }
        assert_eq!(cache.len(), 1);
    }
}
