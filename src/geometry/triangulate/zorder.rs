//! Morton (z-order) codes of positions quantised to a 15-bit grid, and BIGMIN (Tropf & Herzog,
//! "Multidimensional range search in dynamically balanced trees", 1981): the smallest code
//! inside a query box that is greater than a given code. With it a walk over z-sorted points
//! jumps over the stretches of the box's code range that lie outside the box, which for long
//! thin boxes (the ears of a star's spikes) is nearly all of it.

/// Quantisation of positions to the 15-bit grid the Morton codes are built on.
#[derive(Clone, Copy, Debug)]
pub(super) struct ZHash {
    pub min_x: f64,
    pub min_y: f64,
    /// 32767 / the larger side of the bounding box (0 for a box of no size).
    pub inv_size: f64,
}

impl ZHash {
    /// The hash for points in the box from `min` to `max`.
    pub fn new(min: [f64; 2], max: [f64; 2]) -> Self {
        let size = (max[0] - min[0]).max(max[1] - min[1]);
        Self { min_x: min[0], min_y: min[1], inv_size: if size > 0.0 { 32767.0 / size } else { 0.0 } }
    }

    /// The aligned cell of 2^k × 2^k grid steps that holds code `z`, as the box of positions
    /// whose codes fall in it (widened by one grid step each way against rounding), and the last
    /// code of the cell. `None` for a cell on the grid's border, where positions from outside the
    /// box are clamped to, and for a hash of no size.
    #[inline]
    pub fn cell(&self, z: u32, k: u32) -> Option<([f64; 2], [f64; 2], u32)> {
        let side = 1u32 << k;
        let (qx, qy) = (compact(z) & !(side - 1), compact(z >> 1) & !(side - 1));
        if self.inv_size == 0.0 || qx == 0 || qy == 0 || qx + side > 32767 || qy + side > 32767 {
            return None;
        }
        let step = 1.0 / self.inv_size;
        let at = |q: u32, min: f64| min + f64::from(q) * step;
        let lo = [at(qx - 1, self.min_x), at(qy - 1, self.min_y)];
        let hi = [at(qx + side + 1, self.min_x), at(qy + side + 1, self.min_y)];
        Some((lo, hi, z | ((1u32 << (2 * k)) - 1)))
    }

    /// Morton code of a position (clamped, so points outside the box still order monotonically).
    #[inline]
    pub fn z(&self, x: f64, y: f64) -> u32 {
        // `as` takes negatives (and NaN) to 0; only the top needs a clamp.
        let q = |v: f64, min: f64| {
            let scaled = (v - min) * self.inv_size;
            (if scaled < 32767.0 { scaled } else { 32767.0 }) as u32
        };
        spread(q(x, self.min_x)) | (spread(q(y, self.min_y)) << 1)
    }
}

/// Nodes sorted by Morton code (the z-order list), with a radix table on the top bits of the code so that finding
/// the first node at or after a code is a short search in one bucket (a binary search over a
/// million nodes costs ~20 cache misses, and a thin ear makes a dozen such jumps).
#[derive(Default)]
pub(super) struct ZIndex {
    /// `code << 32 | node`, sorted by code.
    pub keys: Vec<u64>,
    /// The position of each key's node, in key order: the walk reads these in sequence and
    /// fetches a node (and its neighbours) only for a point inside the ear.
    pub positions: Vec<[f64; 2]>,
    /// Scratch space for sorting keys.
    pub scratch: Vec<u64>,
    /// `skip[i] == i` while key i is on the list; once taken off, a position further on
    /// (union–find with path halving, so runs of removed keys are crossed in near O(1)).
    skip: Vec<u32>,
    /// `buckets[b]` = index of the first key whose code's top bits are ≥ b.
    buckets: Vec<u32>,
    shift: u32,
}

