//! The wrappers of the test-only kernels (`build_test_program`): layout probes and the
//! texture, environment, spawn and BSDF samplers the tests compare with the host.

use super::{Program, kernel};
use crate::cl::types::*;
use crate::cl::{Buffer, ClError, Device, EnvBuffers, SceneBuffers, build_test_program};
use opencl3::kernel::Kernel;

/// The kernels only tests use, from their own program (`build_test_program`).
pub(super) struct TestKernels {
    probe_layout: Kernel,
    sample_texture_test: Kernel,
    sample_env_test: Kernel,
    bsdf_sample_test: Kernel,
    bsdf_eval_test: Kernel,
    bsdf_eval_bent_test: Kernel,
    spawn_test: Kernel,
}

impl Program {
    /// The test-only kernels for the same features, built the first time a test asks.
    fn tests(&self, device: &Device) -> Result<&TestKernels, ClError> {
        if let Some(t) = self.tests.get() {
            return Ok(t);
        }
        let program = build_test_program(device, self.features)?;
        let k = |name: &str| kernel(&program, name);
        let built = TestKernels {
            probe_layout: k("probe_layout")?,
            sample_texture_test: k("sample_texture_test")?,
            sample_env_test: k("sample_env_test")?,
            bsdf_sample_test: k("bsdf_sample_test")?,
            bsdf_eval_test: k("bsdf_eval_test")?,
            bsdf_eval_bent_test: k("bsdf_eval_bent_test")?,
            spawn_test: k("spawn_test")?,
        };
        Ok(self.tests.get_or_init(|| built))
    }

    /// `probe_layout` (test program): sizes and offsets of the shared structs as the device compiler sees them.
    pub fn probe_layout(&self, device: &Device) -> Result<Vec<u32>, ClError> {
        let tests = self.tests(device)?;
        let out = Buffer::<u32>::new(device, 256)?;
        self.run(device, "probe_layout", &tests.probe_layout, 1, |e| unsafe {
            e.set_arg(&out.mem());
        })?;
        out.read(device)
    }

