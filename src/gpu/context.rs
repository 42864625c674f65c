//! Creating the wgpu instance, adapter and device, with our own error handler.

use std::sync::{Arc, Mutex};

use super::tuning::{AdapterKey, Tuning, TuningSource};

/// Which graphics API to ask wgpu for.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum BackendChoice {
    /// Whatever wgpu finds (honours `WGPU_BACKEND`).
    #[default]
    Auto,
    /// Vulkan (lavapipe on a machine without a GPU).
    Vulkan,
    /// OpenGL / GLES through EGL (WGL on Windows).
    Gl,
    /// Direct3D 12 (Windows only).
    Dx12,
}

/// How to pick the adapter.
#[derive(Clone, Debug, Default)]
pub struct GpuOptions {
    /// Graphics API.
    pub backend: BackendChoice,
    /// Case-insensitive substring of the adapter name (e.g. "llvmpipe", "H100").
    pub adapter: Option<String>,
    /// What `auto` parameters take on the adapter (see [`super::tuning`]).
    pub tuning: TuningSource,
}

/// Why no device could be had; each variant's message says what to do.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No adapter at all.
    #[error("no GPU adapter found for backend {backend:?}. {}", no_adapter_hint(*.backend))]
    NoAdapter {
        /// The backend asked for.
        backend: BackendChoice,
    },
    /// Adapters exist, but none matches `--adapter`.
    #[error("no adapter name contains '{wanted}'; adapters found: {found}")]
    NoMatchingAdapter {
        /// The substring asked for.
        wanted: String,
        /// The adapters that exist.
        found: String,
    },
    /// The device request failed.
    #[error("the adapter '{adapter}' refused to create a device: {reason}")]
    Device {
        /// Adapter name.
        adapter: String,
        /// wgpu's reason.
        reason: String,
    },
}

/// What to do when no adapter is found, on this system.
fn no_adapter_hint(backend: BackendChoice) -> &'static str {
    if backend == BackendChoice::Dx12 && !cfg!(windows) {
        "Direct3D 12 exists on Windows only; leave --backend at auto"
    } else if cfg!(windows) {
        "Update the graphics driver (Vulkan, Direct3D 12 or OpenGL 3.3 is needed), or try another --backend"
    } else {
        "On Linux without a GPU install Mesa's software Vulkan: `sudo apt-get install mesa-vulkan-drivers libvulkan1`"
    }
}

/// A device and queue plus what we learned about the adapter.
#[derive(Clone)]
pub struct Gpu {
    /// The wgpu instance (kept to create surfaces).
    pub instance: wgpu::Instance,
    /// The chosen adapter.
    pub adapter: wgpu::Adapter,
    /// The logical device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// Validation errors wgpu raised outside an error scope, newest last. Read and cleared by the
    /// runtime to show them; wgpu's default handler would panic instead.
    pub uncaptured: Arc<Mutex<Vec<String>>>,
    /// Set (with wgpu's reason) when the device is lost: a driver reset, a removed GPU, or
    /// `Device::destroy`. Everything made on this device is then useless; see [`Gpu::replacement`].
    lost: Arc<Mutex<Option<String>>>,
    /// How the adapter was chosen, to choose again after a loss.
    options: GpuOptions,
    /// What `auto` parameters take on this adapter: the choices `indra tune` measured here, or
    /// the built-in defaults.
    pub tuning: Arc<Tuning>,
}

impl Gpu {
    /// A device with no surface, for off-screen rendering, tests and benchmarks.
    pub fn headless(options: &GpuOptions) -> Result<Self, GpuError> {
        let instance = wgpu::Instance::new(instance_descriptor(options.backend));
        pollster::block_on(Self::with_instance(instance, options, None))
    }

