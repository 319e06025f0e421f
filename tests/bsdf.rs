//! The scattering model (kernels/shared/bsdf.h) on the test device (PoCL in CI), through the test
//! kernels of kernels/test/bsdf_test.cl and through whole renders:
//! - χ² goodness of fit of every sampling routine against its pdf (pbrt and Mitsuba style:
//!   directions binned on a sphere grid, expected counts by integrating the pdf, low bins
//!   pooled, Šidák-corrected significance), with the sampled pdf and weight checked per sample;
//! - the delta lobes, the Lambertian limit, directional albedo never above one, the Fresnel table;
//! - white furnaces (uniform sky) of Lambertian, metal, dielectric and glass spheres, coated ones
//!   too, Beer–Lambert absorption, and no NaN at the extremes;
//! - a white base under a clear coat keeps at least what the glTF spec's layering keeps.
//!
//! Tables of observed and expected counts of a failed χ² test go to CARGO_TARGET_TMPDIR/bsdf.

mod common;

use common::stats::chi2;
use common::{Gltf, Prim, cuboid, horizontal_square, output_dir, render_exr, sphere};
use penumbra::cl::types::DeviceMaterial;
use penumbra::cl::{Device, DeviceChoice, KernelFeatures, Program};
use penumbra::scene::Material;
use serde_json::json;
use std::f64::consts::PI;

// ---------------------------------------------------------------------------------------------
// Materials and the device

/// A material as the kernels take it (the DeviceMaterial lanes bsdf.h reads).
#[derive(Clone, Copy, Debug)]
struct Mat {
    base: [f32; 3],
    metallic: f32,
    roughness: f32,
    ior: f32,
    specular: f32,
    specular_color: [f32; 3],
    transmission: f32,
    thickness: f32,
    clearcoat: f32,
    coat_roughness: f32,
    sheen: [f32; 3],
    sheen_roughness: f32,
    anisotropy: f32,
    anisotropy_rotation: f32,
    /// iridescenceFactor, iridescenceIor, thickness (nm).
    iridescence: [f32; 3],
    /// diffuseTransmissionFactor and its color.
    diffuse_transmission: (f32, [f32; 3]),
    /// `KHR_materials_dispersion` dispersion (20 / Abbe number).
    dispersion: f32,
}

impl Mat {
    fn dielectric(base: [f32; 3], roughness: f32) -> Self {
        Self {
            base,
            metallic: 0.0,
            roughness,
            ior: 1.5,
            specular: 1.0,
            specular_color: [1.0; 3],
            transmission: 0.0,
            thickness: 0.0,
            clearcoat: 0.0,
            coat_roughness: 0.0,
            sheen: [0.0; 3],
            sheen_roughness: 0.0,
            anisotropy: 0.0,
            anisotropy_rotation: 0.0,
            iridescence: [0.0, 1.3, 400.0],
            diffuse_transmission: (0.0, [1.0; 3]),
            dispersion: 0.0,
        }
    }

    /// This material dispersive (`KHR_materials_dispersion`, 20 / Abbe number).
    fn dispersive(self, dispersion: f32) -> Self {
        Self { dispersion, ..self }
    }

    /// This material transmitting `factor` of its diffuse base (`KHR_materials_diffuse_transmission`).
    fn translucent(self, factor: f32, color: [f32; 3]) -> Self {
        Self {
            diffuse_transmission: (factor, color),
            ..self
        }
    }

    /// This material under a thin film (`KHR_materials_iridescence`).
    fn iridescent(self, factor: f32, ior: f32, thickness: f32) -> Self {
        Self {
            iridescence: [factor, ior, thickness],
            ..self
        }
    }

    /// This material anisotropic (`KHR_materials_anisotropy`), its direction turned by
    /// `rotation` radians from the kernels' tangent.
    fn anisotropic(self, anisotropy: f32, anisotropy_rotation: f32) -> Self {
        Self {
            anisotropy,
            anisotropy_rotation,
            ..self
        }
    }

    /// This material under a sheen (`KHR_materials_sheen`).
    fn sheened(self, sheen: [f32; 3], sheen_roughness: f32) -> Self {
        Self {
            sheen,
            sheen_roughness,
            ..self
        }
    }

    /// This material under a clear coat (`KHR_materials_clearcoat`).
    fn coated(self, clearcoat: f32, coat_roughness: f32) -> Self {
        Self {
            clearcoat,
            coat_roughness,
            ..self
        }
    }

    fn lambert(base: [f32; 3]) -> Self {
        Self {
            specular: 0.0,
            ..Self::dielectric(base, 1.0)
        }
    }

    fn metal(base: [f32; 3], roughness: f32) -> Self {
        Self {
            metallic: 1.0,
            ..Self::dielectric(base, roughness)
        }
    }

    /// Glass: a volume when `thickness` > 0, else thin-walled.
    fn glass(roughness: f32, thickness: f32) -> Self {
        Self {
            transmission: 1.0,
            thickness,
            ..Self::dielectric([1.0; 3], roughness)
        }
    }

    /// The device form, packed as the renderer packs a scene's material.
    fn device(&self) -> DeviceMaterial {
        let b = self.base;
        penumbra::render::gpu_material(&Material {
            base_color: [b[0], b[1], b[2], 1.0],
            metallic: self.metallic,
            roughness: self.roughness,
            ior: self.ior,
            specular_factor: self.specular,
            specular_color: self.specular_color,
            transmission: self.transmission,
            thickness: self.thickness,
            clearcoat: self.clearcoat,
            clearcoat_roughness: self.coat_roughness,
            sheen_color: self.sheen,
            sheen_roughness: self.sheen_roughness,
            anisotropy: self.anisotropy,
            anisotropy_rotation: self.anisotropy_rotation,
            iridescence: self.iridescence[0],
            iridescence_ior: self.iridescence[1],
            iridescence_thickness: [100.0, self.iridescence[2]],
            diffuse_transmission: self.diffuse_transmission.0,
            diffuse_transmission_color: self.diffuse_transmission.1,
            dispersion: self.dispersion,
            ..Material::default()
        })
    }
}

/// The BSDF test kernels built on the test device.
struct BsdfKernels {
    device: Device,
    program: Program,
}

impl BsdfKernels {
    fn new() -> Self {
        // Every lobe compiled in; a material without them reduces to the plain BSDF.
        Self::with(KernelFeatures {
            clearcoat: true,
            sheen: true,
            anisotropy: true,
            iridescence: true,
            diffuse_transmission: true,
            ..KernelFeatures::default()
        })
    }

    fn with(features: KernelFeatures) -> Self {
        let choice: DeviceChoice = common::test_device().parse().expect("a valid test device");
        let device = Device::open(&choice).expect("the test's OpenCL device is available");
        let program = Program::build(&device, features).expect("kernels build");
        Self { device, program }
    }

    /// (f·|cos|, pdf) at a vertex of geometric normal +Z whose normal map gives `n`, its normals
    /// bent for wo and each wi as shading bends them.
    fn bent(&self, m: &Mat, wo: V, n: V, wi: &[[f32; 4]]) -> Vec<[f32; 4]> {
        self.program
            .bsdf_eval_bent_test(&self.device, &m.device(), f4(wo), f4(n), wi)
            .unwrap()
    }

    /// `count` samples: (wi, pdf) and (weight, delta flag).
    fn sample(&self, m: &Mat, wo: V, n: V, inside: bool, count: usize, seed: u32) -> Samples {
        let (wi, w) = self
            .program
            .bsdf_sample_test(
                &self.device,
                &m.device(),
                f4(wo),
                f4(n),
                inside,
                count,
                seed,
            )
            .unwrap();
        Samples { wi, w }
    }

    /// (f·|cos|, pdf) for each direction.
    fn eval(&self, m: &Mat, wo: V, n: V, inside: bool, wi: &[[f32; 4]]) -> Vec<[f32; 4]> {
        let mut out = Vec::with_capacity(wi.len());
        for chunk in wi.chunks(1 << 20) {
            out.extend(
                self.program
                    .bsdf_eval_test(&self.device, &m.device(), f4(wo), f4(n), inside, chunk)
                    .unwrap(),
            );
        }
        out
    }
}

struct Samples {
    wi: Vec<[f32; 4]>,
    w: Vec<[f32; 4]>,
}

impl Samples {
    /// Channel `ch` of each sample's weight as energy: a refracted one (through a solid, `m`
    /// with a thickness) times eta², undoing the radiance compression by eta².
    fn energy(&self, m: &Mat, eta: f64, ch: usize) -> Vec<f64> {
        (self.wi.iter().zip(&self.w))
            .map(|(wi, w)| {
                let refracted = wi[2] < 0.0 && m.thickness > 0.0;
                w[ch] as f64 * if refracted { eta * eta } else { 1.0 }
            })
            .collect()
    }
}

// ---------------------------------------------------------------------------------------------
// Small vector math in f64

type V = [f64; 3];

