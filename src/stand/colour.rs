//! The colour of the angle measurement's noise, estimated per frequency from the data.
//!
//! A real stand's angles are not white-noised: an optical reference or an encoder's interpolation
//! error puts most of its noise inside the motion's band, where a white floor read near Nyquist
//! says nothing about it, and the observer would pass it into the blocks' inputs as motion
//! (errors in variables: gains biased low where the motion is weak, a gain that varies with
//! frequency, which the order selection then "explains" with poles).
//!
//! A run with a gyro block carries a second, independent measurement of the same motion: the
//! gyro's outputs, turned into Euler rates at the measured angles
//! ([`super::kinematics::euler_rate`]), the **witness** `w` (in platform axes first when the gyro
//! is mounted turned, [`super::mount`]; [`super::witness_delay`] builds it and aligns it).
//! Per bin the part of each measured angle that no linear filter of the witness explains is
//!
//! `N_c = S_yy - S_yw S_ww^-1 S_wy`,
//!
//! with the cross-periodograms of the Hann-windowed record (the strong low-frequency motion
//! would leak through a rectangular window into the weak high-frequency bins) summed over the
//! observer's Daniell windows, the witness's transfer taken as a straight line in frequency across
//! a window where it is seen to turn within one (a gyro's sharp resonance:
//! [`super::colour_window`]), and corrected by `M / (M - p)` for the `p` regressors fitted in a
//! window of `M` equivalent samples (the window's bins times `(2n/3) / L_fft`; short of the bins'
//! correlation's count by 3-6 % of the level, said there). The witness's own misalignment and
//! dynamics are linear filters, so they do not enter as far as the attitude is steady (a gyro's
//! dynamics act per body axis, and a moving attitude modulates them on their way into the Euler
//! rates: there the witness is also split by gyro axis, [`super::colour_split`]); its bulk delay
//! is taken out (a delay turns the phase across a window); the kinematic coupling does not enter
//! either, because the witness is converted to Euler rates sample by sample with the exact
//! kinematics, at the angles one delay earlier (in a fast rotation the attitude turns within the
//! delay).
//!
//! What `N_c` also holds: the gyro's own noise as seen in angle units, `S_psi / w^2`; its white
//! floor, read near Nyquist, is taken out ([`super::witness_floor`]: behind a gyro's own filter
//! it grows as the filter cuts the signal). Where the
//! gyro's signal-to-noise ratio is high (most of a certification run's band) it is negligible;
//! where it is not, taking it as the reference's noise shrinks the input estimate by the gyro's
//! noise-to-signal ratio (gains biased high by that ratio), the mirror of the white model's
//! error. The observer uses `clamp(N_c, white floor, S_yy)` per axis and bin; with one block of
//! outputs the two noises cannot be told apart in a bin beyond the gyro's floor, and this choice
//! errs on the side the gyro's quality bounds. Where the unexplained part is below a thousandth of the angles' power
//! ([`MIN_SHARE`]) the white floor is kept: there it is as likely the gyro's noise (which, seen in
//! angle units, grows as `1/f^2` at low frequency, where the angles are strong) and either way
//! moves a gain by less than a thousandth; taking it as angle noise put a false 0.1 mm lever-arm
//! error on a clean 30-minute run.
//!
//! The witness's delay behind the angles and its drift through a stretch: [`super::witness_delay`].
//!
//! Robustness: the estimate is the median over up to five equal stretches of the record, each
//! estimated on its own (a stretch where the gyro is no witness, a hold or a dead start, would
//! otherwise pass its unexplained motion for angle noise everywhere), with windows of at least
//! 24 of the window's equivalent samples (`2n/3` over the bins; 18.5 independent bins by the
//! Hann bins' correlation). The model is used for the input estimate only: the error the observer
//! reports for the noise terms ([`super::observer::ErrorPsd`]) is the white floor's.
//!
//! Units: the per-bin values are periodogram levels `|Y|^2 / L_eff` (rad^2 per sample, the units
//! of a white noise's variance); densities are `2 / fs` times them. Windows of too few bins or a
//! singular `S_ww` give the white floor (nothing is known beyond it). NaN cannot arise from
//! finite input.

