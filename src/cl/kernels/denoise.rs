//! Typed wrappers over the denoiser's kernels (kernels/denoise/): the U-Net's convolutions and
//! the input and output preparation. Each launches under its kernel's name and returns the
//! profiling event.
#![allow(unsafe_code)]

use super::{Launch, kernel};
use crate::cl::{Buffer, ClError, Device, build_denoise_program, call_err};
use opencl3::kernel::{ExecuteKernel, Kernel};

/// A 2D kernel's work-group (the preparation kernels).
const GROUP_2D: [usize; 2] = [16, 4];

/// Where the denoiser reads each pixel's colour (kernels/denoise/prepare.cl, `color_value`).
#[derive(Clone, Copy)]
pub enum ColorSource<'a> {
    /// Linear RGB, RGBA f32 per pixel: `.xyz` is the value, `.w` is ignored.
    Image(&'a Buffer<[f32; 4]>),
    /// The renderer's film as it accumulates (kernels/shared/film.h): per pixel the fixed-point
    /// sum of its samples, divided by its own sample count.
    Film(&'a Buffer<[u64; 4]>, FilmCount<'a>),
}

/// How a film pixel's sample count is known.
#[derive(Clone, Copy)]
pub enum FilmCount<'a> {
    /// The film's `.w`: it counts the samples.
    Own,
    /// Every pixel took this many (the film's `.w` counts only the hits).
    Taken(u32),
    /// Each pixel took the samples its adaptive state records (`PIXEL_SAMPLES` bits;
    /// kernels/shared/adaptive.h).
    State(&'a Buffer<u32>),
}

impl ColorSource<'_> {
    /// The kernels' `color_mode` (`DN_COLOR_*`) and `taken`.
    fn mode(&self) -> (i32, f32) {
        match self {
            ColorSource::Image(_) => (0, 0.0),
            ColorSource::Film(_, FilmCount::Own) => (1, 0.0),
            ColorSource::Film(_, FilmCount::Taken(n)) => (2, *n as f32),
            ColorSource::Film(_, FilmCount::State(_)) => (3, 0.0),
        }
    }

    /// Sets the colour's five arguments: the image, the film, the states (a buffer the mode
    /// does not read stands in for those it has not), the mode and `taken`.
    ///
    /// # Safety
    /// Only for kernels whose next five parameters are exactly those.
    unsafe fn set_args(&self, e: &mut ExecuteKernel, placeholder: &Buffer<[f32; 4]>) {
        let (mode, taken) = self.mode();
        let (mut image, mut film, mut state) =
            (placeholder.mem(), placeholder.mem(), placeholder.mem());
        match self {
            ColorSource::Image(b) => image = b.mem(),
            ColorSource::Film(f, count) => {
                film = f.mem();
                if let FilmCount::State(s) = count {
                    state = s.mem();
                }
            }
        }
        // SAFETY: the caller's kernel declares these five parameters next, in this order.
        unsafe {
            e.set_arg(&image)
                .set_arg(&film)
                .set_arg(&state)
                .set_arg(&mode)
                .set_arg(&taken);
        }
    }
}

/// The guides the denoiser reads: per pixel sums over the count in the albedo's `.w` (1 for
/// images of means), RGBA f32 (kernels/shared/aovs.h's layout).
#[derive(Clone, Copy)]
pub struct GuideSums<'a> {
    /// `.xyz` the albedos' sum, `.w` the count.
    pub albedo: &'a Buffer<[f32; 4]>,
    /// `.xyz` the normals' sum (`.w` unused).
    pub normal: &'a Buffer<[f32; 4]>,
}

/// One convolution's operands: `dst = relu(conv3x3(concat(upsample?(src0), src1)) + bias)`,
/// max-pooled 2x2 when `pool`. Tensors are laid out as kernels/denoise/tensor.h says.
pub struct ConvArgs<'a> {
    /// The first input and its channels.
    pub src0: &'a Buffer<f32>,
    /// Channels of `src0`.
    pub c0: usize,
    /// `src0` is at half the resolution and read upsampled (nearest).
    pub up0: bool,
    /// The skip connection concatenated after `src0`, and its channels (0: none).
    pub src1: Option<(&'a Buffer<f32>, usize)>,
    /// Weights blocked as `[out / ocb][in][tap][ocb]`.
    pub weights: &'a Buffer<f32>,
    /// Biases, padded to the output channels.
    pub bias: &'a Buffer<f32>,
    /// The output tensor.
    pub dst: &'a Buffer<f32>,
    /// Output channels (a multiple of [`DenoiseKernels::ocb`]).
    pub out_channels: usize,
    /// The convolution's resolution (the output's before pooling).
    pub width: usize,
    /// See `width`.
    pub height: usize,
    /// Max-pool the output 2x2.
    pub pool: bool,
}

