//! Per-pass GPU timing with timestamp queries. Results are read a few frames late (never
//! stalling the frame) and shown as rolling medians.

use std::collections::{BTreeMap, VecDeque};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// The median of the last `capacity` samples.
#[derive(Clone, Debug)]
pub struct RollingMedian {
    samples: VecDeque<f64>,
    capacity: usize,
}

impl RollingMedian {
    /// Keeps the last `capacity` samples.
    pub fn new(capacity: usize) -> Self {
        Self { samples: VecDeque::with_capacity(capacity), capacity: capacity.max(1) }
    }

    /// Adds a sample, forgetting the oldest past capacity.
    pub fn push(&mut self, value: f64) {
        if self.samples.len() == self.capacity {
            self.samples.pop_front();
        }
        self.samples.push_back(value);
    }

    /// The median, or `None` before the first sample.
    pub fn median(&self) -> Option<f64> {
        let mut sorted: Vec<f64> = self.samples.iter().copied().collect();
        if sorted.is_empty() {
            return None;
        }
        sorted.sort_by(f64::total_cmp);
        let mid = sorted.len() / 2;
        Some(if sorted.len().is_multiple_of(2) { (sorted[mid - 1] + sorted[mid]) / 2.0 } else { sorted[mid] })
    }

    /// Number of samples held.
    pub fn len(&self) -> usize {
        self.samples.len()
    }

    /// Whether no sample is held.
    pub fn is_empty(&self) -> bool {
        self.samples.is_empty()
    }
}

/// One pass's timing, as shown in the UI and printed by `indra bench`.
#[derive(Clone, Debug, PartialEq)]
pub struct PassTiming {
    /// Pass name (`<technique>/<pass>`).
    pub name: String,
    /// Rolling median of its GPU time, milliseconds.
    pub median_ms: f64,
    /// Samples behind the median.
    pub samples: usize,
}

const MAX_PASSES: u32 = 256;
const IN_FLIGHT: usize = 3;
const WINDOW: usize = 120;

struct Slot {
    buffer: wgpu::Buffer,
    ready: Arc<AtomicBool>,
    names: Vec<String>,
    busy: bool,
}

/// Records a timestamp before and after each pass and collects the results asynchronously.
pub(crate) struct GpuTimer {
    queries: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    slots: Vec<Slot>,
    next: usize,
    period_ns: f64,
    medians: BTreeMap<String, RollingMedian>,
    frame_total: RollingMedian,
    /// Per frame, the first pass's start to the last pass's end: the passes' time and the GPU's
    /// gaps between them.
    frame_span: RollingMedian,
    /// The slot of the latest frame read back (its names stay until it is reused), and its
    /// passes' milliseconds: kept without copying names, as every frame reads one back.
    latest: Option<usize>,
    latest_ms: Vec<f64>,
    current: Option<usize>,
}

