//! The kernels' source text: every kernel file embedded at compile time, and the expansion of a
//! root file's `#include "..."` lines into one program source, as the OpenCL compiler takes it.
//!
//! Include paths are relative to `kernels/` (`#include "shared/types.h"`), except
//! `generated/constants.h`, the constants shared with the host (generated from `cl/types.rs`).
//! A file is expanded once, at its first inclusion (`#pragma once`'s meaning; the headers' guards
//! say the same to other tools), so an `#include` must not sit under a condition: the inclusion
//! the condition drops could be the one that counts. `#line` directives before and after each
//! inclusion keep the compiler's messages naming the file and line.

use super::ClError;
use std::path::Path;

/// The production program's root: every kernel the renderer launches.
const PROGRAM_ROOT: &str = "program.cl";

/// The test program's root: the production program and the kernels only tests use.
const TEST_PROGRAM_ROOT: &str = "test/program.cl";

/// The denoiser's program root (its own program, built apart from the path tracer's).
const DENOISE_PROGRAM_ROOT: &str = "denoise/program.cl";

/// Every kernel file, by its path in the repository.
const KERNELS: &[(&str, &str)] = &[
    (
        "kernels/program.cl",
        include_str!("../../kernels/program.cl"),
    ),
    (
        "kernels/shared/types.h",
        include_str!("../../kernels/shared/types.h"),
    ),
    (
        "kernels/shared/vec3.h",
        include_str!("../../kernels/shared/vec3.h"),
    ),
    (
        "kernels/shared/rng.h",
        include_str!("../../kernels/shared/rng.h"),
    ),
    (
        "kernels/shared/textures.h",
        include_str!("../../kernels/shared/textures.h"),
    ),
    (
        "kernels/shared/traverse.h",
        include_str!("../../kernels/shared/traverse.h"),
    ),
    (
        "kernels/shared/traverse_wide.h",
        include_str!("../../kernels/shared/traverse_wide.h"),
    ),
    (
        "kernels/shared/bsdf.h",
        include_str!("../../kernels/shared/bsdf.h"),
    ),
    (
        "kernels/shared/bsdf_tables.h",
        include_str!("../../kernels/shared/bsdf_tables.h"),
    ),
    (
        "kernels/shared/material.h",
        include_str!("../../kernels/shared/material.h"),
    ),
    (
        "kernels/shared/microfacet.h",
        include_str!("../../kernels/shared/microfacet.h"),
    ),
    (
        "kernels/shared/thin_film.h",
        include_str!("../../kernels/shared/thin_film.h"),
    ),
    (
        "kernels/shared/bsdf_layers.h",
        include_str!("../../kernels/shared/bsdf_layers.h"),
    ),
    (
        "kernels/shared/lambert.h",
        include_str!("../../kernels/shared/lambert.h"),
    ),
    (
        "kernels/shared/surface.h",
        include_str!("../../kernels/shared/surface.h"),
    ),
    (
        "kernels/shared/env.h",
        include_str!("../../kernels/shared/env.h"),
    ),
    (
        "kernels/shared/lights.h",
        include_str!("../../kernels/shared/lights.h"),
    ),
    (
        "kernels/shared/aovs.h",
        include_str!("../../kernels/shared/aovs.h"),
    ),
    (
        "kernels/shared/path.h",
        include_str!("../../kernels/shared/path.h"),
    ),
    (
        "kernels/shared/film.h",
        include_str!("../../kernels/shared/film.h"),
    ),
    (
        "kernels/shared/adaptive.h",
        include_str!("../../kernels/shared/adaptive.h"),
    ),
    (
        "kernels/gpu/stages.cl",
        include_str!("../../kernels/gpu/stages.cl"),
    ),
    (
        "kernels/cpu/simd.h",
        include_str!("../../kernels/cpu/simd.h"),
    ),
    (
        "kernels/cpu/traverse_lanes.h",
        include_str!("../../kernels/cpu/traverse_lanes.h"),
    ),
    (
        "kernels/cpu/traverse_packet.h",
        include_str!("../../kernels/cpu/traverse_packet.h"),
    ),
    (
        "kernels/cpu/shade_lanes.h",
        include_str!("../../kernels/cpu/shade_lanes.h"),
    ),
    (
        "kernels/cpu/megakernel.h",
        include_str!("../../kernels/cpu/megakernel.h"),
    ),
    (
        "kernels/cpu/megakernel.cl",
        include_str!("../../kernels/cpu/megakernel.cl"),
    ),
    (
        "kernels/cpu/megakernel_lanes.cl",
        include_str!("../../kernels/cpu/megakernel_lanes.cl"),
    ),
    ("kernels/tools.cl", include_str!("../../kernels/tools.cl")),
    (
        "kernels/denoise/program.cl",
        include_str!("../../kernels/denoise/program.cl"),
    ),
    (
        "kernels/denoise/tensor.h",
        include_str!("../../kernels/denoise/tensor.h"),
    ),
    (
        "kernels/denoise/transfer.h",
        include_str!("../../kernels/denoise/transfer.h"),
    ),
    (
        "kernels/denoise/conv.cl",
        include_str!("../../kernels/denoise/conv.cl"),
    ),
    (
        "kernels/denoise/prepare.cl",
        include_str!("../../kernels/denoise/prepare.cl"),
    ),
    (
        "kernels/test/program.cl",
        include_str!("../../kernels/test/program.cl"),
    ),
    (
        "kernels/test/tests.cl",
        include_str!("../../kernels/test/tests.cl"),
    ),
    (
        "kernels/test/bsdf_test.cl",
        include_str!("../../kernels/test/bsdf_test.cl"),
    ),
];

