//! Typed wrappers over the kernels and device buffers: the only `unsafe` code and the only
//! positional kernel arguments in penumbra. Each wrapper takes exactly the kernel's arguments,
//! launches it under its stage name and returns the profiling event.
#![allow(unsafe_code)]

use super::types::*;
use super::{ClError, Gpu, KernelFeatures, build_program, build_test_program, call_err};
use bytemuck::Pod;
use opencl3::event::Event;
use opencl3::kernel::{ExecuteKernel, Kernel};
use opencl3::memory::{CL_MEM_READ_WRITE, CL_MEM_USE_HOST_PTR, ClMem};
use opencl3::types::CL_BLOCKING;
use std::ptr;
use std::sync::OnceLock;
use std::sync::atomic::Ordering;

/// A typed device buffer of `len` elements (at least one is allocated: OpenCL has no empty
/// buffers).
pub struct Buffer<T: Pod> {
    inner: opencl3::memory::Buffer<T>,
    len: usize,
}

impl<T: Pod> Buffer<T> {
    /// An uninitialised buffer of `len` elements. On a CPU device a buffer of a huge page or
    /// more lives in host memory advised for huge pages (see [`HostPages`]).
    pub fn new(gpu: &Gpu, len: usize) -> Result<Self, ClError> {
        let bytes = len.max(1) * std::mem::size_of::<T>();
        let host = if bytes >= HUGE_PAGE && gpu.is_cpu() {
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
            opencl3::memory::Buffer::<T>::create(&gpu.context, flags, len.max(1), host_ptr)
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
    pub fn from_slice(gpu: &Gpu, data: &[T]) -> Result<Self, ClError> {
        let mut b = Self::new(gpu, data.len())?;
        b.write(gpu, data)?;
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

    /// Copies `data` to the start of the buffer (blocking).
    pub fn write(&mut self, gpu: &Gpu, data: &[T]) -> Result<(), ClError> {
        self.write_at(gpu, 0, data)
    }

    /// Copies `data` into the buffer from element `at` on (blocking): an update in place, no
    /// new allocation.
    pub fn write_at(&mut self, gpu: &Gpu, at: usize, data: &[T]) -> Result<(), ClError> {
        assert!(
            at + data.len() <= self.len.max(1),
            "write past the end of a buffer"
        );
        if data.is_empty() {
            return Ok(());
        }
        let offset = at * std::mem::size_of::<T>();
        // SAFETY: the slice fits the buffer from `at` on (checked above); the write is blocking.
        unsafe {
            gpu.queue
                .enqueue_write_buffer(&mut self.inner, CL_BLOCKING, offset, data, &[])
                .map_err(call_err("uploading a buffer"))?;
        }
        Ok(())
    }

    /// Writes every element through a mapping of the whole buffer (blocking): `fill` gets the
    /// buffer's elements, of undefined contents, to write all of them. On a CPU device the
    /// mapping is the buffer's own memory, so that a large array is written once, in place,
    /// with no host copy of it beside the buffer.
    pub fn fill_mapped<R>(
        &mut self,
        gpu: &Gpu,
        fill: impl FnOnce(&mut [T]) -> R,
    ) -> Result<R, ClError> {
        let bytes = self.bytes();
        let mut ptr: opencl3::types::cl_mem = ptr::null_mut();
        // SAFETY: maps the whole allocation for writing and waits for it; the slice made of
        // it covers exactly `len.max(1)` elements of a `Pod` type (any bits are a value) and
        // is gone before the unmap below.
        let result = unsafe {
            gpu.queue
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
            gpu.queue
                .enqueue_unmap_mem_object(self.inner.get(), ptr, &[])
                .map_err(call_err("unmapping a buffer"))?
                .wait()
                .map_err(call_err("unmapping a buffer"))?;
            result
        };
        Ok(result)
    }

    /// Reads the whole buffer back (blocking).
    pub fn read(&self, gpu: &Gpu) -> Result<Vec<T>, ClError> {
        let mut out = Vec::new();
        self.read_into(gpu, &mut out)?;
        Ok(out)
    }

    /// [`Buffer::read`] into `out`, whose allocation is reused when it is large enough (a
    /// frame's film read back without a fresh allocation).
    pub fn read_into(&self, gpu: &Gpu, out: &mut Vec<T>) -> Result<(), ClError> {
        out.truncate(self.len);
        out.resize(self.len, T::zeroed());
        if self.len == 0 {
            return Ok(());
        }
        // SAFETY: `out` has exactly the buffer's length; the read is blocking.
        unsafe {
            gpu.queue
                .enqueue_read_buffer(&self.inner, CL_BLOCKING, 0, out, &[])
                .map_err(call_err("reading a buffer back"))?;
        }
        Ok(())
    }

    /// Sets every element to zero.
    pub fn clear(&mut self, gpu: &Gpu) -> Result<(), ClError> {
        let bytes = self.bytes();
        // SAFETY: fills the whole allocation with a zero pattern of one element.
        unsafe {
            gpu.queue
                .enqueue_fill_buffer(&mut self.inner, &[T::zeroed()], 0, bytes, &[])
                .map_err(call_err("clearing a buffer"))?;
        }
        Ok(())
    }

    fn mem(&self) -> opencl3::types::cl_mem {
        self.inner.get()
    }
}

/// The size of an x86-64 huge page (2 MiB), from which CPU devices' buffers use [`HostPages`].
const HUGE_PAGE: usize = 2 << 20;

/// Host memory for a CPU device's buffer, aligned to and advised for transparent huge pages.
/// PoCL runs kernels on a `CL_MEM_USE_HOST_PTR` buffer's own memory, and with 4 KiB pages the
/// traversal of a large scene misses the TLB on nearly every node and triangle it reads: the
/// 1 M-triangle bunnies render about 6 % faster per CPU second with huge pages
/// (docs/benchmarks.md). Linux gives huge pages to advised memory when
/// /sys/kernel/mm/transparent_hugepage/enabled is `madvise` (Debian's default) or `always`;
/// with `never` this is ordinary aligned memory.
/// Only the first [`HUGE_BUDGET`] bytes of live buffers are advised: on a machine whose memory
/// is fragmented Linux compacts memory to fault a huge page in (`defrag` `madvise`, Debian's
/// default), which cost about 4 s a GB on the development VM against 0.7 s for small pages, and
/// a 16 M-triangle scene's upload took 14 s instead of 5 s (docs/benchmarks.md, sixth
/// session). Scenes of up to about two million triangles keep their huge pages.
struct HostPages {
    ptr: *mut u8,
    len: usize,
    /// Whether the range was advised for huge pages (and counts in [`HUGE_BYTES`]).
    huge: bool,
}

/// The most bytes of CPU device buffers advised for huge pages at once (see [`HostPages`]).
const HUGE_BUDGET: usize = 512 << 20;

/// From this size on, [`HostPages`] are faulted in at once by `MADV_POPULATE_WRITE`, in
/// parallel pieces, instead of page by page as they are first written.
const POPULATE_FROM: usize = 64 << 20;

/// Faults `len` bytes from `start` (a fresh mapping of whole huge pages) in for writing, a
/// piece of [`POPULATE_PIECE`] bytes a task: `MADV_POPULATE_WRITE` (Linux 5.14) takes a page
/// fault's work without the fault. Where it is not supported (or fails) nothing happens, and
/// the pages are faulted in as they are first written.
#[cfg(target_os = "linux")]
fn populate(start: usize, len: usize) {
    use rayon::prelude::*;
    (0..len.div_ceil(POPULATE_PIECE))
        .into_par_iter()
        .for_each(|k| {
            let at = start + k * POPULATE_PIECE;
            let n = POPULATE_PIECE.min(start + len - at);
            // SAFETY: [at, at + n) lies in the caller's mapping; populating changes no contents.
            unsafe { libc::madvise(at as *mut std::ffi::c_void, n, libc::MADV_POPULATE_WRITE) };
        });
}

/// `file` mapped read-only into memory: a large glTF binary is read in place, with no copy in
/// fresh memory (1.5 GB at 64 M triangles; `crate::scene::Bytes`).
pub fn map_file(file: &std::fs::File) -> std::io::Result<memmap2::Mmap> {
    // SAFETY: the mapping is private and read-only; its contents change only if another
    // process writes the file while the scene loads (the bytes are then what the file holds,
    // as with a read racing a writer), and a file truncated meanwhile would fault, the one
    // risk `Mmap` documents, which the loader accepts for files of 64 MiB and more.
    unsafe { memmap2::Mmap::map(file) }
}

/// While a scene opens, blocks of at least this size are mapped fresh and unmapped when freed
/// (glibc's `M_MMAP_THRESHOLD`), so that the loader's and the builders' working arrays go back
/// to the system at once. glibc's default starts at 128 KiB and rises to the largest mapped
/// block freed so far: after a scene's bounds and first BVH build, arrays of several MB came
/// from the heaps of the threads that had freed them, stayed resident there, and new ones were
/// placed beside them (a 1 M-triangle room of 144 K distinct triangles: 155–220 B of peak
/// memory a distinct triangle, growing with every rebuild, against 132–139 B so). 1 MiB saves
/// a few bytes more but faults in 10 % more pages opening a 64 M-triangle scene.
const OPENING_MMAP_THRESHOLD: i32 = 2 << 20;

/// While a scene opens, the heap's free top is given back above this (glibc's default): at
/// twice the mapping threshold, as its dynamic rule would set it, the same room took 151–164 B.
const OPENING_TRIM_THRESHOLD: i32 = 128 << 10;

/// Between openings: glibc's own ceiling for its dynamic threshold (32 MiB on 64-bit), which its
/// default reaches as a session goes on, so that what frames allocate and free again (display
/// images, the driver's own blocks) is reused from the heap rather than faulted in afresh.
const STEADY_MMAP_THRESHOLD: i32 = 32 << 20;

/// Openings in progress ([`OpeningMemory`]).
static OPENINGS: std::sync::Mutex<usize> = std::sync::Mutex::new(0);

/// Sets glibc's mapping and heap-trim thresholds; nothing where the user set one
/// (`MALLOC_MMAP_THRESHOLD_`) or the allocator is not glibc's.
fn set_malloc_thresholds(mmap: i32, trim: i32) {
    if std::env::var_os("MALLOC_MMAP_THRESHOLD_").is_some() {
        return;
    }
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: `mallopt` only changes the allocator's policy for later calls.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, mmap);
        libc::mallopt(libc::M_TRIM_THRESHOLD, trim);
    }
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    let _ = (mmap, trim);
}

/// The allocator's policy while a scene opens (loading, the framing probe, BVH builds, the
/// upload), held as a guard, nested or on several threads: large blocks are mapped while any
/// opening runs ([`OPENING_MMAP_THRESHOLD`]); when the last one ends the steady policy returns
/// ([`STEADY_MMAP_THRESHOLD`], the heap trimmed above twice that, as glibc's dynamic rule
/// does) and what the allocator holds free is given back (`malloc_trim`).
pub struct OpeningMemory(());

impl OpeningMemory {
    /// Starts an opening.
    pub fn begin() -> Self {
        let mut n = OPENINGS.lock().unwrap_or_else(|e| e.into_inner());
        if *n == 0 {
            set_malloc_thresholds(OPENING_MMAP_THRESHOLD, OPENING_TRIM_THRESHOLD);
        }
        *n += 1;
        OpeningMemory(())
    }
}

impl Drop for OpeningMemory {
    fn drop(&mut self) {
        let mut n = OPENINGS.lock().unwrap_or_else(|e| e.into_inner());
        *n -= 1;
        if *n == 0 {
            set_malloc_thresholds(STEADY_MMAP_THRESHOLD, 2 * STEADY_MMAP_THRESHOLD);
            #[cfg(all(target_os = "linux", target_env = "gnu"))]
            // SAFETY: `malloc_trim` only returns free pages of the allocator's heaps.
            unsafe {
                libc::malloc_trim(0);
            }
        }
    }
}

/// The piece of a [`populate`] task (a multiple of [`HUGE_PAGE`]).
const POPULATE_PIECE: usize = 32 << 20;

/// Bytes of live [`HostPages`] advised for huge pages.
static HUGE_BYTES: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

impl HostPages {
    /// `bytes` bytes (rounded up to whole huge pages) of a fresh anonymous mapping aligned to a
    /// huge page, advised before they are first touched, so that the first write faults whole
    /// huge pages in (memory the allocator hands back again may already be backed by small
    /// pages); `None` where they cannot be mapped (the driver then allocates the buffer).
    #[cfg(target_os = "linux")]
    fn new(bytes: usize) -> Option<Self> {
        let len = bytes.next_multiple_of(HUGE_PAGE);
        let mapped = len + HUGE_PAGE;
        // SAFETY: a new private anonymous mapping; no existing memory is touched.
        let base = unsafe {
            libc::mmap(
                ptr::null_mut(),
                mapped,
                libc::PROT_READ | libc::PROT_WRITE,
                libc::MAP_PRIVATE | libc::MAP_ANONYMOUS,
                -1,
                0,
            )
        };
        if base == libc::MAP_FAILED {
            return None;
        }
        let start = base as usize;
        let aligned = start.next_multiple_of(HUGE_PAGE);
        let (head, tail) = (aligned - start, start + mapped - (aligned + len));
        // SAFETY: the slack before and after the aligned range is part of this mapping and
        // unused.
        unsafe {
            if head > 0 {
                libc::munmap(base, head);
            }
            if tail > 0 {
                libc::munmap((aligned + len) as *mut std::ffi::c_void, tail);
            }
        }
        let huge = HUGE_BYTES
            .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |used| {
                (used + len <= HUGE_BUDGET).then_some(used + len)
            })
            .is_ok();
        if huge {
            // SAFETY: the aligned range is this mapping's; the advice changes no contents.
            unsafe { libc::madvise(aligned as *mut std::ffi::c_void, len, libc::MADV_HUGEPAGE) };
        }
        if len >= POPULATE_FROM {
            populate(aligned, len);
        }
        Some(Self {
            ptr: aligned as *mut u8,
            len,
            huge,
        })
    }

    /// Elsewhere the driver allocates every buffer itself.
    #[cfg(not(target_os = "linux"))]
    fn new(_bytes: usize) -> Option<Self> {
        None
    }

    /// Hands the memory to buffer `mem`, which uses it until the driver destroys the buffer:
    /// it is unmapped then, by the buffer's destructor callback. Should the callback not be
    /// accepted, the memory is leaked rather than unmapped under the buffer.
    fn free_with(self, mem: opencl3::types::cl_mem) {
        extern "C" fn free_pages(_mem: opencl3::types::cl_mem, pages: *mut std::ffi::c_void) {
            // SAFETY: `pages` is the Box::into_raw below, handed to this callback alone, which
            // the driver calls once, after the last use of the buffer's memory.
            drop(unsafe { Box::from_raw(pages.cast::<HostPages>()) });
        }
        let pages = Box::into_raw(Box::new(self));
        // SAFETY: `mem` is a live buffer; the callback takes ownership of `pages`.
        let set = unsafe {
            opencl3::memory::set_mem_object_destructor_callback(mem, free_pages, pages.cast())
        };
        if set.is_err() {
            log::warn!("a buffer's host memory cannot be freed with it and is kept");
        }
    }
}

impl Drop for HostPages {
    fn drop(&mut self) {
        if self.huge {
            HUGE_BYTES.fetch_sub(self.len, Ordering::Relaxed);
        }
        #[cfg(target_os = "linux")]
        // SAFETY: the range was mapped by HostPages::new and is unmapped once, here.
        unsafe {
            libc::munmap(self.ptr.cast(), self.len);
        }
    }
}

/// The path tracer's wavefront stages, each one kernel, in launch order (`render::wavefront`
/// launches them; the name is the kernel's, and names the stage in errors and statistics).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Stage {
    /// Camera rays for every slot of the wave.
    Generate,
    /// Closest hits of the queued rays.
    Extend,
    /// Emission, a light sample and the next bounce.
    Shade,
    /// Shadow rays.
    Connect,
    /// Ray counts and the queue swap.
    Advance,
    /// The wave's samples into the film.
    Accumulate,
    /// Whole paths per work item, all bounces in one kernel (CPU devices; no other stage
    /// but `advance` runs then).
    Megakernel,
}