use num_complex::Complex64;
use rayon::prelude::*;

use super::colour_split::split_euler_rates;
use super::colour_window::{Dof, Windows, slide};
use super::mount::{in_platform_axes, turned_mounting};
use super::witness_delay::{
    advance, align, angle_spectra, drift, first_delay, hann_windowed, witness_angles, witness_euler_rates,
};
use super::witness_floor::WitnessFloor;
use crate::fourier::{RecordFft, fast_len};

/// The angle noise the observer assumes, per bin, as per-sample variances per axis.
#[derive(Clone, Debug)]
pub(super) enum AngleNoise {
    /// The same white level in every bin.
    White([f64; 3]),
    /// A level per bin (the coloured model).
    PerBin(Vec<[f64; 3]>),
}

impl AngleNoise {
    /// The variances at bin `k`.
    pub(super) fn at(&self, k: usize) -> [f64; 3] {
        match self {
            Self::White(v) => *v,
            Self::PerBin(v) => v[k],
        }
    }
}

/// `x` late by `samples(i)` at sample `i` (linear interpolation, held at the ends).
fn delayed(x: &[f64], samples: impl Fn(usize) -> f64) -> Vec<f64> {
    let n = x.len();
    (0..n)
        .map(|i| {
            let t = (i as f64 - samples(i)).clamp(0.0, (n - 1) as f64);
            let j = (t.floor() as usize).min(n.saturating_sub(2));
            let frac = t - j as f64;
            x[j] * (1.0 - frac) + x[(j + 1).min(n - 1)] * frac
        })
        .collect()
}

/// Records shorter than this many seconds per stretch are not split (see [`coloured_noise`]).
const MIN_STRETCH_S: f64 = 20.0;
/// Smallest share of the angles' power the unexplained part must have to be taken as their
/// noise; below it the white floor is kept (module docs: where the witness explains all but a
/// thousandth, what is left is as likely the gyro's own noise, and either way moves a gain by
/// less than a thousandth).
const MIN_SHARE: f64 = 1e-3;
/// The sum of the squared correlations between one bin of a Hann-windowed record's spectrum and
/// the others, `1 + 2 (4/9 + 1/36)` (`ident::spectra::bin_correlation` of a Hann window).
const HANN_BIN_CORRELATION: f64 = 35.0 / 18.0;
/// Most stretches the record is split into.
const MAX_STRETCHES: usize = 5;
/// Fewest of the Hann window's equivalent samples (`2n/3` spread over the bins) a smoothing
/// window holds for the conditional spectrum, narrower windows widened: 18.5 independent bins by
/// the Hann bins' correlation (`HANN_BIN_CORRELATION`), the relative standard deviation about
/// `1 / sqrt(18.5 - 3)`, 0.25 (0.28 where the slope is fitted).
const MIN_EQUIVALENT: f64 = 24.0;