/// The name the generated constants header goes by, in `#include` lines and compiler messages.
const DEFINES_NAME: &str = "generated/constants.h";

/// The production program's source, its includes expanded. With `PENUMBRA_KERNEL_DIR` set (for
/// working on the kernels without rebuilding the binary), a file found under that folder by its
/// path (e.g. `PENUMBRA_KERNEL_DIR=.` for `kernels/shared/path.h`) replaces the built-in text.
pub fn program_source() -> Result<String, ClError> {
    expand_with_env(PROGRAM_ROOT)
}

/// The denoiser's program source, its includes expanded (`PENUMBRA_KERNEL_DIR` applies).
pub fn denoise_program_source() -> Result<String, ClError> {
    expand_with_env(DENOISE_PROGRAM_ROOT)
}

/// [`program_source`] followed by the test-only kernels.
pub fn test_program_source() -> Result<String, ClError> {
    expand_with_env(TEST_PROGRAM_ROOT)
}

/// [`expand`] with the override folder of `PENUMBRA_KERNEL_DIR`, warning once when it holds none
/// of the files.
fn expand_with_env(root: &str) -> Result<String, ClError> {
    let dir = std::env::var_os("PENUMBRA_KERNEL_DIR").map(std::path::PathBuf::from);
    let (source, found) = expand(root, dir.as_deref()).map_err(ClError::Build)?;
    if let Some(dir) = dir.filter(|_| found == 0) {
        // Without this, an experiment run with the wrong folder silently measures the
        // built-in kernels (the names carry their `kernels/` folder).
        static WARNED: std::sync::Once = std::sync::Once::new();
        WARNED.call_once(|| {
            log::warn!(
                "PENUMBRA_KERNEL_DIR={}: no kernel file there (it must hold kernels/{root}); \
                 the built-in kernels are used",
                dir.display()
            )
        });
    }
    Ok(source)
}

/// The source of `root` (a path under `kernels/`) with its includes expanded, and how many files
/// the folder `dir` replaced. An include that names no file is an error naming the including
/// file and line.
fn expand(root: &str, dir: Option<&Path>) -> Result<(String, usize), String> {
    let mut e = Expander {
        dir,
        out: String::new(),
        included: Vec::new(),
        replaced: 0,
    };
    e.include(root, None)?;
    Ok((e.out, e.replaced))
}

/// The state of one expansion: the text so far and the files already in it.
struct Expander<'a> {
    dir: Option<&'a Path>,
    out: String,
    included: Vec<String>,
    replaced: usize,
}

