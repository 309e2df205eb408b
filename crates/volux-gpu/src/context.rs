//! The adapter and device the backend renders on.
use std::fmt;

use crate::error::GpuError;

/// An adapter, in words: what `volux info --gpu` lists and the viewer shows.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AdapterSummary {
    /// The device's name (`llvmpipe (LLVM 15.0.6, 256 bits)`, `NVIDIA H200`).
    pub name: String,
    /// The API it is reached through (Vulkan, Metal, DX12, GL).
    pub backend: String,
    /// Discrete, integrated, virtual, CPU (a software rasterizer such as lavapipe).
    pub device_type: String,
    /// The driver and its version, where the adapter says.
    pub driver: String,
}

impl AdapterSummary {
    fn of(info: &wgpu::AdapterInfo) -> Self {
        Self {
            name: info.name.clone(),
            backend: format!("{:?}", info.backend),
            device_type: format!("{:?}", info.device_type),
            driver: format!("{} {}", info.driver, info.driver_info)
                .trim()
                .to_string(),
        }
    }
}

impl fmt::Display for AdapterSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} ({}, {}", self.name, self.backend, self.device_type)?;
        if !self.driver.is_empty() {
            write!(f, ", {}", self.driver)?;
        }
        write!(f, ")")
    }
}

impl AdapterSummary {
    /// Whether the adapter is a software rasterizer on the CPU (Mesa's llvmpipe/lavapipe,
    /// SwiftShader, WARP): wgpu's device type `Cpu`. It draws what a GPU draws, several
    /// times slower than the CPU engine, which is built for the CPU.
    pub fn is_software(&self) -> bool {
        self.device_type == format!("{:?}", wgpu::DeviceType::Cpu)
    }
}

/// Keeps Mesa's Vulkan device-selection layer from probing a Wayland display that a
/// headless machine does not have: without `XDG_RUNTIME_DIR` and `WAYLAND_DISPLAY`, the
/// layer's probe prints "error: XDG_RUNTIME_DIR is invalid or not set in the environment"
/// on every device opened (the layer only picks the GPU that drives the display, and there
/// is none). Sets `NODEVICE_SELECT=1` (the layer's own switch) in that case, unless the user
/// set it. Call it first thing in `main`, before any thread starts (it sets an environment
/// variable).
pub fn quiet_headless_vulkan() {
    let unset = |k: &str| std::env::var_os(k).is_none_or(|v| v.is_empty());
    if unset("XDG_RUNTIME_DIR") && unset("WAYLAND_DISPLAY") && unset("NODEVICE_SELECT") {
        std::env::set_var("NODEVICE_SELECT", "1");
    }
}

/// The adapters of `backends` (`WGPU_BACKEND` overrides them, as in every wgpu program).
fn enumerate(backends: wgpu::Backends) -> Vec<wgpu::Adapter> {
    let backends = wgpu::Backends::from_env().unwrap_or(backends);
    let instance = wgpu::Instance::new(&wgpu::InstanceDescriptor {
        backends,
        ..Default::default()
    });
    instance.enumerate_adapters(backends)
}

/// The adapters of Vulkan, Metal and DX12, or of GL where none of those has one: GL is
/// probed only then (its probe of EGL writes warnings on machines without a display).
fn preferred_adapters() -> Vec<wgpu::Adapter> {
    let primary = enumerate(wgpu::Backends::PRIMARY);
    if primary.is_empty() {
        enumerate(wgpu::Backends::GL)
    } else {
        primary
    }
}

/// Every adapter this machine offers (GL's too), the preferred first (what `--backend gpu`
/// picks).
pub fn adapters() -> Vec<AdapterSummary> {
    let mut all: Vec<wgpu::AdapterInfo> = enumerate(wgpu::Backends::all())
        .iter()
        .map(|a| a.get_info())
        .collect();
    all.sort_by_key(preference);
    all.iter().map(AdapterSummary::of).collect()
}

/// Lower is preferred: a discrete GPU, an integrated one, a virtual one, a CPU rasterizer;
/// Vulkan, Metal and DX12 before GL.
fn preference(info: &wgpu::AdapterInfo) -> (u8, u8) {
    let kind = match info.device_type {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Cpu => 3,
        wgpu::DeviceType::Other => 4,
    };
    (kind, u8::from(info.backend == wgpu::Backend::Gl))
}

/// A device and its queue on the preferred adapter, opened once and shared by renderers.
pub struct GpuContext {
    pub(crate) device: wgpu::Device,
    pub(crate) queue: wgpu::Queue,
    summary: AdapterSummary,
    /// Whether `rgba32float` render targets blend (adapter-specific format features).
    pub(crate) blend_f32: bool,
}

impl GpuContext {
    /// Opens the preferred adapter (a discrete GPU first, GL only where no other API has an
    /// adapter) with its own limits.
    pub fn new() -> Result<Self, GpuError> {
        let mut found = preferred_adapters();
        found.sort_by_key(|a| preference(&a.get_info()));
        let adapter = found.into_iter().next().ok_or(GpuError::NoAdapter)?;
        let info = adapter.get_info();
        let specific = wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES;
        let features = adapter.features() & specific;
        let blend_f32 = features.contains(specific)
            && adapter
                .get_texture_format_features(wgpu::TextureFormat::Rgba32Float)
                .flags
                .contains(wgpu::TextureFormatFeatureFlags::BLENDABLE);
        let desc = wgpu::DeviceDescriptor {
            label: Some("volux"),
            required_features: features,
            required_limits: adapter.limits(),
            ..Default::default()
        };
        let (device, queue) =
            pollster::block_on(adapter.request_device(&desc)).map_err(|e| GpuError::Device {
                adapter: info.name.clone(),
                reason: e.to_string(),
            })?;
        Ok(Self {
            device,
            queue,
            summary: AdapterSummary::of(&info),
            blend_f32,
        })
    }

    /// Whether `rgba32float` render targets blend on this device (else the render-pipeline
    /// paths draw into `rgba16float`).
    pub(crate) fn blends_f32(&self) -> bool {
        self.blend_f32
    }

    /// The adapter rendering, in words.
    pub fn adapter(&self) -> &AdapterSummary {
        &self.summary
    }

    /// The device's limits.
    pub fn limits(&self) -> wgpu::Limits {
        self.device.limits()
    }

    /// Runs `f` with the device's errors captured: a validation or out-of-memory error
    /// becomes [`GpuError::Failed`] instead of wgpu's default panic.
    pub(crate) fn checked<T>(&self, f: impl FnOnce() -> T) -> Result<T, GpuError> {
        self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let out = f();
        let errors = [
            pollster::block_on(self.device.pop_error_scope()),
            pollster::block_on(self.device.pop_error_scope()),
        ];
        match errors.into_iter().flatten().next() {
            Some(e) => Err(GpuError::Failed(e.to_string())),
            None => Ok(out),
        }
    }
}
