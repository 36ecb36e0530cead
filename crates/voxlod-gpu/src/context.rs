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
//! loss, and every wait has a timeout (`VOXLOD_GPU_TIMEOUT_S`, default 120 s): each becomes an
//! [`Error`].

use std::sync::{Arc, Mutex};
use std::time::Duration;

use crate::{Error, Result};

/// What the device reported outside an error scope: a loss or an uncaptured error.
type Incidents = Arc<Mutex<Vec<String>>>;

/// One adapter as found by [`adapters`].
#[derive(Clone, Debug)]
pub struct AdapterSummary {
    /// Index in enumeration order (what `VOXLOD_ADAPTER=<index>` selects).
    pub index: usize,
    /// wgpu's description of the adapter.
    pub info: wgpu::AdapterInfo,
}

impl std::fmt::Display for AdapterSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let i = &self.info;
        write!(f, "[{}] {} ({:?}, {:?}", self.index, i.name, i.backend, i.device_type)?;
        if !i.driver.is_empty() {
            write!(f, ", {} {}", i.driver, i.driver_info)?;
        }
        write!(f, ")")?;
        if i.device_type == wgpu::DeviceType::Cpu {
            write!(f, " — a CPU implementation: its timings are CPU timings")?;
        }
        Ok(())
    }
}

fn instance() -> wgpu::Instance {
    wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env())
}

fn enumerate() -> Vec<wgpu::Adapter> {
    pollster::block_on(instance().enumerate_adapters(wgpu::Backends::all()))
}

/// Every adapter wgpu finds, in enumeration order.
pub fn adapters() -> Vec<AdapterSummary> {
    enumerate()
        .iter()
        .enumerate()
        .map(|(index, a)| AdapterSummary { index, info: a.get_info() })
        .collect()
}

/// Preference rank of a device type for the default choice (lower is preferred).
pub fn preference(device_type: wgpu::DeviceType) -> u32 {
    match device_type {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    }
}

/// Index of the adapter `selector` picks among `infos` (see the module docs), or the default
/// choice when `selector` is `None`.
pub fn select(infos: &[wgpu::AdapterInfo], selector: Option<&str>) -> Result<usize> {
    let list = || {
        infos
            .iter()
            .enumerate()
            .map(|(index, info)| AdapterSummary { index, info: info.clone() }.to_string())
            .collect::<Vec<_>>()
            .join("; ")
    };
    if infos.is_empty() {
        return Err(Error::NoAdapter);
    }
    match selector.map(str::trim).filter(|s| !s.is_empty()) {
        None => Ok((0..infos.len()).min_by_key(|&i| preference(infos[i].device_type)).unwrap()),
        Some(s) => {
            if let Ok(i) = s.parse::<usize>() {
                return if i < infos.len() {
                    Ok(i)
                } else {
                    Err(Error::AdapterNotFound { selector: s.into(), available: list() })
                };
            }
            let needle = s.to_lowercase();
            infos
                .iter()
                .position(|info| info.name.to_lowercase().contains(&needle))
                .ok_or_else(|| Error::AdapterNotFound { selector: s.into(), available: list() })
        }
    }
}

/// The adapter selector from the environment: `VOXLOD_ADAPTER`, else `WGPU_ADAPTER_NAME`.
pub fn env_selector() -> Option<String> {
    std::env::var("VOXLOD_ADAPTER").ok().or_else(|| std::env::var("WGPU_ADAPTER_NAME").ok())
}

/// An open device on one adapter, with its limits.
pub struct Context {
    device: wgpu::Device,
    queue: wgpu::Queue,
    info: wgpu::AdapterInfo,
    index: usize,
    limits: wgpu::Limits,
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

    /// The wgpu device.
    pub fn device(&self) -> &wgpu::Device {
        &self.device
    }

    /// The wgpu queue.
    pub fn queue(&self) -> &wgpu::Queue {
        &self.queue
    }

