//! The growth state as the GPU holds it — attractions and nodes, laid out like the shader's
//! structs — and the book's attraction sources: a jittered lattice in a sphere, seeds among them.

use crate::geometry::SplitMix64;

/// "No node" in `nearest` and `parent`.
pub const NONE: u32 = u32::MAX;

/// An attraction (`Attraction` in the growth shader).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Attraction {
    /// Position, local units.
    pub pos: [f32; 3],
    /// 1 while alive.
    pub alive: u32,
    /// The node it chose in the last search, or [`NONE`].
    pub nearest: u32,
    /// The mesh vertex whose skin it carries (skinned sources; 0 otherwise).
    pub skin: u32,
    /// Padding.
    pub _pad: [u32; 2],
}

impl Attraction {
    /// A live attraction at `pos` with the skin of vertex `skin`.
    pub fn new(pos: [f32; 3], skin: u32) -> Self {
        Self { pos, alive: 1, nearest: NONE, skin, _pad: [0; 2] }
    }
}

/// A node of the growing forest (`Node` in the growth shader).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Node {
    /// Rest position, local units.
    pub pos: [f32; 3],
    /// How far its edge has grown out, 0–1; it attracts once t = 1.
    pub t: f32,
    /// Edges from its root.
    pub depth: u32,
    /// Growth rate factor.
    pub mass: f32,
    /// Its parent, or [`NONE`] for a seed.
    pub parent: u32,
    /// The mesh vertex whose skin it carries.
    pub skin: u32,
}

impl Node {
    /// A fully grown root at `pos`.
    pub fn seed(pos: [f32; 3], skin: u32) -> Self {
        Self { pos, t: 1.0, depth: 0, mass: 1.0, parent: NONE, skin }
    }
}

/// Attractions and where they came from.
#[derive(Clone, Debug)]
pub struct Cloud {
    /// The attractions.
    pub attractions: Vec<Attraction>,
    /// The distance unit the growth parameters are measured in.
    pub unit: f32,
    /// Lowest corner of the attractions' bounds.
    pub lo: [f32; 3],
    /// Highest corner.
    pub hi: [f32; 3],
}

impl Cloud {
    /// A cloud of `attractions` with distance unit `unit`.
    pub fn new(attractions: Vec<Attraction>, unit: f32) -> Self {
        let mut lo = [f32::MAX; 3];
        let mut hi = [f32::MIN; 3];
        for a in &attractions {
            for i in 0..3 {
                lo[i] = lo[i].min(a.pos[i]);
                hi[i] = hi[i].max(a.pos[i]);
            }
        }
        if attractions.is_empty() {
            (lo, hi) = ([0.0; 3], [0.0; 3]);
        }
        Self { attractions, unit, lo, hi }
    }

    /// The book's sphere: a side³ lattice over [−0.5, 0.5]³ keeping points inside radius 0.5,
    /// each jittered by up to half a lattice cell per axis; the unit is 2 / side.
    pub fn lattice_sphere(side: u32, seed: u64) -> Self {
        let side = side.max(2);
        let spacing = 1.0 / (side - 1) as f32;
        let mut rng = SplitMix64::new(seed);
        let mut points = Vec::new();
        for z in 0..side {
            for y in 0..side {
                for x in 0..side {
                    let p = [x, y, z].map(|i| i as f32 * spacing - 0.5);
                    if p.iter().map(|c| c * c).sum::<f32>() < 0.25 {
                        let jittered = p.map(|c| c + (rng.unit() as f32 - 0.5) * spacing);
                        points.push(Attraction::new(jittered, 0));
                    }
                }
            }
        }
        Self::new(points, 2.0 / side as f32)
    }

    /// `count` seeds at distinct attractions, chosen by `seed` (fewer if there are fewer).
    pub fn seeds(&self, count: usize, seed: u64) -> Vec<Node> {
        let mut rng = SplitMix64::new(seed ^ 0x5eed_5eed_5eed_5eed);
        let mut chosen: Vec<usize> = Vec::new();
        let n = self.attractions.len();
        while chosen.len() < count.min(n) {
            let i = rng.below(n);
            if !chosen.contains(&i) {
                chosen.push(i);
            }
        }
        chosen.iter().map(|&i| Node::seed(self.attractions[i].pos, self.attractions[i].skin)).collect()
    }

    /// `count` seeds spread out: the first chosen by `seed`, each next the attraction farthest
    /// from those chosen — so every limb of a model gets one before any part gets two (a limb
    /// joined to the body by less than the influence distance is never reached from outside).
    pub fn spread_seeds(&self, count: usize, seed: u64) -> Vec<Node> {
        let n = self.attractions.len();
        if n == 0 {
            return Vec::new();
        }
        let mut rng = SplitMix64::new(seed ^ 0x5eed_5eed_5eed_5eed);
        let mut chosen = vec![rng.below(n)];
        let d2 = |a: [f32; 3], b: [f32; 3]| (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f32>();
        let mut nearest: Vec<f32> =
            self.attractions.iter().map(|a| d2(a.pos, self.attractions[chosen[0]].pos)).collect();
        while chosen.len() < count.min(n) {
            let (far, _) =
                nearest.iter().enumerate().fold((0, -1.0), |best, (i, &d)| if d > best.1 { (i, d) } else { best });
            chosen.push(far);
            for (i, a) in self.attractions.iter().enumerate() {
                nearest[i] = nearest[i].min(d2(a.pos, self.attractions[far].pos));
            }
        }
        chosen.iter().map(|&i| Node::seed(self.attractions[i].pos, self.attractions[i].skin)).collect()
    }
}
