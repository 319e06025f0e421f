//! Platform and device discovery, device choice, and the one context and in-order queue.

use super::{ClError, call_err};
use opencl3::command_queue::{CL_QUEUE_PROFILING_ENABLE, CommandQueue};
use opencl3::context::Context;
use opencl3::device::{CL_DEVICE_TYPE_ALL, CL_DEVICE_TYPE_GPU, Device as ClDevice};
use opencl3::platform::get_platforms;
use std::str::FromStr;

/// How the user picks a device (`--device gpu|cpu|INDEX`, or `PENUMBRA_DEVICE`).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum DeviceChoice {
    /// The first GPU, else the first CPU (the default).
    #[default]
    Auto,
    /// The first GPU.
    Gpu,
    /// The first CPU device.
    Cpu,
    /// The device with this index in `penumbra devices`.
    Index(usize),
}

impl FromStr for DeviceChoice {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.trim().to_ascii_lowercase().as_str() {
            "" | "auto" => Ok(Self::Auto),
            "gpu" => Ok(Self::Gpu),
            "cpu" => Ok(Self::Cpu),
            other => other.parse().map(Self::Index).map_err(|_| {
                format!("device '{s}' is not 'gpu', 'cpu' or an index from `penumbra devices`")
            }),
        }
    }
}

impl DeviceChoice {
    /// The device among `devices` that the choice names.
    fn pick<'a>(&self, devices: &'a [DeviceInfo]) -> Option<&'a DeviceInfo> {
        match self {
            Self::Auto => devices
                .iter()
                .find(|d| d.is_gpu)
                .or_else(|| devices.first()),
            Self::Gpu => devices.iter().find(|d| d.is_gpu),
            Self::Cpu => devices.iter().find(|d| !d.is_gpu),
            Self::Index(i) => devices.get(*i),
        }
    }

    /// The choice from the command line, else from `PENUMBRA_DEVICE`, else automatic.
    pub fn from_arg_or_env(arg: Option<&str>) -> Result<Self, String> {
        match arg {
            Some(a) => a.parse(),
            None => match std::env::var("PENUMBRA_DEVICE") {
                Ok(v) => v.parse().map_err(|e| format!("PENUMBRA_DEVICE: {e}")),
                Err(_) => Ok(Self::Auto),
            },
        }
    }
}

/// Which devices render (`--device`): one device, every device, or a list of indices.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum DeviceSet {
    /// One device.
    One(DeviceChoice),
    /// Every device `penumbra devices` lists (`all`).
    All,
    /// These indices of `penumbra devices`, in this order (`0,2`); an index may repeat, which
    /// opens the device once more (its own context and queue).
    List(Vec<usize>),
}

impl FromStr for DeviceSet {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        if s.trim().eq_ignore_ascii_case("all") {
            return Ok(Self::All);
        }
        if !s.contains(',') {
            return s.parse().map(Self::One).map_err(|_| {
                format!(
                    "device '{s}' is not 'gpu', 'cpu', 'all', an index from `penumbra devices` \
                     or a list of indices (0,2)"
                )
            });
        }
        s.split(',')
            .map(|item| {
                item.trim().parse().map_err(|_| {
                    format!(
                        "device list '{s}': '{}' is not an index from `penumbra devices`",
                        item.trim()
                    )
                })
            })
            .collect::<Result<_, _>>()
            .map(Self::List)
    }
}

impl DeviceSet {
    /// The choice from the command line, else from `PENUMBRA_DEVICE`, else automatic.
    pub fn from_arg_or_env(arg: Option<&str>) -> Result<Self, String> {
        match arg {
            Some(a) => a.parse(),
            None => match std::env::var("PENUMBRA_DEVICE") {
                Ok(v) => v.parse().map_err(|e| format!("PENUMBRA_DEVICE: {e}")),
                Err(_) => Ok(Self::One(DeviceChoice::Auto)),
            },
        }
    }

    /// The devices of the set among `devices` (`penumbra devices`' list), as indices; an index
    /// that is not in it is one line naming it and the devices there are.
    pub fn indices(&self, devices: &[DeviceInfo]) -> Result<Vec<usize>, String> {
        match self {
            Self::One(choice) => (choice.pick(devices))
                .map(|d| vec![d.index])
                .ok_or_else(|| no_match(choice, devices)),
            Self::All => Ok(devices.iter().map(|d| d.index).collect()),
            Self::List(list) => match list.iter().find(|&&i| i >= devices.len()) {
                Some(&i) => Err(no_match(&DeviceChoice::Index(i), devices)),
                None => Ok(list.clone()),
            },
        }
    }

    /// The one device a single-device command (the viewer) takes from the set: the device
    /// itself, else the set's first GPU, else its first device.
    pub fn primary(&self) -> DeviceChoice {
        match self {
            Self::One(choice) => choice.clone(),
            Self::All => DeviceChoice::Auto,
            Self::List(list) => {
                let gpu = list_devices().ok().and_then(|devices| {
                    list.iter()
                        .copied()
                        .find(|&i| devices.get(i).is_some_and(|d| d.is_gpu))
                });
                DeviceChoice::Index(gpu.unwrap_or(list[0]))
            }
        }
    }
}

