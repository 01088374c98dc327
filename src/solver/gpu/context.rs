//! The card: a wgpu device and queue, which adapter they came from, and whether it runs f64.
//!
//! The app hands over the renderer's device and queue ([`Gpu::from_device`]); the CLI and the
//! tests open their own ([`Gpu::open`]). Nothing here names an engine type.

use std::fmt;
use std::future::Future;
use std::pin::pin;
use std::task::{Context, Poll, Waker};

/// Why the card cannot be used.
#[derive(Debug, Clone, PartialEq)]
pub enum GpuError {
    /// No adapter answered: no Vulkan driver, or none for this machine's card.
    NoAdapter(String),
    /// The adapter refused a device.
    NoDevice(String),
    /// The scene is larger than a buffer on this adapter may be.
    TooLarge(String),
    /// The device refused the kernels or the buffers (out of memory, or a kernel the
    /// driver cannot build).
    Refused(String),
    /// Reading the state back failed.
    ReadBack(String),
}

impl fmt::Display for GpuError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            GpuError::NoAdapter(why) => write!(f, "no graphics adapter: {why}"),
            GpuError::NoDevice(why) => write!(f, "the adapter gave no device: {why}"),
            GpuError::TooLarge(why) => write!(f, "the scene does not fit the adapter: {why}"),
            GpuError::Refused(why) => write!(f, "the card refused the step: {why}"),
            GpuError::ReadBack(why) => write!(f, "reading the state back failed: {why}"),
        }
    }
}

impl std::error::Error for GpuError {}

/// The width of the numbers the kernels compute in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Precision {
    /// f32: every card's native width.
    F32,
    /// f64: only on adapters with `SHADER_F64`.
    F64,
}

impl Precision {
    /// Bytes of one number.
    pub fn bytes(self) -> usize {
        match self {
            Precision::F32 => 4,
            Precision::F64 => 8,
        }
    }

    /// "f32" or "f64".
    pub fn name(self) -> &'static str {
        match self {
            Precision::F32 => "f32",
            Precision::F64 => "f64",
        }
    }
}

/// A device and queue to step on, with what the adapter says of itself.
#[derive(Debug, Clone)]
pub struct Gpu {
    pub(crate) device: wgpu::Device,
    pub(crate) queue: wgpu::Queue,
    info: wgpu::AdapterInfo,
}

impl Gpu {
    /// Opens the best adapter this machine has (the backends `WGPU_BACKEND` names, else every
    /// one built in: Vulkan on Linux), with f64 when the adapter has it and the adapter's own
    /// buffer limits, which the largest cloths need.
    pub fn open() -> Result<Gpu, GpuError> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let options = wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: None,
        };
        let adapter = ready(instance.request_adapter(&options))
            .map_err(|e| GpuError::NoAdapter(e.to_string()))?;
        let features = adapter.features() & wgpu::Features::SHADER_F64;
        let descriptor = wgpu::DeviceDescriptor {
            label: Some("hooke"),
            required_features: features,
            required_limits: adapter.limits(),
            ..Default::default()
        };
        let (device, queue) = ready(adapter.request_device(&descriptor))
            .map_err(|e| GpuError::NoDevice(e.to_string()))?;
        Ok(Gpu {
            device,
            queue,
            info: adapter.get_info(),
        })
    }

    /// A device and queue someone else opened: the app's renderer's.
    pub fn from_device(device: wgpu::Device, queue: wgpu::Queue, info: wgpu::AdapterInfo) -> Gpu {
        Gpu {
            device,
            queue,
            info,
        }
    }

    /// The adapter's name and backend, as "NVIDIA H200 (Vulkan)".
    pub fn adapter(&self) -> String {
        format!("{} ({:?})", self.info.name, self.info.backend)
    }

    /// The device: what a [`super::Painter`] draws with.
    pub fn device(&self) -> &wgpu::Device {
        &self.device
    }

    /// The queue.
    pub fn queue(&self) -> &wgpu::Queue {
        &self.queue
    }

    /// Whether the device computes in f64.
    pub fn has_f64(&self) -> bool {
        self.device.features().contains(wgpu::Features::SHADER_F64)
    }

    /// Waits until everything submitted to the queue has run.
    pub(super) fn wait(&self) -> Result<(), GpuError> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| GpuError::ReadBack(e.to_string()))
    }

    /// The precisions this device runs: f32, and f64 where the adapter has it.
    pub fn precisions(&self) -> Vec<Precision> {
        let mut p = vec![Precision::F32];
        if self.has_f64() {
            p.push(Precision::F64);
        }
        p
    }
}

/// A native wgpu future's value. On native backends adapter and device requests complete at
/// once, so a poll loop with a waker that does nothing is all the executor they need.
pub(super) fn ready<F: Future>(future: F) -> F::Output {
    let mut future = pin!(future);
    let mut cx = Context::from_waker(Waker::noop());
    loop {
        if let Poll::Ready(v) = future.as_mut().poll(&mut cx) {
            return v;
        }
        std::thread::yield_now();
    }
}
