//! The frame graph: passes declare the virtual textures and buffers they read and write;
//! compiling orders them from those dependencies, drops passes whose results reach no output,
//! and serves transient textures from a pool that reuses a texture within the frame once its last
//! reader has run. Knows nothing of what the passes draw.
//!
//! Modelled on the render graphs of Frostbite (O'Donnell, GDC 2017) and kajiya, with one change:
//! a resource's dependencies come from declared accesses, never from the call order of reads.

mod builder;
mod compile;
mod execute;
mod pool;
mod resource;
mod timing;

pub use builder::{FrameGraph, PassBuilder, PassContext, RasterTargets};
pub use compile::{CompiledGraph, GraphError, compile};
pub use execute::{FrameOutput, FrameStats, GraphRuntime};
pub use pool::{BufferPool, TexturePool, texture_bytes};
pub use resource::{BufferHandle, Extent, PersistentTexture, PingPong, TextureDesc, TextureHandle, next_resource_id};
pub use timing::{PassTiming, RollingMedian};
