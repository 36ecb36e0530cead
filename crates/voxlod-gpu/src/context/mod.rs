//! The GPU context: adapter choice, device creation, limit checks, and the guarded
//! submit/readback helpers every kernel uses.
//!
//! # Choosing an adapter
//! [`Context::new`] reads `VOXLOD_ADAPTER` (else wgpu's `WGPU_ADAPTER_NAME`): an index into
//! [`adapters`] or a case-insensitive substring of an adapter's name. Without it, the default
//! prefers a discrete GPU, then an integrated one, then a virtual one, then anything else, and
//! a CPU adapter (Mesa's lavapipe) last; ties go to the first enumerated. `WGPU_BACKEND` limits
//! the backends enumerated (wgpu reads it). [`Context::all`] opens every adapter: the
//! equivalence suite runs on each.
//!
//! # Errors, never hangs or panics
//! Buffer sizes and dispatch sizes are checked against the device's limits before anything is
//! allocated ([`Error::BufferTooLarge`], [`Error::TooLarge`]). Allocations and submissions run
//! inside error scopes for out-of-memory and validation errors, an uncaptured-error handler
//! records what escapes them (wgpu's default handler panics), a device-lost callback records a
//! [`Error`].
//!
//! # What lives where
//! - this module: the [`Context`] itself (opening a device, error scopes, submission and
//!   waiting);
//! - `adapter`: listing adapters, the default preference, the selector;
//! - `buffers`: allocation of storage and uniform buffers within the limits, and readback;
//! - `dispatch`: compiling pipelines, sizing dispatches, binding buffers and recording or
//!   submitting one compute pass — the one place every kernel's dispatch goes through.

use std::sync::{Arc, Mutex};
use std::time::Duration;

use crate::{Error, Result};

mod adapter;
mod buffers;
mod dispatch;

use adapter::enumerate;
pub use adapter::{AdapterSummary, adapters, env_selector, preference, select};
pub use dispatch::{entry, record_pass};

/// What the device reported outside an error scope: a loss or an uncaptured error.
type Incidents = Arc<Mutex<Vec<String>>>;

/// An open device on one adapter, with its limits.
pub struct Context {
    device: wgpu::Device,
    queue: wgpu::Queue,
    info: wgpu::AdapterInfo,
    index: usize,
    limits: wgpu::Limits,
    downlevel: wgpu::DownlevelCapabilities,
    incidents: Incidents,
    timeout: Duration,
}

impl std::fmt::Debug for Context {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Context").field("adapter", &self.summary().to_string()).finish()
    }
}

impl Context {
    /// Opens the adapter chosen by the environment or the default preference (module docs).
    pub fn new() -> Result<Self> {
        Self::with_selector(env_selector().as_deref())
    }

    /// Opens the adapter `selector` picks (an index or a name substring; `None`: the default
    /// preference).
    pub fn with_selector(selector: Option<&str>) -> Result<Self> {
        let mut list = enumerate();
        let infos: Vec<_> = list.iter().map(wgpu::Adapter::get_info).collect();
        let i = select(&infos, selector)?;
        Self::open(list.swap_remove(i), i)
    }

    /// One context per adapter found, in enumeration order (an adapter that fails to open
    /// gives its error in its slot).
    pub fn all() -> Vec<Result<Self>> {
        enumerate().into_iter().enumerate().map(|(i, a)| Self::open(a, i)).collect()
    }

    fn open(adapter: wgpu::Adapter, index: usize) -> Result<Self> {
        let info = adapter.get_info();
        // Ask for everything the adapter offers: kernels check their needs against these.
        let limits = adapter.limits();
        let downlevel = adapter.get_downlevel_capabilities();
        let desc = wgpu::DeviceDescriptor {
            label: Some("voxlod"),
            required_limits: limits.clone(),
            ..Default::default()
        };
        let (device, queue) = pollster::block_on(adapter.request_device(&desc)).map_err(|e| {
            Error::RequestDevice { adapter: info.name.clone(), message: e.to_string() }
        })?;
        let incidents: Incidents = Arc::default();
        let sink = incidents.clone();
        device.set_device_lost_callback(move |reason, message| {
            if reason != wgpu::DeviceLostReason::Destroyed {
                sink.lock().unwrap().push(format!("device lost ({reason:?}): {message}"));
            }
        });
        let sink = incidents.clone();
        device.on_uncaptured_error(Arc::new(move |e| sink.lock().unwrap().push(e.to_string())));
        let timeout =
            std::env::var("VOXLOD_GPU_TIMEOUT_S").ok().and_then(|s| s.parse().ok()).unwrap_or(120);
        Ok(Self {
            device,
            queue,
            info,
            index,
            limits,
            downlevel,
            incidents,
            timeout: Duration::from_secs(timeout),
        })
    }

