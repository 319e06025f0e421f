//! The kernel strategy: which kernels run (the wavefront or the megakernel) and how the CPU
//! megakernel traces and shades (one ray at a time or sixteen in vector lanes, a small scene's
//! triangles tested whole, vertices shaded in batches, nodes loaded as rows or by gathers).
//! [`runs_megakernel`] and [`kernel_strategy`] are the whole decision: pure functions of the
//! device's facts, the scene's and the environment's [`Overrides`], which are read once.
//!
//! | kernels in use | scene | outcome |
//! |---|---|---|
//! | `--kernel auto` on a CPU, `megakernel` anywhere | | the megakernel |
//! | `--kernel auto` on a GPU, `wavefront` anywhere | | the wavefront, none of the rows below |
//! | megakernel on a GPU | | one ray at a time over the tree |
//! | CPU megakernel | two levels, or alpha | one ray at a time over the tree |
//! | CPU megakernel | flat, no alpha, 1 to [`SMALL_SCENE_MAX`] triangles, no lanes | `SMALL_SCENE`: every ray tests every triangle (count rounded up to 16) |
//! | CPU megakernel | flat, no alpha, under 2^27 triangles, leaves of at most 15 | lanes (`MEGA_LANES`), never with guide buffers (`AOVS`, which the lanes do not record); else when `PENUMBRA_LANES=1`; never when `=0`; else with AVX-512 or AVX2 from [`LANES_MIN_TRIANGLES`] on, and below where the lanes test a small scene whole or shade in batches |
//! | lanes | small (as `SMALL_SCENE`), `PENUMBRA_LANES_SMALL` not `0` | `LANES_SMALL`: the lanes test the triangles whole |
//! | lanes | every material Lambertian, none of the features `shades_simply` excludes, `PENUMBRA_LANES_SHADE` not `0` | `LANES_SHADE`: vertices shaded in batches |
//! | lanes | | nodes and triangles loaded as rows on AMD CPUs, else `LANES_GATHERS`; `PENUMBRA_LANES_LOAD=rows\|gathers` chooses |

use super::KernelChoice;
use crate::cl::KernelFeatures;
use crate::cl::types::SMALL_LANES;

/// The most triangles a scene may have for the megakernel to test them all for every ray
/// (`KernelFeatures::small_scene`): up to this many, sixteen at a time in vector lanes, cost
/// less than walking the 4-wide BVH on PoCL (a box of 36 triangles took 7.5–7.8 CPU s against
/// the tree's 8.7–8.8, one of 144 12.6–13.0 against 11.9–12.2).
pub const SMALL_SCENE_MAX: usize = 64;

/// The fewest triangles for which the megakernel walks its rays in lanes even where they do
/// not shade in batches: below, the tree fits the caches, a walk seldom waits on memory, and
/// the lanes measured 6–9 % slower on the shared scenes of about 10,000 triangles; from 41,000
/// on they were 2–6 % faster, and 27 % on the 1 M-triangle bunnies.
pub const LANES_MIN_TRIANGLES: usize = 32_768;

/// The lanes' stack entry packs a triangle index (below this) with a leaf's count.
const LANES_MAX_TRIANGLES: usize = 1 << 27;

/// The largest leaf the lanes' stack entry can hold (four bits).
const LANES_MAX_LEAF: u32 = 15;

/// What the strategy needs to know of the device.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DeviceFacts {
    /// The device is a CPU (`CL_DEVICE_TYPE_CPU`: PoCL's, which is the host's CPU).
    pub cpu: bool,
    /// The host CPU has AVX-512 (whose gathers, scatters and compresses the lanes use) or AVX2
    /// (eight lanes: gathers, table-driven compresses, stores for scatters; 17–25 % less time
    /// than one ray at a time on AMD's Zen 3).
    pub vectors: bool,
    /// The host CPU is AMD's, by its CPUID vendor string: the lanes load rows there. On AMD's
    /// Zen 5 a gather loads about one element a cycle from L2, and rows make the walk 1.3–1.8×
    /// faster natively; on an Intel Xeon gathers are 3–7 % faster.
    pub amd: bool,
}

impl DeviceFacts {
    /// The facts of a device that is (`cpu`) or is not a CPU, the host's CPU asked by CPUID.
    pub fn of(cpu: bool) -> Self {
        Self {
            cpu,
            vectors: host_has_vectors(),
            amd: host_cpu_is_amd(),
        }
    }
}