/// The line that says no device among `devices` matches `choice`, naming those there are.
fn no_match(choice: &DeviceChoice, devices: &[DeviceInfo]) -> String {
    let names: Vec<String> = devices
        .iter()
        .map(|d| format!("{}: {}", d.index, d.name))
        .collect();
    format!(
        "no OpenCL device matches {choice:?} (devices: {})",
        names.join(", ")
    )
}

/// One OpenCL device as `penumbra devices` lists it.
#[derive(Clone, Debug)]
pub struct DeviceInfo {
    /// Index `--device` takes.
    pub index: usize,
    /// Platform name.
    pub platform: String,
    /// Device name.
    pub name: String,
    /// Whether it is a GPU.
    pub is_gpu: bool,
    /// OpenCL version string.
    pub version: String,
    /// Driver version.
    pub driver: String,
    /// Compute units.
    pub compute_units: u32,
    /// Global memory in bytes.
    pub memory: u64,
    /// The device handle.
    pub handle: ClDevice,
}

/// Every device of every platform, in platform order.
pub fn list_devices() -> Result<Vec<DeviceInfo>, ClError> {
    let platforms = get_platforms().map_err(|e| {
        ClError::Device(format!(
            "no OpenCL platform found ({e}); install an OpenCL driver such as pocl-opencl-icd"
        ))
    })?;
    let mut out = Vec::new();
    for platform in platforms {
        let pname = platform.name().unwrap_or_default();
        let Ok(ids) = platform.get_devices(CL_DEVICE_TYPE_ALL) else {
            continue;
        };
        for id in ids {
            let d = ClDevice::new(id);
            out.push(DeviceInfo {
                index: out.len(),
                platform: pname.clone(),
                name: d.name().unwrap_or_default().trim().to_string(),
                is_gpu: d.dev_type().is_ok_and(|t| t & CL_DEVICE_TYPE_GPU != 0),
                version: d.version().unwrap_or_default(),
                driver: d.driver_version().unwrap_or_default(),
                compute_units: d.max_compute_units().unwrap_or(0),
                memory: d.global_mem_size().unwrap_or(0),
                handle: d,
            });
        }
    }
    if out.is_empty() {
        return Err(ClError::Device(
            "no OpenCL device found; install an OpenCL driver such as pocl-opencl-icd".into(),
        ));
    }
    Ok(out)
}

/// The chosen device with its context and in-order profiling queue.
pub struct Device {
    /// What was chosen.
    pub info: DeviceInfo,
    /// The device.
    pub device: ClDevice,
    /// The context.
    pub context: Context,
    /// The in-order queue with profiling enabled.
    pub queue: CommandQueue,
}

impl Device {
    /// Whether the device is a CPU (CL_DEVICE_TYPE_CPU): the megakernel, flushed denormals and
    /// the CPU's `--bvh auto` rule are chosen by it.
    pub fn is_cpu(&self) -> bool {
        self.device
            .dev_type()
            .is_ok_and(|t| t & opencl3::device::CL_DEVICE_TYPE_CPU != 0)
    }

    /// Whether the device's OpenCL reports `extension` (e.g. `cl_nv_compiler_options`).
    pub fn has_extension(&self, extension: &str) -> bool {
        self.device
            .extensions()
            .is_ok_and(|e| e.split_whitespace().any(|x| x == extension))
    }

    /// Opens the device the choice names.
    pub fn open(choice: &DeviceChoice) -> Result<Self, ClError> {
        let _setup = super::CL_SETUP.lock().unwrap_or_else(|e| e.into_inner());
        let devices = list_devices()?;
        let info = (choice.pick(&devices).cloned())
            .ok_or_else(|| ClError::Device(no_match(choice, &devices)))?;
        let device = info.handle;
        let context = Context::from_device(&device).map_err(call_err("creating the context"))?;
        #[allow(deprecated)] // clCreateCommandQueue keeps OpenCL 1.2 devices working.
        let queue = CommandQueue::create_default(&context, CL_QUEUE_PROFILING_ENABLE)
            .map_err(call_err("creating the queue"))?;
        Ok(Self {
            info,
            device,
            context,
            queue,
        })
    }

    /// "name (platform)" for summaries and the overlay.
    pub fn description(&self) -> String {
        format!("{} ({})", self.info.name, self.info.platform)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_device_choices() {
        assert_eq!("gpu".parse::<DeviceChoice>(), Ok(DeviceChoice::Gpu));
        assert_eq!("CPU".parse::<DeviceChoice>(), Ok(DeviceChoice::Cpu));
        assert_eq!("2".parse::<DeviceChoice>(), Ok(DeviceChoice::Index(2)));
        assert!("fastest".parse::<DeviceChoice>().is_err());
    }

    #[test]
    fn parses_device_sets() {
        assert_eq!("all".parse::<DeviceSet>(), Ok(DeviceSet::All));
        assert_eq!(
            "gpu".parse::<DeviceSet>(),
            Ok(DeviceSet::One(DeviceChoice::Gpu))
        );
        assert_eq!(
            "0, 2,0".parse::<DeviceSet>(),
            Ok(DeviceSet::List(vec![0, 2, 0]))
        );
        let e = "0,x".parse::<DeviceSet>().unwrap_err();
        assert!(e.contains("'x' is not an index"), "{e}");
        assert!("0,".parse::<DeviceSet>().is_err());
    }
}
