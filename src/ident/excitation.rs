//! Is every input direction driven in the analysis band? A stand axis held still leaves a
//! direction of the block's input `u` with (almost) no power, and the identified response along it
//! is noise: the standard deviation of `W_u`'s column `j` grows as `sqrt((S_uu^-1)_jj)`. Such a
//! run is refused with a plain diagnosis instead of numbers.
//!
//! Criterion: the band-integrated input spectral matrix `P = sum_{f in band} S_uu(f)` (Hermitian,
//! positive semi-definite) must have its smallest eigenvalue at least [`MIN_EXCITATION`] times its
//! largest. The eigenvalues are the input powers of the principal directions, so the test is
//! independent of how the motion is shared among the axes; a failing direction is named by the
//! input axis with the largest share of its eigenvector. Both eigenvalues are in the same units
//! (all inputs of a block share them), so the ratio is dimensionless.
//!
//! Units: `S_uu` in input units^2/Hz; frequencies in Hz. Empty band: nothing to check (the Wiener
//! stage reports the empty band). Non-finite spectra: refused as not excited.

use nalgebra::{Matrix3, SymmetricEigen};
use num_complex::Complex64;
use serde::Serialize;

use super::IdentError;
use super::signals::channel_names;
use super::spectra::BlockSpectra;
use super::wiener::band_bins;
use crate::block::Block;

/// Smallest ratio of the weakest to the strongest principal input power over the band. At this
/// ratio the weakest direction's response is estimated about 30 times less precisely than the
/// strongest's (standard deviation ~ power^-1/2). Measured on 60 s simulated runs over the default
/// band (`tests/numerical_edges.rs`): the regimes give 5e-2 to 1.2e-1 (gyro) and 6e-3 to 5.4e-2
/// (accelerometer, whose x and y specific forces are nearly collinear at high frequency); a stand
/// axis held still, its angle sensor's noise (1e-5 rad) remaining, gives 3e-5 to 5e-5 (gyro).
pub const MIN_EXCITATION: f64 = 1e-3;

/// The largest standard deviation of a weak run's gains, relative to its largest gain, for which
/// it is still identified rather than refused: a tenth, the plausibility tolerance of a calibrated
/// block's gains ([`super::selfcheck::GAIN_TOLERANCE`]). Between [`HELD_STILL`] and
/// [`MIN_EXCITATION`] the fit decides: an independent simulator's runs with one axis at 3.8e-4 to
/// 9.3e-4 of the strongest's power (refused before) gave K within 0.13 % and honest sigmas (z rms
/// 0.3-1.0).
pub const UNDETERMINED: f64 = 0.1;

/// Below this ratio of the weakest to the strongest principal input power a direction is refused
/// whatever the fit says: a stand axis held still, its angle sensor's noise remaining, gives
/// 3e-5 to 5e-5 (above); the weakest run identified right gave 3.8e-4.
pub const HELD_STILL: f64 = 1e-4;

/// What moves the input axis `axis` (the refusal's advice): a gyro input is the rate about a
/// stand axis (`wx` roll, `wy` yaw, `wz` pitch, near level); a specific force varies with the
/// tilt of gravity into it (`fx` by pitch, `fz` by roll) and with the lever arm's accelerations,
/// the vertical `fy` to first order only with the latter (tilt moves it by `g (1 - cos)`), so a
/// zero lever arm, declared or a missing sidecar's, leaves it nearly flat.
#[must_use]
pub fn advice(axis: &str) -> &'static str {
    match axis {
        "wx" => "move the stand in roll",
        "wy" => "move the stand in yaw",
        "wz" => "move the stand in pitch",
        "fx" => "tilt the stand in pitch (gravity along x) or move it more at the declared lever arm",
        "fz" => "tilt the stand in roll (gravity along z) or move it more at the declared lever arm",
        "fy" => {
            "the vertical specific force varies, to first order, only with the lever arm's \
             accelerations: check the sidecar's accel_lever_arm_m (zero leaves fy nearly flat) and \
             move the stand more"
        }
        _ => "move that stand axis",
    }
}

/// The band's principal input powers.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Excitation {
    /// Eigenvalues of the band-integrated `S_uu`, ascending, input units^2/Hz summed over bins.
    pub principal_power: [f64; 3],
    /// Weakest over strongest (0 when the strongest is 0 or not finite).
    pub ratio: f64,
    /// Index (0..3) of the input axis with the largest share of the weakest direction.
    pub weakest_axis: usize,
}

/// The principal input powers of `spectra` over `band_hz`; `None` when no bin lies in the band.
#[must_use]
pub fn excitation(spectra: &BlockSpectra, band_hz: [f64; 2]) -> Option<Excitation> {
    let band = band_bins(&spectra.frequency_hz, band_hz);
    if band.is_empty() {
        return None;
    }
    let mut p = Matrix3::<Complex64>::zeros();
    for &k in &band {
        p += spectra.s_uu[k];
    }
    if p.iter().any(|v| !(v.re.is_finite() && v.im.is_finite())) {
        return Some(Excitation {
            principal_power: [0.0; 3],
            ratio: 0.0,
            weakest_axis: 0,
        });
    }
    let p = (p + p.adjoint()) * Complex64::from(0.5);
    let eig = SymmetricEigen::new(p);
    let mut order = [0, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    let principal_power = order.map(|i| eig.eigenvalues[i]);
    let strongest = principal_power[2];
    let ratio = if strongest > 0.0 && strongest.is_finite() {
        (principal_power[0] / strongest).max(0.0)
    } else {
        0.0
    };
    let weakest = eig.eigenvectors.column(order[0]);
    let weakest_axis = (0..3)
        .max_by(|&a, &b| weakest[a].norm().total_cmp(&weakest[b].norm()))
        .unwrap_or(0);
    Some(Excitation {
        principal_power,
        ratio,
        weakest_axis,
    })
}

/// Refuses a block whose inputs are not all excited in the band.
///
/// # Errors
/// [`IdentError::NotExcited`] naming the block, the weakest input axis and the band.
pub fn check_excitation(spectra: &BlockSpectra, block: Block, band_hz: [f64; 2]) -> Result<(), IdentError> {
    match excitation(spectra, band_hz) {
        Some(e) if e.ratio < MIN_EXCITATION => Err(IdentError::NotExcited {
            block: block.name(),
            axis: channel_names(block).0[e.weakest_axis],
            low_hz: band_hz[0],
            high_hz: band_hz[1],
            relative_power: e.ratio,
            others: true,
        }),
        _ => Ok(()),
    }
}