impl Expander<'_> {
    /// Appends the file `include` names, unless already there; `from` is the including file and
    /// line, for the message when no file has that name.
    fn include(&mut self, include: &str, from: Option<(&str, usize)>) -> Result<(), String> {
        let name = match include {
            DEFINES_NAME => DEFINES_NAME.to_string(),
            _ => format!("kernels/{include}"),
        };
        if self.included.contains(&name) {
            return Ok(());
        }
        let text = self.text(&name).ok_or_else(|| match from {
            Some((file, line)) => format!("{file}:{line}: error: cannot find \"{include}\""),
            None => format!("error: cannot find {name}"),
        })?;
        self.included.push(name.clone());
        self.out.push_str(&format!("#line 1 \"{name}\"\n"));
        // How deep in #if blocks each line is, and how deep an include may be: a header's guard
        // (its first directive, an #ifndef) is the one block around it allowed.
        let mut depth = 0usize;
        let mut guarded = None;
        for (i, line) in text.lines().enumerate() {
            match directive(line) {
                Some(d @ ("if" | "ifdef" | "ifndef")) => {
                    guarded.get_or_insert(name.ends_with(".h") && d == "ifndef");
                    depth += 1;
                }
                Some("endif") => depth = depth.saturating_sub(1),
                Some(_) => {
                    guarded.get_or_insert(false);
                }
                None => {}
            }
            match included_path(line) {
                Some(_) if depth > usize::from(guarded == Some(true)) => {
                    return Err(format!(
                        "{name}:{}: error: an #include under a condition (a file is expanded \
                         once, where it is first included)",
                        i + 1
                    ));
                }
                Some(path) => {
                    let before = self.out.len();
                    self.include(path, Some((&name, i + 1)))?;
                    // The next line keeps its number: after the included text, a #line says
                    // so; for a file already included, an empty line stands in.
                    if self.out.len() == before {
                        self.out.push('\n');
                    } else {
                        self.out.push_str(&format!("#line {} \"{name}\"\n", i + 2));
                    }
                }
                None => {
                    self.out.push_str(line);
                    self.out.push('\n');
                }
            }
        }
        Ok(())
    }

    /// The text of a file by its name: the generated constants, the override folder's file or
    /// the built-in one.
    fn text(&mut self, name: &str) -> Option<String> {
        if name == DEFINES_NAME {
            return Some(super::types::kernel_defines());
        }
        if let Some(edited) = self
            .dir
            .and_then(|d| std::fs::read_to_string(d.join(name)).ok())
        {
            self.replaced += 1;
            return Some(edited);
        }
        let text = KERNELS.iter().find(|(n, _)| *n == name)?.1;
        Some(text.to_string())
    }
}

/// The directive of a preprocessor line (`ifdef` of `#ifdef X`).
fn directive(line: &str) -> Option<&str> {
    let rest = line.trim_start().strip_prefix('#')?.trim_start();
    rest.split(|c: char| !c.is_ascii_alphabetic()).next()
}

