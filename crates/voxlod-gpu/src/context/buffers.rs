//! Buffers: storage and uniform buffers checked against the device's limits before they are
//! allocated, and the guarded copy back to the host.

use crate::{Context, Error, Result};

impl Context {
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

    /// A storage buffer holding the array `values`, or one zeroed element when `values` is
    /// empty: a WGSL array binding holds at least one element (the kernels then read none).
    pub fn storage_array<T: bytemuck::Pod>(
        &self,
        what: &'static str,
        values: &[T],
    ) -> Result<wgpu::Buffer> {
        if values.is_empty() {
            self.storage_init(what, bytemuck::bytes_of(&T::zeroed()))
        } else {
            self.storage_init(what, bytemuck::cast_slice(values))
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
