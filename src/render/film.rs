//! The film as the host reads it: per pixel the sum of its samples' radiance in 64-bit fixed
//! point and their count (kernels/shared/film.h), and the image made from it. Integer sums are
//! associative, so films of disjoint sample ranges add up to the film of all of them bit for bit
//! (shards: `crate::shard`).

use crate::cl::types::FILM_FRACTION_BITS;

/// A pixel of the film: the red, green and blue sums in fixed point, then the count.
pub type FilmPixel = [u64; 4];

/// One radiance unit in the film's fixed point.
const FILM_ONE: f64 = (1u64 << FILM_FRACTION_BITS) as f64;

/// The pixel as the kernels' `film_float` reads it: the sums in radiance units and the count.
pub fn as_float(p: FilmPixel) -> [f32; 4] {
    let one = FILM_ONE as f32;
    [
        p[0] as f32 / one,
        p[1] as f32 / one,
        p[2] as f32 / one,
        p[3] as f32,
    ]
}

/// `b` added to `a`, lane by lane, saturating as the kernels' sums do.
pub fn add(a: FilmPixel, b: FilmPixel) -> FilmPixel {
    std::array::from_fn(|c| a[c].saturating_add(b[c]))
}

/// Adds the film `b` to the film `a`, pixel by pixel ([`add`]): the film of both's samples.
pub fn add_films(a: &mut [FilmPixel], b: &[FilmPixel]) {
    for (p, q) in a.iter_mut().zip(b) {
        *p = add(*p, *q);
    }
}

/// The image (each pixel's mean, linear RGB) into `image` and, when asked, each pixel's coverage
/// into `coverage`, from the film. `taken(i)` is the number of samples pixel `i` took. With
/// `counted`, a pixel's count is the samples whose camera ray hit: the mean is over all samples
/// taken and the coverage is the hits' share; otherwise the count is the samples and the
/// coverage 1.
pub fn image_into(
    film: &[FilmPixel],
    counted: bool,
    taken: impl Fn(usize) -> f64,
    image: &mut Vec<[f32; 3]>,
    coverage: Option<&mut Vec<f32>>,
) {
    let mean = |p: &FilmPixel, n: f64| {
        let n = n.max(1.0);
        [0, 1, 2].map(|c| (p[c] as f64 / FILM_ONE / n) as f32)
    };
    image.clear();
    if counted {
        image.extend(film.iter().enumerate().map(|(i, p)| mean(p, taken(i))));
    } else {
        image.extend(film.iter().map(|p| mean(p, p[3] as f64)));
    }
    if let Some(coverage) = coverage {
        coverage.clear();
        if counted {
            coverage.extend(
                film.iter()
                    .enumerate()
                    .map(|(i, p)| (p[3] as f64 / taken(i).max(1.0)).clamp(0.0, 1.0) as f32),
            );
        } else {
            coverage.resize(film.len(), 1.0);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_mean_is_the_sum_over_the_count() {
        let one = 1u64 << FILM_FRACTION_BITS;
        let film = [[3 * one, one / 2, 0, 2]];
        let mut image = Vec::new();
        let mut coverage = Vec::new();
        image_into(&film, false, |_| 4.0, &mut image, Some(&mut coverage));
        assert_eq!(image, vec![[1.5, 0.25, 0.0]]);
        assert_eq!(coverage, vec![1.0]);
        // Counted: the count is the hits, 2 of 4 samples.
        image_into(&film, true, |_| 4.0, &mut image, Some(&mut coverage));
        assert_eq!(image, vec![[0.75, 0.125, 0.0]]);
        assert_eq!(coverage, vec![0.5]);
        assert_eq!(as_float(film[0]), [3.0, 0.5, 0.0, 2.0]);
    }

    #[test]
    fn sums_saturate_instead_of_wrapping() {
        assert_eq!(
            add([u64::MAX - 1, 1, 2, 3], [5, 1, 2, 3]),
            [u64::MAX, 2, 4, 6]
        );
    }
}
