//! The denoiser's input preparation as Open Image Denoise does it for HDR colour with albedo and
//! normal (its `UNetFilter`, `Autoexposure` and `PUTransferFunction`): the exposure, the
//! perceptually uniform transfer curve, and the tiling of large images with overlap. The
//! kernels in kernels/denoise/prepare.cl apply the per-pixel parts; this is their host side.
// The PU curve's constants are OIDN's as it writes them, with more digits than an f32 holds.
#![allow(clippy::excessive_precision)]

/// OIDN's autoexposure: the log-average luminance of blocks of at most this many pixels a side.
pub const EXPOSURE_BIN: usize = 16;

/// The log-average the exposure maps to (Reinhard's key).
const EXPOSURE_KEY: f32 = 0.18;

/// Blocks darker than this do not count towards the exposure.
const EXPOSURE_EPS: f32 = 1e-8;

/// Tiles are multiples of this (the U-Net pools four times).
pub const TILE_ALIGNMENT: usize = 16;

/// The U-Net's receptive field in pixels (OIDN's `receptiveField`).
const RECEPTIVE_FIELD: usize = 174;

/// Pixels each tile shares with its neighbours on each side: half the receptive field, rounded
/// up to the alignment (96), as OIDN overlaps its tiles.
pub const TILE_OVERLAP: usize = (RECEPTIVE_FIELD / 2).div_ceil(TILE_ALIGNMENT) * TILE_ALIGNMENT;

/// The largest value of half floats, which the PU curve maps to 1.
const HDR_Y_MAX: f32 = 65504.0;

const PU_A: f32 = 1.41283765e+03;
const PU_B: f32 = 1.64593172e+00;
const PU_C: f32 = 4.31384981e-01;
const PU_D: f32 = -2.94139609e-03;
const PU_E: f32 = 1.92653254e-01;
const PU_F: f32 = 6.26026094e-03;
const PU_G: f32 = 9.98620152e-01;
const PU_Y0: f32 = 1.57945760e-06;
const PU_Y1: f32 = 3.22087631e-02;
const PU_X0: f32 = 2.23151711e-03;
const PU_X1: f32 = 3.70974749e-01;

/// The PU curve before normalisation (kernels/denoise/transfer.h's `pu_forward`).
pub fn pu_forward(y: f32) -> f32 {
    if y <= PU_Y0 {
        PU_A * y
    } else if y <= PU_Y1 {
        PU_B * y.powf(PU_C) + PU_D
    } else {
        PU_E * (y + PU_F).ln() + PU_G
    }
}

/// The inverse of [`pu_forward`].
pub fn pu_inverse(x: f32) -> f32 {
    if x <= PU_X0 {
        x / PU_A
    } else if x <= PU_X1 {
        ((x - PU_D) / PU_B).powf(1.0 / PU_C)
    } else {
        ((x - PU_G) / PU_E).exp() - PU_F
    }
}

/// `pu_forward(65504)`: the encoded value of the largest half, which the network sees as 1.
pub fn pu_max() -> f32 {
    pu_forward(HDR_Y_MAX)
}

/// OIDN's blocks of the autoexposure: (across, down).
pub fn exposure_bins(width: usize, height: usize) -> (usize, usize) {
    (width.div_ceil(EXPOSURE_BIN), height.div_ceil(EXPOSURE_BIN))
}

/// The exposure from the blocks' mean luminances: `0.18 / 2^mean(log2 L)` over the blocks
/// brighter than 1e-8, or 1 when none is.
pub fn exposure_from_bins(bins: &[f32]) -> f32 {
    let (sum, count) = bins
        .iter()
        .filter(|&&l| l > EXPOSURE_EPS)
        .fold((0.0f32, 0u32), |(s, n), &l| (s + l.log2(), n + 1));
    if count == 0 {
        1.0
    } else {
        EXPOSURE_KEY / (sum / count as f32).exp2()
    }
}

/// How an image is cut into tiles: OIDN's rule, with its alignment and overlap.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tiling {
    /// The tile buffer's width (a multiple of 16, overlap included).
    pub tile_w: usize,
    /// The tile buffer's height.
    pub tile_h: usize,
    /// Tiles across.
    pub across: usize,
    /// Tiles down.
    pub down: usize,
}

/// One tile: the image region the network reads (`input`) and the region of its output that
/// is kept (`output`, the input less the overlap shared with neighbours).
pub type TileWindow = crate::cl::kernels::TileWindow;

impl Tiling {
    /// The tiling of a `width` x `height` image whose tiles hold at most `max_pixels`: one tile
    /// when it fits, else the longer side split further until it does (never below three
    /// overlaps a side), as OIDN's `UNetFilter::init` does.
    pub fn new(width: usize, height: usize, max_pixels: usize) -> Self {
        let (o, a) = (TILE_OVERLAP, TILE_ALIGNMENT);
        let min_dim = 3 * o;
        let (mut count_w, mut count_h) = (1usize, 1usize);
        let mut tile_h = height.max(1).next_multiple_of(a);
        let mut tile_w = width.max(1).next_multiple_of(a);
        // The tile size when `size` is cut into `count` tiles that overlap.
        let split = |size: usize, count: usize| {
            (size
                .saturating_sub(2 * o)
                .div_ceil(count)
                .next_multiple_of(a)
                + 2 * o)
                .max(min_dim)
        };
        while tile_w * tile_h > max_pixels {
            if tile_h > min_dim && tile_h > tile_w {
                count_h += 1;
                tile_h = split(height, count_h);
            } else if tile_w > min_dim {
                count_w += 1;
                tile_w = split(width, count_w);
            } else {
                break;
            }
        }
        let count = |size: usize, tile: usize| {
            if size > tile {
                (size - 2 * o).div_ceil(tile - 2 * o)
            } else {
                1
            }
        };
        Self {
            tile_w,
            tile_h,
            across: count(width, tile_w),
            down: count(height, tile_h),
        }
    }

