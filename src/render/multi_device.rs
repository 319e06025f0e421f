//! Several devices rendering one image (`render --device all|0,2`): each [`Renderer`] renders
//! batches of sample indices — contiguous ranges of the deterministic sequence — into its own
//! film, and the host adds the films ([`film::add_films`]). The films' sums are integers, so any
//! partition of the indices gives the same film bit for bit: the batches are claimed as the
//! devices become free (work stealing), which changes each device's share from run to run but
//! never the image.
//!
//! Each device first renders a fixed batch of its own, which measures its speed; a device
//! whose speed is under [`DROP_SHARE`] of the devices' total (measured so far) takes no more
//! batches, unless the devices were listed by hand. Later batches are sized by each device's
//! speed: about a call's time, and at most half the device's share of the samples left, so
//! that the devices finish close together.

use super::{Renderer, film};
use crate::cl::ClError;
use std::sync::Mutex;
use std::time::Instant;

/// A device whose samples per second are under this share of all the devices' stops after
/// its first batch (`--device all`): it would add little and its last batch could end after
/// the others', and on a CPU device its threads take the host's cores from the other
/// devices' drivers.
pub const DROP_SHARE: f64 = 0.1;

/// What the devices render.
#[derive(Clone, Copy, Debug)]
pub struct Plan {
    /// The index of the first sample in the sequence.
    pub start: u32,
    /// Samples per pixel in all.
    pub spp: u32,
    /// Every device keeps rendering, however slow (a list given by hand).
    pub keep_all: bool,
    /// No batch is claimed after this many seconds.
    pub time_limit: Option<f64>,
    /// The samples a pixel of a batch that takes a call's time, from a sample's seconds.
    pub call_size: fn(f64) -> u32,
}

/// One device's part of a render.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Share {
    /// Samples per pixel it rendered.
    pub samples: u32,
    /// Seconds it spent rendering them.
    pub seconds: f64,
    /// It stopped after its first batch: too slow beside the others.
    pub dropped: bool,
}

/// The samples left to claim and each device's measured speed (samples a pixel per second).
struct Pool {
    next: u32,
    end: u32,
    speeds: Vec<Option<f64>>,
    failed: bool,
}

/// Renders `plan` on `renderers` at once (each on its own thread), calls `progress` with the
/// samples a pixel done so far after each batch, and returns each device's share. The
/// renderers' films then hold disjoint sample ranges whose union is `plan.start` … on,
/// contiguous: [`film_sum`] adds them.
pub fn render(
    renderers: &mut [Renderer],
    plan: &Plan,
    progress: &(dyn Fn(u32) + Sync),
) -> Result<Vec<Share>, ClError> {
    let devices = renderers.len() as u32;
    let end = plan.start + plan.spp;
    // The first batches: fixed ranges of one sample a pixel, one a device, so each is
    // measured at the least cost: a slow device's first batch is what the others may wait
    // for at the end (on an H100 machine, 8 samples on its 16 host cores took 1.39 s of a
    // render the GPU alone finished in 0.96 s).
    let first = 1;
    let firsts: Vec<(u32, u32)> = (0..devices)
        .map(|i| {
            let from = (plan.start + i * first).min(end);
            (from, (from + first).min(end) - from)
        })
        .collect();
    let pool = Mutex::new(Pool {
        next: (plan.start + devices * first).min(end),
        end,
        speeds: vec![None; renderers.len()],
        failed: false,
    });
    let done = Mutex::new(0u32);
    let started = Instant::now();
    let report = |n: u32| {
        let mut d = done.lock().unwrap_or_else(|e| e.into_inner());
        *d += n;
        progress(*d);
    };
    std::thread::scope(|scope| {
        let workers: Vec<_> = (renderers.iter_mut().enumerate())
            .map(|(i, renderer)| {
                let (pool, report, first) = (&pool, &report, firsts[i]);
                scope.spawn(move || {
                    let result = work(renderer, i, first, pool, plan, started, report);
                    if result.is_err() {
                        pool.lock().unwrap_or_else(|e| e.into_inner()).failed = true;
                    }
                    result
                })
            })
            .collect();
        workers
            .into_iter()
            .map(|w| w.join().expect("a device's thread does not panic"))
            .collect()
    })
}