    /// `sample_texture_test` (test program): texture lookups; query .xy = uv, .z = footprint level (see
    /// kernels/test/tests.cl), .w = texture reference (i32 bits). Zeros without `HAS_TEXTURES`.
    pub fn sample_texture_test(
        &self,
        device: &Device,
        scene: &SceneBuffers,
        queries: &[[f32; 4]],
    ) -> Result<Vec<[f32; 4]>, ClError> {
        let tests = self.tests(device)?;
        let q = Buffer::from_slice(device, queries)?;
        let out = Buffer::<[f32; 4]>::new(device, queries.len())?;
        let count = queries.len() as u32;
        self.run(
            device,
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
        out.read(device)
    }

    /// `sample_env_test` (test program): environment samples from uniform pairs: (direction, pdf) each, and
    /// the pdf the miss shader gives the same direction. Zeros without `HAS_ENV_MAP`.
    #[allow(clippy::type_complexity)]
    pub fn sample_env_test(
        &self,
        device: &Device,
        env: &EnvBuffers,
        u: &[[f32; 2]],
    ) -> Result<(Vec<[f32; 4]>, Vec<f32>), ClError> {
        let tests = self.tests(device)?;
        let ub = Buffer::from_slice(device, u)?;
        let out = Buffer::<[f32; 4]>::new(device, u.len())?;
        let eval = Buffer::<f32>::new(device, u.len())?;
        let count = u.len() as u32;
        self.run(
            device,
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
        Ok((out.read(device)?, eval.read(device)?))
    }

    /// `spawn_test` (test program): rays spawned with the kernels' hit point and offset; case i
    /// leaves triangle `groups[i][0]` (vertices `verts[3k..3k + 3]`, xyz) at barycentrics
    /// `bary[i]` along `dirs[i]` (.w = tmax) and counts its hits among the `groups[i][2]`
    /// triangles from `groups[i][1]` (`groups[i][3]` is unused).
    pub fn spawn_test(
        &self,
        device: &Device,
        verts: &[[f32; 4]],
        groups: &[[u32; 4]],
        bary: &[[f32; 2]],
        dirs: &[[f32; 4]],
    ) -> Result<Vec<u32>, ClError> {
        let tests = self.tests(device)?;
        let vb = Buffer::from_slice(device, verts)?;
        let gb = Buffer::from_slice(device, groups)?;
        let bb = Buffer::from_slice(device, bary)?;
        let db = Buffer::from_slice(device, dirs)?;
        let hits = Buffer::<u32>::new(device, dirs.len())?;
        let count = dirs.len() as u32;
        self.run(
            device,
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
        hits.read(device)
    }

    /// `bsdf_sample_test` (test program): `count` BSDF samples of `material` at (`wo`, `n`), seen from inside
    /// its volume when `inside`; returns (wi, pdf) and (weight, 1 for a delta lobe) per sample.
    #[allow(clippy::too_many_arguments, clippy::type_complexity)]
    pub fn bsdf_sample_test(
        &self,
        device: &Device,
        material: &DeviceMaterial,
        wo: [f32; 4],
        n: [f32; 4],
        inside: bool,
        count: usize,
        seed: u32,
    ) -> Result<(Vec<[f32; 4]>, Vec<[f32; 4]>), ClError> {
        let tests = self.tests(device)?;
        let material = Buffer::from_slice(device, &[*material])?;
        let wi_pdf = Buffer::<[f32; 4]>::new(device, count)?;
        let weight = Buffer::<[f32; 4]>::new(device, count)?;
        let inside = inside as u32;
        let count32 = count as u32;
        self.run(
            device,
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
        Ok((wi_pdf.read(device)?, weight.read(device)?))
    }

    /// `bsdf_eval_test` (test program): (f·|cos|, pdf) of `material` at (`wo`, `n`) for each direction of `wi`.
    pub fn bsdf_eval_test(
        &self,
        device: &Device,
        material: &DeviceMaterial,
        wo: [f32; 4],
        n: [f32; 4],
        inside: bool,
        wi: &[[f32; 4]],
    ) -> Result<Vec<[f32; 4]>, ClError> {
        let tests = self.tests(device)?;
        let kernel = ("bsdf_eval_test", &tests.bsdf_eval_test);
        self.eval_test(device, kernel, material, (wo, n), inside, wi)
    }

    /// `bsdf_eval_bent_test` (test program): as [`Program::bsdf_eval_test`] at a normal-mapped
    /// vertex of geometric normal +Z and mapped normal `n`, its normals bent for `wo` and each
    /// `wi` as the shade kernel bends them (kernels/shared/surface.h, `bsdf_eval_bent`).
    pub fn bsdf_eval_bent_test(
        &self,
        device: &Device,
        material: &DeviceMaterial,
        wo: [f32; 4],
        n: [f32; 4],
        wi: &[[f32; 4]],
    ) -> Result<Vec<[f32; 4]>, ClError> {
        let tests = self.tests(device)?;
        let kernel = ("bsdf_eval_bent_test", &tests.bsdf_eval_bent_test);
        self.eval_test(device, kernel, material, (wo, n), false, wi)
    }

    /// Runs one of the BSDF evaluation test kernels, which share their parameters.
    fn eval_test(
        &self,
        device: &Device,
        (name, kernel): (&'static str, &Kernel),
        material: &DeviceMaterial,
        (wo, n): ([f32; 4], [f32; 4]),
        inside: bool,
        wi: &[[f32; 4]],
    ) -> Result<Vec<[f32; 4]>, ClError> {
        let material = Buffer::from_slice(device, &[*material])?;
        let wi_buf = Buffer::from_slice(device, wi)?;
        let out = Buffer::<[f32; 4]>::new(device, wi.len())?;
        let inside = inside as u32;
        let count = wi.len() as u32;
        self.run(device, name, kernel, wi.len(), |e| unsafe {
            e.set_arg(&material.mem())
                .set_arg(&wo)
                .set_arg(&n)
                .set_arg(&inside)
                .set_arg(&count)
                .set_arg(&wi_buf.mem())
                .set_arg(&out.mem());
        })?;
        out.read(device)
    }
}