    /// Number of tiles.
    pub fn count(&self) -> usize {
        self.across * self.down
    }

    /// Every tile of a `width` x `height` image, row by row: (input window, output window).
    /// The image sits at the tile's bottom right where it is smaller than the tile, as in OIDN.
    pub fn windows(&self, width: usize, height: usize) -> Vec<(TileWindow, TileWindow)> {
        let o = TILE_OVERLAP;
        // One axis: (image start, tile offset, input size, kept start in the tile, kept start
        // in the image, kept size) for tile i of n.
        let axis = |i: usize, n: usize, size: usize, tile: usize| {
            let start = i * (tile - 2 * o);
            let before = if i > 0 { o } else { 0 };
            let after = if i + 1 < n { o } else { 0 };
            let len = (size - start).min(tile);
            let offset = tile - len.next_multiple_of(TILE_ALIGNMENT);
            (
                start,
                offset,
                len,
                offset + before,
                start + before,
                len - before - after,
            )
        };
        let mut out = Vec::with_capacity(self.count());
        for j in 0..self.down {
            let (iy, ty, h, ky, ny, kh) = axis(j, self.down, height, self.tile_h);
            for i in 0..self.across {
                let (ix, tx, w, kx, nx, kw) = axis(i, self.across, width, self.tile_w);
                let base = TileWindow {
                    tile_w: self.tile_w,
                    tile_h: self.tile_h,
                    image_x: ix,
                    image_y: iy,
                    tile_x: tx,
                    tile_y: ty,
                    w,
                    h,
                };
                let kept = TileWindow {
                    image_x: nx,
                    image_y: ny,
                    tile_x: kx,
                    tile_y: ky,
                    w: kw,
                    h: kh,
                    ..base
                };
                out.push((base, kept));
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::tonemap::{srgb_decode, srgb_encode};

    #[test]
    fn the_srgb_curve_round_trips_and_meets_itself_at_the_knee() {
        for y in [0.0, 1e-3, 0.0031308, 0.01, 0.18, 0.5, 1.0] {
            let back = srgb_decode(srgb_encode(y));
            assert!((back - y).abs() <= 1e-5, "{y} -> {back}");
        }
        // Middle grey encodes to about 0.46, and the two pieces meet at the knee.
        assert!((srgb_encode(0.18) - 0.4614).abs() < 1e-3);
        let knee = 0.0031308f32;
        assert!((12.92 * knee - (1.055 * knee.powf(1.0 / 2.4) - 0.055)).abs() < 1e-6);
    }

    #[test]
    fn the_pu_curve_round_trips_and_is_normalised() {
        // OIDN's normalisation scale, 0.318967163, is its reciprocal.
        assert!((pu_max() * 0.318_967_16 - 1.0).abs() < 1e-6, "{}", pu_max());
        for y in [0.0, 1e-7, 1e-3, 0.0322, 0.5, 1.0, 10.0, 1000.0, 65504.0] {
            let back = pu_inverse(pu_forward(y));
            assert!((back - y).abs() <= 1e-4 * y.max(1e-3), "{y} -> {back}");
        }
        // Monotone across both breakpoints.
        let mut last = -1.0;
        for i in 0..2000 {
            let x = pu_forward(i as f32 * 1e-4);
            assert!(x > last);
            last = x;
        }
    }

    #[test]
    fn the_exposure_maps_the_log_average_to_the_key() {
        assert_eq!(exposure_from_bins(&[0.0, 0.0]), 1.0);
        // log2 average of 0.5 and 2 is 0: the exposure is the key itself.
        assert!((exposure_from_bins(&[0.5, 2.0, 0.0]) - 0.18).abs() < 1e-6);
        assert_eq!(exposure_bins(33, 16), (3, 1));
    }

    #[test]
    fn a_small_image_is_one_aligned_tile() {
        let t = Tiling::new(100, 50, usize::MAX);
        assert_eq!((t.tile_w, t.tile_h, t.count()), (112, 64, 1));
        let w = t.windows(100, 50);
        assert_eq!(w.len(), 1);
        let (input, kept) = w[0];
        assert_eq!(
            (input.tile_x, input.tile_y, input.w, input.h),
            (0, 0, 100, 50)
        );
        assert_eq!(input, kept);
    }

    #[test]
    fn tiles_cover_the_image_once_with_their_overlap_read() {
        let (w, h) = (1000, 700);
        let t = Tiling::new(w, h, 400 * 400);
        assert!(t.count() > 1);
        assert!(t.tile_w * t.tile_h <= 400 * 400, "{t:?}");
        let mut covered = vec![0u8; w * h];
        for (input, kept) in t.windows(w, h) {
            assert!(input.tile_x + input.w <= t.tile_w && input.tile_y + input.h <= t.tile_h);
            // The kept region lies inside the input with at least the overlap around it,
            // except at the image's edges.
            assert!(kept.image_x >= input.image_x && kept.image_y >= input.image_y);
            if kept.image_x > 0 {
                assert_eq!(kept.image_x - input.image_x, TILE_OVERLAP);
            }
            assert_eq!(kept.tile_x - input.tile_x, kept.image_x - input.image_x);
            for y in kept.image_y..kept.image_y + kept.h {
                for x in kept.image_x..kept.image_x + kept.w {
                    covered[y * w + x] += 1;
                }
            }
        }
        assert!(covered.iter().all(|&c| c == 1));
    }
}
