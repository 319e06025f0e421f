//! Open Image Denoise's U-Net for `rt` with HDR colour, albedo and normal, as its
//! `UNetFilter::buildModel` lays it out (the full and the small weights share the layer list and
//! differ in channels): five encoder convolutions, the last four followed by a 2x2 max pool,
//! two at the bottom, and four decoder stages that upsample (nearest, 2x), concatenate the
//! encoder's output of that resolution and convolve twice; every convolution is 3x3 with a bias
//! and a ReLU, the last one included. Here the upsampling and concatenation are fused into the
//! decoder convolution's reads and the pool into the encoder convolution's writes.
//!
//! The large weights (`rt_hdr_calb_cnrm_large`, OIDN's `high` quality with clean guides) are
//! OIDN's `UNetLarge`: two convolutions at each encoder level, the second pooled, wider
//! channels (64 to 256) and a third full-resolution decoder convolution (`LARGE_STEPS`). The
//! guide prefilters (`rt_alb`, `rt_nrm`) are the standard layer list on 3 input channels.

use super::tza::Tensor;
use crate::cl::{Buffer, ClError, ConvArgs, DenoiseKernels, Device};
use std::collections::HashMap;

/// Channels of the denoising networks' input: colour, albedo and normal (the guide
/// prefilters take 3).
pub const INPUT_CHANNELS: usize = 9;

/// The network's tensors, each at a resolution (`level`: halved that many times). Decoder
/// stages alternate two tensors a level, the full-resolution convolutions two more.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Slot {
    /// The prepared input (9 channels).
    Input,
    /// Full resolution: `enc_conv0`, later `dec_conv1b`.
    Full1,
    /// Full resolution: `dec_conv1a`, later the output.
    Full2,
    /// The pooled encoder outputs kept for the skips (levels 1-3).
    Pool1,
    /// See `Pool1`.
    Pool2,
    /// See `Pool1`.
    Pool3,
    /// Level 4 (`enc_conv4` pooled, then `enc_conv5b`).
    Bottom1,
    /// Level 4 (`enc_conv5a`).
    Bottom2,
    /// Decoder tensors: (level, first or second).
    Decoder(u8, bool),
}

impl Slot {
    /// Halvings of the resolution.
    pub fn level(self) -> u32 {
        match self {
            Slot::Input | Slot::Full1 | Slot::Full2 => 0,
            Slot::Pool1 => 1,
            Slot::Pool2 => 2,
            Slot::Pool3 => 3,
            Slot::Bottom1 | Slot::Bottom2 => 4,
            Slot::Decoder(level, _) => level as u32,
        }
    }
}

/// One convolution of the network: its weights' name, inputs and output.
#[derive(Clone, Copy, Debug)]
pub struct Step {
    /// The tensors' name prefix in the archive (`enc_conv0` for `enc_conv0.weight`).
    pub name: &'static str,
    /// The main input.
    pub src0: Slot,
    /// `src0` is upsampled (it is a level below the output).
    pub up0: bool,
    /// The skip concatenated after it.
    pub src1: Option<Slot>,
    /// The output.
    pub dst: Slot,
    /// The output is max-pooled.
    pub pool: bool,
}

const fn step(name: &'static str, src0: Slot, dst: Slot, pool: bool) -> Step {
    Step {
        name,
        src0,
        up0: false,
        src1: None,
        dst,
        pool,
    }
}

const fn up(name: &'static str, src0: Slot, skip: Slot, dst: Slot) -> Step {
    Step {
        name,
        src0,
        up0: true,
        src1: Some(skip),
        dst,
        pool: false,
    }
}

/// The decoder both networks share, from the bottom level up to the full-resolution tensor
/// before the last convolution.
const DECODER: [Step; 8] = {
    use Slot::*;
    [
        up("dec_conv4a", Bottom1, Pool3, Decoder(3, false)),
        step("dec_conv4b", Decoder(3, false), Decoder(3, true), false),
        up("dec_conv3a", Decoder(3, true), Pool2, Decoder(2, false)),
        step("dec_conv3b", Decoder(2, false), Decoder(2, true), false),
        up("dec_conv2a", Decoder(2, true), Pool1, Decoder(1, false)),
        step("dec_conv2b", Decoder(1, false), Decoder(1, true), false),
        up("dec_conv1a", Decoder(1, true), Input, Full2),
        step("dec_conv1b", Full2, Full1, false),
    ]
};