/// Whether the host CPU has AVX-512 or AVX2.
fn host_has_vectors() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx512f")
            || std::arch::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Whether the host CPU is AMD's, by its CPUID vendor string.
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

/// What the strategy needs to know of the scene.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SceneFacts {
    /// The features its materials, lights, acceleration structure and environment map need
    /// (the strategy's own fields unset).
    pub features: KernelFeatures,
    /// Triangles the kernels trace.
    pub triangles: usize,
    /// The most triangles in one leaf of the flat BVH (0 for two levels).
    pub largest_leaf: u32,
}

/// How the lanes load each lane's node and triangles.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LanesLoad {
    /// As rows, transposed into vectors by shuffles.
    Rows,
    /// By gathers (`LANES_GATHERS`).
    Gathers,
}

/// The environment's overrides of the strategy, for measuring and for tests; each changes
/// speed, never the image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Overrides {
    /// `PENUMBRA_LANES`: `0` never walks in lanes, `1` walks in lanes on any CPU device at any
    /// size (lane by lane where the CPU has neither AVX-512 nor AVX2).
    pub lanes: Option<bool>,
    /// `PENUMBRA_LANES_SHADE`: `0` shades the lanes' vertices one by one.
    pub lanes_shade: bool,
    /// `PENUMBRA_LANES_SMALL`: `0` walks a small scene's tree in lanes instead of testing its
    /// triangles whole.
    pub lanes_small: bool,
    /// `PENUMBRA_LANES_LOAD`: `rows` or `gathers`.
    pub lanes_load: Option<LanesLoad>,
}

impl Default for Overrides {
    /// No override: the strategy as the table says.
    fn default() -> Self {
        Self {
            lanes: None,
            lanes_shade: true,
            lanes_small: true,
            lanes_load: None,
        }
    }
}

impl Overrides {
    /// The overrides in the process's environment, read once (later calls return the first
    /// answer); an unrecognised value is warned about and ignored.
    pub fn from_env() -> Self {
        static READ: std::sync::OnceLock<Overrides> = std::sync::OnceLock::new();
        *READ.get_or_init(|| Self::parse(|name| std::env::var(name).ok()))
    }

    /// The overrides that `var` gives for each variable's name.
    fn parse(var: impl Fn(&str) -> Option<String>) -> Self {
        let mut o = Self::default();
        for name in [
            "PENUMBRA_LANES",
            "PENUMBRA_LANES_SHADE",
            "PENUMBRA_LANES_SMALL",
            "PENUMBRA_LANES_LOAD",
        ] {
            let Some(value) = var(name) else { continue };
            let v = value.trim();
            let known = match (name, v) {
                (_, "") => true,
                ("PENUMBRA_LANES", "0" | "1") => {
                    o.lanes = Some(v == "1");
                    true
                }
                ("PENUMBRA_LANES_SHADE", "0" | "1") => {
                    o.lanes_shade = v == "1";
                    true
                }
                ("PENUMBRA_LANES_SMALL", "0" | "1") => {
                    o.lanes_small = v == "1";
                    true
                }
                ("PENUMBRA_LANES_LOAD", "rows") => {
                    o.lanes_load = Some(LanesLoad::Rows);
                    true
                }
                ("PENUMBRA_LANES_LOAD", "gathers") => {
                    o.lanes_load = Some(LanesLoad::Gathers);
                    true
                }
                _ => false,
            };
            if !known {
                log::warn!("{name}={value:?} is not a value it takes: ignored");
            }
        }
        o
    }
}

/// Whether `choice` runs the megakernel on the device: `Auto` picks it on CPU devices.
pub fn runs_megakernel(device: &DeviceFacts, choice: KernelChoice) -> bool {
    match choice {
        KernelChoice::Auto => device.cpu,
        KernelChoice::Wavefront => false,
        KernelChoice::Megakernel => true,
    }
}