impl Stage {
    /// Every stage, in launch order.
    pub const ALL: [Stage; 7] = [
        Stage::Generate,
        Stage::Extend,
        Stage::Shade,
        Stage::Connect,
        Stage::Advance,
        Stage::Accumulate,
        Stage::Megakernel,
    ];

    /// The kernel's (and the stage's) name.
    pub fn name(self) -> &'static str {
        match self {
            Stage::Generate => "generate",
            Stage::Extend => "extend",
            Stage::Shade => "shade",
            Stage::Connect => "connect",
            Stage::Advance => "advance",
            Stage::Accumulate => "accumulate",
            Stage::Megakernel => "megakernel",
        }
    }
}

/// A launched kernel: its name and profiling event.
pub struct Launch {
    /// The kernel's name.
    pub stage: &'static str,
    /// The event, for profiling.
    pub event: Event,
}

impl Launch {
    /// Kernel run time in milliseconds from the profiling timestamps (waits for the event).
    pub fn millis(&self) -> f64 {
        let start = self.event.profiling_command_start().unwrap_or(0);
        let end = self.event.profiling_command_end().unwrap_or(start);
        end.saturating_sub(start) as f64 * 1e-6
    }
}

/// The built program with every production kernel.
pub struct Program {
    generate: Kernel,
    extend: Kernel,
    shade: Kernel,
    connect: Kernel,
    advance: Kernel,
    accumulate: Kernel,
    trace_closest: Kernel,
    trace_any: Kernel,
    trace_closest_wide: Kernel,
    trace_any_wide: Kernel,
    megakernel: Kernel,
    /// Work-group size of the megakernel (see `megakernel_local_size`).
    mega_local_size: usize,
    /// The test-only kernels, built on first use (never in production).
    tests: OnceLock<TestKernels>,
    local_size: usize,
    /// Features it was built with.
    pub features: KernelFeatures,
}