impl ZIndex {
    /// Sorts `keys`, gathers their positions (`position_of` a node) and builds the radix table
    /// (about one bucket per key).
    pub fn build(&mut self, position_of: impl Fn(u32) -> [f64; 2]) {
        sort_by_code(&mut self.keys, &mut self.scratch);
        self.positions.clear();
        self.positions.extend(self.keys.iter().map(|&key| position_of(key as u32)));
        self.skip.clear();
        self.skip.extend(0..=self.keys.len() as u32);
        let bits = (usize::BITS - self.keys.len().leading_zeros()).clamp(1, 30);
        self.shift = 30 - bits;
        self.buckets.clear();
        self.buckets.resize((1 << bits) + 1, 0);
        let (keys, shift) = (&self.keys, self.shift);
        let mut at = 0;
        for (bucket, start) in self.buckets.iter_mut().enumerate() {
            while at < keys.len() && ((keys[at] >> 32) as u32 >> shift) < bucket as u32 {
                at += 1;
            }
            *start = at as u32;
        }
    }

    /// The position of the first key whose code is at least `z` (the length if none).
    #[inline]
    pub fn first_at_or_after(&self, z: u32) -> usize {
        let bucket = ((z >> self.shift) as usize).min(self.buckets.len() - 2);
        let (lo, hi) = (self.buckets[bucket] as usize, self.buckets[bucket + 1] as usize);
        lo + self.keys[lo..hi].partition_point(|&key| code(key) < z)
    }

    /// Takes the key at `at` off the list.
    #[inline]
    pub fn remove(&mut self, at: usize) {
        self.skip[at] = at as u32 + 1;
    }

    /// The first position at or after `at` whose key is still on the list (the length if none).
    #[inline]
    pub fn live_from(&mut self, at: usize) -> usize {
        let mut i = at;
        while self.skip[i] as usize != i {
            let next = self.skip[i] as usize;
            self.skip[i] = self.skip[next];
            i = next;
        }
        i
    }
}

/// Sorts `code << 32 | node` keys by code: a byte-wise radix sort above a few hundred keys
/// (codes have 30 bits), a comparison sort below. `scratch` is reused space.
pub(super) fn sort_by_code(keys: &mut [u64], scratch: &mut Vec<u64>) {
    if keys.len() < 512 {
        keys.sort_unstable();
        return;
    }
    let mut counts = [[0u32; 256]; 4];
    for &key in keys.iter() {
        let z = code(key);
        for (byte, count) in counts.iter_mut().enumerate() {
            count[(z >> (8 * byte) & 0xFF) as usize] += 1;
        }
    }
    scratch.clear();
    scratch.resize(keys.len(), 0);
    let mut in_keys = true;
    for (byte, count) in counts.iter().enumerate() {
        // A byte every key shares orders nothing.
        if count.iter().any(|&c| c as usize == keys.len()) {
            continue;
        }
        let mut offsets = [0u32; 256];
        let mut sum = 0;
        for (offset, &c) in offsets.iter_mut().zip(count) {
            *offset = sum;
            sum += c;
        }
        let (from, to): (&[u64], &mut [u64]) =
            if in_keys { (&*keys, scratch.as_mut_slice()) } else { (scratch.as_slice(), &mut *keys) };
        for &key in from {
            let bucket = (code(key) >> (8 * byte) & 0xFF) as usize;
            to[offsets[bucket] as usize] = key;
            offsets[bucket] += 1;
        }
        in_keys = !in_keys;
    }
    if !in_keys {
        keys.copy_from_slice(scratch);
    }
}

/// The code of a key.
#[inline]
pub(super) fn code(key: u64) -> u32 {
    (key >> 32) as u32
}

/// The codes of the lowest and the highest corner of the box around three coded points, from
/// their codes alone: quantising is monotone, and the x bits (even) and the y bits (odd) of a
/// code, masked apart, compare as the coordinates do. So the least x bits of the three are the
/// x bits of the box's least corner: no float is quantised again.
#[inline]
pub(super) fn box_codes(a: u32, b: u32, c: u32) -> (u32, u32) {
    const X: u32 = 0x5555_5555;
    const Y: u32 = !X;
    let least = |m: u32| (a & m).min(b & m).min(c & m);
    let most = |m: u32| (a & m).max(b & m).max(c & m);
    (least(X) | least(Y), most(X) | most(Y))
}

/// Spreads the low 16 bits of `v` to the even bit positions.
#[inline]
fn spread(mut v: u32) -> u32 {
    v &= 0xFFFF;
    v = (v | (v << 8)) & 0x00FF_00FF;
    v = (v | (v << 4)) & 0x0F0F_0F0F;
    v = (v | (v << 2)) & 0x3333_3333;
    (v | (v << 1)) & 0x5555_5555
}

