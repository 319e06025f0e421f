//! The kernels' build at run time with the scene's feature defines (their source: `source.rs`).

use super::{ClError, Gpu};
use opencl3::device::CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT;

/// The scene features that decide which kernel code is compiled in.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct KernelFeatures {
    /// Some triangles emit light (area lights with MIS).
    pub triangle_lights: bool,
    /// Some material has a texture (`HAS_TEXTURES`).
    pub textures: bool,
    /// Some material has a normal map (`HAS_NORMAL_MAPS`; implies textures).
    pub normal_maps: bool,
    /// Some material is alpha-masked or blended (`HAS_ALPHA`: alpha tests in traversal).
    pub alpha: bool,
    /// Some material transmits light (`HAS_TRANSMISSION`).
    pub transmission: bool,
    /// An environment map lights the scene (`HAS_ENV_MAP`).
    pub env_map: bool,
    /// Some material is a transmissive thin wall (`HAS_THIN_WALLS`: shadow rays pass the smooth
    /// ones).
    pub thin_walls: bool,
    /// Some material is unlit (`HAS_UNLIT`, `KHR_materials_unlit`).
    pub unlit: bool,
    /// Some material has a clear coat (`HAS_CLEARCOAT`, `KHR_materials_clearcoat`).
    pub clearcoat: bool,
    /// Some material has a sheen (`HAS_SHEEN`, `KHR_materials_sheen`).
    pub sheen: bool,
    /// Some material transmits diffusely (`HAS_DIFFUSE_TRANSMISSION`,
    /// `KHR_materials_diffuse_transmission`).
    pub diffuse_transmission: bool,
    /// Some material is iridescent (`HAS_IRIDESCENCE`, `KHR_materials_iridescence`).
    pub iridescence: bool,
    /// Some transmitting volume is dispersive (`HAS_DISPERSION`, `KHR_materials_dispersion`):
    /// paths through it pick a wavelength.
    pub dispersion: bool,
    /// Some material is anisotropic (`HAS_ANISOTROPY`, `KHR_materials_anisotropy`).
    pub anisotropy: bool,
    /// Tangents are uploaded for the anisotropic materials' frames (`HAS_TANGENTS`; only set
    /// with `anisotropy`).
    pub tangents: bool,
    /// Every material is Lambertian (`LAMBERT_ONLY`: no specular layer, metal, transmission,
    /// coat or sheen anywhere), so the BSDF is evaluated as base color / pi.
    pub lambert_only: bool,
    /// Rays descend a top level over instances, then their meshes' bottom levels (`TWO_LEVEL`).
    pub two_level: bool,
    /// Some top-level pieces are single triangles of small meshes, tested in world space
    /// (`HAS_TRIANGLE_PIECES`, with `TWO_LEVEL`).
    pub triangle_pieces: bool,
    /// The scene's triangles rounded up to a multiple of 16 when the megakernel tests them all
    /// for every ray instead of walking the BVH (`SMALL_SCENE`, kernels/shared/traverse_wide.h; the
    /// count itself comes with each frame): a flat scene of at most [`SMALL_SCENE_MAX`]
    /// triangles without alpha, on a CPU device; 0 otherwise.
    pub small_scene: u32,
    /// The megakernel walks sixteen paths' rays together in vector lanes (`MEGA_LANES`,
    /// kernels/cpu/traverse_lanes.h): a flat scene that is not small, without alpha, on a CPU
    /// device with AVX-512 or AVX2 (see [`lanes_megakernel`]).
    pub lanes: bool,
    /// The megakernel's lanes shade their paths' vertices in batches, in vectors
    /// (`LANES_SHADE`, kernels/cpu/shade_lanes.h; see [`lanes_shade`]).
    pub lanes_shade: bool,
    /// The megakernel's lanes test every triangle of a small scene (one that would be
    /// `small_scene` one ray at a time) instead of walking the tree (`LANES_SMALL`,
    /// kernels/cpu/traverse_lanes.h; the count comes with each frame).
    pub lanes_small: bool,
}