/// The kernels only tests use, from their own program (`build_test_program`).
struct TestKernels {
    probe_layout: Kernel,
    sample_texture_test: Kernel,
    sample_env_test: Kernel,
    bsdf_sample_test: Kernel,
    bsdf_eval_test: Kernel,
    spawn_test: Kernel,
}

fn kernel(program: &opencl3::program::Program, name: &str) -> Result<Kernel, ClError> {
    Kernel::create(program, name).map_err(|e| ClError::Build(format!("{name}: {e}")))
}

/// Rounds `n` up to a multiple of `local` (and at least one group).
fn global_size(n: usize, local: usize) -> usize {
    n.max(1).div_ceil(local) * local
}

impl Program {
    /// Builds the kernels for `features`.
    pub fn build(gpu: &Gpu, features: KernelFeatures) -> Result<Self, ClError> {
        let program = build_program(gpu, features)?;
        let k = |stage: Stage| kernel(&program, stage.name());
        let max_group = gpu.device.max_work_group_size().unwrap_or(64).max(1);
        Ok(Self {
            generate: k(Stage::Generate)?,
            extend: k(Stage::Extend)?,
            shade: k(Stage::Shade)?,
            connect: k(Stage::Connect)?,
            advance: k(Stage::Advance)?,
            accumulate: k(Stage::Accumulate)?,
            trace_closest: kernel(&program, "trace_closest")?,
            trace_any: kernel(&program, "trace_any")?,
            trace_closest_wide: kernel(&program, "trace_closest_wide")?,
            trace_any_wide: kernel(&program, "trace_any_wide")?,
            megakernel: k(Stage::Megakernel)?,
            mega_local_size: megakernel_local_size(features.lanes).min(max_group),
            tests: OnceLock::new(),
            local_size: 64.min(max_group),
            features,
        })
    }