/// `encoder`, then [`DECODER`], then `last`: `N` steps.
const fn network<const N: usize>(encoder: &[Step], last: Step) -> [Step; N] {
    assert!(encoder.len() + DECODER.len() + 1 == N);
    let mut out = [last; N];
    let mut i = 0;
    while i < encoder.len() {
        out[i] = encoder[i];
        i += 1;
    }
    while i < encoder.len() + DECODER.len() {
        out[i] = DECODER[i - encoder.len()];
        i += 1;
    }
    out
}

/// The network in execution order (OIDN's `UNet`).
pub const STEPS: [Step; 16] = {
    use Slot::*;
    network(
        &[
            step("enc_conv0", Input, Full1, false),
            step("enc_conv1", Full1, Pool1, true),
            step("enc_conv2", Pool1, Pool2, true),
            step("enc_conv3", Pool2, Pool3, true),
            step("enc_conv4", Pool3, Bottom1, true),
            step("enc_conv5a", Bottom1, Bottom2, false),
            step("enc_conv5b", Bottom2, Bottom1, false),
        ],
        step("dec_conv0", Full1, Full2, false),
    )
};

/// OIDN's `UNetLarge` in execution order. The first convolution of each encoder level below
/// the input writes the decoder's first tensor of that level, free until the decoder runs.
pub const LARGE_STEPS: [Step; 19] = {
    use Slot::*;
    network(
        &[
            step("enc_conv1a", Input, Full1, false),
            step("enc_conv1b", Full1, Pool1, true),
            step("enc_conv2a", Pool1, Decoder(1, false), false),
            step("enc_conv2b", Decoder(1, false), Pool2, true),
            step("enc_conv3a", Pool2, Decoder(2, false), false),
            step("enc_conv3b", Decoder(2, false), Pool3, true),
            step("enc_conv4a", Pool3, Decoder(3, false), false),
            step("enc_conv4b", Decoder(3, false), Bottom1, true),
            step("enc_conv5a", Bottom1, Bottom2, false),
            step("enc_conv5b", Bottom2, Bottom1, false),
        ],
        step("dec_conv1c", Full1, Full2, false),
    )
};

/// The layer list the weights are for: `UNetLarge`'s when they hold its first convolution.
pub fn steps_for(weights: &HashMap<String, Tensor>) -> &'static [Step] {
    if weights.contains_key("enc_conv1a.weight") {
        &LARGE_STEPS
    } else {
        &STEPS
    }
}

/// The slot holding the network's output (channels 0-2).
pub const OUTPUT: Slot = Slot::Full2;

/// One convolution's weights on the device.
struct Layer {
    step: Step,
    /// Channels of src0 and src1 as the weights expect them.
    c0: usize,
    c1: usize,
    /// Output channels, padded to the kernels' block.
    out_channels: usize,
    weights: Buffer<f32>,
    bias: Buffer<f32>,
}

/// The network's weights on the device and, once an image size is known, its tensors.
pub struct Network {
    layers: Vec<Layer>,
    /// Channels of the input slot: 9 for the denoising networks, 3 for the guide prefilters.
    input_channels: usize,
    /// Channels each slot holds at most (padded), by slot.
    channels: Vec<(Slot, usize)>,
    tensors: Option<Tensors>,
}

/// The tensors for one tile size.
struct Tensors {
    width: usize,
    height: usize,
    buffers: Vec<(Slot, Buffer<f32>)>,
}

/// Floats a slot's tensor takes at `width` x `height` (the level's size) with `channels`: the
/// bordered planes and what a block's reads may take past the last one (rows of a partial
/// block of four, a vector of 16 past a row's end).
pub fn tensor_len(width: usize, height: usize, channels: usize) -> usize {
    (width + 2) * (height + 2) * channels + (width + 2) * 6 + 32
}