    /// Checks that a storage buffer of `bytes` bytes can be created and bound.
    pub fn check_storage(&self, what: &'static str, bytes: u64) -> Result<()> {
        let binding = self.limits.max_storage_buffer_binding_size;
        let (limit, limit_name) = if binding < self.limits.max_buffer_size {
            (binding, "max_storage_buffer_binding_size")
        } else {
            (self.limits.max_buffer_size, "max_buffer_size")
        };
        if bytes > limit {
            return Err(Error::BufferTooLarge {
                what,
                bytes,
                limit,
                limit_name,
                adapter: self.info.name.clone(),
            });
        }
        Ok(())
    }

    /// Splits `workgroups` into a 2D dispatch `(x, y)` within
    /// `max_compute_workgroups_per_dimension` (kernels rebuild the flat index from
    /// `num_workgroups`), or an error with the numbers.
    pub fn dispatch_size(&self, what: &'static str, workgroups: u64) -> Result<(u32, u32)> {
        let max = self.limits.max_compute_workgroups_per_dimension as u64;
        let x = workgroups.clamp(1, max);
        let y = workgroups.div_ceil(x).max(1);
        if y > max {
            return Err(Error::TooLarge { what, requested: workgroups, limit: max * max });
        }
        Ok((x as u32, y as u32))
    }