    /// The test-only kernels for the same features, built the first time a test asks.
    fn tests(&self, gpu: &Gpu) -> Result<&TestKernels, ClError> {
        if let Some(t) = self.tests.get() {
            return Ok(t);
        }
        let program = build_test_program(gpu, self.features)?;
        let k = |name: &str| kernel(&program, name);
        let built = TestKernels {
            probe_layout: k("probe_layout")?,
            sample_texture_test: k("sample_texture_test")?,
            sample_env_test: k("sample_env_test")?,
            bsdf_sample_test: k("bsdf_sample_test")?,
            bsdf_eval_test: k("bsdf_eval_test")?,
            spawn_test: k("spawn_test")?,
        };
        Ok(self.tests.get_or_init(|| built))
    }

    fn run(
        &self,
        gpu: &Gpu,
        stage: &'static str,
        kernel: &Kernel,
        n: usize,
        set: impl FnOnce(&mut ExecuteKernel),
    ) -> Result<Launch, ClError> {
        self.run_local(gpu, stage, kernel, n, self.local_size, set)
    }

    fn run_local(
        &self,
        gpu: &Gpu,
        stage: &'static str,
        kernel: &Kernel,
        n: usize,
        local_size: usize,
        set: impl FnOnce(&mut ExecuteKernel),
    ) -> Result<Launch, ClError> {
        let mut exec = ExecuteKernel::new(kernel);
        set(&mut exec);
        exec.set_global_work_size(global_size(n, local_size))
            .set_local_work_size(local_size);
        // SAFETY: every wrapper below sets exactly the kernel's arguments, in order, with the
        // types the kernel declares; buffers outlive the launch because the queue is in order
        // and every reader of results waits on it.
        let event = unsafe { exec.enqueue_nd_range(&gpu.queue) }.map_err(call_err(stage))?;
        Ok(Launch { stage, event })
    }

    /// `generate`: camera rays for every slot of the wave; resets the queue counters.
    #[allow(clippy::too_many_arguments)]
    pub fn generate(
        &self,
        gpu: &Gpu,
        frame: &GpuFrame,
        camera: &GpuCamera,
        paths: &Buffer<GpuPath>,
        queue: &Buffer<u32>,
        counters: &Buffer<u32>,
        cones: &Buffer<[f32; 2]>,
        slots: usize,
    ) -> Result<Launch, ClError> {
        self.run(
            gpu,
            Stage::Generate.name(),
            &self.generate,
            slots,
            |e| unsafe {
                e.set_arg(frame)
                    .set_arg(camera)
                    .set_arg(&paths.mem())
                    .set_arg(&queue.mem())
                    .set_arg(&counters.mem())
                    .set_arg(&cones.mem());
            },
        )
    }

    /// `extend`: closest hits of the queued paths' rays (alpha-tested with `HAS_ALPHA`).
    #[allow(clippy::too_many_arguments)]
    pub fn extend(
        &self,
        gpu: &Gpu,
        scene: &SceneBuffers,
        paths: &Buffer<GpuPath>,
        queue: &Buffer<u32>,
        counters: &Buffer<u32>,
        hits: &Buffer<GpuHit>,
        slots: usize,
    ) -> Result<Launch, ClError> {
        self.run(gpu, Stage::Extend.name(), &self.extend, slots, |e| unsafe {
            set_geometry(e, scene.nodes.mem(), scene);
            set_surfaces(e, scene);
            e.set_arg(&paths.mem())
                .set_arg(&queue.mem())
                .set_arg(&counters.mem())
                .set_arg(&hits.mem());
        })
    }

    /// `shade`: emission, a light sample (queued for `connect`) and the next bounce.
    #[allow(clippy::too_many_arguments)]
    pub fn shade(
        &self,
        gpu: &Gpu,
        frame: &GpuFrame,
        env: &EnvBuffers,
        scene: &SceneBuffers,
        paths: &Buffer<GpuPath>,
        queue_in: &Buffer<u32>,
        hits: &Buffer<GpuHit>,
        queue_out: &Buffer<u32>,
        shadow_rays: &Buffer<GpuShadowRay>,
        counters: &Buffer<u32>,
        cones: &Buffer<[f32; 2]>,
        slots: usize,
    ) -> Result<Launch, ClError> {
        self.run(gpu, Stage::Shade.name(), &self.shade, slots, |e| unsafe {
            e.set_arg(frame)
                .set_arg(&env.info)
                .set_arg(&scene.triangles.mem())
                .set_arg(&scene.instances.mem());
            set_surfaces(e, scene);
            e.set_arg(&env.texels.mem())
                .set_arg(&env.marginal.mem())
                .set_arg(&env.conditional.mem())
                .set_arg(&scene.lights.mem())
                .set_arg(&scene.light_cdf.mem())
                .set_arg(&paths.mem())
                .set_arg(&queue_in.mem())
                .set_arg(&hits.mem())
                .set_arg(&queue_out.mem())
                .set_arg(&shadow_rays.mem())
                .set_arg(&counters.mem())
                .set_arg(&cones.mem());
        })
    }