/// Blocks `oihw` weights as the convolution kernel reads them: `[o / ocb][i][tap][o % ocb]`,
/// the output channels padded with zeros to a multiple of `ocb`.
pub fn block_weights(w: &Tensor, ocb: usize) -> Vec<f32> {
    let (o, i) = (w.dims[0], w.dims[1]);
    let op = o.next_multiple_of(ocb);
    let mut out = vec![0.0; op * i * 9];
    for oc in 0..o {
        for ic in 0..i {
            for t in 0..9 {
                let (b, k) = (oc / ocb, oc % ocb);
                out[((b * i + ic) * 9 + t) * ocb + k] = w.values[(oc * i + ic) * 9 + t];
            }
        }
    }
    out
}

impl Network {
    /// Loads the archive's tensors onto the device, checking that each layer's shape chains
    /// with the layers it reads.
    pub fn new(
        device: &Device,
        kernels: &DenoiseKernels,
        weights: &HashMap<String, Tensor>,
    ) -> Result<Self, String> {
        let ocb = kernels.ocb;
        let steps = steps_for(weights);
        let first = format!("{}.weight", steps[0].name);
        let input_channels = match weights.get(&first).map(|w| w.dims.as_slice()) {
            Some(&[_, c, ..]) => c,
            _ => return Err(format!("the weights have no tensor '{first}'")),
        };
        // Real (unpadded) output channels of each slot's last writer, as a reader sees them.
        let mut produced: Vec<(Slot, usize)> = vec![(Slot::Input, input_channels)];
        let mut channels: Vec<(Slot, usize)> = vec![(Slot::Input, input_channels)];
        let mut layers = Vec::new();
        for &s in steps {
            let get = |suffix: &str| {
                let name = format!("{}.{suffix}", s.name);
                weights
                    .get(&name)
                    .ok_or_else(|| format!("the weights have no tensor '{name}'"))
            };
            let (w, b) = (get("weight")?, get("bias")?);
            let real = |slot: Slot| {
                produced
                    .iter()
                    .rev()
                    .find(|(s, _)| *s == slot)
                    .map(|&(_, c)| c)
                    .unwrap_or(0)
            };
            let c0 = real(s.src0);
            let c1 = s.src1.map_or(0, real);
            if w.layout != "oihw" || w.dims.len() != 4 || w.dims[2..] != [3, 3] {
                return Err(format!("{}.weight is not 3x3 oihw: {:?}", s.name, w.dims));
            }
            if w.dims[1] != c0 + c1 {
                return Err(format!(
                    "{}.weight takes {} input channels; its inputs have {}",
                    s.name,
                    w.dims[1],
                    c0 + c1
                ));
            }
            let o = w.dims[0];
            if b.values.len() != o {
                return Err(format!(
                    "{}.bias has {} values, not {o}",
                    s.name,
                    b.values.len()
                ));
            }
            let out_channels = o.next_multiple_of(ocb);
            let mut bias = b.values.clone();
            bias.resize(out_channels, 0.0);
            let cl = |e: ClError| e.to_string();
            layers.push(Layer {
                step: s,
                c0,
                c1,
                out_channels,
                weights: Buffer::from_slice(device, &block_weights(w, ocb)).map_err(cl)?,
                bias: Buffer::from_slice(device, &bias).map_err(cl)?,
            });
            produced.push((s.dst, o));
            match channels.iter_mut().find(|(slot, _)| *slot == s.dst) {
                Some((_, c)) => *c = (*c).max(out_channels),
                None => channels.push((s.dst, out_channels)),
            }
        }
        if layers.last().map(|l| l.step.dst) != Some(OUTPUT)
            || produced.last().map(|p| p.1) != Some(3)
        {
            return Err("the network's last layer does not output 3 channels".into());
        }
        Ok(Self {
            layers,
            input_channels,
            channels,
            tensors: None,
        })
    }

    /// Channels of the input tensor the weights expect.
    pub fn input_channels(&self) -> usize {
        self.input_channels
    }

    /// Device bytes the tensors take for a `width` x `height` tile.
    pub fn tensor_bytes(&self, width: usize, height: usize) -> usize {
        self.channels
            .iter()
            .map(|&(slot, c)| {
                let l = slot.level();
                tensor_len(width >> l, height >> l, c) * 4
            })
            .sum()
    }

