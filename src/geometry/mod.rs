//! CPU geometry algorithms of the book (chapters 1, 5 and 7) and of projection mapping. No wgpu,
//! scenes or UI in here.

pub mod outline;
pub mod poisson;
mod rng;
pub mod skinned;
pub mod triangulate;
pub mod volume;
pub mod warp;

pub use rng::SplitMix64;
