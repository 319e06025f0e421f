//! The path tracer's stages: one kernel each, named the same in the kernel, its wrapper, the
//! statistics and the overlay.

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
    /// Adaptive sampling's convergence check between waves (`converge`, then
    /// `converge_dilate`).
    Converge,
}

impl Stage {
    /// Every stage, in launch order.
    pub const ALL: [Stage; 8] = [
        Stage::Generate,
        Stage::Extend,
        Stage::Shade,
        Stage::Connect,
        Stage::Advance,
        Stage::Accumulate,
        Stage::Megakernel,
        Stage::Converge,
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
            Stage::Converge => "converge",
        }
    }
}