    /// The dispatch of an image kernel with one thread per pixel in 8×8 workgroups:
    /// `(⌈width/8⌉, ⌈height/8⌉)`, or an error with the numbers when an edge exceeds
    /// `max_compute_workgroups_per_dimension`.
    pub fn image_dispatch(
        &self,
        what: &'static str,
        width: u32,
        height: u32,
    ) -> Result<(u32, u32)> {
        let (x, y) = (width.div_ceil(8), height.div_ceil(8));
        let max = self.limits.max_compute_workgroups_per_dimension;
        if x.max(y) > max {
            return Err(Error::TooLarge { what, requested: x.max(y) as u64, limit: max as u64 });
        }
        Ok((x, y))
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

    /// A storage buffer holding `contents` (checked against the limits; at least 4 bytes, as
    /// bindings may not be empty).
    pub fn storage_init(&self, what: &'static str, contents: &[u8]) -> Result<wgpu::Buffer> {
        let size = (contents.len() as u64).max(4).next_multiple_of(4);
        self.check_storage(what, size)?;
        self.guarded("allocating a buffer", || {
            let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(what),
                size,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: true,
            });
            if !contents.is_empty() {
                let mut view = buffer
                    .slice(..contents.len() as u64)
                    .get_mapped_range_mut()
                    .expect("a buffer mapped at creation maps");
                view.copy_from_slice(contents);
            }
            buffer.unmap();
            buffer
        })
    }

    /// A zeroed storage buffer of `bytes` bytes (readable back).
    pub fn storage_zeroed(&self, what: &'static str, bytes: u64) -> Result<wgpu::Buffer> {
        let size = bytes.max(4).next_multiple_of(4);
        self.check_storage(what, size)?;
        self.guarded("allocating a buffer", || {
            self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(what),
                size,
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_SRC
                    | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        })
    }

    /// A small parameter buffer holding `contents`, bindable as a uniform or a read-only
    /// storage buffer.
    ///
    /// The kernels read their parameters as `var<storage, read>`, not `var<uniform>`: Mesa's
    /// lavapipe compiles a new variant of a kernel for every new value of a uniform that a
    /// branch or a loop bound reads (whole seconds per dispatch for the larger kernels, and
    /// every frame or case has new values), and it never does so for storage buffers.
    pub fn uniform(&self, what: &'static str, contents: &[u8]) -> Result<wgpu::Buffer> {
        self.guarded("allocating a uniform buffer", || {
            let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(what),
                size: (contents.len() as u64).max(16).next_multiple_of(16),
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::STORAGE,
                mapped_at_creation: true,
            });
            buffer
                .slice(..contents.len() as u64)
                .get_mapped_range_mut()
                .expect("a buffer mapped at creation maps")
                .copy_from_slice(contents);
            buffer.unmap();
            buffer
        })
    }

    /// A compute pipeline from WGSL source, with its layout inferred from the shader.
    pub fn pipeline(&self, label: &'static str, wgsl: &str) -> Result<wgpu::ComputePipeline> {
        self.guarded("compiling a kernel", || {
            let module = self.device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(label),
                source: wgpu::ShaderSource::Wgsl(wgsl.into()),
            });
            self.device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(label),
                layout: None,
                module: &module,
                entry_point: Some("main"),
                compilation_options: Default::default(),
                cache: None,
            })
        })
    }

    /// Compute pipelines for the entry points `entries` of one WGSL module, sharing the
    /// explicit `layout` (one bind group for all of them).
    pub fn pipelines(
        &self,
        label: &'static str,
        wgsl: &str,
        entries: &[&str],
        layout: &wgpu::PipelineLayout,
    ) -> Result<Vec<wgpu::ComputePipeline>> {
        self.guarded("compiling a kernel", || {
            let module = self.device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(label),
                source: wgpu::ShaderSource::Wgsl(wgsl.into()),
            });
            entries
                .iter()
                .map(|entry| {
                    self.device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                        label: Some(label),
                        layout: Some(layout),
                        module: &module,
                        entry_point: Some(entry),
                        compilation_options: Default::default(),
                        cache: None,
                    })
                })
                .collect()
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

    /// Copies `buffer` (its first `bytes` bytes) back to the host.
    pub fn read(&self, buffer: &wgpu::Buffer, bytes: u64) -> Result<Vec<u8>> {
        if bytes == 0 {
            return Ok(Vec::new());
        }
        let size = bytes.next_multiple_of(4);
        let staging = self.guarded("allocating a readback buffer", || {
            self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("readback"),
                size,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        })?;
        let mut encoder = self.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, size);
        self.submit("copying results back", encoder)?;
        let (tx, rx) = std::sync::mpsc::channel();
        staging.slice(..).map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.wait("mapping results", None)?;
        let mapped = rx.recv_timeout(self.timeout).map_err(|_| Error::Timeout {
            adapter: self.info.name.clone(),
            during: "mapping results",
            seconds: self.timeout.as_secs(),
        })?;
        mapped.map_err(|e| Error::Device {
            adapter: self.info.name.clone(),
            during: "mapping results",
            message: e.to_string(),
        })?;
        let view = staging.slice(..).get_mapped_range().map_err(|e| Error::Device {
            adapter: self.info.name.clone(),
            during: "mapping results",
            message: e.to_string(),
        })?;
        let out = view[..bytes as usize].to_vec();
        drop(view);
        staging.unmap();
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn info(name: &str, device_type: wgpu::DeviceType) -> wgpu::AdapterInfo {
        wgpu::AdapterInfo {
            name: name.into(),
            vendor: 0,
            device: 0,
            device_type,
            device_pci_bus_id: String::new(),
            driver: String::new(),
            driver_info: String::new(),
            backend: wgpu::Backend::Vulkan,
            subgroup_min_size: 0,
            subgroup_max_size: 0,
            transient_saves_memory: None,
            limit_bucket: None,
        }
    }

    #[test]
    fn default_choice_prefers_discrete_then_integrated_then_cpu() {
        use wgpu::DeviceType::*;
        let infos =
            [info("llvmpipe", Cpu), info("Intel UHD", IntegratedGpu), info("RTX", DiscreteGpu)];
        assert_eq!(select(&infos, None).unwrap(), 2);
        assert_eq!(select(&infos[..2], None).unwrap(), 1);
        assert_eq!(select(&infos[..1], None).unwrap(), 0);
        assert!(matches!(select(&[], None), Err(Error::NoAdapter)));
    }

    #[test]
    fn selector_is_an_index_or_a_name_substring() {
        use wgpu::DeviceType::*;
        let infos = [info("llvmpipe (LLVM 15)", Cpu), info("NVIDIA RTX", DiscreteGpu)];
        assert_eq!(select(&infos, Some("0")).unwrap(), 0);
        assert_eq!(select(&infos, Some("LLVMPIPE")).unwrap(), 0);
        assert_eq!(select(&infos, Some("rtx")).unwrap(), 1);
        assert_eq!(select(&infos, Some(" ")).unwrap(), 1, "blank means default");
        let err = select(&infos, Some("7")).unwrap_err().to_string();
        assert!(err.contains("\"7\"") && err.contains("llvmpipe"), "{err}");
        assert!(matches!(select(&infos, Some("radeon")), Err(Error::AdapterNotFound { .. })));
    }
}