/// The coloured model, and what the witness bounds the angle noise by.
///
/// The bound's contract: per axis, a white-equivalent level (rad per sample) at or above the
/// angles' own noise over most of [`BOUND_BAND_HZ`] (what the gyro leaves unexplained holds that
/// noise, the gyro's own and the witness's misfit); cells where the witness says nothing (too
/// few bins, a singular `S_ww`) are left out, and without a witnessed half of the band's bins on
/// every axis there is no bound. Angles low-passed or interpolated from a slower rate have less
/// noise above that rate than a white noise of their per-sample variance: there the level reads
/// lower than that variance.
pub(super) struct Coloured {
    /// Per bin of the observer's grid and axis, the model (see [`coloured_noise`]).
    pub per_bin: Vec<[f64; 3]>,
    /// Per bin and axis, what the witness left unexplained above the white floor where the model
    /// kept the floor ([`MIN_SHARE`]), the same medians: the angles' noise may be up to this much
    /// more than the model (it may as well be the gyro's own noise; one run cannot tell them
    /// apart), and the gains fitted on the inputs read low by up to its share of the motion
    /// (`ident::left_out_noise`). 0 where the model is the unexplained part itself, and below
    /// the frequency where the gyro's drift is kept out; elsewhere it holds the gyro's own
    /// low-frequency noise as it comes (that rule's minimum lies where the model is the floor,
    /// so it takes out at most one floor): the ambiguity this part stands for.
    pub left_out_per_bin: Vec<[f64; 3]>,
    /// Per axis, the white level that bounds the angles' noise from above: the median over the
    /// bins between [`BOUND_BAND_HZ`]'s ends (the top capped at `0.4 fs`) of `min(N_c, S_yy)`
    /// without the floor (the unexplained part holds the angles' noise and more: the gyro's own,
    /// the witness's misfit), as a standard deviation, rad. `None` where no bin is there.
    pub bound_rad: Option<[f64; 3]>,
}

/// Where [`Coloured::bound_rad`] is read, Hz: the auto band's search limits
/// (`ident::band::AUTO_LIMITS_HZ`, the same numbers: a unit test holds them equal).
pub(super) const BOUND_BAND_HZ: [f64; 2] = [0.1, 40.0];

/// The coloured model on the observer's grid `grid`: per bin and axis, `clamp(N_c, white, S_yy)`
/// (module docs), the median over up to five equal stretches of the record, each estimated on its
/// own: a stretch where the gyro is no witness of the motion (a hold, a dropout, a dead start)
/// leaves much of the motion unexplained there and would pass for angle noise everywhere; the
/// median ignores up to two such stretches. The smoothing windows are the observer's
/// (`max(smoothing_hz, smoothing_fraction f)` wide), widened to [`MIN_EQUIVALENT`] bins. With it,
/// the bound the same medians put on the angles' noise ([`Coloured::bound_rad`]).
pub(super) fn coloured_noise(
    angles: [&[f64]; 3],
    body_rates: [&[f64]; 3],
    grid: &RecordFft,
    smoothing: (f64, f64),
    white: [f64; 3],
) -> Coloured {
    let n = angles[0].len();
    let rate = grid.sample_rate_hz();
    // A gyro mounted turned: its outputs in platform axes first (`super::mount`).
    let platform = turned_mounting(angles, body_rates, rate).map(|q| in_platform_axes(&q, body_rates));
    let body_rates = platform
        .as_ref()
        .map_or(body_rates, |p| p.each_ref().map(Vec::as_slice));
    let count = ((n as f64 / (MIN_STRETCH_S * rate)) as usize).clamp(1, MAX_STRETCHES);
    let count = if count.is_multiple_of(2) { count - 1 } else { count };
    let stretches: Vec<(f64, Vec<Cell>)> = (0..count)
        .into_par_iter()
        .map(|j| {
            let range = j * n / count..(j + 1) * n / count;
            let a = angles.map(|x| &x[range.clone()]);
            let w = body_rates.map(|x| &x[range.clone()]);
            stretch_noise(a, w, rate, smoothing, white).0
        })
        .collect();
    let mut values = Vec::with_capacity(count);
    let mut median = |k: usize, a: usize, of: fn(&Cell) -> [f64; 3]| {
        let f = grid.frequency_hz(k);
        values.clear();
        values.extend(stretches.iter().map(|(cell_hz, v)| {
            let i = ((f / cell_hz) as usize).min(v.len() - 1);
            of(&v[i])[a]
        }));
        values.sort_by(f64::total_cmp);
        values[values.len() / 2]
    };
    let mut out: Vec<[f64; 3]> = (0..grid.n_bins())
        .map(|k| [0, 1, 2].map(|a| median(k, a, |c| c.model)))
        .collect();
    let mut left_out: Vec<[f64; 3]> = (0..grid.n_bins())
        .map(|k| [0, 1, 2].map(|a| median(k, a, |c| c.left_out)))
        .collect();
    let top = BOUND_BAND_HZ[1].min(0.4 * rate);
    let band: Vec<usize> = (0..grid.n_bins())
        .filter(|&k| (BOUND_BAND_HZ[0]..=top).contains(&grid.frequency_hz(k)))
        .collect();
    // Per axis, the median over the band's bins where the witness's median says something; no
    // bound unless it does in at least half of them.
    let per_axis = [0, 1, 2].map(|a| {
        let mut levels: Vec<f64> = band
            .iter()
            .map(|&k| median(k, a, |c| c.bound))
            .filter(|v| v.is_finite())
            .collect();
        levels.sort_by(f64::total_cmp);
        (!levels.is_empty() && 2 * levels.len() >= band.len())
            .then(|| levels[levels.len() / 2].max(0.0).sqrt())
    });
    let bound_rad = match per_axis {
        [Some(x), Some(y), Some(z)] => Some([x, y, z]),
        _ => None,
    };
    keep_the_gyro_s_drift_out(&mut out, &mut left_out, grid, white);
    Coloured {
        per_bin: out,
        left_out_per_bin: left_out,
        bound_rad,
    }
}