    /// The adapter's description.
    pub fn info(&self) -> &wgpu::AdapterInfo {
        &self.info
    }

    /// Index and description, printable (`[0] llvmpipe (…) (Vulkan, Cpu, …)`).
    pub fn summary(&self) -> AdapterSummary {
        AdapterSummary { index: self.index, info: self.info.clone() }
    }

    /// Short name for tables: the adapter name and backend.
    pub fn label(&self) -> String {
        format!("{} ({:?})", self.info.name, self.info.backend)
    }

    /// Whether this adapter is a CPU implementation (lavapipe, WARP, SwiftShader): its
    /// timings are CPU timings.
    pub fn is_cpu(&self) -> bool {
        self.info.device_type == wgpu::DeviceType::Cpu
    }

    /// The device's limits (all the adapter offers).
    pub fn limits(&self) -> &wgpu::Limits {
        &self.limits
    }

    /// The adapter's downlevel capabilities (what it supports below full WebGPU, e.g. storage
    /// buffers written from fragment shaders): kernels check their needs against these.
    pub fn downlevel(&self) -> &wgpu::DownlevelCapabilities {
        &self.downlevel
    }

    /// The wgpu device.
    pub fn device(&self) -> &wgpu::Device {
        &self.device
    }

    /// The wgpu queue.
    pub fn queue(&self) -> &wgpu::Queue {
        &self.queue
    }

    /// Runs `f` inside out-of-memory and validation error scopes and turns what they catch,
    /// or what the device reported meanwhile, into an error.
    pub fn guarded<T>(&self, during: &'static str, f: impl FnOnce() -> T) -> Result<T> {
        let oom = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let value = f();
        let v = pollster::block_on(validation.pop());
        let o = pollster::block_on(oom.pop());
        let adapter = self.info.name.clone();
        if let Some(e) = o {
            return Err(Error::OutOfMemory { adapter, during, message: e.to_string() });
        }
        if let Some(e) = v {
            return Err(Error::Device { adapter, during, message: e.to_string() });
        }
        self.check_incidents(during)?;
        Ok(value)
    }

    fn check_incidents(&self, during: &'static str) -> Result<()> {
        let mut incidents = self.incidents.lock().unwrap();
        if incidents.is_empty() {
            return Ok(());
        }
        let message = incidents.drain(..).collect::<Vec<_>>().join("; ");
        let adapter = self.info.name.clone();
        Err(if message.starts_with("device lost") {
            Error::DeviceLost { adapter, during, message }
        } else {
            Error::Device { adapter, during, message }
        })
    }

    /// Submits `encoder` and waits for it (with the timeout), inside error scopes.
    pub fn submit(&self, during: &'static str, encoder: wgpu::CommandEncoder) -> Result<()> {
        let index = self.guarded(during, || self.queue.submit([encoder.finish()]))?;
        self.wait(during, Some(index))
    }

    fn wait(&self, during: &'static str, index: Option<wgpu::SubmissionIndex>) -> Result<()> {
        let poll = self
            .device
            .poll(wgpu::PollType::Wait { submission_index: index, timeout: Some(self.timeout) });
        self.check_incidents(during)?;
        match poll {
            Ok(_) => Ok(()),
            Err(wgpu::PollError::Timeout) => Err(Error::Timeout {
                adapter: self.info.name.clone(),
                during,
                seconds: self.timeout.as_secs(),
            }),
            Err(e) => Err(Error::Device {
                adapter: self.info.name.clone(),
                during,
                message: e.to_string(),
            }),
        }
    }
}