    /// `connect`: traces the queued shadow rays (any hit) and adds the visible contributions.
    pub fn connect(
        &self,
        gpu: &Gpu,
        scene: &SceneBuffers,
        shadow_rays: &Buffer<GpuShadowRay>,
        counters: &Buffer<u32>,
        paths: &Buffer<GpuPath>,
        slots: usize,
    ) -> Result<Launch, ClError> {
        self.run(
            gpu,
            Stage::Connect.name(),
            &self.connect,
            slots,
            |e| unsafe {
                set_geometry(e, scene.nodes.mem(), scene);
                set_surfaces(e, scene);
                e.set_arg(&shadow_rays.mem())
                    .set_arg(&counters.mem())
                    .set_arg(&paths.mem());
            },
        )
    }

    /// `advance`: counts this bounce's rays and turns the output queue into the next input.
    pub fn advance(
        &self,
        gpu: &Gpu,
        counters: &Buffer<u32>,
        stats: &Buffer<u64>,
    ) -> Result<Launch, ClError> {
        self.run(gpu, Stage::Advance.name(), &self.advance, 1, |e| unsafe {
            e.set_arg(&counters.mem()).set_arg(&stats.mem());
        })
    }

    /// `accumulate`: adds the wave's finished samples to the film.
    pub fn accumulate(
        &self,
        gpu: &Gpu,
        frame: &GpuFrame,
        paths: &Buffer<GpuPath>,
        film: &Buffer<[f32; 4]>,
        counters: &Buffer<u32>,
    ) -> Result<Launch, ClError> {
        let pixels = (frame.width * frame.height) as usize;
        self.run(
            gpu,
            Stage::Accumulate.name(),
            &self.accumulate,
            pixels,
            |e| unsafe {
                e.set_arg(frame)
                    .set_arg(&paths.mem())
                    .set_arg(&film.mem())
                    .set_arg(&counters.mem());
            },
        )
    }

    /// `trace_closest`: closest hits of arbitrary rays (tests and `bench trace`).
    pub fn trace_closest(
        &self,
        gpu: &Gpu,
        bvh: &SceneBuffers,
        rays: &Buffer<GpuRay>,
        hits: &Buffer<GpuHit>,
        counters: &Buffer<u32>,
    ) -> Result<Launch, ClError> {
        let (stage, kernel) = ("trace_closest", &self.trace_closest);
        self.trace(
            gpu,
            stage,
            kernel,
            bvh.nodes.mem(),
            bvh,
            rays,
            hits,
            counters,
        )
    }

    /// `trace_any`: occlusion of arbitrary rays (tests and `bench trace`).
    pub fn trace_any(
        &self,
        gpu: &Gpu,
        bvh: &SceneBuffers,
        rays: &Buffer<GpuRay>,
        occluded: &Buffer<u32>,
        counters: &Buffer<u32>,
    ) -> Result<Launch, ClError> {
        let (stage, kernel) = ("trace_any", &self.trace_any);
        self.trace(
            gpu,
            stage,
            kernel,
            bvh.nodes.mem(),
            bvh,
            rays,
            occluded,
            counters,
        )
    }

    /// `trace_closest_wide`: as `trace_closest`, through the 4-wide BVH.
    pub fn trace_closest_wide(
        &self,
        gpu: &Gpu,
        bvh: &SceneBuffers,
        rays: &Buffer<GpuRay>,
        hits: &Buffer<GpuHit>,
        counters: &Buffer<u32>,
    ) -> Result<Launch, ClError> {
        let (stage, kernel) = ("trace_closest_wide", &self.trace_closest_wide);
        self.trace(
            gpu,
            stage,
            kernel,
            bvh.wide_nodes.mem(),
            bvh,
            rays,
            hits,
            counters,
        )
    }

    /// `trace_any_wide`: as `trace_any`, through the 4-wide BVH.
    pub fn trace_any_wide(
        &self,
        gpu: &Gpu,
        bvh: &SceneBuffers,
        rays: &Buffer<GpuRay>,
        occluded: &Buffer<u32>,
        counters: &Buffer<u32>,
    ) -> Result<Launch, ClError> {
        let (stage, kernel) = ("trace_any_wide", &self.trace_any_wide);
        self.trace(
            gpu,
            stage,
            kernel,
            bvh.wide_nodes.mem(),
            bvh,
            rays,
            occluded,
            counters,
        )
    }

    /// The four tracing kernels share their arguments: nodes (binary or wide), triangles,
    /// surfaces, rays, count, results, counters.
    #[allow(clippy::too_many_arguments)]
    fn trace<T: Pod>(
        &self,
        gpu: &Gpu,
        stage: &'static str,
        kernel: &Kernel,
        nodes: opencl3::types::cl_mem,
        bvh: &SceneBuffers,
        rays: &Buffer<GpuRay>,
        out: &Buffer<T>,
        counters: &Buffer<u32>,
    ) -> Result<Launch, ClError> {
        let wide = nodes == bvh.wide_nodes.mem();
        let uploaded = if wide {
            bvh.forms.wide
        } else {
            bvh.forms.binary
        };
        if !uploaded {
            return Err(ClError::Device(format!(
                "{stage}: the scene was uploaded without its {} nodes (Renderer::set_node_forms)",
                if wide { "wide" } else { "binary" }
            )));
        }
        let count = rays.len() as u32;
        self.run(gpu, stage, kernel, rays.len(), |e| unsafe {
            set_geometry(e, nodes, bvh);
            set_surfaces(e, bvh);
            e.set_arg(&rays.mem())
                .set_arg(&count)
                .set_arg(&out.mem())
                .set_arg(&counters.mem());
        })
    }

    /// `megakernel`: `frame.samples_in_wave` whole paths per pixel, from the camera to their
    /// end, added to the film; the ray counts go to the counters that `advance` reads.
    #[allow(clippy::too_many_arguments)]
    pub fn megakernel(
        &self,
        gpu: &Gpu,
        frame: &GpuFrame,
        camera: &GpuCamera,
        env: &EnvBuffers,
        scene: &SceneBuffers,
        film: &Buffer<[f32; 4]>,
        counters: &Buffer<u32>,
    ) -> Result<Launch, ClError> {
        let pixels = (frame.width * frame.height) as usize;
        // With lanes a work item takes a LANES_TILE-square of pixels (kernels/cpu/megakernel_lanes.cl).
        let items = if self.features.lanes {
            (frame.width as usize).div_ceil(LANES_TILE)
                * (frame.height as usize).div_ceil(LANES_TILE)
        } else {
            pixels
        };
        let local = self.mega_local_size;
        self.run_local(
            gpu,
            Stage::Megakernel.name(),
            &self.megakernel,
            items,
            local,
            |e| unsafe {
                e.set_arg(frame).set_arg(camera).set_arg(&env.info);
                set_geometry(e, scene.wide_nodes.mem(), scene);
                set_surfaces(e, scene);
                e.set_arg(&env.texels.mem())
                    .set_arg(&env.marginal.mem())
                    .set_arg(&env.conditional.mem())
                    .set_arg(&scene.lights.mem())
                    .set_arg(&scene.light_cdf.mem())
                    .set_arg(&film.mem())
                    .set_arg(&counters.mem());
            },
        )
    }