fn dot(a: V, b: V) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn add(a: V, b: V) -> V {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn scale(a: V, s: f64) -> V {
    [a[0] * s, a[1] * s, a[2] * s]
}
fn norm(a: V) -> V {
    scale(a, 1.0 / dot(a, a).sqrt())
}
fn f4(v: V) -> [f32; 4] {
    [v[0] as f32, v[1] as f32, v[2] as f32, 0.0]
}
fn v3(v: [f32; 4]) -> V {
    [v[0] as f64, v[1] as f64, v[2] as f64]
}

/// An orthonormal frame (t, b) around unit n.
fn frame(n: V) -> (V, V) {
    let s = if n[2] >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (s + n[2]);
    let c = n[0] * n[1] * a;
    (
        [1.0 + s * n[0] * n[0] * a, s * c, -s * n[0]],
        [c, s + n[1] * n[1] * a, -n[1]],
    )
}

/// wo at `theta_deg` from n (in the plane of n and its frame's first tangent).
fn direction_at(n: V, theta_deg: f64) -> V {
    let (t, _) = frame(n);
    let th = theta_deg.to_radians();
    norm(add(scale(n, th.cos()), scale(t, th.sin())))
}

fn reflect(wo: V, n: V) -> V {
    add(scale(n, 2.0 * dot(wo, n)), scale(wo, -1.0))
}

/// Refraction of wo (on n's side) into the far side, relative index eta; None under total
/// internal reflection.
fn refract(wo: V, n: V, eta: f64) -> Option<V> {
    let c = dot(wo, n);
    let c2 = 1.0 - (1.0 - c * c) / (eta * eta);
    (c2 > 0.0).then(|| add(scale(wo, -1.0 / eta), scale(n, c / eta - c2.sqrt())))
}

// ---------------------------------------------------------------------------------------------
// χ² machinery

/// Bins on the sphere around `axis`: polar edges `theta` (0..π) times `n_phi` equal azimuth bins.
/// Each bin is integrated with a composite Simpson rule of `k_theta[i]` × `k_phi` panels.
struct Grid {
    axis: V,
    t: V,
    b: V,
    theta: Vec<f64>,
    n_phi: usize,
    k_theta: Vec<usize>,
    k_phi: usize,
}

impl Grid {
    fn new(axis: V, theta: Vec<f64>, n_phi: usize, k_theta: Vec<usize>, k_phi: usize) -> Self {
        let (t, b) = frame(axis);
        Self {
            axis,
            t,
            b,
            theta,
            n_phi,
            k_theta,
            k_phi,
        }
    }

    /// 10 × 20 bins equal in cos θ and φ around n, panels at most `h` radians wide.
    fn sphere(n: V, h: f64) -> Self {
        let theta: Vec<f64> = (0..=10)
            .map(|i| (1.0 - 2.0 * i as f64 / 10.0).clamp(-1.0, 1.0).acos())
            .collect();
        let k_theta = theta
            .windows(2)
            .map(|w| ((w[1] - w[0]) / h).ceil() as usize)
            .collect();
        let k_phi = (2.0 * PI / 20.0 / h).ceil() as usize;
        Self::new(n, theta, 20, k_theta, k_phi)
    }

    /// Bins around a narrow lobe's axis: polar edges growing from a fraction of the lobe's width
    /// `s` geometrically, then coarse bins to the antipode.
    fn lobe(axis: V, s: f64) -> Self {
        let mut theta = vec![0.0];
        for f in [0.5, 1.0, 1.5, 2.0, 3.0] {
            theta.push(f * s);
        }
        let mut x = 3.0 * s;
        while x * 1.5 < 0.6 {
            x *= 1.5;
            theta.push(x);
        }
        let steps = ((PI - x) / 0.3).ceil() as usize;
        for i in 1..=steps {
            theta.push(x + (PI - x) * i as f64 / steps as f64);
        }
        let k_theta = vec![4; theta.len() - 1];
        Self::new(axis, theta, 16, k_theta, 6)
    }

    fn dir(&self, theta: f64, phi: f64) -> V {
        let (s, c) = theta.sin_cos();
        add(
            add(scale(self.t, s * phi.cos()), scale(self.b, s * phi.sin())),
            scale(self.axis, c),
        )
    }

    fn bins(&self) -> usize {
        (self.theta.len() - 1) * self.n_phi
    }

    fn bin_of(&self, w: V) -> usize {
        let x = dot(w, self.t);
        let y = dot(w, self.b);
        let z = dot(w, self.axis);
        let theta = (x * x + y * y).sqrt().atan2(z);
        let phi = y.atan2(x).rem_euclid(2.0 * PI);
        let i = self
            .theta
            .partition_point(|&e| e <= theta)
            .clamp(1, self.theta.len() - 1)
            - 1;
        let j = ((phi / (2.0 * PI) * self.n_phi as f64) as usize).min(self.n_phi - 1);
        i * self.n_phi + j
    }

    /// Probability of each bin under the pdf that `eval` computes for a list of directions.
    fn integrate(&self, eval: impl Fn(&[[f32; 4]]) -> Vec<f32>) -> Vec<f64> {
        let simpson = |k: usize, i: usize| -> f64 {
            if i == 0 || i == 2 * k {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            }
        };
        let mut dirs = vec![];
        let mut weights = vec![];
        let mut owner = vec![];
        let dphi = 2.0 * PI / self.n_phi as f64;
        for (i, w) in self.theta.windows(2).enumerate() {
            let kt = self.k_theta[i].max(1);
            let ht = (w[1] - w[0]) / (2 * kt) as f64;
            let hp = dphi / (2 * self.k_phi) as f64;
            for j in 0..self.n_phi {
                for a in 0..=2 * kt {
                    // Nodes on a bin's edge sit just inside it: the pdf may jump there (the
                    // horizon).
                    let eps = 1e-6 * (w[1] - w[0]);
                    let theta = (w[0] + a as f64 * ht).clamp(w[0] + eps, w[1] - eps);
                    for c in 0..=2 * self.k_phi {
                        let phi = j as f64 * dphi + c as f64 * hp;
                        let weight =
                            simpson(kt, a) * simpson(self.k_phi, c) * ht * hp / 9.0 * theta.sin();
                        if weight == 0.0 {
                            continue;
                        }
                        dirs.push(f4(self.dir(theta, phi)));
                        weights.push(weight);
                        owner.push(i * self.n_phi + j);
                    }
                }
            }
        }
        let pdf = eval(&dirs);
        let mut out = vec![0.0; self.bins()];
        for ((p, w), o) in pdf.iter().zip(&weights).zip(&owner) {
            out[*o] += *p as f64 * w;
        }
        out
    }
}

/// One χ² case: sampling `mat` at `wo` about `n` against its pdf on `grid`.
struct Case {
    name: String,
    mat: Mat,
    n: V,
    wo: V,
    inside: bool,
    grid: Grid,
}

fn case(name: &str, mat: Mat, theta_o: f64, inside: bool) -> Case {
    let n = [0.0, 0.0, 1.0];
    Case {
        name: format!("{name}, theta_o {theta_o}"),
        mat,
        n,
        wo: direction_at(n, theta_o),
        inside,
        grid: Grid::sphere(n, 0.02),
    }
}

/// Checks per sample that the pdf and weight bsdf_sample returns match bsdf_eval for the same
/// direction; returns the number of samples that made a direction by a non-delta lobe. Only a
/// smooth clear coat over a rough base may add delta samples.
fn check_samples(d: &BsdfKernels, c: &Case, s: &Samples) -> Result<usize, String> {
    let evals = d.eval(&c.mat, c.wo, c.n, c.inside, &s.wi);
    let mut made = 0;
    for (k, ((wi, w), e)) in s.wi.iter().zip(&s.w).zip(&evals).enumerate() {
        let pdf = wi[3];
        if !(w.iter().all(|x| x.is_finite()) && pdf.is_finite()) {
            return Err(format!("sample {k}: non-finite {wi:?} {w:?}"));
        }
        if pdf == 0.0 {
            if w[..3].iter().any(|&x| x != 0.0) {
                return Err(format!("sample {k}: weight {w:?} without a pdf"));
            }
            continue;
        }
        if w[3] != 0.0 {
            if c.mat.clearcoat > 0.0 && c.mat.coat_roughness == 0.0 {
                continue;
            }
            return Err(format!("sample {k}: a delta lobe in a rough material"));
        }
        made += 1;
        if w[..3].iter().any(|&x| x < 0.0) {
            return Err(format!("sample {k}: negative weight {w:?}"));
        }
        let rel = |a: f32, b: f32| (a - b).abs() <= 1e-3 * a.abs().max(b.abs()) + 1e-7;
        if !rel(pdf, e[3]) {
            return Err(format!("sample {k}: sampled pdf {pdf}, evaluated {}", e[3]));
        }
        for ch in 0..3 {
            if !rel(w[ch], e[ch] / e[3]) {
                return Err(format!(
                    "sample {k}: weight {:?} but f·cos/pdf {:?}",
                    &w[..3],
                    [e[0] / e[3], e[1] / e[3], e[2] / e[3]]
                ));
            }
        }
    }
    Ok(made)
}

/// Runs a case; returns (χ², dof, p) or why it failed outright.
fn run_case(
    d: &BsdfKernels,
    c: &Case,
    count: usize,
    seed: u32,
) -> Result<(f64, usize, f64), String> {
    let s = d.sample(&c.mat, c.wo, c.n, c.inside, count, seed);
    let made = check_samples(d, c, &s)?;
    let mut observed = vec![0u64; c.grid.bins()];
    for (wi, w) in s.wi.iter().zip(&s.w) {
        if wi[3] > 0.0 && w[3] == 0.0 {
            observed[c.grid.bin_of(v3(*wi))] += 1;
        }
    }
    let probability = c.grid.integrate(|dirs| {
        d.eval(&c.mat, c.wo, c.n, c.inside, dirs)
            .iter()
            .map(|e| e[3])
            .collect()
    });
    let expected: Vec<f64> = probability.iter().map(|p| p * count as f64).collect();
    // The pdf's total is the chance that sampling makes a direction.
    let total: f64 = probability.iter().sum();
    let made_fraction = made as f64 / count as f64;
    let sigma = (total * (1.0 - total).max(0.0) / count as f64).sqrt();
    let result = chi2(&observed, &expected);
    let ok_total = (made_fraction - total).abs() < 5.0 * sigma + 2e-3;
    if result.as_ref().map_or(true, |r| r.2 < 1e-6) || !ok_total {
        write_table(c, &observed, &expected);
    }
    if !ok_total {
        return Err(format!(
            "{made_fraction:.5} of the samples made a direction, but the pdf integrates to {total:.5}"
        ));
    }
    result
}

fn write_table(c: &Case, observed: &[u64], expected: &[f64]) {
    let dir = output_dir("bsdf");
    let mut s = format!(
        "{}\nrows: polar bins (edges {:?}), columns: azimuth bins; observed / expected\n",
        c.name, c.grid.theta
    );
    for i in 0..c.grid.theta.len() - 1 {
        for j in 0..c.grid.n_phi {
            let k = i * c.grid.n_phi + j;
            s.push_str(&format!("{:>7}/{:<9.1}", observed[k], expected[k]));
        }
        s.push('\n');
    }
    let name: String = c
        .name
        .chars()
        .map(|ch| if ch.is_ascii_alphanumeric() { ch } else { '_' })
        .collect();
    std::fs::write(dir.join(format!("{name}.txt")), s).unwrap();
}

#[test]
fn sampling_matches_pdf_chi_square() {
    let d = BsdfKernels::new();
    let white = [1.0f32; 3];
    let mut cases = vec![case("diffuse", Mat::lambert([0.8, 0.5, 0.3]), 45.0, false)];
    // The GGX visible-normal sampling alone (a white metal), narrow lobes on a grid about the
    // mirror direction.
    for r in [0.3, 0.7, 1.0] {
        for t in [10.0, 45.0, 80.0] {
            cases.push(case(
                &format!("GGX roughness {r}"),
                Mat::metal(white, r),
                t,
                false,
            ));
        }
    }
    for t in [10.0, 45.0, 80.0] {
        let mut c = case("GGX roughness 0.05", Mat::metal(white, 0.05), t, false);
        c.grid = Grid::lobe(reflect(c.wo, c.n), 0.05f64.powi(2));
        cases.push(c);
    }
    // Dielectric: diffuse + specular, and the metal mix.
    let mut plastic = Mat::dielectric([0.8, 0.4, 0.2], 0.5);
    plastic.specular_color = [1.0, 0.7, 1.2];
    for t in [10.0, 45.0, 80.0] {
        cases.push(case("dielectric roughness 0.5", plastic, t, false));
    }
    cases.push(case(
        "dielectric roughness 0.3",
        Mat::dielectric(white, 0.3),
        60.0,
        false,
    ));
    let mut half = Mat::metal([0.9, 0.6, 0.3], 0.4);
    half.metallic = 0.5;
    cases.push(case("half metal roughness 0.4", half, 45.0, false));
    // Glass: reflection and refraction over the whole sphere, from outside and inside.
    for t in [10.0, 45.0, 80.0] {
        cases.push(case("rough glass 0.3", Mat::glass(0.3, 1.0), t, false));
    }
    cases.push(case("rough glass 0.7", Mat::glass(0.7, 1.0), 45.0, false));
    cases.push(case(
        "rough glass 0.3 inside",
        Mat::glass(0.3, 1.0),
        20.0,
        true,
    ));
    cases.push(case(
        "rough glass 0.5 inside, past critical",
        Mat::glass(0.5, 1.0),
        60.0,
        true,
    ));
    cases.push(case(
        "thin rough glass 0.4",
        Mat::glass(0.4, 0.0),
        30.0,
        false,
    ));
    let mut frosted = Mat::dielectric([0.9, 0.8, 0.7], 0.5);
    frosted.transmission = 0.5;
    frosted.thickness = 1.0;
    frosted.ior = 1.33;
    cases.push(case(
        "half transmissive roughness 0.5",
        frosted,
        30.0,
        false,
    ));
    // Clear coat: a rough coat over diffuse, over a glossy dielectric and over metal; a smooth
    // coat (its delta lobe aside) over diffuse.
    for t in [10.0, 45.0, 80.0] {
        cases.push(case(
            "rough coat 0.3 over diffuse",
            Mat::lambert([0.8, 0.5, 0.3]).coated(1.0, 0.3),
            t,
            false,
        ));
    }
    cases.push(case(
        "rough coat 0.6 over dielectric 0.2",
        Mat::dielectric([0.2, 0.4, 0.8], 0.2).coated(0.7, 0.6),
        45.0,
        false,
    ));
    cases.push(case(
        "rough coat 0.2 over metal 0.5",
        Mat::metal([0.9, 0.6, 0.3], 0.5).coated(1.0, 0.2),
        30.0,
        false,
    ));
    cases.push(case(
        "smooth coat over diffuse",
        Mat::lambert([0.8, 0.5, 0.3]).coated(1.0, 0.0),
        60.0,
        false,
    ));
    // Sheen: over diffuse (narrow and wide), over a glossy dielectric, under a coat.
    for t in [10.0, 45.0, 80.0] {
        cases.push(case(
            "sheen 0.3 over diffuse",
            Mat::lambert([0.3, 0.3, 0.6]).sheened([1.0, 0.8, 0.6], 0.3),
            t,
            false,
        ));
    }
    cases.push(case(
        "sheen 0.8 over dielectric 0.4",
        Mat::dielectric([0.6, 0.2, 0.2], 0.4).sheened([0.5, 0.9, 0.7], 0.8),
        60.0,
        false,
    ));
    cases.push(case(
        "coat 0.3 over sheen 0.5 over metal 0.5",
        Mat::metal([0.9, 0.6, 0.3], 0.5)
            .sheened([0.6; 3], 0.5)
            .coated(0.8, 0.3),
        30.0,
        false,
    ));
    // Anisotropy: stretched visible normals of a metal, a dielectric over diffuse and rough
    // glass, at several angles and rotations of the direction.
    for (t, rot) in [(10.0, 0.0), (45.0, 0.6), (80.0, 1.9)] {
        cases.push(case(
            &format!("anisotropic metal 0.3, strength 0.8, rotation {rot}"),
            Mat::metal([0.9, 0.6, 0.3], 0.3).anisotropic(0.8, rot),
            t,
            false,
        ));
    }
    cases.push(case(
        "anisotropic dielectric 0.5, strength 0.5",
        plastic.anisotropic(0.5, -0.7),
        45.0,
        false,
    ));
    for (r, s, rot) in [
        (0.3, 0.0, 0.0),
        (0.3, 0.6, 0.0),
        (0.3, 0.6, 0.4),
        (0.5, 0.6, 0.4),
        (0.3, 0.6, 1.5707964),
    ] {
        let mut c = case(
            &format!("anisotropic rough glass {r}, strength {s}, rotation {rot}"),
            Mat::glass(r, 1.0).anisotropic(s, rot),
            30.0,
            false,
        );
        c.grid = Grid::sphere(c.n, 0.005);
        cases.push(c);
    }
    cases.push(case(
        "anisotropic metal 0.2, strength 1, under a coat",
        Mat::metal(white, 0.2)
            .anisotropic(1.0, 0.3)
            .coated(0.5, 0.2),
        60.0,
        false,
    ));
    // Any normal: the kernels' frame must not matter.
    let n = norm([1.0, -2.0, 3.0]);
    cases.push(Case {
        name: "dielectric roughness 0.5, tilted normal".into(),
        mat: plastic,
        n,
        wo: direction_at(n, 50.0),
        inside: false,
        grid: Grid::sphere(n, 0.02),
    });

    // Iridescence: the film's Fresnel decides reflection against transmission per microfacet.
    cases.push(case(
        "iridescent dielectric 0.4, film 1.8 / 300 nm",
        plastic.iridescent(1.0, 1.8, 300.0),
        30.0,
        false,
    ));
    cases.push(case(
        "iridescent metal 0.3, film 1.3 / 500 nm",
        Mat::metal([0.9, 0.6, 0.3], 0.3).iridescent(0.7, 1.3, 500.0),
        60.0,
        false,
    ));
    cases.push(case(
        "iridescent rough glass 0.4, film 1.5 / 250 nm",
        Mat::glass(0.4, 1.0).iridescent(1.0, 1.5, 250.0),
        45.0,
        false,
    ));
    // Diffuse transmission: the cosine lobe below the surface, alone, beside a glossy layer and
    // under a coat.
    cases.push(case(
        "diffuse transmission 1, lambert",
        Mat::lambert([0.8, 0.5, 0.3]).translucent(1.0, [0.4, 0.9, 0.6]),
        30.0,
        false,
    ));
    for t in [10.0, 70.0] {
        cases.push(case(
            "diffuse transmission 0.5, dielectric 0.4",
            Mat::dielectric([0.8, 0.5, 0.3], 0.4).translucent(0.5, [1.0, 0.6, 0.2]),
            t,
            false,
        ));
    }
    cases.push(case(
        "diffuse transmission 0.7 under a coat 0.3",
        Mat::dielectric([0.6; 3], 0.2)
            .translucent(0.7, [0.9; 3])
            .coated(0.8, 0.3),
        45.0,
        false,
    ));
    // PENUMBRA_CHI2_ONLY=TEXT runs only the cases whose name contains TEXT (while debugging).
    if let Ok(only) = std::env::var("PENUMBRA_CHI2_ONLY") {
        cases.retain(|c| c.name.contains(&only));
    }
    let count = 1 << 20;
    // Šidák correction: overall significance 1% over all cases.
    let alpha = 1.0 - (1.0f64 - 0.01).powf(1.0 / cases.len() as f64);
    let mut failures = vec![];
    for (i, c) in cases.iter().enumerate() {
        match run_case(&d, c, count, 1000 + i as u32) {
            Ok((chsq, dof, p)) => {
                eprintln!("{:<50} chi2 {chsq:>8.1} dof {dof:>4} p {p:.4}", c.name);
                if p < alpha {
                    failures.push(format!("{}: p = {p:.2e} < {alpha:.2e}", c.name));
                }
            }
            Err(e) => failures.push(format!("{}: {e}", c.name)),
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} cases failed (tables in {}):\n{}",
        failures.len(),
        cases.len(),
        output_dir("bsdf").display(),
        failures.join("\n")
    );
}

// ---------------------------------------------------------------------------------------------
// Exact properties

/// INV_PI_F of kernels/shared/rng.h.
const INV_PI_F: f32 = std::f32::consts::FRAC_1_PI;

/// Scenes whose materials are all Lambertian build the BSDF as base color / pi (LAMBERT_ONLY):
/// it must sample the same directions with the same weights and pdfs as the general BSDF.
#[test]
fn lambert_only_build_matches_the_general_bsdf() {
    let general = BsdfKernels::new();
    let lambert = BsdfKernels::with(KernelFeatures {
        lambert_only: true,
        ..KernelFeatures::default()
    });
    let m = Mat::lambert([0.8, 0.5, 0.3]);
    let n = norm([0.3, -0.2, 1.0]);
    let mut compared = 0;
    for theta in [0.0, 30.0, 60.0, 85.0, 89.9] {
        let wo = direction_at(n, theta);
        let a = general.sample(&m, wo, n, false, 4096, 11);
        let b = lambert.sample(&m, wo, n, false, 4096, 11);
        let ea = general.eval(&m, wo, n, false, &a.wi);
        let eb = lambert.eval(&m, wo, n, false, &a.wi);
        for i in 0..a.wi.len() {
            for c in 0..4 {
                let close = |x: f32, y: f32| (x - y).abs() <= 2e-6 * (1.0 + x.abs());
                assert!(
                    close(a.wi[i][c], b.wi[i][c]),
                    "θ {theta}: wi/pdf {i}: {:?} vs {:?}",
                    a.wi[i],
                    b.wi[i]
                );
                assert!(
                    close(a.w[i][c], b.w[i][c]),
                    "θ {theta}: weight {i}: {:?} vs {:?}",
                    a.w[i],
                    b.w[i]
                );
                assert!(
                    close(ea[i][c], eb[i][c]),
                    "θ {theta}: eval {i}: {:?} vs {:?}",
                    ea[i],
                    eb[i]
                );
            }
            compared += usize::from(a.wi[i][3] > 0.0);
        }
        // From below the surface neither scatters.
        let below = [-wo[0], -wo[1], -wo[2]];
        let e = lambert.eval(&m, below, n, false, &a.wi[..64]);
        assert!(
            e.iter().all(|v| v[..4] == [0.0; 4]),
            "no scattering seen from below"
        );
    }
    assert!(
        compared > 15_000,
        "most samples are valid directions ({compared})"
    );
}

#[test]
fn specular_factor_zero_is_exactly_lambertian() {
    let d = BsdfKernels::new();
    let m = Mat::lambert([0.8, 0.5, 0.3]);
    let n = [0.0, 0.0, 1.0];
    for theta in [0.0, 30.0, 60.0, 85.0, 89.9] {
        let wo = direction_at(n, theta);
        let s = d.sample(&m, wo, n, false, 4096, 7);
        let e = d.eval(&m, wo, n, false, &s.wi);
        for ((wi, w), e) in s.wi.iter().zip(&s.w).zip(&e) {
            if wi[3] == 0.0 {
                continue;
            }
            let c = wi[2] * INV_PI_F;
            assert_eq!(w[3], 0.0, "no delta lobe");
            assert_eq!(e[3], c, "pdf = cos/pi exactly");
            assert_eq!(wi[3], c, "sampled pdf = cos/pi exactly");
            for ch in 0..3 {
                assert_eq!(e[ch], m.base[ch] * c, "f·cos = base·cos/pi exactly");
                assert!((w[ch] - m.base[ch]).abs() <= 1e-6, "weight = base");
            }
        }
    }
}

#[test]
fn delta_lobes_reflect_and_refract_exactly() {
    let d = BsdfKernels::new();
    let n = [0.0, 0.0, 1.0];
    let close = |a: V, b: V| (0..3).all(|i| (a[i] - b[i]).abs() < 2e-6);
    let schlick = |f0: f64, c: f64| f0 + (1.0 - f0) * (1.0 - c).powi(5);

    // A smooth metal: the mirror direction, weight = Fresnel, pdf 1.
    let metal = Mat::metal([0.9, 0.6, 0.3], 0.0);
    let wo = direction_at(n, 60.0);
    let s = d.sample(&metal, wo, n, false, 1000, 1);
    for (wi, w) in s.wi.iter().zip(&s.w) {
        assert_eq!(w[3], 1.0, "delta lobe flagged");
        assert!(close(v3(*wi), reflect(wo, n)), "mirror direction {wi:?}");
        assert_eq!(wi[3], 1.0);
        for ch in 0..3 {
            let f = schlick(metal.base[ch] as f64, 0.5);
            assert!((w[ch] as f64 - f).abs() < 1e-5, "metal Fresnel {w:?}");
        }
    }
    // Nothing to evaluate for a delta lobe.
    let e = d.eval(&metal, wo, n, false, &s.wi[..1]);
    assert_eq!(e[0], [0.0; 4]);

    // Smooth glass from outside: Fresnel-weighted choice of mirror and Snell refraction, with
    // weight 1 for white glass, and 1/ior^2 for refraction (radiance is compressed entering it).
    let glass = Mat::glass(0.0, 1.0);
    let wo = direction_at(n, 45.0);
    let count = 200_000;
    let s = d.sample(&glass, wo, n, false, count, 2);
    let t = refract(wo, n, 1.5).unwrap();
    let mut reflected = 0;
    for (wi, w) in s.wi.iter().zip(&s.w) {
        let v = v3(*wi);
        assert_eq!(w[3], 1.0);
        let expected = if close(v, reflect(wo, n)) {
            reflected += 1;
            1.0
        } else {
            assert!(close(v, t), "refraction {v:?}, Snell says {t:?}");
            1.0 / (1.5f32 * 1.5)
        };
        assert!(
            w[..3].iter().all(|&x| (x - expected).abs() < 1e-5),
            "weight {w:?}"
        );
    }
    let f = schlick(0.04, 45f64.to_radians().cos());
    let fraction = reflected as f64 / count as f64;
    let sigma = (f * (1.0 - f) / count as f64).sqrt();
    assert!(
        (fraction - f).abs() < 5.0 * sigma,
        "reflected {fraction}, Fresnel {f}"
    );

    // From inside at 20 degrees: refraction out (relative index 1/1.5); at 60 degrees, past the
    // critical angle, total internal reflection.
    let wo = direction_at(n, 20.0);
    let s = d.sample(&glass, wo, n, true, 10_000, 3);
    let t = refract(wo, n, 1.0 / 1.5).unwrap();
    assert!(
        s.wi.iter().any(|wi| close(v3(*wi), t)),
        "some samples refract out along {t:?}"
    );
    let wo = direction_at(n, 60.0);
    let s = d.sample(&glass, wo, n, true, 10_000, 4);
    for (wi, w) in s.wi.iter().zip(&s.w) {
        assert!(close(v3(*wi), reflect(wo, n)), "total internal reflection");
        assert!(
            w[..3].iter().all(|&x| (x - 1.0).abs() < 1e-6),
            "weight {w:?}"
        );
    }

    // A thin wall: transmission goes straight through.
    let thin = Mat::glass(0.0, 0.0);
    let wo = direction_at(n, 30.0);
    let s = d.sample(&thin, wo, n, false, 10_000, 5);
    let through =
        s.wi.iter()
            .filter(|wi| close(v3(**wi), scale(wo, -1.0)))
            .count();
    assert!(through > 9000, "{through} of 10000 went straight through");

    // Smooth plastic: a delta mirror beside a diffuse lobe that bsdf_eval still sees.
    let plastic = Mat::dielectric([0.5; 3], 0.0);
    let s = d.sample(&plastic, wo, n, false, 10_000, 6);
    let e = d.eval(&plastic, wo, n, false, &s.wi);
    let mut diffuse = 0;
    for ((wi, w), e) in s.wi.iter().zip(&s.w).zip(&e) {
        if w[3] == 1.0 {
            assert!(close(v3(*wi), reflect(wo, n)));
        } else {
            diffuse += 1;
            assert!(wi[2] > 0.0 && (wi[3] - e[3]).abs() <= 1e-6 * e[3].max(1.0));
        }
    }
    assert!(diffuse > 8000, "mostly diffuse: {diffuse}");
}

/// Base color tints light once per pass through glass: smooth glass of base color
/// (0.5, 0.7, 0.9) refracts into a volume, and out of it, with weights whose channels stand as
/// the square roots of the base color's (two crossings make one tint), and through a thin wall
/// as the base color's (one crossing); the reflection is not tinted.
#[test]
fn a_volume_boundary_tints_by_the_square_root_of_base_color() {
    let d = BsdfKernels::new();
    let n = [0.0, 0.0, 1.0];
    let c = [0.5f64, 0.7, 0.9];
    let wo = direction_at(n, 30.0);
    for (name, thickness, inside) in [
        ("into a volume", 1.0, false),
        ("out of a volume", 1.0, true),
        ("through a thin wall", 0.0, false),
    ] {
        let mut m = Mat::glass(0.0, thickness);
        m.base = c.map(|x| x as f32);
        let s = d.sample(&m, wo, n, inside, 2000, 7);
        let (mut passed, mut reflected) = (0, 0);
        for w in &s.w {
            let ratios = [w[0] as f64 / w[2] as f64, w[1] as f64 / w[2] as f64];
            if (ratios[0] - 1.0).abs() < 1e-5 && (ratios[1] - 1.0).abs() < 1e-5 {
                reflected += 1;
                continue;
            }
            passed += 1;
            let tint: Vec<f64> = if thickness > 0.0 {
                c.iter().map(|x| x.sqrt()).collect()
            } else {
                c.to_vec()
            };
            for k in 0..2 {
                let expected = tint[k] / tint[2];
                assert!(
                    (ratios[k] / expected - 1.0).abs() < 1e-4,
                    "{name}: weight {w:?}, channel ratio {} where {expected} is the tint's",
                    ratios[k]
                );
            }
        }
        assert!(
            passed > 1500 && reflected > 0,
            "{name}: {passed} passed, {reflected} reflected"
        );
    }
}

#[test]
fn directional_albedo_never_exceeds_one() {
    let d = BsdfKernels::new();
    let n = [0.0, 0.0, 1.0];
    let white = [1.0f32; 3];
    let mut materials = vec![];
    for r in [0.0, 0.1, 0.3, 0.6, 1.0] {
        materials.push((format!("dielectric {r}"), Mat::dielectric(white, r), false));
        materials.push((format!("metal {r}"), Mat::metal(white, r), false));
        materials.push((format!("glass {r}"), Mat::glass(r, 1.0), false));
        materials.push((format!("glass {r} inside"), Mat::glass(r, 1.0), true));
        materials.push((format!("thin glass {r}"), Mat::glass(r, 0.0), false));
    }
    let mut strong = Mat::dielectric(white, 0.2);
    strong.ior = 3.0;
    strong.specular_color = [2.0, 1.0, 4.0];
    materials.push(("ior 3, specular color > 1".into(), strong, false));
    let mut half = Mat::glass(0.4, 1.0);
    half.transmission = 0.5;
    half.metallic = 0.3;
    materials.push(("half glass, a little metal".into(), half, false));
    for r in [0.0, 0.3, 1.0] {
        let coat = |m: Mat| m.coated(1.0, r);
        materials.push((
            format!("coat {r} over white"),
            coat(Mat::lambert(white)),
            false,
        ));
        materials.push((
            format!("coat {r} over dielectric 0.3"),
            coat(Mat::dielectric(white, 0.3)),
            false,
        ));
        materials.push((
            format!("coat {r} over metal 0.2"),
            coat(Mat::metal(white, 0.2)),
            false,
        ));
        materials.push((
            format!("coat {r} over metal 1"),
            coat(Mat::metal(white, 1.0)),
            false,
        ));
        materials.push((
            format!("coat {r} over thin glass"),
            coat(Mat::glass(0.0, 0.0)),
            false,
        ));
    }
    for r in [0.0, 0.3, 1.0] {
        let sheen = |m: Mat| m.sheened([1.0; 3], r);
        materials.push((
            format!("sheen {r} over white"),
            sheen(Mat::lambert(white)),
            false,
        ));
        materials.push((
            format!("sheen {r} over dielectric 0.3"),
            sheen(Mat::dielectric(white, 0.3)),
            false,
        ));
        materials.push((
            format!("sheen {r} over metal 1"),
            sheen(Mat::metal(white, 1.0)),
            false,
        ));
        materials.push((
            format!("coat 0.2 over sheen {r} over white"),
            sheen(Mat::lambert(white)).coated(1.0, 0.2),
            false,
        ));
        materials.push((
            format!("sheen {r} over thin glass"),
            sheen(Mat::glass(0.0, 0.0)),
            false,
        ));
    }

    for s in [0.3, 0.7, 1.0] {
        for (r, rot) in [(0.0, 0.0), (0.3, 0.8), (1.0, 1.6)] {
            let a = |m: Mat| m.anisotropic(s, rot);
            materials.push((
                format!("anisotropic {s} metal {r}"),
                a(Mat::metal(white, r)),
                false,
            ));
            materials.push((
                format!("anisotropic {s} dielectric {r}"),
                a(Mat::dielectric(white, r)),
                false,
            ));
            materials.push((
                format!("anisotropic {s} glass {r}"),
                a(Mat::glass(r, 1.0)),
                false,
            ));
            materials.push((
                format!("anisotropic {s} glass {r} inside"),
                a(Mat::glass(r, 1.0)),
                true,
            ));
            materials.push((
                format!("anisotropic {s} thin glass {r}"),
                a(Mat::glass(r, 0.0)),
                false,
            ));
        }
    }

    for (ior, d) in [(1.3, 200.0), (1.8, 350.0), (2.5, 600.0), (1.5, 0.0)] {
        let film = |m: Mat| m.iridescent(1.0, ior, d);
        materials.push((
            format!("film {ior} / {d} nm over white"),
            film(Mat::dielectric(white, 0.3)),
            false,
        ));
        materials.push((
            format!("film {ior} / {d} nm over metal 0.5"),
            film(Mat::metal(white, 0.5)),
            false,
        ));
        materials.push((
            format!("film {ior} / {d} nm over smooth white"),
            film(Mat::dielectric(white, 0.0)),
            false,
        ));
        materials.push((
            format!("film {ior} / {d} nm over thin glass"),
            film(Mat::glass(0.0, 0.0)),
            false,
        ));
        materials.push((
            format!("film {ior} / {d} nm over glass 0.3"),
            film(Mat::glass(0.3, 1.0)),
            false,
        ));
    }

    for dt in [0.3, 1.0] {
        let tr = |m: Mat| m.translucent(dt, [1.0; 3]);
        materials.push((
            format!("translucent {dt} white"),
            tr(Mat::lambert(white)),
            false,
        ));
        for r in [0.0, 0.4, 1.0] {
            materials.push((
                format!("translucent {dt} dielectric {r}"),
                tr(Mat::dielectric(white, r)),
                false,
            ));
        }
        materials.push((
            format!("translucent {dt} under coat and sheen"),
            tr(Mat::dielectric(white, 0.3))
                .sheened([0.8; 3], 0.5)
                .coated(1.0, 0.2),
            false,
        ));
    }

    let count = 1 << 16;
    let mut worst = (f64::MIN, String::new());
    let mut worst_aniso = (f64::MIN, String::new());
    for (name, m, inside) in &materials {
        for (k, mu) in [0.01f64, 0.1, 0.3, 0.6, 0.9, 1.0].iter().enumerate() {
            let wo = direction_at(n, mu.acos().to_degrees());
            let s = d.sample(m, wo, n, *inside, count, 100 + k as u32);
            // Refraction carries radiance, compressed by eta^2 (eta = ior, or 1/ior from
            // inside); energy is what it carries times eta^2.
            let eta = if *inside { 1.0 / m.ior } else { m.ior } as f64;
            for ch in 0..3 {
                let w = s.energy(m, eta, ch);
                assert!(
                    w.iter().all(|x| x.is_finite() && *x >= 0.0),
                    "{name}: weights"
                );
                let mean = w.iter().sum::<f64>() / count as f64;
                let var = w.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / count as f64;
                // Thin films: the base is layered under the film's largest normal reflectance,
                // which bounds the film's RGB reflectance only roughly (1.8% over seen in one
                // channel at cos 0.1; docs/materials.md).
                let slack = if m.iridescence[0] > 0.0 { 0.03 } else { 1e-4 };
                let bound = 1.0 + 4.0 * (var / count as f64).sqrt() + slack;
                if m.anisotropy > 0.0 && mean > worst_aniso.0 {
                    worst_aniso = (mean, format!("{name} at cos {mu}"));
                }
                let excess = mean - bound + 1.0;
                if excess > worst.0 {
                    worst = (excess, format!("{name} at cos {mu}: albedo {mean:.5}"));
                }
                assert!(
                    mean <= bound,
                    "{name} at cos(theta_o) {mu}, channel {ch}: albedo {mean} > 1"
                );
            }
        }
    }
    eprintln!("highest albedo less its noise allowance: {}", worst.1);
    eprintln!(
        "highest anisotropic albedo: {:.4} ({})",
        worst_aniso.0, worst_aniso.1
    );
}

/// The directional albedo of `m` seen from `wo` (energy: refracted weights times eta², as in
/// `directional_albedo_never_exceeds_one`) per channel, with its standard error.
fn albedo(d: &BsdfKernels, m: &Mat, wo: V, count: usize, seed: u32) -> [(f64, f64); 3] {
    let s = d.sample(m, wo, [0.0, 0.0, 1.0], false, count, seed);
    let eta = m.ior as f64;
    std::array::from_fn(|ch| {
        let w = s.energy(m, eta, ch);
        let mean = w.iter().sum::<f64>() / count as f64;
        let var = w.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / count as f64;
        (mean, (var / count as f64).sqrt())
    })
}

#[test]
fn a_film_of_no_thickness_or_of_the_base_index_reflects_as_the_plain_material() {
    // A viewer sees no film on these: one of thickness 0 is no film (the extension's rule,
    // and the film Fresnel's), and a film of the base's own index has no second interface to
    // interfere with. Each gives the plain material's directional albedo within noise and
    // 1 %. The diffuse base under a vanishing film was once layered under the film's largest
    // reflectance (a white base under a 2.5 film of no thickness: albedo 0.76 at cos 0.2), and
    // Schlick's Fresnel at the film's lower face left fringes where it has the base's index
    // (0.97).
    let d = BsdfKernels::new();
    let white = [1.0f32; 3];
    let count = 1 << 16;
    let mut dense = Mat::dielectric([0.4; 3], 0.1);
    dense.ior = 2.0;
    for plain in [
        Mat::dielectric(white, 0.3),
        dense,
        Mat::metal([0.4; 3], 0.1),
        Mat::glass(0.1, 1.0),
        Mat::glass(0.3, 0.0),
    ] {
        for film in [
            plain.iridescent(1.0, 2.5, 0.0),
            plain.iridescent(1.0, 1.3, 0.0),
            plain.iridescent(1.0, plain.ior, 400.0),
        ] {
            if film.iridescence[2] > 0.0 && plain.metallic > 0.0 {
                continue; // a metal's index is complex: no film matches it
            }
            for (k, mu) in [0.2f64, 0.5, 0.9, 1.0].into_iter().enumerate() {
                let wo = direction_at([0.0, 0.0, 1.0], mu.acos().to_degrees());
                let a = albedo(&d, &plain, wo, count, 900 + k as u32);
                let b = albedo(&d, &film, wo, count, 900 + k as u32);
                for ch in 0..3 {
                    let noise = 4.0 * (a[ch].1.powi(2) + b[ch].1.powi(2)).sqrt();
                    assert!(
                        (a[ch].0 - b[ch].0).abs() <= noise + 0.01,
                        "{plain:?} under {:?} at cos {mu}: albedo {} against {} plain",
                        film.iridescence,
                        b[ch].0,
                        a[ch].0
                    );
                    assert!(b[ch].0 <= 1.0 + noise, "{film:?}: albedo {}", b[ch].0);
                }
            }
        }
    }
}

/// A white Lambertian base under a clear coat keeps at least what the glTF spec's layering
/// keeps, `(1 - c F(mu)) + c F(mu) E(mu)` (fresnel_coat with the coat's Fresnel-free GGX lobe of
/// albedo E), and never more than all of it.
#[test]
fn white_under_a_clear_coat_loses_at_most_what_the_spec_loses() {
    let d = BsdfKernels::new();
    let n = [0.0, 0.0, 1.0];
    let count = 1 << 17;
    for c in [0.5f32, 1.0] {
        for r in [0.0f32, 0.2, 0.5, 1.0] {
            let m = Mat::lambert([1.0; 3]).coated(c, r);
            for (k, mu) in [0.05f64, 0.2, 0.5, 0.8, 1.0].iter().enumerate() {
                let wo = direction_at(n, mu.acos().to_degrees());
                let s = d.sample(&m, wo, n, false, count, 300 + k as u32);
                let w: Vec<f64> = s.w.iter().map(|w| w[1] as f64).collect();
                let mean = w.iter().sum::<f64>() / count as f64;
                let var = w.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / count as f64;
                let noise = 4.0 * (var / count as f64).sqrt() + 2e-3;
                let fresnel = 0.04 + 0.96 * (1.0 - mu).powi(5);
                let (e, _) = ggx_albedo(*mu, (r * r) as f64, 256);
                let spec = 1.0 - c as f64 * fresnel * (1.0 - e);
                eprintln!("coat {c} roughness {r} at cos {mu}: albedo {mean:.4}, spec {spec:.4}");
                assert!(
                    mean <= 1.0 + noise,
                    "coat {c} {r} at cos {mu} gains: {mean}"
                );
                assert!(
                    mean >= spec - noise,
                    "coat {c} {r} at cos {mu}: albedo {mean:.4} below the spec's {spec:.4}"
                );
            }
        }
    }
}

/// A white Lambertian base under a sheen reflects what the glTF spec's layering says,
/// `sheenColor E(mu) + (1 - max3(sheenColor) E(mu))` per channel (E the bounded sheen lobe's
/// albedo, by quadrature here), within noise (and 2% below cos 0.1, the tables' interpolation
/// error there): it neither loses more nor gains.
#[test]
fn white_under_a_sheen_keeps_what_the_spec_keeps() {
    let d = BsdfKernels::new();
    let charlie = kernel_table("SHEEN_E_CHARLIE");
    let n = [0.0, 0.0, 1.0];
    let count = 1 << 17;
    let mut worst = 0.0f64;
    for color in [[1.0f32; 3], [0.9, 0.4, 0.1]] {
        for r in [0.1f32, 0.4, 1.0] {
            let m = Mat::lambert([1.0; 3]).sheened(color, r);
            let s_max = color.iter().cloned().fold(0.0f32, f32::max) as f64;
            for (k, mu) in [0.05f64, 0.2, 0.5, 0.8, 1.0].iter().enumerate() {
                let wo = direction_at(n, mu.acos().to_degrees());
                let s = d.sample(&m, wo, n, false, count, 500 + k as u32);
                let e = sheen_albedo(*mu, r as f64, 256, Some(&charlie));
                for ch in 0..3 {
                    let w: Vec<f64> = s.w.iter().map(|w| w[ch] as f64).collect();
                    let mean = w.iter().sum::<f64>() / count as f64;
                    let var = w.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / count as f64;
                    // Near grazing the tables' bilinear interpolation errs by up to 2%.
                    let table = if *mu < 0.1 { 0.02 } else { 3e-3 };
                    let noise = 4.0 * (var / count as f64).sqrt() + table;
                    let spec = color[ch] as f64 * e + 1.0 - s_max * e;
                    worst = worst.max((mean - spec).abs());
                    assert!(
                        mean <= 1.0 + noise,
                        "sheen {color:?} {r} at cos {mu} gains: {mean}"
                    );
                    assert!(
                        (mean - spec).abs() <= noise,
                        "sheen {color:?} {r} at cos {mu}, channel {ch}: albedo {mean:.4}, spec {spec:.4}"
                    );
                }
            }
        }
    }
    eprintln!("largest difference from the spec's layering: {worst:.4}");
}

/// The directional albedo of a GGX reflection lobe (alpha) at cos(theta_o) = mu: with Fresnel 1
/// (E) and with the Schlick weight (1 - wo.h)^5 as its Fresnel (E_s), by a midpoint rule over
/// the spherical-caps visible-normal sampler's unit square (f·cos / pdf = G2 / G1 there).
fn ggx_albedo(mu: f64, alpha: f64, n: usize) -> (f64, f64) {
    if alpha == 0.0 {
        return (1.0, (1.0 - mu).powi(5));
    }
    aniso_albedo([(1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu], alpha, alpha, n)
}

/// Rows for roughness 0, 1/32 .. 1: E at cos 0, 1/32 .. 1 (33 values), then E_s likewise, then
/// the cosine-weighted averages 2∫E mu dmu and 2∫E_s mu dmu.
fn energy_table_row(r: usize) -> (Vec<f64>, Vec<f64>, f64, f64) {
    let alpha = (r as f64 / 32.0).powi(2);
    let (e, es): (Vec<f64>, Vec<f64>) = (0..=32)
        .map(|m| ggx_albedo((m as f64 / 32.0).max(1e-4), alpha, 256))
        .unzip();
    let steps = 128;
    let (mut avg, mut avg_s) = (0.0, 0.0);
    for m in 0..steps {
        let mu = (m as f64 + 0.5) / steps as f64;
        let (a, b) = ggx_albedo(mu, alpha, 96);
        avg += 2.0 * a * mu / steps as f64;
        avg_s += 2.0 * b * mu / steps as f64;
    }
    (e, es, avg, avg_s)
}

/// A table of kernels/shared/bsdf_tables.h by its name.
fn kernel_table(name: &str) -> Vec<f64> {
    // Read when the test runs, so that scripts/bsdf_tables.sh, which runs this file's print_*
    // tests, can write the header even when it is missing or stale.
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/kernels/shared/bsdf_tables.h");
    let src = std::fs::read_to_string(path).expect(path);
    let key = format!("{name}[");
    let start = src.find(&key).expect("the table");
    let start = start + src[start..].find('{').unwrap() + 1;
    let end = start + src[start..].find("};").unwrap();
    src[start..end]
        .split(',')
        .map(|s| s.trim().trim_end_matches('f'))
        .filter(|s| !s.is_empty())
        .map(|s| s.parse().unwrap())
        .collect()
}

/// The energy tables against an independent Monte Carlo estimate: uniform hemisphere directions
/// wi, f·cos = D G2 / (4 mu_o) with the Smith G2 written out afresh.
#[test]
fn ggx_energy_tables_match_monte_carlo() {
    let e = kernel_table("GGX_E");
    let es = kernel_table("GGX_E_SCHLICK");
    let avg = kernel_table("GGX_E_AVG");
    let avg_s = kernel_table("GGX_E_SCHLICK_AVG");
    assert_eq!(
        (e.len(), es.len(), avg.len(), avg_s.len()),
        (33 * 33, 33 * 33, 33, 33)
    );
    let mut rng = 0x2545_f491_4f6c_dd1du64;
    let mut uniform = move || {
        rng ^= rng << 13;
        rng ^= rng >> 7;
        rng ^= rng << 17;
        (rng >> 11) as f64 / (1u64 << 53) as f64
    };
    let count = 200_000;
    for r in [3usize, 8, 16, 24, 32] {
        let alpha = (r as f64 / 32.0).powi(2);
        let a2 = alpha * alpha;
        let g1 = |w: V| 2.0 * w[2] / (w[2] + (a2 + (1.0 - a2) * w[2] * w[2]).sqrt());
        for m in [4usize, 12, 20, 32] {
            let mu = m as f64 / 32.0;
            let wo = [(1.0 - mu * mu).sqrt(), 0.0, mu];
            let (mut sum, mut sum_s, mut sq) = (0.0, 0.0, 0.0);
            for _ in 0..count {
                let z = uniform();
                let phi = 2.0 * PI * uniform();
                let s = (1.0 - z * z).sqrt();
                let wi = [s * phi.cos(), s * phi.sin(), z];
                let h = norm(add(wo, wi));
                let c2 = h[2] * h[2];
                let d = a2 / (PI * (c2 * (a2 - 1.0) + 1.0).powi(2));
                // Height-correlated Smith: 1 / (1 + Λo + Λi) with Λ = 1/G1 - 1.
                let g2 = 1.0 / (1.0 / g1(wo) + 1.0 / g1(wi) - 1.0);
                let v = d * g2 / (4.0 * mu) * 2.0 * PI;
                sum += v;
                sq += v * v;
                sum_s += v * (1.0 - dot(wo, h)).powi(5);
            }
            let mean = sum / count as f64;
            let err = ((sq / count as f64 - mean * mean) / count as f64).sqrt();
            let k = r * 33 + m;
            assert!(
                (e[k] - mean).abs() < 5.0 * err + 2e-3,
                "E(roughness {r}/32, cos {m}/32): table {} vs Monte Carlo {mean} ± {err}",
                e[k]
            );
            let mean_s = sum_s / count as f64;
            assert!(
                (es[k] - mean_s).abs() < 5.0 * err + 2e-3,
                "E_s(roughness {r}/32, cos {m}/32): table {} vs Monte Carlo {mean_s}",
                es[k]
            );
        }
        // The averages: 2∫E mu dmu over the table's own columns (trapezoids).
        let row = &e[r * 33..r * 33 + 33];
        let trap: f64 = (0..32)
            .map(|i| {
                let (m0, m1) = (i as f64 / 32.0, (i + 1) as f64 / 32.0);
                (row[i] * m0 + row[i + 1] * m1) / 32.0
            })
            .sum();
        assert!(
            (avg[r] - trap).abs() < 3e-3,
            "E_avg(roughness {r}/32): table {} vs the E column's {trap}",
            avg[r]
        );
    }
    // A roughness-1 lobe loses a lot, a smooth one nothing.
    assert!(
        e[32 * 33 + 32] < 0.85 && avg[32] < 0.7,
        "rough GGX loses energy"
    );
    assert!(e[..33].iter().all(|&v| v == 1.0) && avg[0] == 1.0);
}

/// Prints the tables for kernels/shared/bsdf_tables.h (scripts/bsdf_tables.sh writes the file).
#[test]
#[ignore]
fn print_energy_tables() {
    let rows: Vec<_> = (0..=32).map(energy_table_row).collect();
    print_table("GGX_E", rows.iter().flat_map(|r| r.0.clone()).collect());
    print_table(
        "GGX_E_SCHLICK",
        rows.iter().flat_map(|r| r.1.clone()).collect(),
    );
    print_table("GGX_E_AVG", rows.iter().map(|r| r.2).collect());
    print_table("GGX_E_SCHLICK_AVG", rows.iter().map(|r| r.3).collect());
}

/// Prints a table as kernels/shared/bsdf_tables.h declares it.
fn print_table(name: &str, values: Vec<f64>) {
    println!("constant float {name}[{}] = {{", values.len());
    for line in values.chunks(11) {
        let s: Vec<String> = line.iter().map(|v| format!("{v:.5}f")).collect();
        println!("    {},", s.join(", "));
    }
    println!("}};");
}

// ---------------------------------------------------------------------------------------------
// Anisotropic GGX (KHR_materials_anisotropy): its energy tables

/// The anisotropic tables' grid: cos(theta) 0, 1/16 .. 1; cos²(phi) from the anisotropy
/// direction 0, 1/4 .. 1; base perceptual roughness r = sqrt(alpha_y) 0, 1/8 .. 1; the
/// stretch u = (sqrt(alpha_x) - r) / (1 - r) 0, 1/4 .. 1 (alpha_x's perceptual roughness from r
/// to 1, in which the albedo is smoother than in strength).
const ANISO_MU: usize = 17;
const ANISO_C: usize = 5;
const ANISO_R: usize = 9;
const ANISO_U: usize = 5;

/// The lobe's (alpha_x, alpha_y) at base perceptual roughness r and stretch u (both alphas at
/// least 1e-3, as kernels/shared/bsdf.h clamps them).
fn aniso_alphas(r: f64, u: f64) -> (f64, f64) {
    let rx = r + u * (1.0 - r);
    ((rx * rx).max(1e-3), (r * r).max(1e-3))
}

/// (E, E_s) of an anisotropic GGX reflection lobe at local wo (alpha_x along x), by the midpoint
/// rule over its visible-normal sampler's unit square (f·cos / pdf = G2 / G1 there).
fn aniso_albedo(wo: V, ax: f64, ay: f64, n: usize) -> (f64, f64) {
    let lambda = |w: V| {
        let x = (ax * ax * w[0] * w[0] + ay * ay * w[1] * w[1]) / (w[2] * w[2]);
        ((1.0 + x).sqrt() - 1.0) / 2.0
    };
    let v = norm([ax * wo[0], ay * wo[1], wo[2]]);
    let (mut e, mut es) = (0.0, 0.0);
    for i in 0..n {
        for j in 0..n {
            let phi = 2.0 * PI * (i as f64 + 0.5) / n as f64;
            let z = (1.0 - (j as f64 + 0.5) / n as f64) * (1.0 + v[2]) - v[2];
            let s = (1.0 - z * z).max(0.0).sqrt();
            let h = add([s * phi.cos(), s * phi.sin(), z], v);
            let h = norm([ax * h[0], ay * h[1], h[2].max(0.0)]);
            let wi = reflect(wo, h);
            if wi[2] <= 0.0 {
                continue;
            }
            let g = (1.0 + lambda(wo)) / (1.0 + lambda(wo) + lambda(wi));
            e += g;
            es += g * (1.0 - dot(wo, h)).clamp(0.0, 1.0).powi(5);
        }
    }
    let k = (n * n) as f64;
    (e / k, es / k)
}

/// The local direction at cos(theta) = mu whose azimuth from x has cos² = c.
fn aniso_direction(mu: f64, c: f64) -> V {
    let mu = mu.max(1e-4);
    let s = (1.0 - mu * mu).max(0.0).sqrt();
    [s * c.sqrt(), s * (1.0 - c).max(0.0).sqrt(), mu]
}

/// Index of grid point (u, r, c, mu) in the anisotropic tables.
fn aniso_index(u: usize, r: usize, c: usize, m: usize) -> usize {
    ((u * ANISO_R + r) * ANISO_C + c) * ANISO_MU + m
}

/// A table's value at (mu, c) of grid slice (u, r), bilinear in mu and c as the kernel reads it.
fn aniso_table_at(table: &[f64], u: usize, r: usize, mu: f64, c: f64) -> f64 {
    let x = mu.clamp(0.0, 1.0) * (ANISO_MU - 1) as f64;
    let y = c.clamp(0.0, 1.0) * (ANISO_C - 1) as f64;
    let (i, j) = (
        (x as usize).min(ANISO_MU - 2),
        (y as usize).min(ANISO_C - 2),
    );
    let (fx, fy) = (x - i as f64, y - j as f64);
    let at = |c, m| table[aniso_index(u, r, c, m)];
    let a = at(j, i) * (1.0 - fx) + at(j, i + 1) * fx;
    let b = at(j + 1, i) * (1.0 - fx) + at(j + 1, i + 1) * fx;
    a * (1.0 - fy) + b * fy
}

/// The cosine-weighted hemisphere mean (1/pi)∫E cos dω of a table's bilinear reading at each
/// grid slice (u, r), capped at 1 as the kernel caps it: what the kernel's multiple-scattering
/// lobe integrates to there (between slices the kernel's capped reading is at least the
/// interpolated mean's, so the lobe never integrates to more).
fn aniso_table_avg(table: &[f64]) -> Vec<f64> {
    let (nm, np) = (256, 64);
    let mut out = vec![];
    for u in 0..ANISO_U {
        for r in 0..ANISO_R {
            let mut sum = 0.0;
            for m in 0..nm {
                let mu = (m as f64 + 0.5) / nm as f64;
                for p in 0..np {
                    let phi = 0.5 * PI * (p as f64 + 0.5) / np as f64;
                    let e = aniso_table_at(table, u, r, mu, phi.cos().powi(2));
                    sum += 2.0 * mu * e.min(1.0);
                }
            }
            out.push(sum / (nm * np) as f64);
        }
    }
    out
}

/// The anisotropic tables: E and E_s at every grid point, then their means per (u, r).
///
/// The albedo falls steeply and concavely with the stretch where the base is smooth (a lobe of
/// alpha_x 0.25 over alpha_y 0.001 keeps only 0.90 at cos 0.5), so the tables' multilinear
/// reading would under-estimate it there and the compensation would gain up to 1%. Each grid
/// value is therefore raised by the largest shortfall of that reading against the albedo at
/// points inside the cells around it, which makes the tables an upper envelope: the
/// compensation then loses a little where the albedo is concave and never gains. Raised values
/// may exceed 1; the kernel caps its reading at 1.
fn aniso_tables() -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
    let albedo = |u: f64, r: f64, c: usize, m: usize, n: usize| {
        let (ax, ay) = aniso_alphas(r, u);
        aniso_albedo(aniso_direction(m as f64 / 16.0, c as f64 / 4.0), ax, ay, n)
    };
    let (mut e, mut es) = (vec![], vec![]);
    for u in 0..ANISO_U {
        for r in 0..ANISO_R {
            for c in 0..ANISO_C {
                for m in 0..ANISO_MU {
                    let (a, b) = albedo(u as f64 / 4.0, r as f64 / 8.0, c, m, 128);
                    e.push(a);
                    es.push(b);
                }
            }
        }
    }
    // The shortfall of each cell: the largest of albedo - multilinear reading at its points
    // (u in ninths, r in quarters, c and mu at both ends and the middle), which raises each of
    // the cell's corners (raising all 16 raises the reading inside by as much).
    let mut bump_e = vec![0.0f64; e.len()];
    let mut bump_s = vec![0.0f64; e.len()];
    let points: Vec<[f64; 4]> = (0..=8)
        .flat_map(|i| (0..=4).map(move |j| (i, j)))
        .flat_map(|(i, j)| {
            [0.0, 0.5].into_iter().flat_map(move |fc| {
                [0.0, 0.5].map(move |fm| [i as f64 / 8.0, j as f64 / 4.0, fc, fm])
            })
        })
        .collect();
    for u in 0..ANISO_U - 1 {
        for r in 0..ANISO_R - 1 {
            for c in 0..ANISO_C - 1 {
                for m in 0..ANISO_MU - 1 {
                    let corner = |t: &[f64], k: usize| {
                        t[aniso_index(
                            u + (k & 1),
                            r + (k >> 1 & 1),
                            c + (k >> 2 & 1),
                            m + (k >> 3),
                        )]
                    };
                    let (mut short_e, mut short_s) = (0.0f64, 0.0f64);
                    for f in &points {
                        let reading = |t: &[f64]| {
                            (0..16)
                                .map(|k| {
                                    let w: f64 = (0..4)
                                        .map(|d| if k >> d & 1 == 1 { f[d] } else { 1.0 - f[d] })
                                        .product();
                                    w * corner(t, k)
                                })
                                .sum::<f64>()
                        };
                        let (ax, ay) =
                            aniso_alphas((r as f64 + f[1]) / 8.0, (u as f64 + f[0]) / 4.0);
                        let wo = aniso_direction((m as f64 + f[3]) / 16.0, (c as f64 + f[2]) / 4.0);
                        let (a, b) = aniso_albedo(wo, ax, ay, 48);
                        short_e = short_e.max(a - reading(&e));
                        short_s = short_s.max(b - reading(&es));
                    }
                    for k in 0..16 {
                        let i = aniso_index(
                            u + (k & 1),
                            r + (k >> 1 & 1),
                            c + (k >> 2 & 1),
                            m + (k >> 3),
                        );
                        bump_e[i] = bump_e[i].max(short_e);
                        bump_s[i] = bump_s[i].max(short_s);
                    }
                }
            }
        }
    }
    let e: Vec<f64> = e.iter().zip(&bump_e).map(|(v, b)| round5(v + b)).collect();
    let es: Vec<f64> = es.iter().zip(&bump_s).map(|(v, b)| round5(v + b)).collect();
    let avg = aniso_table_avg(&e);
    let avg_s = aniso_table_avg(&es);
    (e, es, avg, avg_s)
}

/// Prints the anisotropic tables for kernels/shared/bsdf_tables.h (scripts/bsdf_tables.sh).
#[test]
#[ignore]
fn print_aniso_tables() {
    let (e, es, avg, avg_s) = aniso_tables();
    print_table("ANISO_E", e);
    print_table("ANISO_E_SCHLICK", es);
    print_table("ANISO_E_AVG", avg);
    print_table("ANISO_E_SCHLICK_AVG", avg_s);
}

/// The anisotropic energy tables against an independent Monte Carlo estimate (uniform hemisphere
/// directions, f·cos = D G2 / (4 mu_o) with the anisotropic D and Smith G2 written out afresh),
/// their isotropic slice against the isotropic tables, and their means against the tables.
#[test]
fn aniso_energy_tables_match_monte_carlo() {
    let e = kernel_table("ANISO_E");
    let es = kernel_table("ANISO_E_SCHLICK");
    let avg = kernel_table("ANISO_E_AVG");
    let avg_s = kernel_table("ANISO_E_SCHLICK_AVG");
    let n = ANISO_U * ANISO_R * ANISO_C * ANISO_MU;
    assert_eq!(
        (e.len(), es.len(), avg.len(), avg_s.len()),
        (n, n, ANISO_U * ANISO_R, ANISO_U * ANISO_R)
    );
    let mut rng = 0x9e37_79b9_7f4a_7c15u64;
    let mut uniform = move || {
        rng ^= rng << 13;
        rng ^= rng >> 7;
        rng ^= rng << 17;
        (rng >> 11) as f64 / (1u64 << 53) as f64
    };
    let count = 200_000;
    for (u, r, c, m) in [
        (2, 2, 0, 8),
        (4, 2, 0, 6),
        (4, 2, 4, 6),
        (4, 2, 2, 12),
        (1, 5, 1, 4),
        (3, 4, 3, 16),
        (4, 6, 0, 3),
    ] {
        let (ax, ay) = aniso_alphas(r as f64 / 8.0, u as f64 / 4.0);
        let lambda = |w: V| {
            let x = (ax * ax * w[0] * w[0] + ay * ay * w[1] * w[1]) / (w[2] * w[2]);
            ((1.0 + x).sqrt() - 1.0) / 2.0
        };
        let d = |h: V| {
            let k = (h[0] / ax).powi(2) + (h[1] / ay).powi(2) + h[2] * h[2];
            1.0 / (PI * ax * ay * k * k)
        };
        let wo = aniso_direction(m as f64 / 16.0, c as f64 / 4.0);
        let (mut sum, mut sum_s, mut sq) = (0.0, 0.0, 0.0);
        for _ in 0..count {
            let z = uniform();
            let phi = 2.0 * PI * uniform();
            let s = (1.0 - z * z).sqrt();
            let wi = [s * phi.cos(), s * phi.sin(), z];
            let h = norm(add(wo, wi));
            let g2 = 1.0 / (1.0 + lambda(wo) + lambda(wi));
            let v = d(h) * g2 / (4.0 * wo[2]) * 2.0 * PI;
            sum += v;
            sq += v * v;
            sum_s += v * (1.0 - dot(wo, h)).powi(5);
        }
        let mean = sum / count as f64;
        let err = ((sq / count as f64 - mean * mean) / count as f64).sqrt();
        // Never below the albedo (the compensation would gain), and above it by at most the
        // envelope's raise.
        let k = aniso_index(u, r, c, m);
        let mean_s = sum_s / count as f64;
        for (name, table, mc) in [("E", e[k], mean), ("E_s", es[k], mean_s)] {
            assert!(
                table > mc - 5.0 * err - 2e-3 && table < mc + 5.0 * err + 0.05,
                "{name}(u {u}, r {r}, c {c}, mu {m}): table {table} vs Monte Carlo {mc} ± {err}"
            );
        }
    }
    // Strength 0 is the isotropic lobe: the isotropic tables at the same points, at most the
    // envelope's raise above them (from cos 1/4: near grazing the raise is larger).
    let iso = kernel_table("GGX_E");
    let iso_s = kernel_table("GGX_E_SCHLICK");
    for r in 1..ANISO_R {
        for c in 0..ANISO_C {
            for m in 4..ANISO_MU {
                let (k, i) = (aniso_index(0, r, c, m), r * 4 * 33 + m * 2);
                let close = |a: f64, b: f64| a > b - 4e-3 && a < b + 0.05;
                assert!(
                    close(e[k], iso[i]) && close(es[k], iso_s[i]),
                    "strength 0, r {r}/8, cos {m}/16: ({}, {}) vs isotropic ({}, {})",
                    e[k],
                    es[k],
                    iso[i],
                    iso_s[i]
                );
            }
        }
    }
    // The means are those of the tables as read, so that the multiple-scattering lobe
    // integrates to 1 - E_avg.
    for (name, table, means) in [("E", &e, &avg), ("E_s", &es, &avg_s)] {
        for (k, (got, want)) in means.iter().zip(aniso_table_avg(table)).enumerate() {
            assert!(
                (got - want).abs() < 2e-5,
                "{name}_avg slice {k}: table {got} vs its mean {want}"
            );
        }
    }
    // Stretched over a smooth base, the lobe reflects differently along the direction and
    // across it at grazing angles.
    let along = e[aniso_index(4, 2, 4, 3)];
    let across = e[aniso_index(4, 2, 0, 3)];
    assert!(
        (along - across).abs() > 0.1,
        "along {along}, across {across}"
    );
}

// ---------------------------------------------------------------------------------------------
// Sheen (KHR_materials_sheen): the Charlie distribution's albedo table

/// Charlie sheen: D(h) for cos(theta_h) = `cos_h` and alpha = roughness², as kernels/shared/bsdf.h.
fn charlie_d(cos_h: f64, alpha: f64) -> f64 {
    let inv = 1.0 / alpha;
    let sin2 = (1.0 - cos_h * cos_h).max(0.0);
    (2.0 + inv) * sin2.powf(0.5 * inv) / (2.0 * PI)
}

/// Estevez and Kulla's fitted Lambda of the sheen visibility.
fn sheen_lambda(cos: f64, alpha: f64) -> f64 {
    let t = (1.0 - alpha) * (1.0 - alpha);
    let mix = |a: f64, b: f64| a + (b - a) * t;
    let l = |x: f64| {
        mix(21.5473, 25.3245) / (1.0 + mix(3.82987, 3.32435) * x.powf(mix(0.19823, 0.16801)))
            + mix(-1.97760, -1.27393) * x
            + mix(-4.32054, -4.85967)
    };
    if cos < 0.5 {
        l(cos).exp()
    } else {
        (2.0 * l(0.5) - l(1.0 - cos)).exp()
    }
}

/// The sheen roughness the kernels use: at least 3/32 (narrower lobes are not tabulated).
fn sheen_roughness(r: f64) -> f64 {
    r.clamp(3.0 / 32.0, 1.0)
}

/// f·cos of a white Charlie sheen lobe (unbounded) at local wo, wi.
fn sheen_f_cos(wo: V, wi: V, roughness: f64) -> f64 {
    if wo[2] <= 0.0 || wi[2] <= 0.0 {
        return 0.0;
    }
    let alpha = sheen_roughness(roughness).powi(2);
    let h = norm(add(wo, wi));
    let v = 1.0
        / ((1.0 + sheen_lambda(wo[2], alpha) + sheen_lambda(wi[2], alpha)) * 4.0 * wo[2] * wi[2]);
    charlie_d(h[2], alpha) * v * wi[2]
}

/// A sheen table (rows roughness 0, 1/32 .. 1, columns cos (0/32)², (1/32)² .. 1) at
/// (mu, roughness), bilinear in (sqrt(mu), roughness) as kernels/shared/bsdf.h reads it.
fn table_at(table: &[f64], mu: f64, roughness: f64) -> f64 {
    let x = mu.clamp(0.0, 1.0).sqrt() * 32.0;
    let y = roughness.clamp(0.0, 1.0) * 32.0;
    let (i, j) = ((x as usize).min(31), (y as usize).min(31));
    let k = j * 33 + i;
    let (fx, fy) = (x - i as f64, y - j as f64);
    let a = table[k] + (table[k + 1] - table[k]) * fx;
    let b = table[k + 33] + (table[k + 34] - table[k + 33]) * fx;
    a + (b - a) * fy
}

/// The directional albedo of a white sheen lobe at cos(theta_o) = mu: midpoint quadrature over
/// (cos theta_i, phi) with n × n points (phi over half the circle, by symmetry). With
/// `charlie` (the unbounded lobe's albedo table) the lobe is the bounded one, times
/// k(mu_o) k(mu_i), k = 1 / max(1, E_charlie).
fn sheen_albedo(mu: f64, roughness: f64, n: usize, charlie: Option<&[f64]>) -> f64 {
    let mu = mu.max(1e-4);
    let r = sheen_roughness(roughness);
    let k = |m: f64| charlie.map_or(1.0, |t| 1.0 / table_at(t, m, r).max(1.0));
    let wo = [(1.0 - mu * mu).sqrt(), 0.0, mu];
    let mut sum = 0.0;
    for i in 0..n {
        let z = (i as f64 + 0.5) / n as f64;
        let s = (1.0 - z * z).sqrt();
        let mut ring = 0.0;
        for j in 0..n {
            let phi = PI * (j as f64 + 0.5) / n as f64;
            let wi = [s * phi.cos(), s * phi.sin(), z];
            ring += sheen_f_cos(wo, wi, roughness);
        }
        sum += ring * k(z);
    }
    sum * k(mu) * 2.0 * PI / (n * n) as f64
}

/// Rounds as the printed tables do.
fn round5(v: f64) -> f64 {
    (v * 1e5).round() / 1e5
}

/// The sheen tables: the unbounded lobe's albedo (33 × 33), the bounded lobe's, and the bounded
/// lobe's cosine-weighted means per roughness row.
fn sheen_tables() -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let cell = |m: usize, r: usize| ((m as f64 / 32.0).powi(2), (r as f64 / 32.0));
    let charlie: Vec<f64> = (0..33 * 33)
        .map(|k| {
            let (mu, r) = cell(k % 33, k / 33);
            round5(sheen_albedo(mu, r, 512, None))
        })
        .collect();
    let bounded: Vec<f64> = (0..33 * 33)
        .map(|k| {
            let (mu, r) = cell(k % 33, k / 33);
            round5(sheen_albedo(mu, r, 512, Some(&charlie)))
        })
        .collect();
    let steps = 128;
    let avg = (0..=32)
        .map(|r| {
            let roughness = r as f64 / 32.0;
            round5(
                (0..steps)
                    .map(|m| {
                        let mu = (m as f64 + 0.5) / steps as f64;
                        let e = sheen_albedo(mu, roughness, 192, Some(&charlie));
                        2.0 * e * mu / steps as f64
                    })
                    .sum(),
            )
        })
        .collect();
    (charlie, bounded, avg)
}

