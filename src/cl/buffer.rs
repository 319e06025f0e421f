//! Typed device buffers: allocation (on a CPU device, a buffer of a huge page or more lives in
//! host memory advised for huge pages, `host_memory`), blocking writes and read-backs, writes
//! through a mapping, and clears.
#![allow(unsafe_code)]

use super::host_memory::{HUGE_PAGE, HostPages};
use super::{ClError, Device, call_err};
use bytemuck::Pod;
use opencl3::memory::{CL_MEM_READ_WRITE, CL_MEM_USE_HOST_PTR, ClMem};
use opencl3::types::CL_BLOCKING;
use std::ptr;

/// A typed device buffer of `len` elements (at least one is allocated: OpenCL has no empty
/// buffers).
pub struct Buffer<T: Pod> {
    inner: opencl3::memory::Buffer<T>,
    len: usize,
}

/// Checks one allocation against the device's `CL_DEVICE_MAX_MEM_ALLOC_SIZE` (`max_alloc`)
/// and `CL_DEVICE_GLOBAL_MEM_SIZE` (`global`) before it is asked for: a driver may fail a
/// larger one with an assertion (PoCL, a 16384² film) rather than an error code.
fn fits_one_buffer(bytes: u64, max_alloc: Option<u64>, global: Option<u64>) -> Result<(), String> {
    let gb = |b: u64| b as f64 / 1e9;
    for (limit, what) in [(max_alloc, "in one buffer"), (global, "in all")] {
        if let Some(limit) = limit
            && bytes > limit
        {
            return Err(format!(
                "a device buffer of {bytes} bytes ({:.2} GB) is more than the device allows \
                 {what} ({limit} bytes, {:.2} GB)",
                gb(bytes),
                gb(limit)
            ));
        }
    }
    Ok(())
}

impl<T: Pod> Buffer<T> {
    /// An uninitialised buffer of `len` elements. On a CPU device a buffer of a huge page or
    /// more lives in host memory advised for huge pages (see `HostPages`).
    pub fn new(device: &Device, len: usize) -> Result<Self, ClError> {
        let bytes = len
            .max(1)
            .checked_mul(std::mem::size_of::<T>())
            .ok_or_else(|| ClError::Device(format!("a buffer of {len} elements overflows")))?;
        fits_one_buffer(
            bytes as u64,
            device.device.max_mem_alloc_size().ok(),
            device.device.global_mem_size().ok(),
        )
        .map_err(ClError::Device)?;
        let host = if bytes >= HUGE_PAGE && device.is_cpu() {
            HostPages::new(bytes)
        } else {
            None
        };
        let (flags, host_ptr) = match &host {
            Some(pages) => (CL_MEM_READ_WRITE | CL_MEM_USE_HOST_PTR, pages.ptr.cast()),
            None => (CL_MEM_READ_WRITE, ptr::null_mut()),
        };
        // SAFETY: the size is at least one element; a host pointer, when passed, points to
        // `bytes` bytes that live until the driver destroys the buffer (HostPages::free_with).
        let inner = unsafe {
            opencl3::memory::Buffer::<T>::create(&device.context, flags, len.max(1), host_ptr)
        }
        .map_err(|e| ClError::Call {
            stage: format!("allocating {bytes} bytes"),
            message: e.to_string(),
        })?;
        if let Some(pages) = host {
            pages.free_with(inner.get());
        }
        Ok(Self { inner, len })
    }

    /// A buffer holding a copy of `data`.
    pub fn from_slice(device: &Device, data: &[T]) -> Result<Self, ClError> {
        let mut b = Self::new(device, data.len())?;
        b.write(device, data)?;
        Ok(b)
    }

    /// Number of elements.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the buffer holds no elements.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Size in bytes on the device.
    pub fn bytes(&self) -> usize {
        self.len.max(1) * std::mem::size_of::<T>()
    }

    /// Copies `data` to the start of the buffer (blocking); the bytes written.
    pub fn write(&mut self, device: &Device, data: &[T]) -> Result<usize, ClError> {
        self.write_at(device, 0, data)
    }

    /// Copies `data` into the buffer from element `at` on (blocking): an update in place, no
    /// new allocation. The bytes written.
    pub fn write_at(&mut self, device: &Device, at: usize, data: &[T]) -> Result<usize, ClError> {
        assert!(
            at + data.len() <= self.len.max(1),
            "write past the end of a buffer"
        );
        if data.is_empty() {
            return Ok(0);
        }
        let offset = at * std::mem::size_of::<T>();
        // SAFETY: the slice fits the buffer from `at` on (checked above); the write is blocking.
        unsafe {
            device
                .queue
                .enqueue_write_buffer(&mut self.inner, CL_BLOCKING, offset, data, &[])
                .map_err(call_err("uploading a buffer"))?;
        }
        Ok(std::mem::size_of_val(data))
    }