/// The fewest triangles for which the megakernel walks its rays in lanes: below, the tree fits
/// the caches, a walk seldom waits on memory, and the lanes measured 1–4 % slower on the shared
/// scenes of about 10,000 triangles (6–9 % after the fifteenth session's changes); from 41,000
/// on they were 2–6 % faster, and 17 % on the 1 M-triangle bunnies (27 % after;
/// docs/benchmarks.md, "Fourteenth session", "Fifteenth session").
pub const LANES_MIN_TRIANGLES: usize = 32_768;

/// Whether the megakernel walks a flat scene's rays in lanes (`KernelFeatures::lanes`): the
/// answer of [`lanes_megakernel`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lanes {
    /// One ray at a time.
    Never,
    /// In lanes.
    Always,
    /// In lanes where they shade their vertices in batches ([`lanes_shade`]), which pays at any
    /// size, or where the scene is small enough to be tested whole in lanes
    /// (`KernelFeatures::lanes_small`): the scene has fewer than [`LANES_MIN_TRIANGLES`], where
    /// the walk alone does not pay.
    WhenBatched,
}

/// Whether the megakernel should walk a flat scene's rays in lanes on a CPU device: no alpha,
/// fewer than 2^27 triangles in leaves of at most 15 (a lane's stack entry packs
/// both in a word), the host CPU (PoCL's device) has AVX-512 (whose gathers, scatters and
/// compresses the walk uses) or AVX2 (eight lanes: gathers, table-driven compresses, stores for
/// scatters; 17-25 % less time than one ray at a time on AMD's Zen 3, docs/benchmarks.md,
/// "Twenty-third session"), and `PENUMBRA_LANES` is not `0` (docs/benchmarks.md, "Fourteenth
/// session"); below [`LANES_MIN_TRIANGLES`] only where the vertices are shaded in batches
/// (the bundled box 12 % faster at 64 bounces, its viewer 1.3× on Zen 3: docs/benchmarks.md,
/// "Twenty-eighth session") or the scene is small (`SMALL_SCENE`'s sizes), whose lanes then
/// test its triangles whole (`KernelFeatures::lanes_small`; "Thirty-first session").
/// `PENUMBRA_LANES=1` walks in lanes on any CPU device at any size (lane by lane where the CPU
/// has neither: for measurements).
pub fn lanes_megakernel(cpu: bool, alpha: bool, triangles: usize, largest_leaf: u32) -> Lanes {
    if !cpu || alpha || triangles >= 1 << 27 || largest_leaf > 15 {
        return Lanes::Never;
    }
    match std::env::var("PENUMBRA_LANES").as_deref().map(str::trim) {
        Ok("0") => return Lanes::Never,
        Ok("1") => return Lanes::Always,
        _ => {}
    }
    #[cfg(target_arch = "x86_64")]
    let vectors = std::arch::is_x86_feature_detected!("avx512f")
        || std::arch::is_x86_feature_detected!("avx2");
    #[cfg(not(target_arch = "x86_64"))]
    let vectors = false;
    match (vectors, triangles >= LANES_MIN_TRIANGLES) {
        (false, _) => Lanes::Never,
        (true, true) => Lanes::Always,
        (true, false) => Lanes::WhenBatched,
    }
}

/// Whether the megakernel's lanes shade their vertices in batches of LANES, in vectors
/// (`KernelFeatures::lanes_shade`): with lanes, where shading is simplest (every material
/// Lambertian, no textures, normal maps, environment map, unlit materials, thin walls or two
/// levels), unless `PENUMBRA_LANES_SHADE` is `0`. It is path.h's `shade_vertex` lane by lane,
/// the same image; 12 % fewer instructions and about 6 % less time on the 1 M-triangle room
/// (docs/benchmarks.md, "Twenty-fifth session").
pub fn lanes_shade(f: &KernelFeatures) -> bool {
    f.lanes
        && f.lambert_only
        && f.small_scene == 0
        && !(f.textures
            || f.normal_maps
            || f.two_level
            || f.env_map
            || f.unlit
            || f.thin_walls
            || f.transmission
            || f.clearcoat
            || f.sheen
            || f.diffuse_transmission
            || f.iridescence
            || f.anisotropy
            || f.dispersion)
        && std::env::var("PENUMBRA_LANES_SHADE")
            .as_deref()
            .map(str::trim)
            != Ok("0")
}

