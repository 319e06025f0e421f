//! Kernel sources (embedded at compile time) and their run-time build with feature defines.

use super::{ClError, Gpu};
use opencl3::device::CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT;

/// Kernel sources in the order they are concatenated; headers first.
const SOURCES: &[(&str, &str)] = &[
    ("kernels/types.h", include_str!("../../kernels/types.h")),
    ("kernels/rng.h", include_str!("../../kernels/rng.h")),
    (
        "kernels/textures.h",
        include_str!("../../kernels/textures.h"),
    ),
    (
        "kernels/traverse.h",
        include_str!("../../kernels/traverse.h"),
    ),
    (
        "kernels/traverse_wide.h",
        include_str!("../../kernels/traverse_wide.h"),
    ),
    (
        "kernels/traverse_lanes.h",
        include_str!("../../kernels/traverse_lanes.h"),
    ),
    (
        "kernels/traverse_packet.h",
        include_str!("../../kernels/traverse_packet.h"),
    ),
    ("kernels/bsdf.h", include_str!("../../kernels/bsdf.h")),
    ("kernels/surface.h", include_str!("../../kernels/surface.h")),
    ("kernels/env.h", include_str!("../../kernels/env.h")),
    ("kernels/lights.h", include_str!("../../kernels/lights.h")),
    ("kernels/path.h", include_str!("../../kernels/path.h")),
    (
        "kernels/shade_lanes.h",
        include_str!("../../kernels/shade_lanes.h"),
    ),
    ("kernels/stages.cl", include_str!("../../kernels/stages.cl")),
    (
        "kernels/megakernel.cl",
        include_str!("../../kernels/megakernel.cl"),
    ),
    ("kernels/tools.cl", include_str!("../../kernels/tools.cl")),
];

/// Kernels only the tests use; [`build_test_program`] adds them after [`SOURCES`].
const TEST_SOURCES: &[(&str, &str)] = &[
    ("kernels/tests.cl", include_str!("../../kernels/tests.cl")),
    (
        "kernels/bsdf_test.cl",
        include_str!("../../kernels/bsdf_test.cl"),
    ),
];

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
    /// for every ray instead of walking the BVH (`SMALL_SCENE`, kernels/traverse_wide.h; the
    /// count itself comes with each frame); 0 otherwise. This and the lanes' fields below are
    /// the CPU strategy, decided by [`crate::render::strategy::kernel_strategy`].
    pub small_scene: u32,
    /// The megakernel walks sixteen paths' rays together in vector lanes (`MEGA_LANES`,
    /// kernels/traverse_lanes.h).
    pub lanes: bool,
    /// The megakernel's lanes shade their paths' vertices in batches, in vectors
    /// (`LANES_SHADE`, kernels/shade_lanes.h).
    pub lanes_shade: bool,
    /// The megakernel's lanes test every triangle of a small scene instead of walking the tree
    /// (`LANES_SMALL`, kernels/traverse_lanes.h; the count comes with each frame).
    pub lanes_small: bool,
    /// The lanes load their nodes and triangles by gathers (`LANES_GATHERS`,
    /// kernels/traverse_lanes.h) rather than as rows transposed by shuffles.
    pub lanes_gathers: bool,
}

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
        if self.lanes_gathers {
            d.push_str(" -DLANES_GATHERS");
        }
        d
    }
}

/// The name the generated constants header goes by in compiler messages.
const DEFINES_NAME: &str = "generated/constants.h";

/// The full program source: the constants shared with the host (generated from
/// `cl/types.rs`), then every file, each behind a `#line` directive so the compiler's messages
/// name the file and line.
pub fn program_source() -> String {
    let mut s = format!(
        "#line 1 \"{DEFINES_NAME}\"\n{}",
        super::types::kernel_defines()
    );

    append_sources(&mut s, SOURCES);
    s
}

/// [`program_source`] followed by the test-only kernels.
pub fn test_program_source() -> String {
    let mut s = program_source();
    append_sources(&mut s, TEST_SOURCES);
    s
}

/// Appends each source behind its `#line` directive. With `PENUMBRA_KERNEL_DIR` set (for
/// working on the kernels without rebuilding the binary), a file of that name found under
/// the directory (e.g. `PENUMBRA_KERNEL_DIR=.` for `kernels/path.h`) replaces the built-in text.
fn append_sources(s: &mut String, sources: &[(&str, &str)]) {
    let dir = std::env::var_os("PENUMBRA_KERNEL_DIR").map(std::path::PathBuf::from);
    let found = with_overrides(s, sources, dir.as_deref());
    if let Some(dir) = dir.filter(|_| found == 0) {
        // Without this, an experiment run with the wrong folder silently measures the
        // built-in kernels (the names carry their `kernels/` folder).
        static WARNED: std::sync::Once = std::sync::Once::new();
        WARNED.call_once(|| {
            log::warn!(
                "PENUMBRA_KERNEL_DIR={}: no kernel file there (it must hold kernels/{}); \
                 the built-in kernels are used",
                dir.display(),
                sources.first().map_or("", |(name, _)| {
                    name.strip_prefix("kernels/").unwrap_or(name)
                })
            )
        });
    }
}

