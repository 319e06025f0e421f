//! Where the image goes in the window: beside the overlay's side panel, never under it. The
//! film is rendered at the size of the area right of the panel (so its aspect is the area's and
//! nothing is letterboxed), and the window's frame buffer is composed on the CPU: the panel's
//! strip, then the film scaled (nearest) into the area, which it fills exactly at full
//! resolution and by whole-pixel blocks while the camera moves at a reduced one.

/// The side panel's width in points (at most: see [`panel_points`]).
pub const PANEL_WIDTH: f32 = 300.0;
/// The panel never takes more than this share of the window's width.
const PANEL_SHARE: f32 = 0.45;
/// Squares of the checkerboard shown behind transparent pixels, in pixels.
const CHECKER: u32 = 8;

/// The side panel's width in points for a window `window_width` points wide: fixed, so that
/// it never grows while the overlay is edited.
pub fn panel_points(window_width: f32) -> f32 {
    PANEL_WIDTH
        .min((PANEL_SHARE * window_width).floor())
        .max(0.0)
}

/// The image's rectangle in the window, in physical pixels; it spans the window's height.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ImageArea {
    /// Left edge (the panel's width, 0 without the overlay).
    pub left: u32,
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
}

impl ImageArea {
    /// The area right of a panel `panel` pixels wide in a window of `window` pixels.
    pub fn new(window: (u32, u32), panel: u32) -> Self {
        let left = panel.min(window.0.saturating_sub(1));
        Self {
            left,
            width: (window.0 - left).max(1),
            height: window.1.max(1),
        }
    }

    /// The film size that fills it.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Width over height.
    pub fn aspect(&self) -> f32 {
        self.width as f32 / self.height as f32
    }

    /// A window position as a position in the image, both in [0, 1); `None` outside it.
    pub fn image_position(self, x: f64, y: f64) -> Option<(f32, f32)> {
        let u = (x - self.left as f64) / self.width as f64;
        let v = y / self.height as f64;
        ((0.0..1.0).contains(&u) && (0.0..1.0).contains(&v)).then_some((u as f32, v as f32))
    }
}

/// Draws `image` (RGBA8, `size`) scaled to fill `area` of `frame` (RGBA8, `window`), over a
/// checkerboard where it is transparent, and paints the rest of the frame dark grey.
pub fn compose(
    frame: &mut [u8],
    window: (u32, u32),
    area: ImageArea,
    image: &[u8],
    size: (u32, u32),
) {
    let (ww, wh) = (window.0 as usize, window.1 as usize);
    if frame.len() != ww * wh * 4 || image.len() != (size.0 * size.1 * 4) as usize {
        return;
    }
    let (iw, ih) = (size.0.max(1) as usize, size.1.max(1) as usize);
    let (left, aw, ah) = (
        area.left as usize,
        area.width as usize,
        area.height as usize,
    );
    // Source column of each area column.
    let columns: Vec<usize> = (0..aw.min(ww.saturating_sub(left)))
        .map(|x| (x * iw / aw).min(iw - 1))
        .collect();
    for (y, row) in frame.chunks_exact_mut(ww * 4).enumerate() {
        row[..left.min(ww) * 4]
            .chunks_exact_mut(4)
            .for_each(|p| p.copy_from_slice(&[27, 27, 27, 255]));
        if y >= ah {
            continue;
        }
        let src = &image[(y * ih / ah).min(ih - 1) * iw * 4..][..iw * 4];
        for (x, &sx) in columns.iter().enumerate() {
            let s = &src[sx * 4..sx * 4 + 4];
            let d = &mut row[(left + x) * 4..(left + x) * 4 + 4];
            if s[3] == 255 {
                d.copy_from_slice(s);
            } else {
                let light = ((x as u32 / CHECKER) + (y as u32 / CHECKER)).is_multiple_of(2);
                let check = if light { 160u32 } else { 110 };
                let a = s[3] as u32;
                for i in 0..3 {
                    d[i] = ((s[i] as u32 * a + check * (255 - a) + 127) / 255) as u8;
                }
                d[3] = 255;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_panel_has_a_fixed_width_and_the_image_the_rest() {
        assert_eq!(panel_points(960.0), PANEL_WIDTH);
        assert_eq!(panel_points(1920.0), PANEL_WIDTH);
        assert_eq!(panel_points(320.0), 144.0);
        let a = ImageArea::new((960, 600), 300);
        assert_eq!((a.left, a.size()), (300, (660, 600)));
        assert_eq!(ImageArea::new((960, 600), 0).size(), (960, 600));
        assert_eq!(a.image_position(299.0, 10.0), None);
        assert_eq!(a.image_position(300.0, 0.0), Some((0.0, 0.0)));
        assert_eq!(a.image_position(630.0, 300.0), Some((0.5, 0.5)));
    }

    #[test]
    fn compose_fills_the_area_exactly_beside_the_panel() {
        let window = (6, 2);
        let area = ImageArea::new(window, 2);
        // A 4×2 image at full size, then a 2×1 one (moving, half resolution) scaled up.
        let full: Vec<u8> = (0..8u8).flat_map(|i| [i, i, i, 255]).collect();
        let mut frame = vec![0u8; 6 * 2 * 4];
        compose(&mut frame, window, area, &full, (4, 2));
        let grey = |f: &[u8], x: usize, y: usize| f[(y * 6 + x) * 4];
        assert_eq!(grey(&frame, 0, 0), 27);
        assert_eq!(grey(&frame, 1, 1), 27);
        assert_eq!(
            (2..6).map(|x| grey(&frame, x, 1)).collect::<Vec<_>>(),
            [4, 5, 6, 7]
        );
        let half = [10, 10, 10, 255, 20, 20, 20, 255];
        compose(&mut frame, window, area, &half, (2, 1));
        assert_eq!(
            (2..6).map(|x| grey(&frame, x, 0)).collect::<Vec<_>>(),
            [10, 10, 20, 20]
        );
        assert_eq!(grey(&frame, 5, 1), 20);
        // A transparent pixel shows the checkerboard, opaque.
        let clear = [0u8; 8];
        compose(&mut frame, window, area, &clear, (2, 1));
        assert!(grey(&frame, 2, 0) >= 110 && frame[(2) * 4 + 3] == 255);
    }
}