    /// A device on `instance` that can present to `surface` (if given).
    pub async fn with_instance(
        instance: wgpu::Instance,
        options: &GpuOptions,
        surface: Option<&wgpu::Surface<'_>>,
    ) -> Result<Self, GpuError> {
        let adapter = pick_adapter(&instance, options, surface).await?;
        let info = adapter.get_info();
        // Optional, used where the adapter has them: timestamps for per-pass timing; the
        // adapter's own sample counts (8× MSAA; WebGPU guarantees only 1 and 4); 64-bit atomics
        // for drawing in compute (the tessellation's visibility buffer).
        let wanted = wgpu::Features::TIMESTAMP_QUERY
            | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS
            | wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES
            // HAP clips upload their BC blocks as they are (a CPU decode where this is missing).
            | wgpu::Features::TEXTURE_COMPRESSION_BC
            | wgpu::Features::SHADER_INT64
            | wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX;
        let required_features = adapter.features() & wanted;
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("indra_device"),
                required_features,
                required_limits: adapter.limits(),
                ..Default::default()
            })
            .await
            .map_err(|e| GpuError::Device { adapter: info.name.clone(), reason: e.to_string() })?;
        let uncaptured = Arc::new(Mutex::new(Vec::new()));
        let sink = uncaptured.clone();
        device.on_uncaptured_error(Arc::new(move |error: wgpu::Error| {
            let text = error.to_string();
            log::error!("GPU error: {text}");
            if let Ok(mut list) = sink.lock() {
                list.push(text);
                let excess = list.len().saturating_sub(32);
                list.drain(..excess);
            }
        }));
        let lost = Arc::new(Mutex::new(None));
        let flag = lost.clone();
        device.set_device_lost_callback(move |reason, message| {
            let text = if message.is_empty() { format!("{reason:?}") } else { format!("{reason:?}: {message}") };
            if let Ok(mut slot) = flag.lock() {
                slot.get_or_insert(text);
            }
        });
        log::debug!("adapter: {} ({:?}, {:?})", info.name, info.backend, info.device_type);
        // Lavapipe compiles and keeps a shader variant per dispatch of values it can inline
        // from uniform buffers: bind parameter blocks as storage there (see `blocks_in_storage`).
        super::binding::set_blocks_in_storage(is_lavapipe(&info));
        let (tuning, note) = Tuning::load(&options.tuning, &AdapterKey::of(&info));
        if let Some(note) = note {
            log::warn!("{note}");
        }
        let tuning = Arc::new(tuning);
        Ok(Self { instance, adapter, device, queue, uncaptured, lost, options: options.clone(), tuning })
    }

    /// A new device on the same instance, chosen as this one was, for a show to move to after
    /// this device was lost or hung. `surface` (the window's, if any) must be presentable.
    pub async fn replacement(&self, surface: Option<&wgpu::Surface<'_>>) -> Result<Self, GpuError> {
        Self::with_instance(self.instance.clone(), &self.options, surface).await
    }

    /// Why the device was lost, once it has been (wgpu reports it while polling).
    pub fn lost_reason(&self) -> Option<String> {
        self.lost.lock().ok().and_then(|l| l.clone())
    }

    /// "name (backend)" of the adapter, for logs, reports and golden file names.
    pub fn adapter_label(&self) -> String {
        let info = self.adapter.get_info();
        format!("{} ({:?})", info.name, info.backend)
    }

    /// Whether per-pass GPU timestamps can be recorded.
    pub fn has_timestamps(&self) -> bool {
        self.device.features().contains(wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS)
    }

    /// Takes the errors wgpu reported outside error scopes since the last call.
    pub fn take_uncaptured_errors(&self) -> Vec<String> {
        self.uncaptured.lock().map(|mut l| std::mem::take(&mut *l)).unwrap_or_default()
    }
}

/// The instance descriptor for a backend choice; `Auto` reads `WGPU_BACKEND` and friends.
pub fn instance_descriptor(backend: BackendChoice) -> wgpu::InstanceDescriptor {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
    match backend {
        BackendChoice::Auto => {}
        BackendChoice::Vulkan => desc.backends = wgpu::Backends::VULKAN,
        BackendChoice::Gl => desc.backends = wgpu::Backends::GL,
        BackendChoice::Dx12 => desc.backends = wgpu::Backends::DX12,
    }
    desc
}

async fn pick_adapter(
    instance: &wgpu::Instance,
    options: &GpuOptions,
    surface: Option<&wgpu::Surface<'_>>,
) -> Result<wgpu::Adapter, GpuError> {
    let all = instance.enumerate_adapters(wgpu::Backends::all()).await;
    let usable: Vec<wgpu::Adapter> =
        all.into_iter().filter(|a| surface.is_none_or(|s| a.is_surface_supported(s))).collect();
    if usable.is_empty() {
        return Err(GpuError::NoAdapter { backend: options.backend });
    }
    if let Some(wanted) = &options.adapter {
        let lower = wanted.to_lowercase();
        let found = usable.iter().map(|a| a.get_info().name).collect::<Vec<_>>().join(", ");
        return usable
            .into_iter()
            .find(|a| a.get_info().name.to_lowercase().contains(&lower))
            .ok_or(GpuError::NoMatchingAdapter { wanted: wanted.clone(), found });
    }
    // Prefer a real GPU over a software one; among equals keep wgpu's order: Vulkan first (the
    // backend every test and golden runs on, lavapipe and NVIDIA), then Direct3D 12 on Windows
    // (which Wine cannot test here), then GL.
    let rank = |a: &wgpu::Adapter| match a.get_info().device_type {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Cpu => 3,
        wgpu::DeviceType::Other => 4,
    };
    let mut usable = usable;
    usable.sort_by_key(rank);
    Ok(usable.remove(0))
}

/// Whether `info` is Mesa's lavapipe: the CPU Vulkan driver (llvmpipe behind Vulkan).
fn is_lavapipe(info: &wgpu::AdapterInfo) -> bool {
    info.backend == wgpu::Backend::Vulkan && info.device_type == wgpu::DeviceType::Cpu
}