    /// `probe_layout` (test program): sizes and offsets of the shared structs as the device compiler sees them.
    pub fn probe_layout(&self, gpu: &Gpu) -> Result<Vec<u32>, ClError> {
        let tests = self.tests(gpu)?;
        let out = Buffer::<u32>::new(gpu, 256)?;
        self.run(gpu, "probe_layout", &tests.probe_layout, 1, |e| unsafe {
            e.set_arg(&out.mem());
        })?;
        out.read(gpu)
    }

    /// `sample_texture_test` (test program): texture lookups; query .xy = uv, .z = footprint level (see
    /// kernels/test/tests.cl), .w = texture reference (i32 bits). Zeros without `HAS_TEXTURES`.
    pub fn sample_texture_test(
        &self,
        gpu: &Gpu,
        scene: &SceneBuffers,
        queries: &[[f32; 4]],
    ) -> Result<Vec<[f32; 4]>, ClError> {
        let tests = self.tests(gpu)?;
        let q = Buffer::from_slice(gpu, queries)?;
        let out = Buffer::<[f32; 4]>::new(gpu, queries.len())?;
        let count = queries.len() as u32;
        self.run(
            gpu,
            "sample_texture_test",
            &tests.sample_texture_test,
            queries.len(),
            |e| unsafe {
                e.set_arg(&scene.tex_refs.mem())
                    .set_arg(&scene.textures.mem())
                    .set_arg(&scene.texels.mem())
                    .set_arg(&q.mem())
                    .set_arg(&count)
                    .set_arg(&out.mem());
            },
        )?;
        out.read(gpu)
    }

    /// `sample_env_test` (test program): environment samples from uniform pairs: (direction, pdf) each, and
    /// the pdf the miss shader gives the same direction. Zeros without `HAS_ENV_MAP`.
    #[allow(clippy::type_complexity)]
    pub fn sample_env_test(
        &self,
        gpu: &Gpu,
        env: &EnvBuffers,
        u: &[[f32; 2]],
    ) -> Result<(Vec<[f32; 4]>, Vec<f32>), ClError> {
        let tests = self.tests(gpu)?;
        let ub = Buffer::from_slice(gpu, u)?;
        let out = Buffer::<[f32; 4]>::new(gpu, u.len())?;
        let eval = Buffer::<f32>::new(gpu, u.len())?;
        let count = u.len() as u32;
        self.run(
            gpu,
            "sample_env_test",
            &tests.sample_env_test,
            u.len(),
            |e| unsafe {
                e.set_arg(&env.info)
                    .set_arg(&env.texels.mem())
                    .set_arg(&env.marginal.mem())
                    .set_arg(&env.conditional.mem())
                    .set_arg(&ub.mem())
                    .set_arg(&count)
                    .set_arg(&out.mem())
                    .set_arg(&eval.mem());
            },
        )?;
        Ok((out.read(gpu)?, eval.read(gpu)?))
    }

    /// `spawn_test` (test program): rays spawned with the kernels' hit point and offset; case i
    /// leaves triangle `groups[i][0]` (vertices `verts[3k..3k + 3]`, xyz) at barycentrics
    /// `bary[i]` along `dirs[i]` (.w = tmax) and counts its hits among the `groups[i][2]`
    /// triangles from `groups[i][1]` (`groups[i][3]` is unused).
    pub fn spawn_test(
        &self,
        gpu: &Gpu,
        verts: &[[f32; 4]],
        groups: &[[u32; 4]],
        bary: &[[f32; 2]],
        dirs: &[[f32; 4]],
    ) -> Result<Vec<u32>, ClError> {
        let tests = self.tests(gpu)?;
        let vb = Buffer::from_slice(gpu, verts)?;
        let gb = Buffer::from_slice(gpu, groups)?;
        let bb = Buffer::from_slice(gpu, bary)?;
        let db = Buffer::from_slice(gpu, dirs)?;
        let hits = Buffer::<u32>::new(gpu, dirs.len())?;
        let count = dirs.len() as u32;
        self.run(
            gpu,
            "spawn_test",
            &tests.spawn_test,
            dirs.len(),
            |e| unsafe {
                e.set_arg(&vb.mem())
                    .set_arg(&gb.mem())
                    .set_arg(&bb.mem())
                    .set_arg(&db.mem())
                    .set_arg(&count)
                    .set_arg(&hits.mem());
            },
        )?;
        hits.read(gpu)
    }

    /// `bsdf_sample_test` (test program): `count` BSDF samples of `material` at (`wo`, `n`), seen from inside
    /// its volume when `inside`; returns (wi, pdf) and (weight, 1 for a delta lobe) per sample.
    #[allow(clippy::too_many_arguments, clippy::type_complexity)]
    pub fn bsdf_sample_test(
        &self,
        gpu: &Gpu,
        material: &GpuMaterial,
        wo: [f32; 4],
        n: [f32; 4],
        inside: bool,
        count: usize,
        seed: u32,
    ) -> Result<(Vec<[f32; 4]>, Vec<[f32; 4]>), ClError> {
        let tests = self.tests(gpu)?;
        let material = Buffer::from_slice(gpu, &[*material])?;
        let wi_pdf = Buffer::<[f32; 4]>::new(gpu, count)?;
        let weight = Buffer::<[f32; 4]>::new(gpu, count)?;
        let inside = inside as u32;
        let count32 = count as u32;
        self.run(
            gpu,
            "bsdf_sample_test",
            &tests.bsdf_sample_test,
            count,
            |e| unsafe {
                e.set_arg(&material.mem())
                    .set_arg(&wo)
                    .set_arg(&n)
                    .set_arg(&inside)
                    .set_arg(&count32)
                    .set_arg(&seed)
                    .set_arg(&wi_pdf.mem())
                    .set_arg(&weight.mem());
            },
        )?;
        Ok((wi_pdf.read(gpu)?, weight.read(gpu)?))
    }