/// Gathers the even bits of `v` into the low 16 bits (the inverse of [`spread`]).
#[inline]
fn compact(mut v: u32) -> u32 {
    v &= 0x5555_5555;
    v = (v | (v >> 1)) & 0x3333_3333;
    v = (v | (v >> 2)) & 0x0F0F_0F0F;
    v = (v | (v >> 4)) & 0x00FF_00FF;
    (v | (v >> 8)) & 0x0000_FFFF
}

/// The bits of one axis (x: even bits, y: odd bits) below `bit`, same axis as `bit`.
#[inline]
fn lower_same_axis(bit: u32) -> u32 {
    (0x5555_5555u32 << (bit & 1)) & ((1u32 << bit) - 1)
}

/// Whether code `z` lies in the box whose corners have codes `min` and `max`.
#[inline]
pub(super) fn in_box(z: u32, min: u32, max: u32) -> bool {
    const X: u32 = 0x5555_5555;
    const Y: u32 = 0xAAAA_AAAA;
    (z & X) >= (min & X) && (z & X) <= (max & X) && (z & Y) >= (min & Y) && (z & Y) <= (max & Y)
}

/// The smallest code greater than `z` inside the box with corner codes `min` ≤ `max`, or `None`
/// when no code of the box is greater; `z` lies between `min` and `max` (as the codes met on a
/// walk through the box's code range do).
pub(super) fn bigmin(z: u32, mut min: u32, mut max: u32) -> Option<u32> {
    let mut best = None;
    // Above the highest bit where the corners differ, every code of the box (and z, which lies
    // between them) has the same bits.
    let top = 31 - (min ^ max).max(1).leading_zeros();
    for bit in (0..=top).rev() {
        let mask = 1u32 << bit;
        let lower = lower_same_axis(bit);
        match (z & mask != 0, min & mask != 0, max & mask != 0) {
            (false, false, true) => {
                // The box straddles this bit: the upper half's first code is a candidate; go on
                // in the lower half.
                best = Some((min | mask) & !lower);
                max = (max & !mask) | lower;
            }
            (false, true, true) => return Some(min),
            (true, false, false) => return best,
            (true, false, true) => min = (min | mask) & !lower,
            // (false, false, false) and (true, true, true): same half, go on. The other two
            // combinations need min > max in this bit, which a box never has.
            _ => {}
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    fn code(x: u32, y: u32) -> u32 {
        spread(x) | (spread(y) << 1)
    }

    #[test]
    fn bigmin_finds_the_next_code_inside_every_box_of_a_small_grid() {
        let side = 16u32;
        let boxes = [(0, 0, 15, 15), (3, 5, 4, 13), (1, 1, 1, 1), (6, 2, 11, 3), (0, 7, 15, 8)];
        for (x0, y0, x1, y1) in boxes {
            let (min, max) = (code(x0, y0), code(x1, y1));
            let mut inside: Vec<u32> = (x0..=x1).flat_map(|x| (y0..=y1).map(move |y| code(x, y))).collect();
            inside.sort_unstable();
            for z in 0..side * side {
                assert_eq!(in_box(z, min, max), inside.binary_search(&z).is_ok(), "in_box({z})");
                if z < min || z > max {
                    continue;
                }
                let expected = inside.iter().copied().find(|&c| c > z);
                assert_eq!(bigmin(z, min, max), expected, "bigmin({z}) in {:?}", (x0, y0, x1, y1));
            }
        }
    }

    #[test]
    fn box_codes_are_the_codes_of_the_box_corners() {
        let hash = ZHash::new([-3.0, 2.0], [1000.0, 700.0]);
        let mut rng = crate::geometry::rng::SplitMix64::new(11);
        for _ in 0..10_000 {
            // Some points beyond the hash's box, where codes clamp.
            let mut point = || [-100.0 + 1200.0 * rng.unit(), -100.0 + 900.0 * rng.unit()];
            let [a, b, c] = [point(), point(), point()];
            let (min, max) = (
                [a[0].min(b[0]).min(c[0]), a[1].min(b[1]).min(c[1])],
                [a[0].max(b[0]).max(c[0]), a[1].max(b[1]).max(c[1])],
            );
            let expected = (hash.z(min[0], min[1]), hash.z(max[0], max[1]));
            assert_eq!(box_codes(hash.z(a[0], a[1]), hash.z(b[0], b[1]), hash.z(c[0], c[1])), expected);
        }
    }

    #[test]
    fn the_index_finds_the_first_code_at_or_after_any_code() {
        let mut index = ZIndex::default();
        let codes: Vec<u32> = (0..500u32).map(|i| i.wrapping_mul(2_654_435_761) >> 2).collect();
        index.keys = codes.iter().enumerate().map(|(node, &z)| (u64::from(z) << 32) | node as u64).collect();
        index.build(|_| [0.0; 2]);
        let mut sorted = codes.clone();
        sorted.sort_unstable();
        for probe in (0..1u32 << 30).step_by(1 << 18).chain(codes.iter().copied()) {
            let expected = sorted.iter().find(|&&z| z >= probe);
            let found = index.keys.get(index.first_at_or_after(probe)).map(|&key| codes[key as u32 as usize]);
            assert_eq!(found.as_ref(), expected, "probe {probe}");
        }
    }

    #[test]
    fn the_radix_sort_orders_keys_by_code_as_a_comparison_sort_does() {
        let mut scratch = Vec::new();
        for n in [0, 5, 511, 512, 3000] {
            // Codes share their top byte (a pass skipped) and repeat (stability irrelevant:
            // the node in the low bits breaks ties the same way in both).
            let mut keys: Vec<u64> =
                (0..n as u64).map(|i| ((i.wrapping_mul(2_654_435_761) % 70_000) << 32) | i).collect();
            let mut expected = keys.clone();
            expected.sort_unstable_by_key(|&key| super::code(key));
            sort_by_code(&mut keys, &mut scratch);
            let codes = |k: &[u64]| k.iter().map(|&key| super::code(key)).collect::<Vec<_>>();
            assert_eq!(codes(&keys), codes(&expected), "{n} keys");
            let mut nodes: Vec<u64> = keys.iter().map(|&key| key & 0xFFFF_FFFF).collect();
            nodes.sort_unstable();
            assert_eq!(nodes, (0..n as u64).collect::<Vec<_>>(), "every key kept");
        }
    }

    #[test]
    fn removed_keys_are_stepped_over() {
        let mut index = ZIndex { keys: (0..10u64).map(|i| (i << 32) | i).collect(), ..ZIndex::default() };
        index.build(|_| [0.0; 2]);
        for at in [2, 3, 4, 7, 9] {
            index.remove(at);
        }
        let live: Vec<usize> = (0..=10).map(|at| index.live_from(at)).collect();
        assert_eq!(live, [0, 1, 5, 5, 5, 5, 6, 8, 8, 10, 10]);
    }

    #[test]
    fn a_cell_holds_every_position_whose_code_it_spans() {
        let hash = ZHash::new([-3.0, 2.0], [7.0, 9.0]);
        let mut rng = crate::geometry::rng::SplitMix64::new(7);
        let mut next = || rng.unit();
        for _ in 0..2000 {
            let [x, y] = [-3.0 + 10.0 * next(), 2.0 + 10.0 * next()];
            let z = hash.z(x, y);
            assert_eq!(spread(compact(z)) | (spread(compact(z >> 1)) << 1), z, "compact undoes spread");
            for k in 1..15 {
                let Some((lo, hi, end)) = hash.cell(z, k) else { continue };
                assert!(lo[0] <= x && x <= hi[0] && lo[1] <= y && y <= hi[1], "({x}, {y}) outside its cell at k = {k}");
                assert!(end >= z && end - z < 1 << (2 * k), "cell end {end} for code {z} at k = {k}");
            }
        }
    }

    #[test]
    fn codes_order_points_by_the_quantised_grid() {
        let hash = ZHash::new([0.0, 0.0], [1.0, 1.0]);
        assert_eq!(hash.z(0.0, 0.0), 0);
        assert_eq!(hash.z(1.0, 1.0), code(32767, 32767));
        assert_eq!(hash.z(-5.0, 2.0), code(0, 32767), "outside the box: clamped");
    }
}