impl GpuTimer {
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue) -> Self {
        let bytes = u64::from(MAX_PASSES) * 2 * 8;
        let queries = device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("graph_timestamps"),
            ty: wgpu::QueryType::Timestamp,
            count: MAX_PASSES * 2,
        });
        let resolve = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("graph_timestamp_resolve"),
            size: bytes,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let slots = (0..IN_FLIGHT)
            .map(|_| Slot {
                buffer: device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("graph_timestamp_readback"),
                    size: bytes,
                    usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                }),
                ready: Arc::new(AtomicBool::new(false)),
                names: Vec::new(),
                busy: false,
            })
            .collect();
        Self {
            queries,
            resolve,
            slots,
            next: 0,
            period_ns: f64::from(queue.get_timestamp_period()),
            medians: BTreeMap::new(),
            frame_total: RollingMedian::new(WINDOW),
            frame_span: RollingMedian::new(WINDOW),
            latest: None,
            latest_ms: Vec::new(),
            current: None,
        }
    }

    /// Starts a frame's timing if a readback slot is free (otherwise this frame is not timed).
    pub fn begin_frame(&mut self) -> bool {
        self.collect();
        let free = !self.slots[self.next].busy;
        self.current = free.then_some(self.next);
        if let Some(s) = self.current {
            self.slots[s].names.clear();
            if self.latest == Some(s) {
                self.latest = None;
            }
        }
        free
    }

    /// Writes the timestamp before pass number `index` of this frame.
    pub fn begin_pass(&mut self, encoder: &mut wgpu::CommandEncoder, index: usize, name: &str) {
        if let Some(s) = self.current.filter(|_| (index as u32) < MAX_PASSES) {
            encoder.write_timestamp(&self.queries, index as u32 * 2);
            self.slots[s].names.push(name.to_string());
        }
    }

    /// Writes the timestamp after pass number `index`.
    pub fn end_pass(&mut self, encoder: &mut wgpu::CommandEncoder, index: usize) {
        if self.current.is_some() && (index as u32) < MAX_PASSES {
            encoder.write_timestamp(&self.queries, index as u32 * 2 + 1);
        }
    }

    /// Resolves this frame's queries into its readback slot.
    pub fn end_frame(&mut self, encoder: &mut wgpu::CommandEncoder) {
        let Some(s) = self.current else { return };
        let count = self.slots[s].names.len() as u32 * 2;
        if count == 0 {
            self.current = None;
            return;
        }
        encoder.resolve_query_set(&self.queries, 0..count, &self.resolve, 0);
        encoder.copy_buffer_to_buffer(&self.resolve, 0, &self.slots[s].buffer, 0, u64::from(count) * 8);
    }

    /// After submit: starts mapping this frame's slot; its results are read in a later frame.
    pub fn after_submit(&mut self) {
        let Some(s) = self.current.take() else { return };
        let slot = &mut self.slots[s];
        slot.busy = true;
        slot.ready.store(false, Ordering::Release);
        let ready = slot.ready.clone();
        slot.buffer.slice(..).map_async(wgpu::MapMode::Read, move |r| {
            if r.is_ok() {
                ready.store(true, Ordering::Release);
            }
        });
        self.next = (self.next + 1) % self.slots.len();
    }

    /// Reads every slot whose mapping has completed.
    fn collect(&mut self) {
        for (index, slot) in self.slots.iter_mut().enumerate() {
            if !slot.busy || !slot.ready.load(Ordering::Acquire) {
                continue;
            }
            let bytes = slot.names.len() * 16;
            let stamps: Vec<u64> = match slot.buffer.slice(..bytes as u64).get_mapped_range() {
                Ok(view) => bytemuck::cast_slice(&view).to_vec(),
                Err(_) => Vec::new(),
            };
            slot.buffer.unmap();
            slot.busy = false;
            let mut total = 0.0;
            self.latest = Some(index);
            self.latest_ms.clear();
            for (i, name) in slot.names.iter().enumerate().take(stamps.len() / 2) {
                let ms = stamps[2 * i + 1].wrapping_sub(stamps[2 * i]) as f64 * self.period_ns / 1e6;
                total += ms;
                self.medians.entry(name.clone()).or_insert_with(|| RollingMedian::new(WINDOW)).push(ms);
                self.latest_ms.push(ms);
            }
            self.frame_total.push(total);
            let passes = stamps.len() / 2;
            if passes > 0 {
                let (first, last) = (stamps[0], stamps[2 * passes - 1]);
                self.frame_span.push(last.wrapping_sub(first) as f64 * self.period_ns / 1e6);
            }
        }
    }

    /// Current medians, in pass-name order.
    pub fn timings(&self) -> Vec<PassTiming> {
        self.medians
            .iter()
            .filter_map(|(name, m)| {
                m.median().map(|median_ms| PassTiming { name: name.clone(), median_ms, samples: m.len() })
            })
            .collect()
    }

    /// The passes of the latest frame read back and their milliseconds, in the order they ran.
    pub fn latest_frame(&self) -> Vec<(String, f64)> {
        let Some(slot) = self.latest else { return Vec::new() };
        self.slots[slot].names.iter().cloned().zip(self.latest_ms.iter().copied()).collect()
    }

    /// Median of the summed pass times per frame, milliseconds.
    pub fn frame_median_ms(&self) -> Option<f64> {
        self.frame_total.median()
    }

    /// Median of the span from the first pass's start to the last pass's end, milliseconds.
    pub fn frame_span_median_ms(&self) -> Option<f64> {
        self.frame_span.median()
    }

    /// Forgets every sample so far (a benchmark starts measuring after its seek and warm-up).
    pub fn reset(&mut self) {
        self.medians.clear();
        self.frame_total = RollingMedian::new(WINDOW);
        self.frame_span = RollingMedian::new(WINDOW);
    }

    /// Blocks until every in-flight slot is read (for `indra bench` at the end of a run).
    pub fn drain(&mut self, device: &wgpu::Device) {
        let _ = device.poll(wgpu::PollType::wait_indefinitely());
        self.collect();
    }
}

#[cfg(test)]
mod tests {
    use super::RollingMedian;

    #[test]
    fn rolling_median_forgets_old_samples() {
        let mut m = RollingMedian::new(3);
        assert_eq!(m.median(), None);
        for v in [10.0, 1.0, 2.0] {
            m.push(v);
        }
        assert_eq!(m.median(), Some(2.0));
        m.push(3.0); // drops 10
        assert_eq!(m.median(), Some(2.0));
        m.push(4.0); // drops 1 → [2, 3, 4]
        assert_eq!(m.median(), Some(3.0));
        let mut even = RollingMedian::new(4);
        for v in [1.0, 2.0, 3.0, 10.0] {
            even.push(v);
        }
        assert_eq!(even.median(), Some(2.5));
    }
}