/// Whether a small scene's lanes, where it walks in lanes, test its triangles whole
/// (`KernelFeatures::lanes_small`, `LANES_SMALL`, kernels/cpu/traverse_lanes.h) instead of walking
/// its tree: a scene the megakernel would test whole one ray at a time (`small_scene`), unless
/// `PENUMBRA_LANES_SMALL` is `0`. Faster than both the tree in lanes and `SMALL_SCENE`
/// (docs/benchmarks.md, "Thirty-first session"); the same image.
pub fn lanes_small(f: &KernelFeatures) -> bool {
    f.small_scene > 0
        && std::env::var("PENUMBRA_LANES_SMALL")
            .as_deref()
            .map(str::trim)
            != Ok("0")
}

/// Whether the lanes (`MEGA_LANES`) load their nodes and triangles as rows, transposed into
/// vectors by shuffles, rather than by gathers (`LANES_GATHERS`, kernels/cpu/traverse_lanes.h). On
/// AMD's Zen 5 a gather loads about one element a cycle from L2, and rows make the walk 1.3–1.8×
/// faster natively; on an Intel Xeon (the H200 machine's host) gathers are 3–7 % faster
/// (docs/benchmarks.md, "Seventeenth session"). So rows on AMD CPUs, gathers elsewhere;
/// `PENUMBRA_LANES_LOAD=rows` or `gathers` chooses.
pub fn lanes_load_rows() -> bool {
    static ROWS: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *ROWS.get_or_init(|| {
        match std::env::var("PENUMBRA_LANES_LOAD")
            .as_deref()
            .map(str::trim)
        {
            Ok("rows") => return true,
            Ok("gathers") => return false,
            Ok(other) => {
                log::warn!("PENUMBRA_LANES_LOAD={other:?} is neither rows nor gathers: ignored")
            }
            Err(_) => {}
        }
        host_cpu_is_amd()
    })
}

/// Whether the host CPU (PoCL's device) is AMD's, by its CPUID vendor string.
fn host_cpu_is_amd() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        let r = std::arch::x86_64::__cpuid(0);
        let mut vendor = [0u8; 12];
        vendor[..4].copy_from_slice(&r.ebx.to_le_bytes());
        vendor[4..8].copy_from_slice(&r.edx.to_le_bytes());
        vendor[8..].copy_from_slice(&r.ecx.to_le_bytes());
        &vendor == b"AuthenticAMD"
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// The most triangles a scene may have for the megakernel to test them all for every ray
/// (`KernelFeatures::small_scene`): up to this many, sixteen at a time in vector lanes, cost
/// less than walking the 4-wide BVH on PoCL (docs/benchmarks.md, "Eighth session"; a box of
/// 36 triangles 7.5–7.8 against the tree's 8.7–8.8 CPU s, one of 144 12.6–13.0 against 11.9–12.2:
/// "Ninth session").
pub const SMALL_SCENE_MAX: usize = 64;

impl KernelFeatures {
    /// The `-D` options for these features.
    pub fn defines(&self) -> String {
        let mut d = String::new();
        for (on, name) in [
            (self.triangle_lights, "HAS_TRIANGLE_LIGHTS"),
            (self.textures, "HAS_TEXTURES"),
            (self.normal_maps, "HAS_NORMAL_MAPS"),
            (self.alpha, "HAS_ALPHA"),
            (self.transmission, "HAS_TRANSMISSION"),
            (self.env_map, "HAS_ENV_MAP"),
            (self.thin_walls, "HAS_THIN_WALLS"),
            (self.unlit, "HAS_UNLIT"),
            (self.clearcoat, "HAS_CLEARCOAT"),
            (self.sheen, "HAS_SHEEN"),
            (self.diffuse_transmission, "HAS_DIFFUSE_TRANSMISSION"),
            (self.iridescence, "HAS_IRIDESCENCE"),
            (self.anisotropy, "HAS_ANISOTROPY"),
            (self.dispersion, "HAS_DISPERSION"),
            (self.tangents, "HAS_TANGENTS"),
            (self.lambert_only, "LAMBERT_ONLY"),
            (self.two_level, "TWO_LEVEL"),
            (self.triangle_pieces, "HAS_TRIANGLE_PIECES"),
            (self.lanes, "MEGA_LANES"),
            (self.lanes_shade, "LANES_SHADE"),
            (self.lanes_small, "LANES_SMALL"),
        ] {
            if on {
                d.push_str(" -D");
                d.push_str(name);
            }
        }
        if self.small_scene > 0 {
            d.push_str(&format!(" -DSMALL_SCENE={}", self.small_scene));
        }
        if self.lanes && !lanes_load_rows() {
            d.push_str(" -DLANES_GATHERS");
        }
        d
    }
}

