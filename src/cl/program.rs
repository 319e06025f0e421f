//! The kernels' build at run time with the scene's feature defines (their source: `source.rs`).

use super::{ClError, Device};
use opencl3::device::CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT;
use std::path::Path;

/// The scene features that decide which kernel code is compiled in.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct KernelFeatures {
    /// Some triangles emit light (area lights with MIS).
    pub triangle_lights: bool,
    /// Some material has a texture (`HAS_TEXTURES`).
    pub textures: bool,
    /// Some material has a normal map (`HAS_NORMAL_MAPS`; implies textures).
    pub normal_maps: bool,
    /// Some mesh has vertex colours (`HAS_VERTEX_COLORS`: `COLOR_0` multiplies the base color
    /// and its alpha).
    pub vertex_colors: bool,
    /// Some material is single-sided (`HAS_SINGLE_SIDED`: camera rays pass the backs of its
    /// surfaces, as glTF culls them).
    pub single_sided: bool,
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
    /// count itself comes with each frame); 0 otherwise. This and the lanes' fields below are
    /// the CPU strategy, decided by [`crate::render::strategy::kernel_strategy`].
    pub small_scene: u32,
    /// The megakernel walks sixteen paths' rays together in vector lanes (`MEGA_LANES`,
    /// kernels/cpu/traverse_lanes.h).
    pub lanes: bool,
    /// The megakernel's lanes shade their paths' vertices in batches, in vectors
    /// (`LANES_SHADE`, kernels/cpu/shade_lanes.h).
    pub lanes_shade: bool,
    /// The megakernel's lanes test every triangle of a small scene instead of walking the tree
    /// (`LANES_SMALL`, kernels/cpu/traverse_lanes.h; the count comes with each frame).
    pub lanes_small: bool,
    /// The lanes load their nodes and triangles by gathers (`LANES_GATHERS`,
    /// kernels/cpu/traverse_lanes.h) rather than as rows transposed by shuffles.
    pub lanes_gathers: bool,
    /// Each path records guide buffers for a denoiser (`AOVS`, kernels/shared/aovs.h): the
    /// renderer's choice ([`crate::render::RenderSettings::aovs`]), not the scene's.
    pub aovs: bool,
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
            (self.vertex_colors, "HAS_VERTEX_COLORS"),
            (self.single_sided, "HAS_SINGLE_SIDED"),
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
            (self.aovs, "AOVS"),
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

/// Builds the program for `features` on the device. A failure returns the compiler's first
/// error line, which names the kernel file and line.
pub fn build_program(
    device: &Device,
    features: KernelFeatures,
) -> Result<opencl3::program::Program, ClError> {
    build_source(device, &super::source::program_source()?, features)
}

/// Builds the production kernels together with the test-only ones (layout probe, texture,
/// environment and BSDF test kernels); only tests reach it, through `Program`'s test wrappers.
pub fn build_test_program(
    device: &Device,
    features: KernelFeatures,
) -> Result<opencl3::program::Program, ClError> {
    build_source(device, &super::source::test_program_source()?, features)
}

/// Builds the denoiser's program (kernels/denoise/) with its `-D` options.
pub fn build_denoise_program(
    device: &Device,
    defines: &str,
) -> Result<opencl3::program::Program, ClError> {
    build_with(
        device,
        &super::source::denoise_program_source()?,
        KernelFeatures::default(),
        defines,
    )
}

pub(crate) fn build_source(
    device: &Device,
    source: &str,
    features: KernelFeatures,
) -> Result<opencl3::program::Program, ClError> {
    build_with(device, source, features, "")
}