    /// `bsdf_eval_test` (test program): (f·|cos|, pdf) of `material` at (`wo`, `n`) for each direction of `wi`.
    pub fn bsdf_eval_test(
        &self,
        gpu: &Gpu,
        material: &GpuMaterial,
        wo: [f32; 4],
        n: [f32; 4],
        inside: bool,
        wi: &[[f32; 4]],
    ) -> Result<Vec<[f32; 4]>, ClError> {
        let tests = self.tests(gpu)?;
        let material = Buffer::from_slice(gpu, &[*material])?;
        let wi_buf = Buffer::from_slice(gpu, wi)?;
        let out = Buffer::<[f32; 4]>::new(gpu, wi.len())?;
        let inside = inside as u32;
        let count = wi.len() as u32;
        self.run(
            gpu,
            "bsdf_eval_test",
            &tests.bsdf_eval_test,
            wi.len(),
            |e| unsafe {
                e.set_arg(&material.mem())
                    .set_arg(&wo)
                    .set_arg(&n)
                    .set_arg(&inside)
                    .set_arg(&count)
                    .set_arg(&wi_buf.mem())
                    .set_arg(&out.mem());
            },
        )?;
        out.read(gpu)
    }
}

/// The megakernel's work-group size: `PENUMBRA_MEGAKERNEL_GROUP` when set (for measuring),
/// else 64, or 1 with `lanes`. On PoCL's CPU device a work-group is one task of its thread pool
/// whose work items run one after the other (the kernel's loops defeat vectorisation across
/// work items), so the size only sets the scheduling grain; docs/benchmarks.md has the
/// measurements. A lanes work item renders LANES_TILE² pixels, enough for a task alone.
fn megakernel_local_size(lanes: bool) -> usize {
    std::env::var("PENUMBRA_MEGAKERNEL_GROUP")
        .ok()
        .and_then(|v| v.parse::<usize>().ok())
        .filter(|&n| n > 0)
        .unwrap_or(if lanes { 1 } else { 64 })
}

/// Sets the four geometry arguments every traversing kernel takes first: the nodes (binary or
/// wide), the shading-order triangles, the instances and the object-space triangles (the last
/// two are read with `TWO_LEVEL` only).
///
/// # Safety
/// Only for kernels whose next four parameters are exactly those.
unsafe fn set_geometry(e: &mut ExecuteKernel, nodes: opencl3::types::cl_mem, scene: &SceneBuffers) {
    // SAFETY: the caller's kernel declares these four buffers next, in this order.
    unsafe {
        e.set_arg(&nodes)
            .set_arg(&scene.triangles.mem())
            .set_arg(&scene.instances.mem())
            .set_arg(&scene.object_triangles.mem());
    }
}

/// Sets the seven surface arguments every traversing kernel takes after the triangles, in the
/// order of `SceneSurfaces` (kernels/shared/textures.h).
///
/// # Safety
/// Only for kernels whose next seven parameters are exactly those.
unsafe fn set_surfaces(e: &mut ExecuteKernel, scene: &SceneBuffers) {
    // SAFETY: the caller's kernel declares these seven buffers next, in this order.
    unsafe {
        e.set_arg(&scene.shading.mem())
            .set_arg(&scene.uvs.mem())
            .set_arg(&scene.tangents.mem())
            .set_arg(&scene.materials.mem())
            .set_arg(&scene.tex_refs.mem())
            .set_arg(&scene.textures.mem())
            .set_arg(&scene.texels.mem());
    }
}

/// The environment map on the device (a 1×1 black placeholder when there is none).
pub struct EnvBuffers {
    /// Constants.
    pub info: GpuEnvironment,
    /// RGB f32 texels.
    pub texels: Buffer<f32>,
    /// Cumulative row probabilities.
    pub marginal: Buffer<f32>,
    /// Cumulative column probabilities per row.
    pub conditional: Buffer<f32>,
}

/// Which node arrays of the BVH a scene's buffers hold: the binary one (the wavefront's
/// `extend` and `connect`, `trace_closest` and `trace_any`) and the 4-wide one (the
/// megakernel's, `trace_closest_wide` and `trace_any_wide`). The array left out is a
/// placeholder of one node.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NodeForms {
    /// The binary nodes.
    pub binary: bool,
    /// The 4-wide nodes.
    pub wide: bool,
}

impl NodeForms {
    /// Both arrays (tests and `bench trace`, which trace through either).
    pub const BOTH: Self = Self {
        binary: true,
        wide: true,
    };

    /// Neither array.
    pub const NONE: Self = Self {
        binary: false,
        wide: false,
    };

    /// Those the kernels in use traverse: the megakernel's wide nodes or the wavefront's
    /// binary ones.
    pub fn for_kernels(megakernel: bool) -> Self {
        Self {
            binary: !megakernel,
            wide: megakernel,
        }
    }

    /// Both this one's arrays and `other`'s.
    pub fn with(self, other: Self) -> Self {
        Self {
            binary: self.binary || other.binary,
            wide: self.wide || other.wide,
        }
    }

    /// This one's arrays that `have` lacks.
    pub fn beyond(self, have: Self) -> Self {
        Self {
            binary: self.binary && !have.binary,
            wide: self.wide && !have.wide,
        }
    }
}

