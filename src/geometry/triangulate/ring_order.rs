//! Where nodes stand in the merged ring while holes are bridged, for breaking ties as earcut
//! does. Earcut's bridge searches visit the ring's edges in ring order from the outer ring's
//! first node and keep the first of equal candidates; the band index visits them in another
//! order. Equal candidates are points shared by several rings (touching holes, crossing
//! input): which copy of a point a hole bridges to changes nothing on valid input, but on
//! crossing input it changes the ears cut later, and then the area covered.
//!
//! Labels (increasing in ring order) are made the first time a tie needs them, with one walk
//! round the ring; each hole bridged after that gets labels between those of the nodes it was
//! spliced between, and the ring is labelled afresh when a gap runs out.

use super::linked::Rings;

/// A candidate of a bridge search: the edge (its start node) where the search met it, and the
/// node it stands for.
pub(super) type Candidate = (u32, u32);

/// Ring order of the merged ring's nodes.
#[derive(Default)]
pub(super) struct RingOrder {
    /// The outer ring's first node, where earcut's scans begin (a later live node once it is
    /// removed).
    head: u32,
    /// Per node: its place in ring order from `head` (empty until first needed).
    labels: Vec<u64>,
    /// Scratch lists for the searches.
    pub hits: Vec<Candidate>,
    pub crossings: Vec<Candidate>,
    pub group: Vec<u32>,
}

impl RingOrder {
    /// Starts over on a new outer ring whose scans begin at `head`.
    pub fn reset(&mut self, head: u32) {
        self.head = head;
        self.labels.clear();
    }

    /// The first live node at or after the head (removed nodes keep their links, as earcut's
    /// scan follows them).
    pub fn live_head(&mut self, rings: &Rings) -> u32 {
        let mut steps = rings.nodes.len();
        while !rings.alive(self.head) && steps > 0 {
            self.head = rings.next(self.head);
            steps -= 1;
        }
        self.head
    }

    /// The node earcut's scan would take: that of the candidate met first in ring order. Two
    /// edges that meet are told apart without labels (the edge into their shared node comes
    /// first, unless that node is the head).
    pub fn first(&mut self, rings: &Rings, candidates: &[Candidate]) -> u32 {
        let (edge, node) = candidates[0];
        if candidates.iter().all(|&(_, n)| n == node) {
            return node;
        }
        if let Some(&(other, other_node)) = candidates.iter().find(|&&(e, _)| e != edge)
            && candidates.iter().all(|&(e, _)| e == edge || e == other)
        {
            let head = self.live_head(rings);
            if rings.next(edge) == other && other != head {
                return node;
            }
            if rings.next(other) == edge && edge != head {
                return other_node;
            }
        }
        self.ensure_labels(rings);
        candidates.iter().min_by_key(|&&(e, _)| self.labels[e as usize]).map_or(node, |&(_, n)| n)
    }

    /// Sorts nodes into ring order.
    pub fn sort(&mut self, rings: &Rings, nodes: &mut [u32]) {
        self.ensure_labels(rings);
        nodes.sort_unstable_by_key(|&p| self.labels[p as usize]);
    }

    /// Gives the nodes spliced in after `bridge` (up to `after`, its neighbour before the
    /// splice) labels between theirs, once labels exist.
    pub fn spliced(&mut self, rings: &Rings, bridge: u32, after: u32) {
        if self.labels.is_empty() {
            return;
        }
        self.labels.resize(rings.nodes.len(), 0);
        let mut count = 0u64;
        let mut p = rings.next(bridge);
        while p != after {
            count += 1;
            p = rings.next(p);
        }
        let low = self.labels[bridge as usize];
        // Spliced in after the last node in ring order: up to the end of the label range.
        let high = Some(self.labels[after as usize]).filter(|&high| high > low).unwrap_or(u64::MAX);
        let step = high.saturating_sub(low) / (count + 1);
        if step == 0 {
            self.label_ring(rings);
            return;
        }
        let mut p = rings.next(bridge);
        for k in 1..=count {
            self.labels[p as usize] = low + k * step;
            p = rings.next(p);
        }
    }

    fn ensure_labels(&mut self, rings: &Rings) {
        if self.labels.is_empty() {
            self.label_ring(rings);
        }
    }

    /// Labels the ring from the live head, spread over the whole range.
    fn label_ring(&mut self, rings: &Rings) {
        self.labels.clear();
        self.labels.resize(rings.nodes.len(), 0);
        let head = self.live_head(rings);
        let step = u64::MAX / (rings.nodes.len() as u64 + 2);
        let mut label = step;
        rings.for_each_node(head, |p| {
            self.labels[p as usize] = label;
            label += step;
        });
    }
}