/// One cell of a stretch's estimate: the model `clamp(N_c, white, S_yy)` and the bound
/// `min(N_c, S_yy)`, per axis.
#[derive(Clone, Copy)]
struct Cell {
    model: [f64; 3],
    /// The unexplained part above the floor where the model keeps the floor ([`Coloured`]).
    left_out: [f64; 3],
    bound: [f64; 3],
    /// The angles' power `S_yy`.
    total: [f64; 3],
}

/// The gyro's own noise taken out of the unexplained part. In rate units (`w^2 N`) a gyro's noise
/// is flat or falling with frequency (white, flicker, random walk), an angle measurement's rises
/// (its noise, differentiated, grows as `w^2`). So below the frequency where the unexplained part
/// in rate units is smallest it is the gyro's, and the white floor is kept; above it the gyro's
/// part is at most its level at that minimum, which is subtracted. (Taken as angle noise, a gyro's
/// rate random walk, `1/f^4` in angle units, shrank the inputs at low frequency and hid the walk
/// from the noise terms; its white noise shrank them where the motion is weak.)
/// What the model left out (`left_out`, [`Coloured::left_out_per_bin`]) is treated alike (the
/// minimum is the model's, at most one floor where the model kept it: the gyro's own noise
/// mostly stays in `left_out`, which is meant to hold either).
fn keep_the_gyro_s_drift_out(
    out: &mut [[f64; 3]],
    left_out: &mut [[f64; 3]],
    grid: &RecordFft,
    white: [f64; 3],
) {
    let top = (0.4 * grid.sample_rate_hz()).min(40.0);
    for a in 0..3 {
        let in_rate = |k: usize| {
            let w = 2.0 * std::f64::consts::PI * grid.frequency_hz(k);
            w * w * out[k][a]
        };
        let last = (1..out.len())
            .take_while(|&k| grid.frequency_hz(k) <= top)
            .last()
            .unwrap_or(0);
        let Some(lowest) = (1..=last).min_by(|&i, &j| in_rate(i).total_cmp(&in_rate(j))) else {
            continue;
        };
        // The gyro's part is at most its level at the minimum, and (flat or falling) no more above
        // it: what rises beyond that level is the angle measurement's.
        let floor = in_rate(lowest);
        for (k, (v, l)) in out.iter_mut().zip(left_out.iter_mut()).enumerate() {
            let w = 2.0 * std::f64::consts::PI * grid.frequency_hz(k);
            if k < lowest {
                v[a] = white[a];
                l[a] = 0.0;
            } else {
                v[a] = (v[a] - floor / (w * w)).max(white[a]);
                l[a] = (l[a] - floor / (w * w)).max(0.0);
            }
        }
    }
}

