//! CPU geometry algorithms of the book (chapters 5 and 7). No wgpu, scenes or UI in here.

pub mod outline;
pub mod poisson;
mod rng;
pub mod triangulate;

pub use rng::SplitMix64;
