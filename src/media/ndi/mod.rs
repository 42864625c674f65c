//! NDI in and out through the runtime the user installed (NDI Tools, the NDI SDK, or for the
//! tests the runtime PyPI's `cyndilib` ships), loaded at run time ([`runtime`]) so that the
//! default build links nothing proprietary and starts without it: a sender ([`send`]) for the
//! show's output and a receiver ([`receive`]) behind the `ndi` node. End to end against cyndilib's
//! sender and receiver in `tests/suite/ndi.rs`.

pub mod receive;
pub mod runtime;
pub mod send;

pub use receive::{NdiFeed, NdiFrame, NdiSource, list_sources, names_source};
pub use runtime::{NdiRuntime, RUNTIME_DIR_ENV};
pub use send::NdiSender;