/// One stretch's model on its own grid, per cell of bins: (cell width in Hz, per-cell variances;
/// cell `c` covers `[c, c + 1)` cell widths), and the witness's drift followed (s per s, 0 where
/// its delay is held constant).
///
/// The gyro's rates are late by its delay: converted at the angles of the same instant, a fast
/// rotation turns the attitude within the delay and the conversion itself leaks. So: the delay
/// from a first conversion, then the conversion at the angles that much earlier, the witness
/// moved by the delay before it is windowed (moved after, by a phase turn, its window no longer
/// matches the angles' by the delay over the stretch's length: with the angles 250 ms late on
/// stretches of 24 s, a thousandth of the angles' power left unexplained, taken for their noise,
/// and the gyro's `K` 0.8 % high), then any rest by a phase turn. A delay that changes through
/// the stretch (the gyro's clock drifts, [`drift`]) is followed where following it leaves less of
/// the angles unexplained than the constant delay does ([`unexplained_share`]): the halves'
/// delays are noisy where the motion is weak (on a real recording with its gyro 16 samples late,
/// halves 7 and 59 ms apart), and a drift read from that noise misaligns the witness.
fn stretch_noise(
    angles: [&[f64]; 3],
    body_rates: [&[f64]; 3],
    rate: f64,
    smoothing: (f64, f64),
    white: [f64; 3],
) -> ((f64, Vec<Cell>), f64) {
    let n = angles[0].len();
    let mut fft = RecordFft::new(fast_len(n), rate);
    let fft = &mut fft;
    let y = angle_spectra(angles, fft);
    let (delay_s, _) = first_delay(angles, body_rates, &y, fft);
    let steady = stretch_cells(angles, body_rates, &y, fft, smoothing, white, &|_| delay_s);
    let slope = drift(angles, body_rates, rate);
    if slope == 0.0 {
        return (steady, 0.0);
    }
    // Seconds late at sample `i`: the stretch's delay at its middle, the drift's slope around it.
    let late_s = |i: usize| delay_s + slope * (i as f64 - 0.5 * n as f64) / rate;
    let drifted = stretch_cells(angles, body_rates, &y, fft, smoothing, white, &late_s);
    if unexplained_share(&drifted) < unexplained_share(&steady) {
        (drifted, slope)
    } else {
        (steady, 0.0)
    }
}

/// How much of the angles a stretch's witness leaves unexplained: the mean over the cells inside
/// [`BOUND_BAND_HZ`] and the axes of `min(N_c, S_yy) / S_yy` (each cell counts alike: the
/// angles' power falls by decades across the band, and a misaligned witness loses most at its
/// top). Cells where the witness says nothing count as all unexplained.
fn unexplained_share((cell_hz, cells): &(f64, Vec<Cell>)) -> f64 {
    let in_band: Vec<f64> = cells
        .iter()
        .enumerate()
        .filter(|(c, _)| (BOUND_BAND_HZ[0]..=BOUND_BAND_HZ[1]).contains(&((*c as f64 + 0.5) * cell_hz)))
        .flat_map(|(_, cell)| {
            [0, 1, 2].map(|a| {
                let share = cell.bound[a] / cell.total[a];
                if share.is_finite() {
                    share.clamp(0.0, 1.0)
                } else {
                    1.0
                }
            })
        })
        .collect();
    in_band.iter().sum::<f64>() / in_band.len().max(1) as f64
}