/// The scene on the device: BVH, triangles, shading data, materials and lights.
pub struct SceneBuffers {
    /// Which of the two node arrays are real (the other a placeholder).
    pub forms: NodeForms,
    /// BVH nodes (a placeholder unless `forms.binary`).
    pub nodes: Buffer<GpuBvhNode>,
    /// The same BVH collapsed to 4-wide nodes (the megakernel's; a placeholder unless
    /// `forms.wide`).
    pub wide_nodes: Buffer<GpuWideNode>,
    /// Triangles in shading order (the flat BVH's order, or instance by instance).
    pub triangles: Buffer<GpuTriangle>,
    /// Two levels: the instances in top-level order (one placeholder when flat).
    pub instances: Buffer<GpuInstance>,
    /// Two levels: every distinct mesh's object-space triangles in its bottom level's order
    /// (one placeholder when flat).
    pub object_triangles: Buffer<GpuTriangle>,
    /// Corner normals in BVH order.
    pub shading: Buffer<GpuTriShading>,
    /// Texture coordinates in BVH order (one placeholder element when no material samples a
    /// texture).
    pub uvs: Buffer<GpuTriUvs>,
    /// Tangents in BVH order (one placeholder element without normal maps).
    pub tangents: Buffer<GpuTriTangents>,
    /// Texture references (materials index them).
    pub tex_refs: Buffer<GpuTexRef>,
    /// Texture descriptors.
    pub textures: Buffer<GpuTexture>,
    /// RGBA8 texels of every mip level of every texture.
    pub texels: Buffer<u32>,
    /// Materials.
    pub materials: Buffer<GpuMaterial>,
    /// Lights (emissive triangles first, then punctual lights, then the environment map).
    pub lights: Buffer<GpuLight>,
    /// Cumulative selection probabilities of the lights.
    pub light_cdf: Buffer<f32>,
}

impl SceneBuffers {
    /// Bytes of every buffer: what the scene takes on the device.
    pub fn bytes(&self) -> usize {
        self.nodes.bytes()
            + self.wide_nodes.bytes()
            + self.triangles.bytes()
            + self.instances.bytes()
            + self.object_triangles.bytes()
            + self.shading.bytes()
            + self.uvs.bytes()
            + self.tangents.bytes()
            + self.tex_refs.bytes()
            + self.textures.bytes()
            + self.texels.bytes()
            + self.materials.bytes()
            + self.lights.bytes()
            + self.light_cdf.bytes()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cl::DeviceChoice;

    /// Linux's transparent huge page mode, when it gives huge pages to advised memory.
    fn huge_pages_on() -> bool {
        std::fs::read_to_string("/sys/kernel/mm/transparent_hugepage/enabled")
            .is_ok_and(|mode| mode.contains("[always]") || mode.contains("[madvise]"))
    }

    /// The kB of huge pages /proc/self/smaps reports for the mapping that holds `addr`.
    fn huge_kb_at(addr: usize) -> Option<u64> {
        let smaps = std::fs::read_to_string("/proc/self/smaps").ok()?;
        let mut inside = false;
        for line in smaps.lines() {
            let range = line.split_whitespace().next().unwrap_or("");
            if let Some((lo, hi)) = range.split_once('-')
                && let (Ok(lo), Ok(hi)) =
                    (usize::from_str_radix(lo, 16), usize::from_str_radix(hi, 16))
            {
                inside = (lo..hi).contains(&addr);
            } else if inside && let Some(kb) = line.strip_prefix("AnonHugePages:") {
                return kb.trim().trim_end_matches("kB").trim().parse().ok();
            }
        }
        None
    }

    #[test]
    fn host_pages_are_aligned_and_get_huge_pages_where_linux_gives_them() {
        let pages = HostPages::new(3 * HUGE_PAGE + 1);
        if cfg!(not(target_os = "linux")) {
            assert!(pages.is_none(), "host pages are Linux's");
            return;
        }
        let pages = pages.expect("8 MiB can be mapped");
        assert!(pages.huge, "8 MiB is within the huge-page budget");
        assert_eq!(pages.ptr as usize % HUGE_PAGE, 0);
        assert_eq!(pages.len, 4 * HUGE_PAGE);
        // SAFETY: the mapping is `len` bytes long and ours.
        unsafe { std::ptr::write_bytes(pages.ptr, 1, pages.len) };
        if cfg!(target_os = "linux") && huge_pages_on() {
            let kb = huge_kb_at(pages.ptr as usize).expect("the mapping is in smaps");
            assert!(
                kb >= 2048,
                "no huge page backs the advised memory ({kb} kB)"
            );
        }
    }

    #[test]
    fn host_pages_beyond_the_huge_page_budget_are_not_advised() {
        let big = HostPages::new(HUGE_BUDGET + HUGE_PAGE);
        if cfg!(not(target_os = "linux")) {
            assert!(big.is_none(), "host pages are Linux's");
            return;
        }
        let big = big.expect("address space for the mapping");
        // Mapped but never touched: no memory is used.
        assert!(!big.huge, "more than the whole budget is never advised");
        assert_eq!(big.len, HUGE_BUDGET + HUGE_PAGE);
    }

    #[test]
    fn a_cpu_devices_large_buffer_keeps_what_is_written() {
        let Ok(gpu) = Gpu::open(&DeviceChoice::Cpu) else {
            return; // no CPU device here (a GPU-only machine)
        };
        let len = HUGE_PAGE; // 8 MiB of u32: in host pages
        let data: Vec<u32> = (0..len as u32)
            .map(|i| i.wrapping_mul(2654435761))
            .collect();
        let mut b = Buffer::from_slice(&gpu, &data).expect("the buffer is made");
        assert_eq!(b.read(&gpu).expect("it reads back"), data);
        b.write_at(&gpu, 5, &[7, 8, 9]).expect("a write in place");
        let back = b.read(&gpu).expect("it reads back");
        assert_eq!(&back[4..9], &[data[4], 7, 8, 9, data[8]]);
        b.clear(&gpu).expect("it clears");
        assert!(b.read(&gpu).expect("it reads back").iter().all(|&x| x == 0));
        // Buffers come and go (the destructor callback frees each one's pages).
        for _ in 0..8 {
            drop(Buffer::<u32>::new(&gpu, 3 * len).expect("a buffer"));
        }
    }

    #[test]
    fn reading_into_a_kept_vector_reuses_its_memory_and_reads_every_element() {
        let Ok(gpu) = Gpu::open(&DeviceChoice::Cpu) else {
            return; // no CPU device here (a GPU-only machine)
        };
        let data: Vec<u32> = (0..1000u32).map(|i| i * 3 + 1).collect();
        let b = Buffer::from_slice(&gpu, &data).expect("the buffer is made");
        // Longer than the buffer, with other contents: cut to its length and overwritten.
        let mut out = vec![9u32; 1500];
        let at = out.as_ptr();
        b.read_into(&gpu, &mut out).expect("it reads back");
        assert_eq!(out, data);
        assert_eq!(out.as_ptr(), at, "the vector's allocation is kept");
        // Shorter: grown to the buffer's length.
        let mut short = vec![5u32; 10];
        b.read_into(&gpu, &mut short).expect("it reads back");
        assert_eq!(short, data);
    }
}