    /// Writes every element through a mapping of the whole buffer (blocking): `fill` gets the
    /// buffer's elements, of undefined contents, to write all of them. On a CPU device the
    /// mapping is the buffer's own memory, so that a large array is written once, in place,
    /// with no host copy of it beside the buffer.
    pub fn fill_mapped<R>(
        &mut self,
        device: &Device,
        fill: impl FnOnce(&mut [T]) -> R,
    ) -> Result<R, ClError> {
        let bytes = self.bytes();
        let mut ptr: opencl3::types::cl_mem = ptr::null_mut();
        // SAFETY: maps the whole allocation for writing and waits for it; the slice made of
        // it covers exactly `len.max(1)` elements of a `Pod` type (any bits are a value) and
        // is gone before the unmap below.
        let result = unsafe {
            device
                .queue
                .enqueue_map_buffer(
                    &self.inner,
                    CL_BLOCKING,
                    opencl3::memory::CL_MAP_WRITE_INVALIDATE_REGION,
                    0,
                    bytes,
                    &mut ptr,
                    &[],
                )
                .map_err(call_err("mapping a buffer"))?;
            let elements = std::slice::from_raw_parts_mut(ptr.cast::<T>(), self.len.max(1));
            let result = fill(elements);
            device
                .queue
                .enqueue_unmap_mem_object(self.inner.get(), ptr, &[])
                .map_err(call_err("unmapping a buffer"))?
                .wait()
                .map_err(call_err("unmapping a buffer"))?;
            result
        };
        Ok(result)
    }

    /// Reads the whole buffer back (blocking).
    pub fn read(&self, device: &Device) -> Result<Vec<T>, ClError> {
        let mut out = Vec::new();
        self.read_into(device, &mut out)?;
        Ok(out)
    }

    /// [`Buffer::read`] into `out`, whose allocation is reused when it is large enough (a
    /// frame's film read back without a fresh allocation).
    pub fn read_into(&self, device: &Device, out: &mut Vec<T>) -> Result<(), ClError> {
        out.truncate(self.len);
        out.resize(self.len, T::zeroed());
        if self.len == 0 {
            return Ok(());
        }
        // SAFETY: `out` has exactly the buffer's length; the read is blocking.
        unsafe {
            device
                .queue
                .enqueue_read_buffer(&self.inner, CL_BLOCKING, 0, out, &[])
                .map_err(call_err("reading a buffer back"))?;
        }
        Ok(())
    }

    /// Sets every element to zero.
    pub fn clear(&mut self, device: &Device) -> Result<(), ClError> {
        let bytes = self.bytes();
        // SAFETY: fills the whole allocation with a zero pattern of one element.
        unsafe {
            device
                .queue
                .enqueue_fill_buffer(&mut self.inner, &[T::zeroed()], 0, bytes, &[])
                .map_err(call_err("clearing a buffer"))?;
        }
        Ok(())
    }

    /// The OpenCL memory object, for the kernel wrappers' arguments.
    pub(super) fn mem(&self) -> opencl3::types::cl_mem {
        self.inner.get()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cl::DeviceChoice;

    #[test]
    fn a_buffer_past_the_device_limits_is_refused_naming_both_sizes() {
        assert!(fits_one_buffer(1 << 30, Some(1 << 30), Some(1 << 34)).is_ok());
        assert!(fits_one_buffer(1 << 30, None, None).is_ok());
        let e = fits_one_buffer((1 << 30) + 1, Some(1 << 30), Some(1 << 34)).unwrap_err();
        assert!(
            e.contains("1073741825 bytes") && e.contains("1073741824 bytes"),
            "{e}"
        );
        assert!(e.contains("in one buffer"), "{e}");
        let e = fits_one_buffer(1 << 35, None, Some(1 << 34)).unwrap_err();
        assert!(e.contains("in all"), "{e}");
    }

    #[test]
    fn a_cpu_devices_large_buffer_keeps_what_is_written() {
        let Ok(device) = Device::open(&DeviceChoice::Cpu) else {
            return; // no CPU device here (a GPU-only machine)
        };
        let len = HUGE_PAGE; // 8 MiB of u32: in host pages
        let data: Vec<u32> = (0..len as u32)
            .map(|i| i.wrapping_mul(2654435761))
            .collect();
        let mut b = Buffer::from_slice(&device, &data).expect("the buffer is made");
        assert_eq!(b.read(&device).expect("it reads back"), data);
        b.write_at(&device, 5, &[7, 8, 9])
            .expect("a write in place");
        let back = b.read(&device).expect("it reads back");
        assert_eq!(&back[4..9], &[data[4], 7, 8, 9, data[8]]);
        b.clear(&device).expect("it clears");
        assert!(
            b.read(&device)
                .expect("it reads back")
                .iter()
                .all(|&x| x == 0)
        );
        // Buffers come and go (the destructor callback frees each one's pages).
        for _ in 0..8 {
            drop(Buffer::<u32>::new(&device, 3 * len).expect("a buffer"));
        }
    }

    #[test]
    fn reading_into_a_kept_vector_reuses_its_memory_and_reads_every_element() {
        let Ok(device) = Device::open(&DeviceChoice::Cpu) else {
            return; // no CPU device here (a GPU-only machine)
        };
        let data: Vec<u32> = (0..1000u32).map(|i| i * 3 + 1).collect();
        let b = Buffer::from_slice(&device, &data).expect("the buffer is made");
        // Longer than the buffer, with other contents: cut to its length and overwritten.
        let mut out = vec![9u32; 1500];
        let at = out.as_ptr();
        b.read_into(&device, &mut out).expect("it reads back");
        assert_eq!(out, data);
        assert_eq!(out.as_ptr(), at, "the vector's allocation is kept");
        // Shorter: grown to the buffer's length.
        let mut short = vec![5u32; 10];
        b.read_into(&device, &mut short).expect("it reads back");
        assert_eq!(short, data);
    }
}