/// A stretch's cells (see [`stretch_noise`]) with the witness aligned `late_s(i)` seconds behind
/// the angles at sample `i` (then any rest by a phase turn, [`align`]); `y`: the angles' spectra
/// on `fft`'s grid.
fn stretch_cells(
    angles: [&[f64]; 3],
    body_rates: [&[f64]; 3],
    y: &[Vec<Complex64>; 3],
    fft: &mut RecordFft,
    smoothing: (f64, f64),
    white: [f64; 3],
    late_s: &dyn Fn(usize) -> f64,
) -> (f64, Vec<Cell>) {
    let n = angles[0].len();
    let rate = fft.sample_rate_hz();
    // Hann: sum w^2 = 3n/8 normalises to per-sample variance; (sum w)^2 / sum w^2 = 2n/3, the
    // window's equivalent length, spread over the grid's bins, sizes the smoothing windows and
    // the delay's alignment.
    let power_norm = 3.0 * n as f64 / 8.0;
    let equivalent_per_bin = (2.0 * n as f64 / 3.0 / fft.len() as f64).min(1.0);
    // The Hann-windowed record's bins are correlated (the next -2/3, the one after 1/6, on a grid
    // of the record's own length; more on a longer one): a regressor fitted in a window takes up
    // `HANN_BIN_CORRELATION` of its bins' worth of the noise; the slope's test counts them so
    // (the level's correction counts the `2n/3` samples: `colour_window`).
    let independent_bins_per_bin = (n as f64 / fft.len() as f64).min(1.0) / HANN_BIN_CORRELATION;
    let late = angles.map(|a| delayed(a, |i| late_s(i) * rate));
    let late = late.each_ref().map(Vec::as_slice);
    let len = fft.len();
    let rates = witness_euler_rates(late, body_rates);
    // The gyro's own white floor as the witness carries it (`super::witness_floor`).
    let witness_floor = WitnessFloor::of_rates(&rates, fft, power_norm);
    let mut spectra = |r: Vec<f64>| {
        fft.forward(&hann_windowed(
            &delayed(&witness_angles(&r, rate), |i| -late_s(i) * rate),
            len,
        ))
    };
    let mut w = rates.map(&mut spectra);
    // The witness split by gyro axis (`colour_split`), moved as the witness is.
    let mut v = split_euler_rates(late, body_rates).map(&mut spectra);
    let (delay_s, _) = align(&mut w, y, fft, equivalent_per_bin);
    advance(&mut v, delay_s, fft);
    let min_half = (MIN_EQUIVALENT / equivalent_per_bin / 2.0).ceil() as usize;
    let windows = Windows {
        bins_per_hz: fft.len() as f64 / rate,
        smoothing,
        min_half,
        // The windows hold at least 2 min_half bins: the model is evaluated per cell of a
        // quarter of min_half bins (each cell's sums accumulated once), which is smooth enough
        // and four to eight times cheaper than per bin.
        cell: (min_half / 4).max(1),
        per_bin: Dof {
            equivalent: equivalent_per_bin,
            independent: independent_bins_per_bin,
        },
        power_norm,
        witness_floor,
    };
    let out = slide(y, &w, &v, &windows)
        .into_iter()
        .map(|(total, left)| cell_of(total, left, white))
        .collect();
    (windows.cell as f64 * rate / fft.len() as f64, out)
}

/// `clamp(N_c, white, S_yy)` per axis from what a window says (its angles' power `total` and
/// the part the witness leaves, `left`), and the bound `min(N_c, S_yy)` (the white floor where
/// nothing is known beyond it).
fn cell_of(total: [f64; 3], witnessed: Option<[f64; 3]>, white: [f64; 3]) -> Cell {
    let left = witnessed.unwrap_or(white);
    let kept_white = |a: usize| left[a] < MIN_SHARE * total[a];
    let model = [0, 1, 2].map(|a| {
        if kept_white(a) {
            white[a]
        } else {
            left[a].min(total[a]).max(white[a])
        }
    });
    let left_out = [0, 1, 2].map(|a| {
        if witnessed.is_some() && kept_white(a) {
            (left[a] - white[a]).max(0.0)
        } else {
            0.0
        }
    });
    Cell {
        model,
        left_out,
        // Where the witness says nothing the floor is no bound: NaN, left out of the median.
        bound: witnessed.map_or([f64::NAN; 3], |w| [0, 1, 2].map(|a| w[a].min(total[a]))),
        total,
    }
}

#[cfg(test)]
#[path = "colour_tests.rs"]
mod tests;