/// The path of an `#include "path"` line.
fn included_path(line: &str) -> Option<&str> {
    let rest = line.trim_start().strip_prefix('#')?.trim_start();
    let quoted = rest.strip_prefix("include")?.trim();
    quoted.strip_prefix('"')?.strip_suffix('"')
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A folder holding `files` under kernels/, as PENUMBRA_KERNEL_DIR would name it.
    fn kernel_dir(files: &[(&str, &str)]) -> tempfile::TempDir {
        let dir = tempfile::tempdir().unwrap();
        for (name, text) in files {
            let path = dir.path().join("kernels").join(name);
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(path, text).unwrap();
        }
        dir
    }

    #[test]
    fn a_kernel_folder_replaces_only_the_files_it_holds() {
        let dir = kernel_dir(&[("shared/rng.h", "// edited\n")]);
        let (s, found) = expand(PROGRAM_ROOT, Some(dir.path())).unwrap();
        assert_eq!(found, 1);
        assert!(s.contains("// edited"));
        assert!(
            s.contains("} DeviceBvhNode;"),
            "the other files stay built in"
        );
        assert!(!s.contains("inline uint hash_u32(uint x)"));
        // The files themselves, without their kernels/ folder, are not found.
        let flat = tempfile::tempdir().unwrap();
        std::fs::create_dir_all(flat.path().join("shared")).unwrap();
        std::fs::write(flat.path().join("shared/rng.h"), "x").unwrap();
        assert_eq!(expand(PROGRAM_ROOT, Some(flat.path())).unwrap().1, 0);
        assert_eq!(expand(PROGRAM_ROOT, None).unwrap().1, 0);
    }

    #[test]
    fn every_source_is_marked_with_its_file() {
        // The denoiser's files make a program of their own; every other file is in the test
        // program (which includes the renderer's).
        let tests = test_program_source().unwrap();
        let denoise = denoise_program_source().unwrap();
        for (name, _) in KERNELS {
            let (s, program) = if name.starts_with("kernels/denoise/") {
                (&denoise, "denoiser")
            } else {
                (&tests, "test")
            };
            assert_eq!(
                s.matches(&format!("#line 1 \"{name}\"\n")).count(),
                1,
                "{name} is in the {program} program once"
            );
        }
    }

    #[test]
    fn an_inclusion_is_followed_by_the_includer_s_next_line() {
        let root = "// root\n#include \"a.h\"\n#include \"a.h\"\nkernel void f() {}\n";
        let dir = kernel_dir(&[("root.cl", root), ("a.h", "#define A 1\n")]);
        let (s, _) = expand("root.cl", Some(dir.path())).unwrap();
        assert_eq!(
            s,
            "#line 1 \"kernels/root.cl\"\n// root\n#line 1 \"kernels/a.h\"\n#define A 1\n\
             #line 3 \"kernels/root.cl\"\n\nkernel void f() {}\n",
            "a file included twice appears once"
        );
    }

    #[test]
    fn a_missing_include_names_the_including_file_and_line() {
        let dir = kernel_dir(&[("root.cl", "\n#include \"shared/nowhere.h\"\n")]);
        let err = expand("root.cl", Some(dir.path())).unwrap_err();
        assert_eq!(
            err,
            "kernels/root.cl:2: error: cannot find \"shared/nowhere.h\""
        );
    }

    #[test]
    fn an_include_under_a_condition_is_an_error() {
        let dir = kernel_dir(&[
            ("a.h", "#define A 1\n"),
            (
                "b.h",
                "#ifndef B_H\n#define B_H\n#include \"a.h\"\n#endif\n",
            ),
            ("root.cl", "#ifdef X\n#include \"a.h\"\n#endif\n"),
        ]);
        assert!(
            expand("b.h", Some(dir.path())).is_ok(),
            "a guard is no condition"
        );
        let err = expand("root.cl", Some(dir.path())).unwrap_err();
        assert!(err.starts_with("kernels/root.cl:2: error:"), "{err}");
    }

    #[test]
    fn a_build_error_names_the_included_file_and_line() {
        let device =
            crate::cl::Device::open(&crate::cl::DeviceChoice::Cpu).expect("an OpenCL CPU device");
        let root = "// root\n#include \"a.h\"\nkernel void f(global int* x) { x[0] = A; }\n";
        let dir = kernel_dir(&[("root.cl", root)]);
        let error = |a_h: &str| {
            std::fs::write(dir.path().join("kernels/a.h"), a_h).unwrap();
            let (source, _) = expand("root.cl", Some(dir.path())).unwrap();
            let features = super::super::KernelFeatures::default();
            super::super::program::build_source(&device, &source, features)
                .expect_err("the source does not compile")
                .to_string()
        };
        let err = error("#define A 1\nint g(void) { return undeclared; }\n");
        assert!(err.contains("kernels/a.h:2"), "{err}");
        let err = error("#define B 1\n");
        assert!(err.contains("kernels/root.cl:3"), "{err}");
    }

    #[test]
    fn the_production_program_has_no_test_kernels() {
        let s = program_source().unwrap();
        for (name, _) in KERNELS
            .iter()
            .filter(|(n, _)| n.starts_with("kernels/test/"))
        {
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
        let s = program_source().unwrap();
        let defines = s.find(DEFINES_NAME).expect("the generated header");
        assert!(defines < s.find("typedef").unwrap());
        assert!(s.contains("#define LIGHT_ENVIRONMENT 4u\n"), "{s:.2000}");
        assert!(s.contains("#define WRAP_MIRROR 2\n"));
        assert!(s.contains("#define COUNT_OVERFLOW 4\n"));
        for line in super::super::types::kernel_defines().lines() {
            let name = line.split_whitespace().nth(1).unwrap();
            let written = format!("#define {name} ");
            assert_eq!(s.matches(&written).count(), 1, "{name} is defined once");
        }
    }
}