/// The features to build the kernels with: the scene's, and the strategy of the module's table
/// for the kernels in use (`megakernel`: else the wavefront, which takes none of it).
pub fn kernel_strategy(
    device: &DeviceFacts,
    megakernel: bool,
    scene: &SceneFacts,
    overrides: &Overrides,
) -> KernelFeatures {
    let f = scene.features;
    if !(megakernel && device.cpu) || f.two_level || f.alpha {
        return f;
    }
    // Small scenes: kernels built for whole batches of sixteen triangles, the count itself
    // with each frame, so that hiding or showing an object mostly builds nothing.
    let small = (1..=SMALL_SCENE_MAX).contains(&scene.triangles);
    // Testing a small scene whole in lanes is faster than both its tree in lanes and
    // `SMALL_SCENE` one ray at a time, with the same hits.
    let small_in_lanes = small && overrides.lanes_small;
    let batched = overrides.lanes_shade && shades_simply(&f);
    // The lanes record no guide buffers: with them, paths go one at a time.
    let lanes = !f.aovs
        && scene.triangles < LANES_MAX_TRIANGLES
        && scene.largest_leaf <= LANES_MAX_LEAF
        && overrides.lanes.unwrap_or(
            device.vectors && (scene.triangles >= LANES_MIN_TRIANGLES || small_in_lanes || batched),
        );
    let rows = overrides
        .lanes_load
        .map_or(device.amd, |l| l == LanesLoad::Rows);
    KernelFeatures {
        small_scene: if small && !lanes {
            scene.triangles.next_multiple_of(SMALL_LANES) as u32
        } else {
            0
        },
        lanes,
        lanes_small: lanes && small_in_lanes,
        lanes_shade: lanes && batched,
        lanes_gathers: lanes && !rows,
        ..f
    }
}

