//! Adapters: listing what wgpu finds, the default preference and the `VOXLOD_ADAPTER`
//! selector (an index or a case-insensitive name substring).

use crate::{Error, Result};

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

/// The adapters wgpu finds, in enumeration order (not yet opened).
pub(super) fn enumerate() -> Vec<wgpu::Adapter> {
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