    /// Allocates (and clears, which zeroes the borders) the tensors for a `width` x `height`
    /// tile, unless they are there.
    pub fn prepare(&mut self, device: &Device, width: usize, height: usize) -> Result<(), ClError> {
        if self
            .tensors
            .as_ref()
            .is_some_and(|t| t.width == width && t.height == height)
        {
            return Ok(());
        }
        self.tensors = None;
        let mut buffers = Vec::new();
        for &(slot, c) in &self.channels {
            let l = slot.level();
            let mut b = Buffer::new(device, tensor_len(width >> l, height >> l, c))?;
            b.clear(device)?;
            buffers.push((slot, b));
        }
        self.tensors = Some(Tensors {
            width,
            height,
            buffers,
        });
        Ok(())
    }

    /// The tensor of a slot (after [`Network::prepare`]).
    pub fn tensor(&self, slot: Slot) -> &Buffer<f32> {
        let t = self.tensors.as_ref().expect("tensors prepared");
        &t.buffers.iter().find(|(s, _)| *s == slot).expect("slot").1
    }

    /// Runs every convolution on the prepared input tensor; returns their launches.
    pub fn run(
        &self,
        device: &Device,
        kernels: &DenoiseKernels,
    ) -> Result<Vec<crate::cl::Launch>, ClError> {
        let t = self.tensors.as_ref().expect("tensors prepared");
        let mut launches = Vec::with_capacity(self.layers.len());
        for layer in &self.layers {
            let s = layer.step;
            // The convolution runs at its output's resolution before pooling.
            let level = s.dst.level() - u32::from(s.pool);
            launches.push(kernels.conv(
                device,
                &ConvArgs {
                    src0: self.tensor(s.src0),
                    c0: layer.c0,
                    up0: s.up0,
                    src1: s.src1.map(|slot| (self.tensor(slot), layer.c1)),
                    weights: &layer.weights,
                    bias: &layer.bias,
                    dst: self.tensor(s.dst),
                    out_channels: layer.out_channels,
                    width: t.width >> level,
                    height: t.height >> level,
                    pool: s.pool,
                },
            )?);
        }
        Ok(launches)
    }

    /// Multiply-adds of one run over a `width` x `height` tile, times two (FLOP).
    pub fn flops(&self, width: usize, height: usize) -> f64 {
        self.layers
            .iter()
            .map(|l| {
                let level = l.step.dst.level() - u32::from(l.step.pool);
                let px = (width >> level) * (height >> level);
                2.0 * 9.0 * (l.c0 + l.c1) as f64 * l.out_channels as f64 * px as f64
            })
            .sum()
    }
}

/// A host reference of the network's layer kinds on plain CHW tensors (no border), for the
/// device tests.
#[cfg(test)]
pub(crate) mod reference {
    use super::*;

    /// A tensor of `c` planes of `w` x `h`.
    #[derive(Clone, Debug)]
    pub struct Planes {
        pub c: usize,
        pub w: usize,
        pub h: usize,
        pub v: Vec<f32>,
    }

    impl Planes {
        pub fn at(&self, c: usize, x: isize, y: isize) -> f32 {
            if x < 0 || y < 0 || x >= self.w as isize || y >= self.h as isize {
                0.0
            } else {
                self.v[(c * self.h + y as usize) * self.w + x as usize]
            }
        }

        /// The device layout: bordered planes plus the slack rows.
        pub fn bordered(&self, channels: usize) -> Vec<f32> {
            let mut out = vec![0.0; tensor_len(self.w, self.h, channels)];
            let (pw, plane) = (self.w + 2, (self.w + 2) * (self.h + 2));
            for c in 0..self.c {
                for y in 0..self.h {
                    for x in 0..self.w {
                        out[c * plane + (y + 1) * pw + x + 1] =
                            self.v[(c * self.h + y) * self.w + x];
                    }
                }
            }
            out
        }

        /// The first `c` planes of a device tensor of `w` x `h`.
        pub fn from_bordered(d: &[f32], c: usize, w: usize, h: usize) -> Self {
            let (pw, plane) = (w + 2, (w + 2) * (h + 2));
            let mut v = Vec::with_capacity(c * w * h);
            for ch in 0..c {
                for y in 0..h {
                    for x in 0..w {
                        v.push(d[ch * plane + (y + 1) * pw + x + 1]);
                    }
                }
            }
            Self { c, w, h, v }
        }
    }