/// Prints the sheen tables for kernels/shared/bsdf_tables.h (scripts/bsdf_tables.sh).
#[test]
#[ignore]
fn print_sheen_tables() {
    let (charlie, bounded, avg) = sheen_tables();
    print_table("SHEEN_E_CHARLIE", charlie);
    print_table("SHEEN_E", bounded);
    print_table("SHEEN_E_AVG", avg);
}

/// The sheen tables against quadrature done afresh (with other points).
#[test]
fn sheen_albedo_tables_match_quadrature() {
    let charlie = kernel_table("SHEEN_E_CHARLIE");
    let e = kernel_table("SHEEN_E");
    let avg = kernel_table("SHEEN_E_AVG");
    assert_eq!((charlie.len(), e.len(), avg.len()), (33 * 33, 33 * 33, 33));
    for r in [3usize, 6, 12, 20, 32] {
        for m in [1usize, 4, 12, 20, 32] {
            let (mu, roughness) = ((m as f64 / 32.0).powi(2), r as f64 / 32.0);
            let k = r * 33 + m;
            for (name, table, q) in [
                ("Charlie", &charlie, sheen_albedo(mu, roughness, 400, None)),
                (
                    "bounded",
                    &e,
                    sheen_albedo(mu, roughness, 400, Some(&charlie)),
                ),
            ] {
                assert!(
                    (table[k] - q).abs() < 2e-3 + 5e-3 * q,
                    "sheen {name} E(roughness {r}/32, cos {m}/32): table {} vs quadrature {q}",
                    table[k]
                );
            }
        }
        let row = &e[r * 33..r * 33 + 33];
        let trap: f64 = (0..32)
            .map(|i| {
                let (m0, m1) = ((i as f64 / 32.0).powi(2), ((i + 1) as f64 / 32.0).powi(2));
                (row[i] * m0 + row[i + 1] * m1) * (m1 - m0)
            })
            .sum();
        assert!(
            (avg[r] - trap).abs() < 3e-3,
            "sheen E_avg(roughness {r}/32): table {} vs the E column's {trap}",
            avg[r]
        );
    }
    // The Charlie lobe reflects more than it receives at grazing angles; the bounded one never.
    assert!(charlie[3 * 33] > 1.5, "{}", charlie[3 * 33]);
    assert_eq!(e[..33], e[3 * 33..4 * 33]);
    assert!(
        e.iter().all(|&v| (0.0..=1.0).contains(&v)),
        "sheen albedo in [0, 1]"
    );
}