/// One device's loop: its first batch, then batches claimed from `pool` until none is left,
/// the time is up, another device failed, or it is too slow beside the others.
fn work(
    renderer: &mut Renderer,
    me: usize,
    (from, n): (u32, u32),
    pool: &Mutex<Pool>,
    plan: &Plan,
    started: Instant,
    report: &(dyn Fn(u32) + Sync),
) -> Result<Share, ClError> {
    let mut share = Share::default();
    let batch = |renderer: &mut Renderer, from: u32, n: u32, share: &mut Share| {
        let t = Instant::now();
        renderer.set_next_sample(from);
        renderer.render(n)?;
        share.samples += n;
        share.seconds += t.elapsed().as_secs_f64();
        report(n);
        Ok::<_, ClError>(f64::from(share.samples) / share.seconds.max(1e-9))
    };
    if n > 0 {
        let speed = batch(renderer, from, n, &mut share)?;
        pool.lock().unwrap_or_else(|e| e.into_inner()).speeds[me] = Some(speed);
    }
    loop {
        let (from, n) = {
            let mut p = pool.lock().unwrap_or_else(|e| e.into_inner());
            if p.failed {
                break;
            }
            let seconds_left = (plan.time_limit).map(|l| l - started.elapsed().as_secs_f64());
            match next_batch(p.end - p.next, me, &p.speeds, plan, seconds_left) {
                Next::Claim(n) => {
                    p.next += n;
                    (p.next - n, n)
                }
                Next::Drop => {
                    share.dropped = true;
                    break;
                }
                Next::Done => break,
            }
        };
        let speed = batch(renderer, from, n, &mut share)?;
        pool.lock().unwrap_or_else(|e| e.into_inner()).speeds[me] = Some(speed);
    }
    Ok(share)
}

/// What a device does when it is free.
#[derive(Debug, PartialEq)]
enum Next {
    /// Render this many samples a pixel, the next of the pool.
    Claim(u32),
    /// Stop: too slow beside the others.
    Drop,
    /// Stop: no sample left, or no time.
    Done,
}

/// The next batch of device `me`, with `left` samples a pixel in the pool, the devices'
/// measured `speeds` (samples a pixel per second) and `seconds_left` before the time limit.
fn next_batch(
    left: u32,
    me: usize,
    speeds: &[Option<f64>],
    plan: &Plan,
    seconds_left: Option<f64>,
) -> Next {
    if left == 0 || seconds_left.is_some_and(|s| s <= 0.0) {
        return Next::Done;
    }
    let total: f64 = speeds.iter().flatten().sum();
    let n = match speeds[me] {
        Some(s) if !plan.keep_all && s < DROP_SHARE * total => return Next::Drop,
        Some(s) => {
            // About a call's time, at most half this device's share of what is left, and
            // what fits in the time left.
            let own = (f64::from(left) * s / total / 2.0).ceil() as u32;
            let timed = seconds_left.map_or(u32::MAX, |t| (t * s).ceil() as u32);
            (plan.call_size)(1.0 / s).min(own).min(timed)
        }
        None => left.div_ceil(2 * speeds.len() as u32),
    };
    Next::Claim(n.clamp(1, left))
}

/// The sum of the renderers' films: the film of all their samples.
pub fn film_sum(renderers: &mut [Renderer]) -> Result<Vec<film::FilmPixel>, ClError> {
    let (first, rest) = renderers.split_first_mut().expect("at least one renderer");
    let mut sum = first.film()?;
    for r in rest {
        film::add_films(&mut sum, &r.film()?);
    }
    Ok(sum)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plan(keep_all: bool) -> Plan {
        Plan {
            start: 0,
            spp: 1000,
            keep_all,
            time_limit: None,
            // A call of 2 s.
            call_size: |seconds| (2.0 / seconds) as u32,
        }
    }

    #[test]
    fn batches_fill_a_call_and_shrink_towards_the_end() {
        let speeds = [Some(10.0), Some(10.0)];
        // 2 s at 10 samples a second.
        assert_eq!(
            next_batch(500, 0, &speeds, &plan(false), None),
            Next::Claim(20)
        );
        // Half of this device's half of 30.
        assert_eq!(
            next_batch(30, 0, &speeds, &plan(false), None),
            Next::Claim(8)
        );
        assert_eq!(
            next_batch(1, 1, &speeds, &plan(false), None),
            Next::Claim(1)
        );
        assert_eq!(next_batch(0, 1, &speeds, &plan(false), None), Next::Done);
        // Unmeasured: a quarter of what is left between two devices.
        assert_eq!(
            next_batch(10, 0, &[None, None], &plan(false), None),
            Next::Claim(3)
        );
        // Half a second left: 5 samples.
        assert_eq!(
            next_batch(500, 0, &speeds, &plan(false), Some(0.5)),
            Next::Claim(5)
        );
        assert_eq!(
            next_batch(500, 0, &speeds, &plan(false), Some(0.0)),
            Next::Done
        );
    }

    #[test]
    fn a_slow_device_drops_out_unless_listed() {
        // 1 of 31 samples a second: under a tenth.
        let speeds = [Some(30.0), Some(1.0)];
        assert_eq!(next_batch(500, 1, &speeds, &plan(false), None), Next::Drop);
        assert!(matches!(
            next_batch(500, 0, &speeds, &plan(false), None),
            Next::Claim(_)
        ));
        // Listed by hand, it keeps its share: a half of its 1/31 of 500.
        assert_eq!(
            next_batch(500, 1, &speeds, &plan(true), None),
            Next::Claim(2)
        );
        // A fifth of the total stays.
        let speeds = [Some(4.0), Some(1.0)];
        assert!(matches!(
            next_batch(500, 1, &speeds, &plan(false), None),
            Next::Claim(_)
        ));
    }
}