/// Builds `source` with the features' defines and `defines` after them.
fn build_with(
    device: &Device,
    source: &str,
    features: KernelFeatures,
    defines: &str,
) -> Result<opencl3::program::Program, ClError> {
    let mut options = String::new();
    // Correctly rounded division keeps the device's triangle tests identical to the host's.
    if device
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
    if device.is_cpu() {
        options.push_str(" -cl-denorms-are-zero");
    } else {
        // The watertight test's axis permutation by selects, not shuffle() (kernels/shared/traverse.h,
        // `ray_permute`): faster on an H200, while a CPU does a shuffle in one instruction.
        options.push_str(" -DPERMUTE_BY_SELECT");
    }
    options.push_str(&features.defines());
    options.push_str(defines);
    if let Some(cap) = register_cap(device, features) {
        options.push_str(&format!(" -cl-nv-maxrregcount={cap}"));
    }
    // Extra compiler options for experiments (e.g. `-cl-mad-enable`), space-separated.
    if let Ok(extra) = std::env::var("PENUMBRA_CL_OPTIONS") {
        options.push(' ');
        options.push_str(&extra);
    }
    if let Some(dir) = std::env::var_os("PENUMBRA_DUMP_PROGRAMS") {
        dump_program(Path::new(&dir), source, &options);
    }
    let _setup = super::CL_SETUP.lock().unwrap_or_else(|e| e.into_inner());
    let mut program = opencl3::program::Program::create_from_source(&device.context, source)
        .map_err(|e| ClError::Build(format!("cannot create the program: {e}")))?;
    if program.build(&[device.device.id()], &options).is_err() {
        let log = program
            .get_build_log(device.device.id())
            .unwrap_or_default();
        log::debug!("kernel build log:\n{log}");
        return Err(ClError::Build(first_error(&log)));
    }
    // A successful build's log (warnings; with `PENUMBRA_CL_OPTIONS=-cl-nv-verbose`, NVIDIA's
    // registers and spills per kernel) for RUST_LOG=debug.
    if log::log_enabled!(log::Level::Debug) {
        let log = program
            .get_build_log(device.device.id())
            .unwrap_or_default();
        if !log.trim().is_empty() {
            log::debug!("kernel build log ({options}):\n{log}");
        }
    }
    Ok(program)
}

/// Writes a program's source (`program-HASH.cl`) and its build options (`program-HASH.options`)
/// into `dir`, as they go to the compiler, for reading the kernels' code offline
/// (`scripts/ptx_proxy.sh` compiles them for NVIDIA's PTX with clang). A failure is a warning.
fn dump_program(dir: &Path, source: &str, options: &str) {
    use std::hash::{Hash, Hasher};
    let mut hasher = std::collections::hash_map::DefaultHasher::new();
    (source, options).hash(&mut hasher);
    let stem = dir.join(format!("program-{:016x}", hasher.finish()));
    let written = std::fs::create_dir_all(dir)
        .and_then(|()| std::fs::write(stem.with_extension("cl"), source))
        .and_then(|()| std::fs::write(stem.with_extension("options"), options.trim()));
    if let Err(e) = written {
        log::warn!(
            "PENUMBRA_DUMP_PROGRAMS: cannot write {}: {e}",
            stem.display()
        );
    }
}

/// The register cap for NVIDIA's compiler, where it pays. The two-level traversal needs a few
/// registers more than flat's (the instance's tmin, the stack height of its walk): `extend`
/// and `trace_closest` take 72 against flat's 64 and 62. The cap of 72 keeps ptxas from
/// taking more, so that as many warps fit on a multiprocessor to hide the node loads; it took
/// two-level frames on an H200 from 0.82 to 0.90 of flat's when they took 89-94, and a cap of
/// 64 made frames 2-4 % slower. Flat programs stay under the cap and the cap does not change
/// them.
fn register_cap(device: &Device, features: KernelFeatures) -> Option<u32> {
    (features.two_level && device.has_extension("cl_nv_compiler_options"))
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
    fn a_build_error_names_the_kernel_file_and_line() {
        let device = Device::open(&crate::cl::DeviceChoice::Cpu).expect("an OpenCL CPU device");
        let source = "#line 1 \"kernels/broken.cl\"\nkernel void f(global int* x) {\n  x[0] = undeclared;\n}\n";
        let err = build_source(&device, source, KernelFeatures::default())
            .expect_err("the source does not compile")
            .to_string();
        assert!(err.contains("kernels/broken.cl:2"), "{err}");
        assert!(!err.contains('\n'), "one line: {err}");
    }

    #[test]
    fn a_dumped_program_is_its_source_and_options() {
        let dir = tempfile::tempdir().unwrap();
        dump_program(dir.path(), "kernel void f() {}\n", " -DA -DB");
        dump_program(dir.path(), "kernel void f() {}\n", " -DA");
        let mut names: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        names.sort();
        assert_eq!(
            names.len(),
            4,
            "two programs, each source and options: {names:?}"
        );
        let options: Vec<_> = names
            .iter()
            .filter(|n| n.ends_with(".options"))
            .map(|n| std::fs::read_to_string(dir.path().join(n)).unwrap())
            .collect();
        assert!(options.contains(&"-DA -DB".to_string()) && options.contains(&"-DA".to_string()));
        let source = names.iter().find(|n| n.ends_with(".cl")).unwrap();
        assert_eq!(
            std::fs::read_to_string(dir.path().join(source)).unwrap(),
            "kernel void f() {}\n"
        );
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