    /// relu(conv3x3(src) + bias), zero-padded.
    pub fn conv(src: &Planes, w: &Tensor, b: &[f32]) -> Planes {
        let (o, i) = (w.dims[0], w.dims[1]);
        assert_eq!(i, src.c);
        let mut v = vec![0.0; o * src.w * src.h];
        for oc in 0..o {
            for y in 0..src.h {
                for x in 0..src.w {
                    let mut acc = b[oc];
                    for ic in 0..i {
                        for t in 0..9 {
                            let (dx, dy) = ((t % 3) as isize - 1, (t / 3) as isize - 1);
                            acc += w.values[(oc * i + ic) * 9 + t]
                                * src.at(ic, x as isize + dx, y as isize + dy);
                        }
                    }
                    v[(oc * src.h + y) * src.w + x] = acc.max(0.0);
                }
            }
        }
        Planes {
            c: o,
            w: src.w,
            h: src.h,
            v,
        }
    }

    pub fn pool(src: &Planes) -> Planes {
        let (w, h) = (src.w / 2, src.h / 2);
        let mut v = Vec::with_capacity(src.c * w * h);
        for c in 0..src.c {
            for y in 0..h {
                for x in 0..w {
                    let (x2, y2) = (2 * x as isize, 2 * y as isize);
                    v.push(
                        src.at(c, x2, y2)
                            .max(src.at(c, x2 + 1, y2))
                            .max(src.at(c, x2, y2 + 1))
                            .max(src.at(c, x2 + 1, y2 + 1)),
                    );
                }
            }
        }
        Planes { c: src.c, w, h, v }
    }

    pub fn upsample(src: &Planes) -> Planes {
        let (w, h) = (src.w * 2, src.h * 2);
        let mut v = Vec::with_capacity(src.c * w * h);
        for c in 0..src.c {
            for y in 0..h {
                for x in 0..w {
                    v.push(src.at(c, (x / 2) as isize, (y / 2) as isize));
                }
            }
        }
        Planes { c: src.c, w, h, v }
    }

    pub fn concat(a: &Planes, b: &Planes) -> Planes {
        assert_eq!((a.w, a.h), (b.w, b.h));
        let mut v = a.v.clone();
        v.extend_from_slice(&b.v);
        Planes {
            c: a.c + b.c,
            w: a.w,
            h: a.h,
            v,
        }
    }

    /// The whole network on a prepared input.
    pub fn network(input: &Planes, weights: &HashMap<String, Tensor>) -> Planes {
        let mut slots: Vec<(Slot, Planes)> = vec![(Slot::Input, input.clone())];
        for &s in steps_for(weights) {
            let get = |slot: Slot| {
                slots
                    .iter()
                    .rev()
                    .find(|(x, _)| *x == slot)
                    .unwrap()
                    .1
                    .clone()
            };
            let mut x = get(s.src0);
            if s.up0 {
                x = upsample(&x);
            }
            if let Some(skip) = s.src1 {
                x = concat(&x, &get(skip));
            }
            let w = &weights[&format!("{}.weight", s.name)];
            let b = &weights[&format!("{}.bias", s.name)].values;
            let mut y = conv(&x, w, b);
            if s.pool {
                y = pool(&y);
            }
            slots.push((s.dst, y));
        }
        slots.pop().unwrap().1
    }
}

#[cfg(test)]
mod tests {
    use super::reference::*;
    use super::*;
    use crate::cl::DeviceChoice;

    /// A deterministic pseudo-random value in [-1, 1).
    fn noise(i: usize, seed: u32) -> f32 {
        let mut x = (i as u32).wrapping_mul(0x9E37_79B9) ^ seed.wrapping_mul(0x85EB_CA6B);
        x ^= x >> 16;
        x = x.wrapping_mul(0x7FEB_352D);
        x ^= x >> 15;
        (x >> 8) as f32 / (1u32 << 23) as f32 - 1.0
    }

    fn planes(c: usize, w: usize, h: usize, seed: u32) -> Planes {
        Planes {
            c,
            w,
            h,
            v: (0..c * w * h).map(|i| noise(i, seed)).collect(),
        }
    }

