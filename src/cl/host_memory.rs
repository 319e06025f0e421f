//! The host memory policy: huge-page host memory for a CPU device's large buffers
//! (`HostPages`), the allocator's thresholds while a scene opens ([`OpeningMemory`]), and files
//! mapped in place ([`map_file`]).
#![allow(unsafe_code)]

use std::ptr;
use std::sync::atomic::Ordering;

/// The size of an x86-64 huge page (2 MiB), from which CPU devices' buffers use [`HostPages`].
pub(super) const HUGE_PAGE: usize = 2 << 20;

/// Host memory for a CPU device's buffer, aligned to and advised for transparent huge pages.
/// PoCL runs kernels on a `CL_MEM_USE_HOST_PTR` buffer's own memory, and with 4 KiB pages the
/// traversal of a large scene misses the TLB on nearly every node and triangle it reads: the
/// 1 M-triangle bunnies render about 6 % faster per CPU second with huge pages. Linux gives
/// huge pages to advised memory when /sys/kernel/mm/transparent_hugepage/enabled is `madvise`
/// (Debian's default) or `always`; with `never` this is ordinary aligned memory.
/// Only the first [`HUGE_BUDGET`] bytes of live buffers are advised: on a machine whose memory
/// is fragmented Linux compacts memory to fault a huge page in (`defrag` `madvise`, Debian's
/// default), which cost about 4 s a GB on the development VM against 0.7 s for small pages, and
/// a 16 M-triangle scene's upload took 14 s instead of 5 s. Scenes of up to about two million
/// triangles keep their huge pages.
pub(super) struct HostPages {
    /// The first byte, aligned to a huge page.
    pub(super) ptr: *mut u8,
    len: usize,
    /// Whether the range was advised for huge pages (and counts in [`HUGE_BYTES`]).
    huge: bool,
}

/// The most bytes of CPU device buffers advised for huge pages at once (see [`HostPages`]).
const HUGE_BUDGET: usize = 512 << 20;

/// From this size on, [`HostPages`] are faulted in at once by `MADV_POPULATE_WRITE`, in
/// parallel pieces, instead of page by page as they are first written.
const POPULATE_FROM: usize = 64 << 20;

/// The piece of a [`populate`] task (a multiple of [`HUGE_PAGE`]).
const POPULATE_PIECE: usize = 32 << 20;

/// Bytes of live [`HostPages`] advised for huge pages.
static HUGE_BYTES: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

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

impl HostPages {
    /// `bytes` bytes (rounded up to whole huge pages) of a fresh anonymous mapping aligned to a
    /// huge page, advised before they are first touched, so that the first write faults whole
    /// huge pages in (memory the allocator hands back again may already be backed by small
    /// pages); `None` where they cannot be mapped (the driver then allocates the buffer).
    #[cfg(target_os = "linux")]
    pub(super) fn new(bytes: usize) -> Option<Self> {
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
    pub(super) fn new(_bytes: usize) -> Option<Self> {
        None
    }

    /// Hands the memory to buffer `mem`, which uses it until the driver destroys the buffer:
    /// it is unmapped then, by the buffer's destructor callback. Should the callback not be
    /// accepted, the memory is leaked rather than unmapped under the buffer.
    pub(super) fn free_with(self, mem: opencl3::types::cl_mem) {
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
/// default reaches as the program runs on, so that what frames allocate and free again (display
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
/// opening runs (`OPENING_MMAP_THRESHOLD`); when the last one ends the steady policy returns
/// (`STEADY_MMAP_THRESHOLD`, the heap trimmed above twice that, as glibc's dynamic rule
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

#[cfg(test)]
mod tests {
    use super::*;

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
}