/// How [`DenoiseKernels::planes`] maps each value (`DN_PLANES_*` in kernels/denoise/prepare.cl).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlaneCurve {
    /// As it is.
    Linear = 0,
    /// Into the sRGB curve.
    ToSrgb = 1,
    /// Out of the sRGB curve.
    FromSrgb = 2,
}

/// Where one tile of the image goes in the network's input, and back.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TileWindow {
    /// The tile buffer's size (multiples of 16).
    pub tile_w: usize,
    /// See `tile_w`.
    pub tile_h: usize,
    /// The first image pixel of the region copied.
    pub image_x: usize,
    /// See `image_x`.
    pub image_y: usize,
    /// Where that pixel lies in the tile.
    pub tile_x: usize,
    /// See `tile_x`.
    pub tile_y: usize,
    /// The region's size.
    pub w: usize,
    /// See `w`.
    pub h: usize,
}

/// The denoiser's built kernels.
pub struct DenoiseKernels {
    conv: Kernel,
    conv_up: Kernel,
    conv_pool: Kernel,
    exposure_bins: Kernel,
    input: Kernel,
    output: Kernel,
    planes: Kernel,
    /// Output channels a convolution's work item computes (`DN_OCB`).
    pub ocb: usize,
    /// Neighbouring columns a convolution's work item computes (`DN_VEC`).
    vec: usize,
    /// A convolution's work-group along x.
    group_x: usize,
}

fn round_up(n: usize, m: usize) -> usize {
    n.max(1).div_ceil(m) * m
}

fn launch(
    device: &Device,
    stage: &'static str,
    kernel: &Kernel,
    global: &[usize],
    local: &[usize],
    set: impl FnOnce(&mut ExecuteKernel),
) -> Result<Launch, ClError> {
    let mut exec = ExecuteKernel::new(kernel);
    set(&mut exec);
    let global: Vec<usize> = global
        .iter()
        .zip(local)
        .map(|(&g, &l)| round_up(g, l))
        .collect();
    exec.set_global_work_sizes(&global)
        .set_local_work_sizes(local);
    // SAFETY: every wrapper sets exactly its kernel's arguments, in order, with the types the
    // kernel declares; the buffers outlive the launch because the queue is in order and every
    // reader of the results waits on it.
    let event = unsafe { exec.enqueue_nd_range(&device.queue) }.map_err(call_err(stage))?;
    Ok(Launch { stage, event })
}

impl DenoiseKernels {
    /// Builds the denoiser's program for the device. On a CPU a work item computes 16 columns
    /// (one AVX-512 vector) of 4 rows and 4 output channels, 16 accumulator registers of 32,
    /// a work-group is 4 of them (PoCL runs a group as one task), and the work-groups that run
    /// in turn take the output-channel blocks of the same pixels (`DN_BLOCKS_FIRST`: their
    /// input stays in cache); on a GPU 2 columns of 4 rows and 8 channels, in groups of 64
    /// along the row (coalesced loads).
    pub fn build(device: &Device) -> Result<Self, ClError> {
        let (ocb, vec, group_x, order) = if device.is_cpu() {
            (4, 16, 4, " -DDN_BLOCKS_FIRST")
        } else {
            (8, 2, 64, "")
        };
        let options = format!(" -DDN_OCB={ocb} -DDN_VEC={vec}{order}");
        let program = build_denoise_program(device, &options)?;
        Ok(Self {
            conv: kernel(&program, "conv3x3")?,
            conv_up: kernel(&program, "conv3x3_up")?,
            conv_pool: kernel(&program, "conv3x3_pool")?,
            exposure_bins: kernel(&program, "denoise_exposure_bins")?,
            input: kernel(&program, "denoise_input")?,
            output: kernel(&program, "denoise_output")?,
            planes: kernel(&program, "denoise_planes")?,
            ocb,
            vec,
            group_x,
        })
    }

    /// `conv3x3`, `conv3x3_up` or `conv3x3_pool`.
    pub fn conv(&self, device: &Device, a: &ConvArgs) -> Result<Launch, ClError> {
        assert_eq!(a.out_channels % self.ocb, 0, "output channels not blocked");
        let (src1, c1) = a.src1.unwrap_or((a.src0, 0));
        assert!(!(a.pool && a.up0), "no kernel pools an upsampled input");
        let blocks = a.out_channels / self.ocb;
        let columns = a.width.div_ceil(self.vec);
        let rows = [columns, a.height.div_ceil(4), blocks];
        let (kernel, stage, global) = match (a.pool, a.up0) {
            (true, _) => {
                let g = [columns, a.height / 2, blocks];
                (&self.conv_pool, "conv3x3_pool", g)
            }
            (false, true) => (&self.conv_up, "conv3x3_up", rows),
            (false, false) => (&self.conv, "conv3x3", rows),
        };
        let ints = [a.c0 as i32, c1 as i32];
        let dims = [a.width as i32, a.height as i32];
        launch(
            device,
            stage,
            kernel,
            &global,
            &[self.group_x, 1, 1],
            |e| unsafe {
                e.set_arg(&a.src0.mem())
                    .set_arg(&ints[0])
                    .set_arg(&src1.mem())
                    .set_arg(&ints[1])
                    .set_arg(&a.weights.mem())
                    .set_arg(&a.bias.mem())
                    .set_arg(&a.dst.mem())
                    .set_arg(&dims[0])
                    .set_arg(&dims[1]);
            },
        )
    }