/// Builds the program for `features` on the device. A failure returns the compiler's first
/// error line, which names the kernel file and line.
pub fn build_program(
    gpu: &Gpu,
    features: KernelFeatures,
) -> Result<opencl3::program::Program, ClError> {
    build_source(gpu, &super::source::program_source()?, features)
}

/// Builds the production kernels together with the test-only ones (layout probe, texture,
/// environment and BSDF test kernels); only tests reach it, through `Program`'s test wrappers.
pub fn build_test_program(
    gpu: &Gpu,
    features: KernelFeatures,
) -> Result<opencl3::program::Program, ClError> {
    build_source(gpu, &super::source::test_program_source()?, features)
}

pub(crate) fn build_source(
    gpu: &Gpu,
    source: &str,
    features: KernelFeatures,
) -> Result<opencl3::program::Program, ClError> {
    let mut options = String::new();
    // Correctly rounded division keeps the device's triangle tests identical to the host's.
    if gpu
        .device
        .single_fp_config()
        .is_ok_and(|c| c & CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT != 0)
    {
        options.push_str("-cl-fp32-correctly-rounded-divide-sqrt");
    }
    // On a CPU a denormal float costs a microcode assist (about 100 cycles on x86) wherever one
    // is made, and the kernels make many: the .w lanes of vertices and nodes hold index bits,
    // which read as denormals, and every float4 operation computes them too. Flushing them to
    // zero, as Embree's and Cycles' CPU threads do, makes the megakernel about 1.35 times as
    // fast on PoCL (docs/benchmarks.md). No coordinate, colour or weight a scene means is that
    // small; GPUs keep their own default.
    if gpu.is_cpu() {
        options.push_str(" -cl-denorms-are-zero");
    } else {
        // The watertight test's axis permutation by selects, not shuffle() (kernels/shared/traverse.h,
        // `ray_permute`): faster on an H200, while a CPU does a shuffle in one instruction.
        options.push_str(" -DPERMUTE_BY_SELECT");
    }
    options.push_str(&features.defines());
    if let Some(cap) = register_cap(gpu, features) {
        options.push_str(&format!(" -cl-nv-maxrregcount={cap}"));
    }
    // Extra compiler options for experiments (e.g. `-cl-mad-enable`), space-separated.
    if let Ok(extra) = std::env::var("PENUMBRA_CL_OPTIONS") {
        options.push(' ');
        options.push_str(&extra);
    }
    let _setup = super::CL_SETUP.lock().unwrap_or_else(|e| e.into_inner());
    let mut program = opencl3::program::Program::create_from_source(&gpu.context, source)
        .map_err(|e| ClError::Build(format!("cannot create the program: {e}")))?;
    if program.build(&[gpu.device.id()], &options).is_err() {
        let log = program.get_build_log(gpu.device.id()).unwrap_or_default();
        log::debug!("kernel build log:\n{log}");
        return Err(ClError::Build(first_error(&log)));
    }
    // A successful build's log (warnings; with `PENUMBRA_CL_OPTIONS=-cl-nv-verbose`, NVIDIA's
    // registers and spills per kernel) for RUST_LOG=debug.
    if log::log_enabled!(log::Level::Debug) {
        let log = program.get_build_log(gpu.device.id()).unwrap_or_default();
        if !log.trim().is_empty() {
            log::debug!("kernel build log ({options}):\n{log}");
        }
    }
    dump_binary(&program);
    Ok(program)
}