/// Whether the lanes can shade a scene of features `f` in batches (`LANES_SHADE`,
/// kernels/cpu/shade_lanes.h, path.h's `shade_vertex` lane by lane): every material Lambertian and
/// no textures, vertex colours, normal maps, environment map, unlit materials, thin walls, transmission, coats,
/// sheen, iridescence, anisotropy or dispersion. The batches take 12 % fewer instructions and
/// about 6 % less time on the 1 M-triangle room; they make the bundled box 12 % faster at 64
/// bounces and its viewer 1.3× on AMD's Zen 3, so they pay at any size.
fn shades_simply(f: &KernelFeatures) -> bool {
    f.lambert_only
        && !(f.textures
            || f.vertex_colors
            || f.normal_maps
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
}

#[cfg(test)]
mod tests {
    use super::*;

    const AVX: DeviceFacts = DeviceFacts {
        cpu: true,
        vectors: true,
        amd: false,
    };
    /// A scene whose every material is Lambertian, and nothing else.
    fn lambert() -> KernelFeatures {
        KernelFeatures {
            lambert_only: true,
            ..KernelFeatures::default()
        }
    }

    /// The strategy's outputs for a flat scene of `triangles` in leaves of at most 4:
    /// (small_scene, lanes, lanes_small, lanes_shade, lanes_gathers).
    fn decide(
        device: DeviceFacts,
        megakernel: bool,
        features: KernelFeatures,
        triangles: usize,
        overrides: Overrides,
    ) -> (u32, bool, bool, bool, bool) {
        let scene = SceneFacts {
            features,
            triangles,
            largest_leaf: 4,
        };
        let f = kernel_strategy(&device, megakernel, &scene, &overrides);
        assert_eq!(
            KernelFeatures {
                small_scene: 0,
                lanes: false,
                lanes_small: false,
                lanes_shade: false,
                lanes_gathers: false,
                ..f
            },
            features,
            "the scene's own features pass through"
        );
        (
            f.small_scene,
            f.lanes,
            f.lanes_small,
            f.lanes_shade,
            f.lanes_gathers,
        )
    }

    const NONE: (u32, bool, bool, bool, bool) = (0, false, false, false, false);

    #[test]
    fn auto_runs_the_megakernel_on_cpus_only() {
        let device = DeviceFacts::default();
        assert!(runs_megakernel(&AVX, KernelChoice::Auto));
        assert!(!runs_megakernel(&device, KernelChoice::Auto));
        assert!(!runs_megakernel(&AVX, KernelChoice::Wavefront));
        assert!(runs_megakernel(&device, KernelChoice::Megakernel));
    }

    #[test]
    fn the_wavefront_and_gpus_take_no_cpu_strategy() {
        let o = Overrides {
            lanes: Some(true),
            ..Overrides::default()
        };
        for triangles in [32, 1 << 20] {
            assert_eq!(decide(AVX, false, lambert(), triangles, o), NONE);
            let device = DeviceFacts::default();
            assert_eq!(decide(device, true, lambert(), triangles, o), NONE);
        }
    }

    #[test]
    fn large_flat_scenes_walk_in_lanes_with_vectors() {
        let o = Overrides::default();
        let glossy = KernelFeatures::default();
        let large = LANES_MIN_TRIANGLES;
        assert_eq!(
            decide(AVX, true, glossy, large, o),
            (0, true, false, false, true)
        );
        assert_eq!(
            decide(AVX, true, lambert(), large, o),
            (0, true, false, true, true),
            "Lambertian: shaded in batches"
        );
        assert_eq!(
            decide(AVX, true, glossy, large - 1, o),
            NONE,
            "below the threshold, only where batches or a small scene pay"
        );
        assert_eq!(
            decide(AVX, true, lambert(), 1000, o),
            (0, true, false, true, true)
        );
        let scalar = DeviceFacts {
            vectors: false,
            ..AVX
        };
        assert_eq!(decide(scalar, true, lambert(), large, o), NONE);
        let amd = DeviceFacts { amd: true, ..AVX };
        assert_eq!(
            decide(amd, true, glossy, large, o),
            (0, true, false, false, false),
            "AMD loads rows"
        );
    }

    #[test]
    fn lanes_need_a_flat_scene_without_alpha_that_their_stack_can_hold() {
        let o = Overrides {
            lanes: Some(true),
            ..Overrides::default()
        };
        for f in [
            KernelFeatures {
                alpha: true,
                ..lambert()
            },
            KernelFeatures {
                two_level: true,
                ..lambert()
            },
        ] {
            assert_eq!(decide(AVX, true, f, 32, o), NONE, "{f:?}");
            assert_eq!(decide(AVX, true, f, 1 << 20, o), NONE, "{f:?}");
        }
        assert_eq!(decide(AVX, true, lambert(), LANES_MAX_TRIANGLES, o), NONE);
        let scene = SceneFacts {
            features: lambert(),
            triangles: 1 << 20,
            largest_leaf: LANES_MAX_LEAF + 1,
        };
        assert!(!kernel_strategy(&AVX, true, &scene, &o).lanes);
    }

    #[test]
    fn guide_buffers_take_paths_one_at_a_time_even_where_lanes_are_forced() {
        let o = Overrides {
            lanes: Some(true),
            ..Overrides::default()
        };
        let aovs = KernelFeatures {
            aovs: true,
            ..lambert()
        };
        assert_eq!(decide(AVX, true, aovs, 1 << 20, o), NONE);
        // A small scene is still tested whole, one ray at a time.
        assert_eq!(decide(AVX, true, aovs, 32, o).0, 32);
        assert!(
            decide(AVX, true, lambert(), 1 << 20, o).1,
            "lanes without AOVs"
        );
    }

    #[test]
    fn small_flat_scenes_are_tested_whole_in_lanes_or_one_ray_at_a_time() {
        let o = Overrides::default();
        let glossy = KernelFeatures::default();
        // Lanes test them whole, shaded in batches where the materials allow.
        assert_eq!(
            decide(AVX, true, glossy, 32, o),
            (0, true, true, false, true)
        );
        assert_eq!(
            decide(AVX, true, lambert(), 32, o),
            (0, true, true, true, true)
        );
        // Without vectors, one ray at a time: built for whole batches of sixteen.
        let scalar = DeviceFacts {
            vectors: false,
            ..AVX
        };
        for (triangles, built) in [(1, 16), (17, 32), (22, 32), (32, 32), (36, 48), (64, 64)] {
            assert_eq!(
                decide(scalar, true, glossy, triangles, o),
                (built, false, false, false, false),
                "{triangles}"
            );
        }
        assert_eq!(decide(scalar, true, glossy, SMALL_SCENE_MAX + 1, o), NONE);
        assert_eq!(decide(scalar, true, glossy, 0, o), NONE, "nothing to test");
        let alpha = KernelFeatures {
            alpha: true,
            ..glossy
        };
        assert_eq!(
            decide(scalar, true, alpha, 32, o),
            NONE,
            "alpha tests need the tree's loop"
        );
    }

    #[test]
    fn overrides_turn_each_choice() {
        let off = |f: fn(&mut Overrides)| {
            let mut o = Overrides::default();
            f(&mut o);
            o
        };
        let glossy = KernelFeatures::default();
        let no_lanes = off(|o| o.lanes = Some(false));
        assert_eq!(decide(AVX, true, lambert(), 1 << 20, no_lanes), NONE);
        assert_eq!(
            decide(AVX, true, lambert(), 32, no_lanes),
            (32, false, false, false, false)
        );
        let scalar = DeviceFacts {
            vectors: false,
            ..AVX
        };
        let lanes = off(|o| o.lanes = Some(true));
        assert_eq!(
            decide(scalar, true, glossy, 1000, lanes),
            (0, true, false, false, true),
            "lane by lane"
        );
        let no_shade = off(|o| o.lanes_shade = false);
        assert_eq!(
            decide(AVX, true, lambert(), 1 << 20, no_shade),
            (0, true, false, false, true)
        );
        assert_eq!(decide(AVX, true, lambert(), 1000, no_shade), NONE);
        let no_small = off(|o| o.lanes_small = false);
        assert_eq!(
            decide(AVX, true, glossy, 32, no_small),
            (32, false, false, false, false)
        );
        assert_eq!(
            decide(AVX, true, lambert(), 32, no_small),
            (0, true, false, true, true),
            "the tree in lanes, shaded in batches"
        );
        let tree_in_lanes = off(|o| {
            o.lanes = Some(true);
            o.lanes_small = false
        });
        assert_eq!(
            decide(AVX, true, glossy, 32, tree_in_lanes),
            (0, true, false, false, true)
        );
        let rows = off(|o| o.lanes_load = Some(LanesLoad::Rows));
        assert_eq!(
            decide(AVX, true, glossy, 1 << 20, rows),
            (0, true, false, false, false)
        );
        let amd = DeviceFacts { amd: true, ..AVX };
        let gathers = off(|o| o.lanes_load = Some(LanesLoad::Gathers));
        assert_eq!(
            decide(amd, true, glossy, 1 << 20, gathers),
            (0, true, false, false, true)
        );
    }

    #[test]
    fn batched_shading_is_for_the_simplest_materials() {
        let o = Overrides::default();
        let large = 1 << 20;
        for f in [
            KernelFeatures {
                textures: true,
                ..lambert()
            },
            KernelFeatures {
                env_map: true,
                ..lambert()
            },
            KernelFeatures {
                unlit: true,
                ..lambert()
            },
            KernelFeatures {
                thin_walls: true,
                ..lambert()
            },
            KernelFeatures {
                dispersion: true,
                ..lambert()
            },
        ] {
            assert_eq!(
                decide(AVX, true, f, large, o),
                (0, true, false, false, true),
                "{f:?}"
            );
        }
        let lit = KernelFeatures {
            triangle_lights: true,
            ..lambert()
        };
        assert_eq!(
            decide(AVX, true, lit, large, o),
            (0, true, false, true, true)
        );
    }

    #[test]
    fn overrides_are_read_from_their_variables() {
        let read = |pairs: &[(&str, &str)]| {
            let pairs: Vec<(String, String)> = pairs
                .iter()
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect();
            Overrides::parse(|name| {
                pairs
                    .iter()
                    .find(|(k, _)| k == name)
                    .map(|(_, v)| v.clone())
            })
        };
        assert_eq!(read(&[]), Overrides::default());
        assert_eq!(
            read(&[
                ("PENUMBRA_LANES", " 0 "),
                ("PENUMBRA_LANES_SHADE", "0"),
                ("PENUMBRA_LANES_SMALL", "0"),
                ("PENUMBRA_LANES_LOAD", "rows"),
            ]),
            Overrides {
                lanes: Some(false),
                lanes_shade: false,
                lanes_small: false,
                lanes_load: Some(LanesLoad::Rows),
            }
        );
        assert_eq!(
            read(&[
                ("PENUMBRA_LANES", "1"),
                ("PENUMBRA_LANES_SHADE", "1"),
                ("PENUMBRA_LANES_LOAD", "gathers"),
            ]),
            Overrides {
                lanes: Some(true),
                lanes_load: Some(LanesLoad::Gathers),
                ..Overrides::default()
            }
        );
        // Unrecognised values are ignored (with a warning).
        assert_eq!(
            read(&[("PENUMBRA_LANES", "yes"), ("PENUMBRA_LANES_LOAD", "")]),
            Overrides::default()
        );
    }
}