    fn tensor(o: usize, i: usize, seed: u32) -> (Tensor, Vec<f32>) {
        let w = Tensor {
            dims: vec![o, i, 3, 3],
            layout: "oihw".into(),
            values: (0..o * i * 9).map(|k| noise(k, seed) * 0.3).collect(),
        };
        (w, (0..o).map(|k| noise(k, seed + 1) * 0.1).collect())
    }

    fn device() -> Device {
        let choice = std::env::var("PENUMBRA_TEST_DEVICE").unwrap_or_else(|_| "cpu".into());
        Device::open(&choice.parse::<DeviceChoice>().expect("device")).expect("an OpenCL device")
    }

    fn assert_close(got: &Planes, want: &Planes, what: &str) {
        assert_eq!((got.c, got.w, got.h), (want.c, want.w, want.h), "{what}");
        for (k, (g, w)) in got.v.iter().zip(&want.v).enumerate() {
            assert!(
                (g - w).abs() <= 1e-4 * (1.0 + w.abs()),
                "{what}: value {k}: {g} vs {w}"
            );
        }
    }

    /// Runs one convolution on the device: `src0` (upsampled when `up0`) and `src1`
    /// concatenated, `o` outputs, pooled when `pool`.
    fn device_conv(
        src0: &Planes,
        up0: bool,
        src1: Option<&Planes>,
        o: usize,
        pool: bool,
    ) -> (Planes, Planes) {
        let device = device();
        let k = DenoiseKernels::build(&device).expect("kernels");
        let c1 = src1.map_or(0, |s| s.c);
        let (w, b) = tensor(o, src0.c + c1, 7);
        let (width, height) = if up0 {
            (src0.w * 2, src0.h * 2)
        } else {
            (src0.w, src0.h)
        };
        let op = o.next_multiple_of(k.ocb);
        let mut bias = b.clone();
        bias.resize(op, 0.0);
        let buf = |v: &[f32]| Buffer::from_slice(&device, v).unwrap();
        let s0 = buf(&src0.bordered(src0.c));
        let s1 = src1.map(|s| buf(&s.bordered(s.c)));
        let (ow, oh) = if pool {
            (width / 2, height / 2)
        } else {
            (width, height)
        };
        let dst = buf(&vec![0.0; tensor_len(ow, oh, op)]);
        let (wb, bb) = (buf(&block_weights(&w, k.ocb)), buf(&bias));
        k.conv(
            &device,
            &ConvArgs {
                src0: &s0,
                c0: src0.c,
                up0,
                src1: s1.as_ref().map(|s| (s, c1)),
                weights: &wb,
                bias: &bb,
                dst: &dst,
                out_channels: op,
                width,
                height,
                pool,
            },
        )
        .expect("conv");
        let got = Planes::from_bordered(&dst.read(&device).unwrap(), o, ow, oh);
        let mut x = if up0 { upsample(src0) } else { src0.clone() };
        if let Some(s) = src1 {
            x = concat(&x, s);
        }
        let mut want = conv(&x, &w, &b);
        if pool {
            want = pool_ref(&want);
        }
        (got, want)
    }

    fn pool_ref(p: &Planes) -> Planes {
        super::reference::pool(p)
    }

    #[test]
    fn a_convolution_matches_the_host_at_odd_sizes() {
        // 70 columns: more than one work-group; 13 rows: a partial block of four.
        let (got, want) = device_conv(&planes(9, 70, 13, 1), false, None, 8, false);
        assert_close(&got, &want, "conv");
    }

    #[test]
    fn a_pooled_convolution_matches_conv_then_max_pool() {
        let (got, want) = device_conv(&planes(12, 36, 18, 2), false, None, 16, true);
        assert_close(&got, &want, "conv + pool");
    }

    #[test]
    fn upsampling_and_concatenation_match_the_host() {
        // 3 outputs: padded to the kernels' block like the network's last layer.
        let skip = planes(5, 22, 14, 4);
        let (got, want) = device_conv(&planes(6, 11, 7, 3), true, Some(&skip), 3, false);
        assert_close(&got, &want, "upsample + concat + conv");
    }
}