// ---------------------------------------------------------------------------------------------
// Renders: white furnaces, absorption, extremes

/// The glTF form of a material (metallic-roughness with the specular, ior, transmission and
/// volume extensions).
fn material_json(g: &mut Gltf, m: &Mat, attenuation: Option<([f32; 3], f32)>) -> usize {
    for e in [
        "KHR_materials_specular",
        "KHR_materials_ior",
        "KHR_materials_transmission",
        "KHR_materials_volume",
    ] {
        g.use_ext(e);
    }
    g.use_ext("KHR_materials_clearcoat");
    g.use_ext("KHR_materials_sheen");
    let mut volume = json!({"thicknessFactor": m.thickness});
    if let Some((color, distance)) = attenuation {
        volume["attenuationColor"] = json!(color);
        volume["attenuationDistance"] = json!(distance);
    }
    let b = m.base;
    let mut extensions = json!({
        "KHR_materials_specular": {
            "specularFactor": m.specular,
            "specularColorFactor": m.specular_color
        },
        "KHR_materials_ior": {"ior": m.ior},
        "KHR_materials_transmission": {"transmissionFactor": m.transmission},
        "KHR_materials_volume": volume,
        "KHR_materials_clearcoat": {
            "clearcoatFactor": m.clearcoat,
            "clearcoatRoughnessFactor": m.coat_roughness
        },
        "KHR_materials_sheen": {
            "sheenColorFactor": m.sheen,
            "sheenRoughnessFactor": m.sheen_roughness
        }
    });
    if m.diffuse_transmission.0 > 0.0 {
        g.use_ext("KHR_materials_diffuse_transmission");
        extensions["KHR_materials_diffuse_transmission"] = json!({
            "diffuseTransmissionFactor": m.diffuse_transmission.0,
            "diffuseTransmissionColorFactor": m.diffuse_transmission.1
        });
    }
    if m.iridescence[0] > 0.0 {
        g.use_ext("KHR_materials_iridescence");
        extensions["KHR_materials_iridescence"] = json!({
            "iridescenceFactor": m.iridescence[0],
            "iridescenceIor": m.iridescence[1],
            "iridescenceThicknessMaximum": m.iridescence[2]
        });
    }
    if m.dispersion > 0.0 {
        g.use_ext("KHR_materials_dispersion");
        extensions["KHR_materials_dispersion"] = json!({"dispersion": m.dispersion});
    }
    if m.anisotropy > 0.0 {
        g.use_ext("KHR_materials_anisotropy");
        extensions["KHR_materials_anisotropy"] = json!({
            "anisotropyStrength": m.anisotropy,
            "anisotropyRotation": m.anisotropy_rotation
        });
    }
    g.materials.push(json!({
        "pbrMetallicRoughness": {
            "baseColorFactor": [b[0], b[1], b[2], 1.0],
            "metallicFactor": m.metallic,
            "roughnessFactor": m.roughness
        },
        "extensions": extensions
    }));
    g.materials.len() - 1
}