/// [`append_sources`] with the override folder given: returns how many files it replaced.
fn with_overrides(
    s: &mut String,
    sources: &[(&str, &str)],
    dir: Option<&std::path::Path>,
) -> usize {
    let mut found = 0;
    for (name, text) in sources {
        s.push_str(&format!("#line 1 \"{name}\"\n"));
        match dir.and_then(|d| std::fs::read_to_string(d.join(name)).ok()) {
            Some(edited) => {
                found += 1;
                s.push_str(&edited);
            }
            None => s.push_str(text),
        }
        s.push('\n');
    }
    found
}

/// Builds the program for `features` on the device. A failure returns the compiler's first
/// error line, which names the kernel file and line.
pub fn build_program(
    gpu: &Gpu,
    features: KernelFeatures,
) -> Result<opencl3::program::Program, ClError> {
    build_source(gpu, &program_source(), features)
}

/// Builds the production kernels together with the test-only ones (layout probe, texture,
/// environment and BSDF test kernels); only tests reach it, through `Program`'s test wrappers.
pub fn build_test_program(
    gpu: &Gpu,
    features: KernelFeatures,
) -> Result<opencl3::program::Program, ClError> {
    build_source(gpu, &test_program_source(), features)
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
    // fast on PoCL. No coordinate, colour or weight a scene means is that small; GPUs keep
    // their own default.
    if gpu.is_cpu() {
        options.push_str(" -cl-denorms-are-zero");
    } else {
        // The watertight test's axis permutation by selects, not shuffle() (kernels/traverse.h,
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
    Ok(program)
}

/// The register cap for NVIDIA's compiler, where it pays. The two-level traversal needs a few
/// registers more than flat's (the instance's tmin, the stack height of its walk): `extend`
/// and `trace_closest` take 72 against flat's 64 and 62. The cap of 72 keeps ptxas from
/// taking more, so that as many warps fit on a multiprocessor to hide the node loads; it took
/// two-level frames on an H200 from 0.82 to 0.90 of flat's when they took 89-94, and a cap of
/// 64 made frames 2-4 % slower. Flat programs stay under the cap and the cap does not change
/// them.
fn register_cap(gpu: &Gpu, features: KernelFeatures) -> Option<u32> {
    (features.two_level && gpu.has_extension("cl_nv_compiler_options"))
        .then_some(TWO_LEVEL_REGISTERS)
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
    fn a_kernel_folder_replaces_only_the_files_it_holds() {
        let dir = tempfile::tempdir().unwrap();
        let (name, _) = SOURCES[1];
        let path = dir.path().join(name);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, "// edited\n").unwrap();
        let mut s = String::new();
        assert_eq!(with_overrides(&mut s, SOURCES, Some(dir.path())), 1);
        assert!(s.contains("// edited"));
        assert!(s.contains(SOURCES[0].1), "the other files stay built in");
        assert!(!s.contains(SOURCES[1].1));
        // The files themselves, without their kernels/ folder, are not found.
        let flat = tempfile::tempdir().unwrap();
        std::fs::write(
            flat.path()
                .join(std::path::Path::new(name).file_name().unwrap()),
            "x",
        )
        .unwrap();
        assert_eq!(
            with_overrides(&mut String::new(), SOURCES, Some(flat.path())),
            0
        );
        assert_eq!(with_overrides(&mut String::new(), SOURCES, None), 0);
    }

    #[test]
    fn every_source_is_marked_with_its_file() {
        let s = test_program_source();
        for (name, _) in SOURCES.iter().chain(TEST_SOURCES) {
            assert!(s.contains(&format!("#line 1 \"{name}\"")), "{name}");
        }
    }

    #[test]
    fn the_production_program_has_no_test_kernels() {
        let s = program_source();
        for (name, _) in TEST_SOURCES {
            assert!(!s.contains(name), "{name}");
        }
        assert!(!s.contains("probe_layout") && !s.contains("_test("));
        assert!(
            s.contains("kernel void trace_closest"),
            "bench trace uses it"
        );
    }

    #[test]
    fn the_shared_constants_are_generated_once_before_the_kernels() {
        let s = program_source();
        let defines = s.find(DEFINES_NAME).expect("the generated header");
        assert!(defines < s.find("kernels/types.h").unwrap());
        assert!(s.contains("#define LIGHT_ENVIRONMENT 4u\n"), "{s:.2000}");
        assert!(s.contains("#define WRAP_MIRROR 2\n"));
        assert!(s.contains("#define COUNT_OVERFLOW 4\n"));
        for line in super::super::types::kernel_defines().lines() {
            let name = line.split_whitespace().nth(1).unwrap();
            let written = format!("#define {name} ");
            assert_eq!(s.matches(&written).count(), 1, "{name} is defined once");
        }
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
        let log = "warning: x\nkernels/stages.cl:12:5: error: use of undeclared identifier\n";
        assert_eq!(
            first_error(log),
            "kernels/stages.cl:12:5: error: use of undeclared identifier"
        );
    }
}