    /// `denoise_exposure_bins`: the mean luminance of `bins` = (across, down) blocks of the
    /// `width` x `height` colour; `guides` only stand in for buffers the colour has not.
    #[allow(clippy::too_many_arguments)]
    pub fn exposure_bins(
        &self,
        device: &Device,
        color: ColorSource,
        guides: GuideSums,
        width: usize,
        height: usize,
        bins: (usize, usize),
        out: &Buffer<f32>,
    ) -> Result<Launch, ClError> {
        let ints = [width as i32, height as i32, bins.0 as i32, bins.1 as i32];
        launch(
            device,
            "denoise_exposure_bins",
            &self.exposure_bins,
            &[bins.0 * bins.1],
            &[64],
            |e| unsafe {
                color.set_args(e, guides.albedo);
                for i in &ints {
                    e.set_arg(i);
                }
                e.set_arg(&out.mem());
            },
        )
    }

    /// `denoise_input`: the network's input tensor for one tile of the `width`-wide image.
    #[allow(clippy::too_many_arguments)]
    pub fn input(
        &self,
        device: &Device,
        color: ColorSource,
        guides: GuideSums,
        width: usize,
        tile: TileWindow,
        exposure: f32,
        pu_norm: f32,
        dst: &Buffer<f32>,
    ) -> Result<Launch, ClError> {
        let ints = [
            width,
            tile.image_x,
            tile.image_y,
            tile.tile_x,
            tile.tile_y,
            tile.w,
            tile.h,
            tile.tile_w,
            tile.tile_h,
        ]
        .map(|v| v as i32);
        debug_assert_eq!(
            tile.tile_w % self.vec,
            0,
            "a work item takes DN_VEC columns"
        );
        launch(
            device,
            "denoise_input",
            &self.input,
            &[tile.tile_w / self.vec, tile.tile_h],
            &GROUP_2D,
            |e| unsafe {
                color.set_args(e, guides.albedo);
                e.set_arg(&guides.albedo.mem())
                    .set_arg(&guides.normal.mem());
                for i in &ints {
                    e.set_arg(i);
                }
                e.set_arg(&exposure).set_arg(&pu_norm).set_arg(&dst.mem());
            },
        )
    }

    /// `denoise_output`: one tile's denoised pixels into the `width`-wide output image.
    #[allow(clippy::too_many_arguments)]
    pub fn output(
        &self,
        device: &Device,
        src: &Buffer<f32>,
        tile: TileWindow,
        width: usize,
        pu_max: f32,
        output_scale: f32,
        out: &Buffer<[f32; 4]>,
    ) -> Result<Launch, ClError> {
        let ints = [
            tile.tile_w,
            tile.tile_h,
            tile.tile_x,
            tile.tile_y,
            tile.image_x,
            tile.image_y,
            tile.w,
            tile.h,
            width,
        ]
        .map(|v| v as i32);
        launch(
            device,
            "denoise_output",
            &self.output,
            &[tile.w.div_ceil(self.vec), tile.h],
            &GROUP_2D,
            |e| unsafe {
                e.set_arg(&src.mem());
                for i in &ints {
                    e.set_arg(i);
                }
                e.set_arg(&pu_max)
                    .set_arg(&output_scale)
                    .set_arg(&out.mem());
            },
        )
    }

    /// `denoise_planes`: three planes of one tile's tensor `src` from plane `src_first` into
    /// `dst` from plane `dst_first`, capped at `hi`, mapped by `curve`, zero outside the
    /// tile's image window.
    #[allow(clippy::too_many_arguments)]
    pub fn planes(
        &self,
        device: &Device,
        src: &Buffer<f32>,
        src_first: usize,
        dst: &Buffer<f32>,
        dst_first: usize,
        tile: TileWindow,
        hi: f32,
        curve: PlaneCurve,
    ) -> Result<Launch, ClError> {
        let curve = curve as i32;
        let (src_first, dst_first) = (src_first as i32, dst_first as i32);
        let ints = [
            tile.tile_w,
            tile.tile_h,
            tile.tile_x,
            tile.tile_y,
            tile.w,
            tile.h,
        ]
        .map(|v| v as i32);
        launch(
            device,
            "denoise_planes",
            &self.planes,
            &[tile.tile_w, tile.tile_h],
            &GROUP_2D,
            |e| unsafe {
                e.set_arg(&src.mem())
                    .set_arg(&src_first)
                    .set_arg(&dst.mem())
                    .set_arg(&dst_first);
                for i in &ints {
                    e.set_arg(i);
                }
                e.set_arg(&hi).set_arg(&curve);
            },
        )
    }
}