/// The register cap for NVIDIA's compiler, where it pays. The two-level traversal needs a few
/// registers more than flat's (the instance's tmin, the stack height of its walk): `extend`
/// and `trace_closest` take 72 against flat's 64 and 62. The cap of 72 keeps ptxas from
/// taking more, so that as many warps fit on a multiprocessor to hide the node loads; it once
/// took two-level frames on an H200 from 0.82 to 0.90 of flat's, when they took 89-94 (sixth
/// session), and 64 made frames 2-4 % slower in the eighth. Flat programs stay under the cap
/// and the cap does not change them (docs/benchmarks.md).
/// `PENUMBRA_NV_MAXRREG` sets another cap for measuring (0: none).
fn register_cap(gpu: &Gpu, features: KernelFeatures) -> Option<u32> {
    if !features.two_level || !gpu.has_extension("cl_nv_compiler_options") {
        return None;
    }
    let cap = match std::env::var("PENUMBRA_NV_MAXRREG") {
        Ok(v) => v.trim().parse().unwrap_or(TWO_LEVEL_REGISTERS),
        Err(_) => TWO_LEVEL_REGISTERS,
    };
    (cap > 0).then_some(cap)
}

/// For measuring: with `PENUMBRA_DUMP_BINARY=PREFIX` every program built is written to
/// `PREFIX.N.bin` (N counting the builds of the process). NVIDIA's binary is its PTX, which
/// CUDA's `ptxas` and `cuobjdump` turn into the machine code and its register count
/// (docs/benchmarks.md, seventh and eighth sessions).
fn dump_binary(program: &opencl3::program::Program) {
    static BUILDS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let Some(prefix) = std::env::var_os("PENUMBRA_DUMP_BINARY") else {
        return;
    };
    let n = BUILDS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let path = format!("{}.{n}.bin", prefix.to_string_lossy());
    match program.get_binaries() {
        Ok(binaries) => {
            for binary in binaries {
                if let Err(e) = std::fs::write(&path, binary) {
                    log::warn!("cannot write {path}: {e}");
                }
            }
        }
        Err(e) => log::warn!("cannot read the program binary: {e}"),
    }
}

/// NVIDIA's register cap for two-level programs (see [`register_cap`]).
const TWO_LEVEL_REGISTERS: u32 = 72;

/// The first line of a build log that reports an error (with its file and line), or the
/// log's first line.
fn first_error(log: &str) -> String {
    log.lines()
        .find(|l| l.contains("error"))
        .or_else(|| log.lines().find(|l| !l.trim().is_empty()))
        .unwrap_or("the compiler gave no log")
        .trim()
        .to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_small_scene_is_defined_with_its_triangles() {
        let small = KernelFeatures {
            small_scene: 32,
            lambert_only: true,
            ..Default::default()
        };
        assert_eq!(small.defines(), " -DLAMBERT_ONLY -DSMALL_SCENE=32");
        assert!(!KernelFeatures::default().defines().contains("SMALL_SCENE"));
    }

    #[test]
    fn a_build_error_names_the_kernel_file_and_line() {
        let gpu = Gpu::open(&crate::cl::DeviceChoice::Cpu).expect("an OpenCL CPU device");
        let source = "#line 1 \"kernels/broken.cl\"\nkernel void f(global int* x) {\n  x[0] = undeclared;\n}\n";
        let err = build_source(&gpu, source, KernelFeatures::default())
            .expect_err("the source does not compile")
            .to_string();
        assert!(err.contains("kernels/broken.cl:2"), "{err}");
        assert!(!err.contains('\n'), "one line: {err}");
    }

    #[test]
    fn first_error_picks_the_error_line() {
        let log = "warning: x\nkernels/gpu/stages.cl:12:5: error: use of undeclared identifier\n";
        assert_eq!(
            first_error(log),
            "kernels/gpu/stages.cl:12:5: error: use of undeclared identifier"
        );
    }
}
