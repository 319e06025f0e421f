//! What the user controls about a render.

use crate::cl::types::{
    ADAPTIVE_COST, ADAPTIVE_ERROR, ADAPTIVE_OFF, BACKGROUND_COUNT, BACKGROUND_CUTOUT,
    BACKGROUND_ENV, DeviceFrame, STRATEGY_BSDF, STRATEGY_LIGHTS, STRATEGY_MIS,
};

/// Which estimator feeds direct light.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub enum Strategy {
    /// Light sampling and BSDF sampling combined by the power heuristic.
    #[default]
    Mis,
    /// BSDF sampling only (lights found by hitting them; punctual lights are never hit).
    Bsdf,
    /// Light sampling only (emitters hit by BSDF rays count only when seen directly).
    Lights,
}

/// When adaptive sampling stops a pixel (docs/adaptive-sampling.md, "The rule").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub enum AdaptiveRule {
    /// Its relative error is under the threshold (Cycles' rule).
    #[default]
    Error,
    /// Its relative error is under the threshold times √(rays its samples traced / the
    /// minimum): expensive and well-sampled pixels stop sooner, each near n ∝ √(variance /
    /// cost).
    Cost,
}

impl AdaptiveRule {
    /// The name used on the command line and in summaries.
    pub fn name(self) -> &'static str {
        match self {
            AdaptiveRule::Error => "error",
            AdaptiveRule::Cost => "cost",
        }
    }
}

impl std::str::FromStr for AdaptiveRule {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "error" => Ok(AdaptiveRule::Error),
            "cost" => Ok(AdaptiveRule::Cost),
            other => Err(format!("adaptive rule '{other}' is not 'error' or 'cost'")),
        }
    }
}

/// Settings of the path tracer.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    /// Film width in pixels.
    pub width: u32,
    /// Film height in pixels.
    pub height: u32,
    /// Bounces after the first hit (0 = direct light only).
    pub bounces: u32,
    /// Seed of the random sequence.
    pub seed: u32,
    /// Russian roulette from this bounce on; `None` disables it.
    pub russian_roulette: Option<u32>,
    /// Direct-light strategy.
    pub strategy: Strategy,
    /// Uniform sky radiance (linear RGB); replaced by the environment map when one is set
    /// (`Renderer::set_environment`).
    pub sky: [f32; 3],
    /// Environment map radiance scale.
    pub env_intensity: f32,
    /// Environment map rotation about +Y in degrees (counter-clockwise seen from above).
    pub env_rotation: f32,
    /// Thin-lens radius in scene units; 0 is a pinhole (everything sharp).
    pub lens_radius: f32,
    /// Distance from the eye to the plane in focus, along the view axis, in scene units.
    pub focus_distance: f32,
    /// Escaped camera rays add nothing (the environment still lights the scene) and the film
    /// keeps each pixel's coverage (`Renderer::coverage`): for `--background transparent` and
    /// `--background COLOR`.
    pub cutout: bool,
    /// The film keeps each pixel's coverage with the background shown too (for metering the
    /// subject); the image is the same.
    pub count_coverage: bool,
    /// Adaptive sampling: pixels whose relative error is under this stop taking samples
    /// (docs/adaptive-sampling.md); `None`: every pixel takes every sample.
    pub noise_threshold: Option<f32>,
    /// How adaptive sampling weighs a pixel's error against the threshold.
    pub adaptive_rule: AdaptiveRule,
    /// Guide buffers for a denoiser: the film also sums each sample's albedo, normal and depth
    /// (docs/aovs.md; `Renderer::aovs`). Off, the kernels are built without them.
    pub aovs: bool,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            width: 640,
            height: 480,
            bounces: 4,
            seed: 0,
            russian_roulette: Some(3),
            strategy: Strategy::Mis,
            sky: [0.0; 3],
            env_intensity: 1.0,
            env_rotation: 0.0,
            lens_radius: 0.0,
            focus_distance: 1.0,
            cutout: false,
            count_coverage: false,
            noise_threshold: None,
            adaptive_rule: AdaptiveRule::Error,
            aovs: false,
        }
    }
}

impl RenderSettings {
    /// Width over height.
    pub fn aspect(&self) -> f32 {
        self.width as f32 / self.height.max(1) as f32
    }

    /// The per-wave constants, without the wave-specific fields.
    pub fn gpu_frame(&self, light_count: u32) -> DeviceFrame {
        DeviceFrame {
            width: self.width,
            height: self.height,
            samples_in_wave: 1,
            first_sample: 0,
            seed: self.seed,
            max_bounces: self.bounces,
            rr_depth: self.russian_roulette.unwrap_or(u32::MAX),
            strategy: match self.strategy {
                Strategy::Mis => STRATEGY_MIS,
                Strategy::Bsdf => STRATEGY_BSDF,
                Strategy::Lights => STRATEGY_LIGHTS,
            },
            sky: [self.sky[0], self.sky[1], self.sky[2], 0.0],
            light_count,
            bounce: 0,
            background: match (self.cutout, self.count_coverage) {
                (true, _) => BACKGROUND_CUTOUT,
                (false, true) => BACKGROUND_COUNT,
                (false, false) => BACKGROUND_ENV,
            },
            triangles: 0,
            adaptive: match (self.noise_threshold, self.adaptive_rule) {
                (None, _) => ADAPTIVE_OFF,
                (Some(_), AdaptiveRule::Error) => ADAPTIVE_ERROR,
                (Some(_), AdaptiveRule::Cost) => ADAPTIVE_COST,
            },
            pad: [0; 3],
        }
    }
}