/// A camera at (0, 0, `distance`) looking down -z, and a light of zero intensity (so that the
/// default light rig stays away and only the sky lights the scene).
fn camera_and_no_light(g: &mut Gltf, distance: f32, yfov: f32) {
    g.cameras
        .push(json!({"type": "perspective", "perspective": {"yfov": yfov, "znear": 0.01}}));
    g.node(json!({"camera": 0, "translation": [0.0, 0.0, distance]}));
    g.lights
        .push(json!({"type": "point", "intensity": 0.0, "color": [1.0, 1.0, 1.0]}));
    g.node(json!({"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [0.0, 50.0, 0.0]}));
}

const EYE: f64 = 4.0;
const YFOV: f64 = 0.7;
const SIZE: usize = 48;

/// A flat-shaded unit sphere (flat, so shading and geometric normals agree) seen from EYE.
fn furnace_scene(dir: &std::path::Path, name: &str, m: &Mat) -> std::path::PathBuf {
    let mut g = Gltf::default();
    let mat = material_json(&mut g, m, None);
    let (positions, _, indices) = sphere(1.0, 32, 64, false);
    let mesh = g.mesh(vec![Prim::triangles(positions, indices, mat)]);
    g.node(json!({"mesh": mesh}));
    camera_and_no_light(&mut g, EYE as f32, YFOV as f32);
    g.write_glb(dir, name)
}

/// Pixels whose whole footprint sees the sphere, with cos(theta_o) at the pixel's center.
fn sphere_pixels() -> Vec<(usize, f64)> {
    let h = (YFOV / 2.0).tan();
    let ray = |fx: f64, fy: f64| norm([(2.0 * fx - 1.0) * h, (1.0 - 2.0 * fy) * h, -1.0]);
    // Distance along the ray to a sphere of radius r at the origin from the eye, if hit.
    let hit = |d: V, r: f64| {
        let o = [0.0, 0.0, EYE];
        let b = dot(o, d);
        let disc = b * b - (dot(o, o) - r * r);
        (disc > 0.0).then(|| -b - disc.sqrt())
    };
    let mut out = vec![];
    for y in 0..SIZE {
        for x in 0..SIZE {
            let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)];
            let inside = corners.iter().all(|(a, b)| {
                hit(
                    ray((x as f64 + a) / SIZE as f64, (y as f64 + b) / SIZE as f64),
                    0.99,
                )
                .is_some()
            });
            if inside {
                let d = ray(
                    (x as f64 + 0.5) / SIZE as f64,
                    (y as f64 + 0.5) / SIZE as f64,
                );
                let t = hit(d, 1.0).unwrap();
                let p = add([0.0, 0.0, EYE], scale(d, t));
                out.push((y * SIZE + x, -dot(d, p)));
            }
        }
    }
    out
}

fn furnace_render(
    scene: &std::path::Path,
    spp: u32,
    bounces: u32,
) -> (serde_json::Value, Vec<[f32; 3]>) {
    furnace_render_with(scene, spp, bounces, &[])
}

/// `furnace_render` with more command-line arguments.
fn furnace_render_with(
    scene: &std::path::Path,
    spp: u32,
    bounces: u32,
    extra: &[&str],
) -> (serde_json::Value, Vec<[f32; 3]>) {
    let out = scene.with_extension("exr");
    let size = SIZE.to_string();
    let spp = spp.to_string();
    let bounces = bounces.to_string();
    render_exr(
        scene,
        &out,
        &[
            "--width",
            &size,
            "--height",
            &size,
            "--spp",
            &spp,
            "--bounces",
            &bounces,
            "--sky",
            "1,1,1",
        ]
        .iter()
        .chain(extra)
        .copied()
        .collect::<Vec<_>>(),
    )
}

/// Mean and its standard error over the sphere's pixels (all channels).
fn sphere_mean(px: &[[f32; 3]], pixels: &[(usize, f64)]) -> (f64, f64) {
    let v: Vec<f64> = pixels
        .iter()
        .flat_map(|(i, _)| px[*i].iter().map(|c| *c as f64))
        .collect();
    mean_and_error(&v)
}

/// The mean of `v` and its standard error.
fn mean_and_error(v: &[f64]) -> (f64, f64) {
    let mean = v.iter().sum::<f64>() / v.len() as f64;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / v.len() as f64;
    (mean, (var / v.len() as f64).sqrt())
}

#[test]
fn white_furnace_lambertian_sphere_disappears() {
    let dir = tempfile::tempdir().unwrap();
    let scene = furnace_scene(dir.path(), "lambert", &Mat::lambert([1.0; 3]));
    let (summary, px) = furnace_render(&scene, 16, 4);
    assert_eq!(summary["nonfinite_samples"], 0);
    let pixels = sphere_pixels();
    assert!(pixels.len() > 400);
    for (i, _) in &pixels {
        for c in px[*i] {
            assert!(
                (c - 1.0).abs() < 1e-4,
                "pixel {i}: {:?} instead of the sky",
                px[*i]
            );
        }
    }
}

#[test]
fn white_furnace_spheres_keep_their_energy() {
    let dir = tempfile::tempdir().unwrap();
    let n = [0.0, 0.0, 1.0];
    let white = [1.0f32; 3];
    let pixels = sphere_pixels();
    // (name, material, lowest mean accepted): white metal with multiple scattering, and a white
    // base under the specular layer (and under a clear coat) by albedo scaling, keep all the
    // light (a single-scattering roughness-1 metal kept 0.34); a glossy base under a coat loses
    // what 1 - c max(A_c(mu_o), A_c(mu_i)) takes beyond the coat's reflection.
    let cases = [
        ("smooth metal", Mat::metal(white, 0.0), 0.98),
        ("rough metal", Mat::metal(white, 0.5), 0.98),
        ("very rough metal", Mat::metal(white, 1.0), 0.98),
        ("smooth dielectric", Mat::dielectric(white, 0.0), 0.98),
        ("glossy dielectric", Mat::dielectric(white, 0.2), 0.98),
        ("rough dielectric", Mat::dielectric(white, 0.7), 0.98),
        (
            "white, smooth coat",
            Mat::lambert(white).coated(1.0, 0.0),
            0.98,
        ),
        (
            "white, rough coat",
            Mat::lambert(white).coated(1.0, 0.5),
            0.98,
        ),
        (
            "metal, smooth coat",
            Mat::metal(white, 0.5).coated(1.0, 0.0),
            0.95,
        ),
        (
            "glossy, rough coat",
            Mat::dielectric(white, 0.2).coated(0.8, 0.3),
            0.95,
        ),
        (
            "white, white sheen",
            Mat::lambert(white).sheened(white, 0.5),
            0.98,
        ),
        (
            "rough metal, sheen 0.3",
            Mat::metal(white, 0.7).sheened([0.8; 3], 0.3),
            0.9,
        ),
    ];
    // Render first: a GPU in exclusive-process mode serves one process, so the renderer (a
    // child process) must run before this process opens the device.
    let renders: Vec<(f64, f64)> = cases
        .iter()
        .enumerate()
        .map(|(k, (name, m, _))| {
            let scene = furnace_scene(dir.path(), &format!("furnace{k}"), m);
            let (summary, px) = furnace_render(&scene, 64, 4);
            assert_eq!(summary["nonfinite_samples"], 0, "{name}");
            sphere_mean(&px, &pixels)
        })
        .collect();
    let d = BsdfKernels::new();
    let mut report = vec![];
    for (k, ((name, m, low), (mean, err))) in cases.iter().zip(renders).enumerate() {
        // The directional albedo A(cos theta_o) from the sampling kernel; on a convex object
        // under a uniform sky every pixel shows A times the sky.
        let albedo: Vec<f64> = (0..=32)
            .map(|i| {
                let mu = (i as f64 / 32.0).max(1e-3);
                let wo = direction_at(n, mu.acos().to_degrees());
                let s = d.sample(m, wo, n, false, 1 << 15, 7 + k as u32);
                s.w.iter()
                    .map(|w| (w[0] + w[1] + w[2]) as f64 / 3.0)
                    .sum::<f64>()
                    / s.w.len() as f64
            })
            .collect();
        let predicted = pixels
            .iter()
            .map(|(_, mu)| {
                let x = mu.clamp(0.0, 1.0) * 32.0;
                let i = (x as usize).min(31);
                albedo[i] + (albedo[i + 1] - albedo[i]) * (x - i as f64)
            })
            .sum::<f64>()
            / pixels.len() as f64;
        report.push(format!(
            "{name}: mean {mean:.4} ± {err:.4}, predicted {predicted:.4}"
        ));
        assert!(
            mean <= 1.0 + 4.0 * err + 1e-4,
            "{name} gains energy: {mean}"
        );
        assert!(
            (mean - predicted).abs() < 4.0 * err + 0.01,
            "{name}: furnace mean {mean:.4}, the albedo predicts {predicted:.4}"
        );
        assert!(
            mean >= low - 4.0 * err,
            "{name} loses energy: furnace mean {mean:.4}"
        );
    }
    eprintln!("{}", report.join("\n"));
}

/// The furnace sphere with texture coordinates (u around the axis, v from pole to pole), so
/// that tangents are generated and an anisotropic material is brushed along the parallels.
fn furnace_scene_uv(dir: &std::path::Path, name: &str, m: &Mat) -> std::path::PathBuf {
    let mut g = Gltf::default();
    let mat = material_json(&mut g, m, None);
    let (rings, segments) = (32u32, 64u32);
    let (positions, _, indices) = sphere(1.0, rings, segments, false);
    let uvs: Vec<[f32; 2]> = (0..=rings)
        .flat_map(|r| {
            (0..=segments).map(move |s| [s as f32 / segments as f32, r as f32 / rings as f32])
        })
        .collect();
    let mesh = g.mesh(vec![Prim::triangles(positions, indices, mat)]);
    let uv = g.float_accessor(&uvs);
    g.meshes[mesh]["primitives"][0]["attributes"]["TEXCOORD_0"] = json!(uv);
    g.node(json!({"mesh": mesh}));
    camera_and_no_light(&mut g, EYE as f32, YFOV as f32);
    g.write_glb(dir, name)
}

/// Renders each case's sphere in the white furnace (the scene written by `scene`, 64 spp and
/// `bounces` bounces) and checks that it loads without a warning, has no non-finite sample,
/// gains no energy and keeps at least its lowest accepted mean (within 4 sigma). The EXRs are
/// kept in the test output as TAG0, TAG1, ...
fn check_furnace_cases(
    tag: &str,
    cases: &[(&str, Mat, f64)],
    bounces: u32,
    scene: fn(&std::path::Path, &str, &Mat) -> std::path::PathBuf,
) {
    let dir = tempfile::tempdir().unwrap();
    let pixels = sphere_pixels();
    let out = output_dir("bsdf");
    let mut report = vec![];
    for (k, (name, m, low)) in cases.iter().enumerate() {
        let scene = scene(dir.path(), &format!("{tag}{k}"), m);
        let warnings = penumbra::scene::load(&scene).unwrap().warnings;
        assert!(warnings.is_empty(), "{name}: {warnings:?}");
        let (summary, px) = furnace_render(&scene, 64, bounces);
        assert_eq!(summary["nonfinite_samples"], 0, "{name}");
        let _ = std::fs::copy(
            scene.with_extension("exr"),
            out.join(format!("{tag}{k}.exr")),
        );
        let (mean, err) = sphere_mean(&px, &pixels);
        report.push(format!("{name}: mean {mean:.4} ± {err:.4}"));
        assert!(
            mean <= 1.0 + 4.0 * err + 1e-3,
            "{name} gains energy: {mean}"
        );
        assert!(mean >= low - 4.0 * err, "{name} loses energy: {mean:.4}");
    }
    eprintln!("{}", report.join("\n"));
}

/// Anisotropic spheres in the white furnace: never above the sky, and white metal and white
/// dielectric close to it at every strength: the compensation reads the anisotropic energy
/// tables per direction (an upper envelope of the albedo, so it loses a little where the albedo
/// is concave in the stretch; docs/materials.md). Before those tables a roughness-0.3 white
/// metal kept 0.90 at strength 0.5 and 0.58 at strength 1.
#[test]
fn white_furnace_anisotropic_spheres() {
    let white = [1.0f32; 3];
    let cases = [
        (
            "metal 0.3, anisotropy 0.5",
            Mat::metal(white, 0.3).anisotropic(0.5, 0.0),
            0.98,
        ),
        (
            "metal 0.3, anisotropy 1",
            Mat::metal(white, 0.3).anisotropic(1.0, 0.0),
            0.98,
        ),
        (
            "metal 0, anisotropy 0.8",
            Mat::metal(white, 0.0).anisotropic(0.8, 0.7),
            0.975,
        ),
        (
            "metal 0.6, anisotropy 0.7",
            Mat::metal(white, 0.6).anisotropic(0.7, 0.3),
            0.98,
        ),
        (
            "metal 1, anisotropy 1",
            Mat::metal(white, 1.0).anisotropic(1.0, 0.0),
            0.98,
        ),
        (
            "dielectric 0.2, anisotropy 0.9",
            Mat::dielectric(white, 0.2).anisotropic(0.9, 1.2),
            0.98,
        ),
    ];
    check_furnace_cases("aniso", &cases, 8, furnace_scene_uv);
}

/// Iridescent spheres in the white furnace: a white dielectric under a film keeps at most all
/// the light (the base is layered under the film's largest reflectance, so it loses a little),
/// a white metal under a film keeps what the film reflects.
#[test]
fn white_furnace_iridescent_spheres() {
    let white = [1.0f32; 3];
    let cases = [
        (
            "white dielectric 0.3, film 1.3 / 400 nm",
            Mat::dielectric(white, 0.3).iridescent(1.0, 1.3, 400.0),
            0.97,
        ),
        (
            "white dielectric 0, film 1.8 / 300 nm",
            Mat::dielectric(white, 0.0).iridescent(1.0, 1.8, 300.0),
            0.9,
        ),
        (
            "white metal 0.4, film 1.5 / 250 nm",
            Mat::metal(white, 0.4).iridescent(1.0, 1.5, 250.0),
            0.9,
        ),
    ];
    check_furnace_cases("film", &cases, 8, furnace_scene);
}

/// Translucent spheres in the white furnace: light that goes in diffusely comes out again, so a
/// white sphere that transmits part of its diffuse base keeps all the light (32 bounces).
#[test]
fn white_furnace_translucent_spheres() {
    let white = [1.0f32; 3];
    let cases = [
        (
            "white lambert, transmission 0.5",
            Mat::lambert(white).translucent(0.5, white),
            0.98,
        ),
        (
            "white lambert, transmission 1",
            Mat::lambert(white).translucent(1.0, white),
            0.98,
        ),
        (
            "white dielectric 0.4, transmission 0.6",
            Mat::dielectric(white, 0.4).translucent(0.6, white),
            0.97,
        ),
    ];
    check_furnace_cases("leaf", &cases, 32, furnace_scene);
}

#[test]
fn white_furnace_glass_spheres_conserve_energy() {
    // (name, material, lowest mean accepted): smooth glass loses nothing; rough glass loses what
    // single-scattering microfacets lose at each of its interfaces.
    // Rays that enter near grazing meet the faceted sphere's walls close to the critical angle
    // and may reflect inside for a long time: 256 bounces leave about 0.05% of the light inside.
    let cases = [
        ("smooth glass", Mat::glass(0.0, 1.0), 0.995),
        ("smooth thin glass", Mat::glass(0.0, 0.0), 0.995),
        ("rough glass", Mat::glass(0.3, 1.0), 0.9),
        ("rough thin glass", Mat::glass(0.3, 0.0), 0.9),
    ];
    check_furnace_cases("glass", &cases, 256, furnace_scene);
}

// ---------------------------------------------------------------------------------------------
// Dispersion (KHR_materials_dispersion)

/// Mean and standard error per channel over the sphere's pixels.
fn sphere_channel_means(px: &[[f32; 3]], pixels: &[(usize, f64)]) -> [(f64, f64); 3] {
    std::array::from_fn(|c| {
        let v: Vec<f64> = pixels.iter().map(|(i, _)| px[*i][c] as f64).collect();
        mean_and_error(&v)
    })
}

/// A white dispersive glass sphere in the white furnace keeps the sky's energy in every channel,
/// in both execution shapes: the wavelength a path picks weighs its RGB response by its pdf,
/// which averages 1 per channel, and each wavelength's glass conserves energy.
#[test]
fn white_furnace_dispersive_glass_keeps_every_channel() {
    let dir = tempfile::tempdir().unwrap();
    let pixels = sphere_pixels();
    let glass = Mat::glass(0.0, 1.0).dispersive(1.0);
    let scene = furnace_scene(dir.path(), "dispersive", &glass);
    let warnings = penumbra::scene::load(&scene).unwrap().warnings;
    assert!(warnings.is_empty(), "{warnings:?}");
    for kernel in ["wavefront", "megakernel"] {
        let (summary, px) = furnace_render_with(&scene, 64, 128, &["--kernel", kernel]);
        assert_eq!(summary["nonfinite_samples"], 0, "{kernel}");
        let means = sphere_channel_means(&px, &pixels);
        eprintln!("{kernel}: dispersive glass sphere, channel means {means:.4?}");
        for (c, (mean, err)) in means.iter().enumerate() {
            assert!(
                (mean - 1.0).abs() < 4.0 * err + 0.01,
                "{kernel}, channel {c}: {mean:.4} ± {err:.4} instead of 1"
            );
        }
    }
}

/// A dispersion of 0 is no dispersion: the render is bit for bit that of the same glass without
/// the extension (nothing is compiled in, no wavelength is drawn).
#[test]
fn dispersion_zero_renders_as_no_extension() {
    let dir = tempfile::tempdir().unwrap();
    let glass = Mat::glass(0.1, 1.0);
    let plain = furnace_scene(dir.path(), "plain", &glass);
    let mut g = Gltf::default();
    let mat = material_json(&mut g, &glass, None);
    g.use_ext("KHR_materials_dispersion");
    g.materials[mat]["extensions"]["KHR_materials_dispersion"] = json!({"dispersion": 0.0});
    let (positions, _, indices) = sphere(1.0, 32, 64, false);
    let mesh = g.mesh(vec![Prim::triangles(positions, indices, mat)]);
    g.node(json!({"mesh": mesh}));
    camera_and_no_light(&mut g, EYE as f32, YFOV as f32);
    let zero = g.write_glb(dir.path(), "zero");
    let (_, a) = furnace_render(&plain, 4, 16);
    let (_, b) = furnace_render(&zero, 4, 16);
    assert!(a == b, "dispersion 0 changed the render");
}

/// A vertical glass prism (equilateral section, side √3, turned 15° about y) between the camera
/// and a thin vertical emissive stripe behind it, seen at minimum deviation (about 37° for
/// ior 1.5), black sky; 96 × 48 pixels. Returns the image.
fn prism_render(dir: &std::path::Path, dispersion: f32, kernel: &str) -> Vec<[f32; 3]> {
    let mut g = Gltf::default();
    let light = g.lambert([0.0; 3], [1.0; 3], 1.0, true);
    let glass = material_json(&mut g, &Mat::glass(0.0, 1.0).dispersive(dispersion), None);
    // The section's corners in the xz plane, then the prism from y = -3 to 3.
    let psi = 15f32.to_radians();
    let c: Vec<[f32; 2]> = (0..3)
        .map(|k| {
            let a = psi + std::f32::consts::FRAC_PI_2 + k as f32 * 2.0 * std::f32::consts::PI / 3.0;
            [a.cos(), a.sin()]
        })
        .collect();
    let mut positions = vec![];
    for y in [-3.0f32, 3.0] {
        positions.extend(c.iter().map(|p| [p[0], y, p[1]]));
    }
    let mut indices: Vec<u32> = vec![0, 1, 2, 3, 4, 5];
    for k in 0..3u32 {
        let j = (k + 1) % 3;
        indices.extend([k, j, j + 3, k, j + 3, k + 3]);
    }
    // Each face wound to face outwards (away from the prism's axis).
    for t in indices.chunks_mut(3) {
        let p: Vec<V> = t
            .iter()
            .map(|&i| positions[i as usize].map(|v| v as f64))
            .collect();
        let e1 = add(p[1], scale(p[0], -1.0));
        let e2 = add(p[2], scale(p[0], -1.0));
        let n = [
            e1[1] * e2[2] - e1[2] * e2[1],
            e1[2] * e2[0] - e1[0] * e2[2],
            e1[0] * e2[1] - e1[1] * e2[0],
        ];
        let centre = scale(add(add(p[0], p[1]), p[2]), 1.0 / 3.0);
        if dot(n, centre) < 0.0 {
            t.swap(1, 2);
        }
    }
    let (sx0, sx1, sz) = (-2.3f32, -2.1f32, -3.0f32);
    let stripe = vec![
        [sx0, -10.0, sz],
        [sx1, -10.0, sz],
        [sx1, 10.0, sz],
        [sx0, 10.0, sz],
    ];
    let mesh = g.mesh(vec![
        Prim::triangles(positions, indices, glass),
        Prim::triangles(stripe, vec![0, 1, 2, 0, 2, 3], light),
    ]);
    g.node(json!({"mesh": mesh}));
    g.cameras
        .push(json!({"type": "perspective", "perspective": {"yfov": 0.7, "aspectRatio": 2.0, "znear": 0.01}}));
    g.node(json!({"camera": 0, "translation": [0.0, 0.0, 4.0]}));
    let name = format!("prism_{dispersion}_{kernel}");
    let scene = g.write_glb(dir, &name);
    let (summary, px) = render_exr(
        &scene,
        &dir.join(format!("{name}.exr")),
        &[
            "--width",
            "96",
            "--height",
            "48",
            "--spp",
            "32",
            "--bounces",
            "8",
            "--sky",
            "0,0,0",
            "--kernel",
            kernel,
        ],
    );
    assert_eq!(summary["nonfinite_samples"], 0);
    let _ = std::fs::copy(
        dir.join(format!("{name}.exr")),
        output_dir("bsdf").join(format!("{name}.exr")),
    );
    px
}

/// The column (0..96) of each channel's centroid over the part of the image seen through the
/// prism (columns 36..72).
fn channel_centroids(px: &[[f32; 3]]) -> [f64; 3] {
    std::array::from_fn(|c| {
        let (mut sum, mut weighted) = (0.0, 0.0);
        for (i, p) in px.iter().enumerate() {
            let x = i % 96;
            if (36..72).contains(&x) {
                sum += p[c] as f64;
                weighted += p[c] as f64 * (x as f64 + 0.5);
            }
        }
        assert!(sum > 0.0, "the stripe is seen through the prism");
        weighted / sum
    })
}

/// White light through a dispersive prism splits: seen through it, a thin white stripe shows its
/// blue image deviated further than its red one (blue's index is the higher), by about what the
/// spec's index formula predicts (a 2D trace of this scene: red at column 47, blue at 50-51 for
/// dispersion 2); without dispersion the channels coincide.
#[test]
fn a_dispersive_prism_separates_colours() {
    let dir = tempfile::tempdir().unwrap();
    for kernel in ["wavefront", "megakernel"] {
        let [r0, g0, b0] = channel_centroids(&prism_render(dir.path(), 0.0, kernel));
        let [r2, g2, b2] = channel_centroids(&prism_render(dir.path(), 2.0, kernel));
        eprintln!(
            "{kernel}: centroids r/g/b without dispersion {r0:.2} {g0:.2} {b0:.2}, with 2: {r2:.2} {g2:.2} {b2:.2}"
        );
        assert!(
            (r0 - b0).abs() < 0.3 && (r0 - g0).abs() < 0.3,
            "{kernel}: without dispersion the channels coincide"
        );
        assert!(
            b2 - r2 > 1.5 && b2 > g2 && g2 > r2,
            "{kernel}: blue is deviated further than green, green than red"
        );
    }
}

/// Diffuse transmission is reciprocal: f(wo, wi) with wi behind the sheet equals f(wi, wo) seen
/// from the back (the sheet's normal turned over).
#[test]
fn diffuse_transmission_is_reciprocal() {
    let d = BsdfKernels::new();
    let n = [0.0, 0.0, 1.0];
    let back = [0.0, 0.0, -1.0];
    let materials = [
        (
            "translucent lambert",
            Mat::lambert([0.8, 0.5, 0.3]).translucent(0.6, [0.3, 0.9, 0.5]),
        ),
        (
            "translucent dielectric",
            Mat::dielectric([0.7; 3], 0.5).translucent(1.0, [1.0, 0.8, 0.6]),
        ),
        (
            "translucent, coated",
            Mat::dielectric([0.7; 3], 0.3)
                .translucent(0.5, [0.9; 3])
                .coated(0.6, 0.2),
        ),
    ];
    let angles = [5.0, 40.0, 75.0];
    for (name, m) in &materials {
        for &a in &angles {
            for &b in &angles {
                let wo = direction_at(n, a);
                let wi = scale(direction_at(n, b), -1.0);
                let f = d.eval(m, wo, n, false, &[f4(wi)])[0];
                let g = d.eval(m, wi, back, false, &[f4(wo)])[0];
                assert!(f[0] > 0.0, "{name}: it transmits");
                for ch in 0..3 {
                    let x = f[ch] as f64 / -wi[2];
                    let y = g[ch] as f64 / wo[2];
                    assert!(
                        (x - y).abs() <= 2e-3 * x.abs().max(y.abs()) + 1e-6,
                        "{name}: f(theta_o {a}, theta_i {b}) = {x}, swapped {y}"
                    );
                }
            }
        }
    }
}

#[test]
fn reflection_is_reciprocal() {
    let d = BsdfKernels::new();
    let n = [0.0, 0.0, 1.0];
    let mut plastic = Mat::dielectric([0.8, 0.4, 0.2], 0.5);
    plastic.specular_color = [1.0, 0.7, 1.2];
    let mut half = Mat::metal([0.9, 0.6, 0.3], 0.4);
    half.metallic = 0.5;
    let materials = [
        ("rough dielectric", Mat::dielectric([0.7; 3], 0.8)),
        ("coloured specular", plastic),
        ("half metal", half),
        ("rough metal", Mat::metal([0.9, 0.5, 0.2], 1.0)),
        ("glossy metal", Mat::metal([0.9; 3], 0.2)),
        ("rough coat over plastic", plastic.coated(0.8, 0.4)),
        ("rough coat over half metal", half.coated(1.0, 0.1)),
        ("sheen over plastic", plastic.sheened([0.9, 0.5, 0.7], 0.4)),
        (
            "coat over sheen over half metal",
            half.sheened([0.6; 3], 0.8).coated(0.5, 0.3),
        ),
        (
            "anisotropic metal",
            Mat::metal([0.9, 0.5, 0.2], 0.3).anisotropic(0.9, 0.5),
        ),
        ("anisotropic plastic", plastic.anisotropic(0.6, 2.0)),
        ("iridescent plastic", plastic.iridescent(1.0, 1.8, 320.0)),
        ("iridescent half metal", half.iridescent(0.6, 1.4, 450.0)),
        (
            "anisotropic smooth metal under a coat",
            Mat::metal([0.9; 3], 0.0)
                .anisotropic(1.0, -0.4)
                .coated(0.7, 0.3),
        ),
    ];
    let angles = [5.0, 30.0, 55.0, 80.0];
    for (name, m) in &materials {
        for &a in &angles {
            for &b in &angles {
                for phi in [0.0f64, 100.0, 180.0] {
                    let wo = direction_at(n, a);
                    let (t, bt) = frame(n);
                    let (th, ph) = (b.to_radians(), phi.to_radians());
                    let wi = add(
                        scale(n, th.cos()),
                        add(
                            scale(t, th.sin() * ph.cos()),
                            scale(bt, th.sin() * ph.sin()),
                        ),
                    );
                    // f·cos_i / cos_i against f·cos_o / cos_o with the directions swapped.
                    let f = d.eval(m, wo, n, false, &[f4(wi)])[0];
                    let g = d.eval(m, wi, n, false, &[f4(wo)])[0];
                    for ch in 0..3 {
                        let x = f[ch] as f64 / wi[2];
                        let y = g[ch] as f64 / wo[2];
                        assert!(
                            (x - y).abs() <= 2e-3 * x.abs().max(y.abs()) + 1e-6,
                            "{name}: f(theta_o {a}, theta_i {b}, phi {phi}) = {x}, swapped {y}"
                        );
                    }
                }
            }
        }
    }
}

/// The reflection of `w` about n(θ) = sin θ x + cos θ z (z the geometric normal +Z, x a unit
/// tangent): its height above the surface.
fn reflected_height(w: V, x: V, theta: f64) -> f64 {
    let n = add(scale(x, theta.sin()), scale([0.0, 0.0, 1.0], theta.cos()));
    reflect(w, n)[2]
}

/// The largest θ' ≤ θ whose normal n(θ') reflects `w` at least min(0.9 w_z, lift) above the
/// surface, found by bisection (the kernel's closed form is checked against it): what
/// surface.h's bend_for_reflection turns a shading normal at θ to; a lobe of roughness r is
/// lifted by min(0.01 + 2 r², 0.1) (`reflection_lift`).
fn bent_angle(w: V, x: V, theta: f64, roughness: f64) -> f64 {
    let lift = (0.01 + 2.0 * roughness * roughness).min(0.1);
    let t = (0.9 * w[2]).min(lift);
    if reflected_height(w, x, theta) >= t {
        return theta;
    }
    let (mut lo, mut hi) = (0.0, theta);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if reflected_height(w, x, mid) >= t {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// A steep normal map (the mapped normal 70° from the geometric one): its normals are bent for
/// both directions where the BSDF is evaluated, so f(wo, wi) = f(wi, wo) still holds, with the
/// bent normal the lesser bend of the two (checked here by an independent bisection); rough
/// lobes (the rough metal, the plastic) are not bent.
#[test]
fn reflection_with_a_steep_normal_map_is_reciprocal() {
    let d = BsdfKernels::new();
    let theta_n = 70f64.to_radians();
    let x = [1.0, 0.0, 0.0];
    let n = [theta_n.sin(), 0.0, theta_n.cos()];
    let mut plastic = Mat::dielectric([0.8, 0.4, 0.2], 0.5);
    plastic.specular_color = [1.0, 0.7, 1.2];
    let glossy_plastic = Mat {
        roughness: 0.3,
        ..plastic
    };
    let materials = [
        ("glossy metal", Mat::metal([0.9; 3], 0.2)),
        ("rough metal", Mat::metal([0.9, 0.5, 0.2], 0.7)),
        ("plastic", plastic),
        // Base and coat bent alike (both lifted by the cap, 0.1): f·cos divides by one normal.
        (
            "glossy plastic under a coat",
            glossy_plastic.coated(0.8, 0.4),
        ),
    ];
    let dirs: Vec<V> = [5.0f64, 30.0, 55.0, 80.0]
        .iter()
        .flat_map(|&a| {
            [0.0f64, 100.0, 180.0].map(|phi| {
                let (th, ph) = (a.to_radians(), phi.to_radians());
                [th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()]
            })
        })
        .collect();
    let mut bent = 0;
    for (name, m) in &materials {
        for &wo in &dirs {
            for &wi in &dirs {
                // Both directions are below the mapped normal's horizon for some pairs: f is
                // 0 either way there.
                // The base is bent where it is glossy: roughness below 0.5 (BEND_ROUGHNESS_MAX).
                let r = m.roughness as f64;
                let theta = if r < 0.5 {
                    bent_angle(wo, x, theta_n, r).min(bent_angle(wi, x, theta_n, r))
                } else {
                    theta_n
                };
                bent += (theta < theta_n - 1e-3) as usize;
                let nb = add(scale(x, theta.sin()), [0.0, 0.0, theta.cos()]);
                let f = d.bent(m, wo, n, &[f4(wi)])[0];
                let g = d.bent(m, wi, n, &[f4(wo)])[0];
                for ch in 0..3 {
                    let (ci, co) = (dot(wi, nb), dot(wo, nb));
                    let x = if ci > 1e-3 { f[ch] as f64 / ci } else { 0.0 };
                    let y = if co > 1e-3 { g[ch] as f64 / co } else { 0.0 };
                    assert!(
                        (x - y).abs() <= 2e-3 * x.abs().max(y.abs()) + 1e-5,
                        "{name}: f(wo {wo:?}, wi {wi:?}) = {x}, swapped {y}"
                    );
                }
            }
        }
    }
    assert!(bent > 60, "the bend acts on many pairs ({bent})");
}

/// The render's mean over the image, 24 × 24 pixels, 256 samples, 3 bounces, black sky.
fn mean_of_render(
    dir: &std::path::Path,
    g: &Gltf,
    name: &str,
    strategy: &str,
    kernel: &str,
) -> f64 {
    let scene = g.write_glb(dir, name);
    let (summary, px) = render_exr(
        &scene,
        &dir.join(format!("{name}.exr")),
        &[
            "--width",
            "24",
            "--height",
            "24",
            "--spp",
            "256",
            "--bounces",
            "3",
            "--sky",
            "0,0,0",
            "--strategy",
            strategy,
            "--kernel",
            kernel,
        ],
    );
    assert_eq!(summary["nonfinite_samples"], 0);
    common::mean_gray(&px)
}

/// A translucent sheet seen from below with a light above it: the light comes through by
/// diffuse transmission, found by light sampling from the back hemisphere and by BSDF sampling.
fn back_lit_sheet(dir: &std::path::Path, strategy: &str, kernel: &str) -> f64 {
    let mut g = Gltf::default();
    let light_mat = g.lambert([0.0; 3], [1.0; 3], 5.0, true);
    let sheet = Mat::lambert([0.8; 3]).translucent(0.7, [1.0, 0.8, 0.6]);
    let sheet_mat = material_json(&mut g, &sheet, None);
    let (sp, si) = horizontal_square(1.0, 3.0, false);
    let (lp, li) = horizontal_square(2.0, 0.5, false);
    let mesh = g.mesh(vec![
        Prim::triangles(sp, si, sheet_mat),
        Prim::triangles(lp, li, light_mat),
    ]);
    g.node(json!({"mesh": mesh}));
    g.cameras
        .push(json!({"type": "perspective", "perspective": {"yfov": 0.6, "znear": 0.01}}));
    g.node(json!({"camera": 0, "translation": [0.0, 0.0, 0.0],
                  "rotation": [std::f32::consts::FRAC_1_SQRT_2, 0.0, 0.0, std::f32::consts::FRAC_1_SQRT_2]}));
    mean_of_render(
        dir,
        &g,
        &format!("sheet_{strategy}_{kernel}"),
        strategy,
        kernel,
    )
}

#[test]
fn light_sampling_reaches_through_diffuse_transmission() {
    let dir = tempfile::tempdir().unwrap();
    for kernel in ["wavefront", "megakernel"] {
        let mis = back_lit_sheet(dir.path(), "mis", kernel);
        let bsdf = back_lit_sheet(dir.path(), "bsdf", kernel);
        let lights = back_lit_sheet(dir.path(), "lights", kernel);
        eprintln!("{kernel}: mis {mis:.4}, bsdf {bsdf:.4}, lights {lights:.4}");
        assert!(mis > 0.01, "{kernel}: the sheet is dark ({mis})");
        for (name, v) in [("bsdf", bsdf), ("lights", lights)] {
            assert!(
                (v - mis).abs() < 0.04 * mis,
                "{kernel}: {name}-only {v:.4} and MIS {mis:.4} disagree"
            );
        }
    }
}

/// A floor lit by an emissive panel through a smooth thin glass pane between them, seen from
/// under the pane: the floor's radiance (mean over the image) with `strategy` and `kernel`.
fn lit_through_a_window(dir: &std::path::Path, pane: bool, strategy: &str, kernel: &str) -> f64 {
    let mut g = Gltf::default();
    let floor_mat = g.lambert([0.8; 3], [0.0; 3], 1.0, false);
    let light_mat = g.lambert([0.0; 3], [1.0; 3], 5.0, true);
    let (fp, fi) = horizontal_square(0.0, 1.0, true);
    let (lp, li) = horizontal_square(2.0, 0.5, false);
    let mut prims = vec![
        Prim::triangles(fp, fi, floor_mat),
        Prim::triangles(lp, li, light_mat),
    ];
    if pane {
        let mut glass = Mat::glass(0.0, 0.0);
        glass.base = [0.9, 1.0, 0.8];
        let m = material_json(&mut g, &glass, None);
        g.materials[m]["doubleSided"] = json!(true);
        let (pp, pi) = horizontal_square(1.0, 3.0, true);
        prims.push(Prim::triangles(pp, pi, m));
    }
    let mesh = g.mesh(prims);
    g.node(json!({"mesh": mesh}));
    g.cameras
        .push(json!({"type": "perspective", "perspective": {"yfov": 0.6, "znear": 0.01}}));
    g.node(json!({"camera": 0, "translation": [0.0, 0.5, 0.0],
                  "rotation": [-std::f32::consts::FRAC_1_SQRT_2, 0.0, 0.0, std::f32::consts::FRAC_1_SQRT_2]}));
    mean_of_render(
        dir,
        &g,
        &format!("window_{pane}_{strategy}_{kernel}"),
        strategy,
        kernel,
    )
}

#[test]
fn light_sampling_reaches_through_thin_windows() {
    // Shadow rays pass the pane in both execution shapes (the wavefront's `connect` and the
    // megakernel's own shadow test).
    let dir = tempfile::tempdir().unwrap();
    for kernel in ["wavefront", "megakernel"] {
        let open = lit_through_a_window(dir.path(), false, "mis", kernel);
        let mis = lit_through_a_window(dir.path(), true, "mis", kernel);
        let bsdf = lit_through_a_window(dir.path(), true, "bsdf", kernel);
        let lights = lit_through_a_window(dir.path(), true, "lights", kernel);
        eprintln!(
            "{kernel}: open {open:.4}, through the pane: mis {mis:.4}, bsdf {bsdf:.4}, lights {lights:.4}"
        );
        // Every strategy sees the light through the pane, and they agree.
        for (name, v) in [("bsdf", bsdf), ("lights", lights)] {
            assert!(
                (v - mis).abs() < 0.04 * mis,
                "{kernel}: {name}-only {v:.4} and MIS {mis:.4} disagree"
            );
        }
        // Two faces of ior 1.5 near normal incidence pass (1 - F) / (1 + F) = 0.92 of the
        // light, times the pane's tint (luminance-free mean of 0.9, 1.0, 0.8 = 0.9).
        let ratio = mis / open;
        assert!(
            (0.78..0.88).contains(&ratio),
            "{kernel}: the pane passes {ratio:.3} of the light"
        );
    }
}

/// An 8×8 render of `scene` at 4 spp and 4 bounces under a uniform sky of radiance `sky`.
fn render_8x8_under_sky(
    scene: &std::path::Path,
    out: &std::path::Path,
    sky: &str,
) -> (serde_json::Value, Vec<[f32; 3]>) {
    let args = [
        "--width",
        "8",
        "--height",
        "8",
        "--spp",
        "4",
        "--bounces",
        "4",
        "--sky",
        sky,
    ];
    render_exr(scene, out, &args)
}

#[test]
fn beer_lambert_absorption_through_a_slab() {
    // Index-matched glass (ior 1: no reflection, no bending) one unit thick: the sky comes
    // through attenuated to attenuationColor^(1 / attenuationDistance).
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::default();
    let mut m = Mat::glass(0.0, 1.0);
    m.ior = 1.0;
    let color = [0.5f32, 0.25, 0.8];
    let mat = material_json(&mut g, &m, Some((color, 0.5)));
    let (positions, indices) = cuboid([-2.0, -2.0, -0.5], [2.0, 2.0, 0.5]);
    let mesh = g.mesh(vec![Prim::triangles(positions, indices, mat)]);
    g.node(json!({"mesh": mesh}));
    camera_and_no_light(&mut g, 5.0, 0.2);
    let scene = g.write_glb(dir.path(), "slab");
    let (summary, px) = render_8x8_under_sky(&scene, &dir.path().join("slab.exr"), "1,1,1");
    assert_eq!(summary["nonfinite_samples"], 0);
    let h = (0.1f64).tan();
    for (i, p) in px.iter().enumerate() {
        // The path through the slab is 1 / cos of the pixel's ray to the slab's normal.
        let (fx, fy) = ((i % 8) as f64 + 0.5, (i / 8) as f64 + 0.5);
        let d = norm([(fx / 4.0 - 1.0) * h, (1.0 - fy / 4.0) * h, -1.0]);
        let length = 1.0 / d[2].abs();
        for ch in 0..3 {
            let expected = (color[ch] as f64).powf(length / 0.5);
            assert!(
                (p[ch] as f64 - expected).abs() < 3e-3 * expected,
                "pixel {i}: {p:?}, expected {expected} in channel {ch}"
            );
        }
    }
}

#[test]
fn unlit_material_shows_its_base_color() {
    // KHR_materials_unlit under a bright sky: the color, no shading, no reflection of the sky.
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::default();
    g.use_ext("KHR_materials_unlit");
    let color = [0.2f32, 0.5, 0.8];
    g.materials.push(json!({
        "pbrMetallicRoughness": {"baseColorFactor": [color[0], color[1], color[2], 1.0],
                                 "metallicFactor": 1.0, "roughnessFactor": 0.0},
        "extensions": {"KHR_materials_unlit": {}}
    }));
    let (positions, indices) = cuboid([-2.0, -2.0, -0.5], [2.0, 2.0, 0.5]);
    let mesh = g.mesh(vec![Prim::triangles(positions, indices, 0)]);
    g.node(json!({"mesh": mesh}));
    camera_and_no_light(&mut g, 5.0, 0.2);
    let scene = g.write_glb(dir.path(), "unlit");
    let (summary, px) = render_8x8_under_sky(&scene, &dir.path().join("unlit.exr"), "3,3,3");
    assert_eq!(summary["nonfinite_samples"], 0);
    for (i, p) in px.iter().enumerate() {
        for ch in 0..3 {
            assert!(
                (p[ch] - color[ch]).abs() < 1e-5,
                "pixel {i}: {p:?} instead of the base color {color:?}"
            );
        }
    }
}

#[test]
fn no_nonfinite_samples_at_the_extremes() {
    // Smooth-shaded spheres of every extreme material on a floor, lit by a point light, an
    // emissive panel and the sky, seen at a grazing angle.
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::default();
    let white = [1.0f32; 3];
    let mut materials = vec![];
    for r in [0.0, 1.0] {
        for metallic in [0.0, 1.0] {
            let mut m = Mat::dielectric([0.8, 0.6, 0.4], r);
            m.metallic = metallic;
            materials.push((m, None));
        }
        materials.push((Mat::glass(r, 1.0), Some(([0.3, 0.6, 0.9], 0.7))));
        materials.push((Mat::glass(r, 0.0), None));
    }
    let mut odd = Mat::glass(0.02, 1.0);
    odd.ior = 1.0;
    materials.push((odd, None));
    let mut strong = Mat::dielectric([0.0; 3], 0.05);
    strong.ior = 4.0;
    strong.specular_color = [3.0, 0.0, 1.0];
    materials.push((strong, None));
    let mut tiny = Mat::metal(white, 0.032);
    tiny.base = [1.0, 0.0, 0.5];
    materials.push((tiny, None));
    let (positions, normals, indices) = sphere(0.45, 16, 32, false);
    for (i, (m, att)) in materials.iter().enumerate() {
        let mat = material_json(&mut g, m, *att);
        let mesh = g.mesh(vec![Prim {
            positions: positions.clone(),
            normals: normals.clone(),
            indices: indices.clone(),
            material: Some(mat),
            mode: 4,
        }]);
        let x = (i % 6) as f32 - 2.5;
        let z = -((i / 6) as f32) * 1.2;
        g.node(json!({"mesh": mesh, "translation": [x, 0.45, z]}));
    }
    let floor = material_json(&mut g, &Mat::dielectric([0.5; 3], 0.4), None);
    let (positions, indices) = horizontal_square(0.0, 20.0, true);
    let mesh = g.mesh(vec![Prim::triangles(positions, indices, floor)]);
    g.node(json!({"mesh": mesh}));
    let lamp = g.lambert([0.0; 3], [1.0; 3], 5.0, true);
    let (positions, indices) = horizontal_square(3.0, 1.0, false);
    let mesh = g.mesh(vec![Prim::triangles(positions, indices, lamp)]);
    g.node(json!({"mesh": mesh}));
    g.lights
        .push(json!({"type": "point", "intensity": 20.0, "color": [1.0, 1.0, 1.0]}));
    g.node(json!({"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [2.0, 2.0, 2.0]}));
    g.cameras
        .push(json!({"type": "perspective", "perspective": {"yfov": 0.9, "znear": 0.01}}));
    // Just above the floor, looking along it.
    g.node(json!({"camera": 0, "translation": [0.0, 0.05, 4.0], "rotation": [-0.0087, 0.0, 0.0, 0.99996]}));
    let scene = g.write_glb(dir.path(), "extremes");
    let (summary, px) = render_exr(
        &scene,
        &dir.path().join("extremes.exr"),
        &[
            "--width",
            "64",
            "--height",
            "32",
            "--spp",
            "16",
            "--bounces",
            "12",
            "--sky",
            "0.5,0.5,0.5",
        ],
    );
    assert_eq!(summary["nonfinite_samples"], 0, "{summary}");
    assert!(px.iter().flatten().all(|c| c.is_finite() && *c >= 0.0));
}
