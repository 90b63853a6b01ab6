//! A difference of `K` between two runs split into a rotation of the block's axes as a whole
//! and the block's own scale factors and non-orthogonality.
//!
//! A triad mounted rotated by a small angle vector `theta` (rad) relative to the stand's axes has
//! `K_b = (I + [theta]x) K_a`, `[theta]x` the antisymmetric cross-product matrix: a remount (or a
//! reference realigned between runs) makes `M = K_b K_a^-1 - I` antisymmetric, and changes
//! neither the scale factors (the diagonal) nor the non-orthogonality of the axes (the symmetric
//! part off the diagonal). So for two runs of one unit the antisymmetric part of `M` is the
//! rotation of the axes as a whole between the runs,
//! `theta = (M[2][1] - M[1][2], M[0][2] - M[2][0], M[1][0] - M[0][1]) / 2`, and its symmetric part
//! `(M + M^T) / 2` the change of the block's own figures (to first order in `K - I`).
//!
//! Units: `theta` in mrad, the block's own part dimensionless like `K`. The values are exact for a
//! pure rotation; the standard deviations are first order (those of `K_b - K_a`, the elements of
//! `K` taken as independent, the comparison's own assumption), which is why the split is made
//! only when every element of `K - I` is within [`MAX_DEPARTURE`] in both runs. An unknown
//! standard deviation leaves its figure unjudged, and the words say so. What the split cannot
//! tell: whether a rotation is the mount's, the reference's or inside the unit; and the block's
//! own figures, like the delay, also carry what differs between the runs' estimates beyond their
//! deviations (a regime's errors in variables, say), so "differ" means beyond the stated
//! deviations, not a proof that the unit changed.

use serde::{Deserialize, Serialize};

use nalgebra::Matrix3;

use super::{BlockFigures, Delta};

/// Largest `|K - I|` element for which the first-order split is made.
pub const MAX_DEPARTURE: f64 = 0.1;

/// The change between two runs of the mount's rotation and of the block's own `K`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MountSplit {
    /// Rotation of the axes as a whole about x, y, z from run `a` to run `b` (a remount, the
    /// reference realigned, or inside the unit), mrad.
    pub rotation_mrad: [Delta; 3],
    /// The symmetric part of `K_b K_a^-1 - I`: the change of the scale factors (diagonal) and of the
    /// axes' non-orthogonality (off the diagonal; `[i][j]` and `[j][i]` are the same figure).
    #[serde(rename = "K_own")]
    pub k_own: [[Delta; 3]; 3],
    /// Any of the block's own figures (`K_own` or the delay) different beyond 3 combined standard
    /// deviations: more differs between the runs than the axes' rotation.
    pub own_significant: bool,
    /// The rotation beyond 3 combined standard deviations.
    pub rotation_significant: bool,
}

/// `(x + y) / 2` with its standard deviation, independent `x`, `y` (`None` if either is).
fn half_sum(x: f64, sx: Option<f64>, y: f64, sy: Option<f64>) -> (f64, Option<f64>) {
    let s = match (sx, sy) {
        (Some(a), Some(b)) => Some(0.5 * a.hypot(b)).filter(|s| s.is_finite()),
        _ => None,
    };
    (0.5 * (x + y), s)
}

impl MountSplit {
    /// The split of `fb` against `fa` (`k` the comparison's element differences, for their
    /// standard deviations; `tau` the delay's); `None` when either `K` is too far from the
    /// identity for the first-order deviations, or `K_a` is singular.
    #[must_use]
    pub fn new(fa: &BlockFigures, fb: &BlockFigures, k: &[[Delta; 3]; 3], tau: &Delta) -> Option<Self> {
        let near_identity = |f: &BlockFigures| {
            (0..3).all(|i| (0..3).all(|j| (f.k[i][j] - f64::from(u8::from(i == j))).abs() <= MAX_DEPARTURE))
        };
        if !near_identity(fa) || !near_identity(fb) {
            return None;
        }
        let matrix = |f: &BlockFigures| Matrix3::from_fn(|i, j| f.k[i][j]);
        let m = matrix(fb) * matrix(fa).try_inverse()? - Matrix3::identity();
        let delta = |(value, std): (f64, Option<f64>)| Delta::new(0.0, Some(0.0), value, std);
        let s = |i: usize, j: usize| k[i][j].std;
        // theta_x from (2,1) and (1,2), theta_y from (0,2) and (2,0), theta_z from (1,0), (0,1).
        let rotation_mrad = [(2, 1), (0, 2), (1, 0)].map(|(i, j)| {
            let (value, std) = half_sum(m[(i, j)], s(i, j), -m[(j, i)], s(j, i));
            delta((value * 1e3, std.map(|v| v * 1e3)))
        });
        let k_own = std::array::from_fn(|i| {
            std::array::from_fn(|j| {
                if i == j {
                    delta((m[(i, i)], s(i, i)))
                } else {
                    delta(half_sum(m[(i, j)], s(i, j), m[(j, i)], s(j, i)))
                }
            })
        });
        let significant = |d: &Delta| d.significant == Some(true);
        Some(Self {
            own_significant: k_own.iter().flatten().chain([tau]).any(significant),
            rotation_significant: rotation_mrad.iter().any(significant),
            rotation_mrad,
            k_own,
        })
    }

    /// In words, e.g. `the axes are rotated by 7.57 mrad between the runs (mostly about x:
    /// a remount, or the reference realigned); the block's own scale factors,
    /// non-orthogonality and delay agree within their deviations`.
    #[must_use]
    pub fn words(&self) -> String {
        let angle = self
            .rotation_mrad
            .iter()
            .map(|d| d.diff * d.diff)
            .sum::<f64>()
            .sqrt();
        let judged = |d: &Delta| d.significant.is_some();
        let mount = if self.rotation_significant {
            let axis = (0..3)
                .max_by(|&a, &b| {
                    self.rotation_mrad[a]
                        .diff
                        .abs()
                        .total_cmp(&self.rotation_mrad[b].diff.abs())
                })
                .map_or("x", |a| ["x", "y", "z"][a]);
            format!(
                "the axes are rotated by {angle:.2} mrad between the runs (mostly about {axis}: a remount, \
                 or the reference realigned)"
            )
        } else if self.rotation_mrad.iter().all(judged) {
            format!("the axes' rotation agrees ({angle:.2} mrad, within the deviations)")
        } else {
            format!("the axes' rotation ({angle:.2} mrad) is not judged: a standard deviation is unknown")
        };
        let own = if self.own_significant {
            "the block's own scale factors, non-orthogonality or delay differ beyond their deviations"
        } else if self.k_own.iter().flatten().all(judged) {
            "the block's own scale factors, non-orthogonality and delay agree within their deviations"
        } else {
            "the block's own figures are not all judged: a standard deviation is unknown"
        };
        format!("{mount}; {own}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn figures(k: [[f64; 3]; 3], std: f64) -> BlockFigures {
        BlockFigures {
            k,
            k_std: [[Some(std); 3]; 3],
            tau_s: 4e-3,
            tau_std_s: Some(1e-5),
            order: 0,
            k_at_low_frequency: false,
        }
    }

    fn split(ka: [[f64; 3]; 3], kb: [[f64; 3]; 3], std: f64) -> Option<MountSplit> {
        let (fa, fb) = (figures(ka, std), figures(kb, std));
        let k = std::array::from_fn(|i| {
            std::array::from_fn(|j| Delta::new(fa.k[i][j], fa.k_std[i][j], fb.k[i][j], fb.k_std[i][j]))
        });
        let tau = Delta::new(fa.tau_s, fa.tau_std_s, fb.tau_s, fb.tau_std_s);
        MountSplit::new(&fa, &fb, &k, &tau)
    }

    const I: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

    /// `(I + [theta]x) K`, exactly (no first-order shortcut in the reference).
    fn rotated(theta: [f64; 3], k: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
        let [x, y, z] = theta;
        let r = [[1.0, -z, y], [z, 1.0, -x], [-y, x, 1.0]];
        std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|m| r[i][m] * k[m][j]).sum()))
    }

    #[test]
    fn a_remount_is_a_rotation_and_leaves_the_block_s_own_figures() {
        // The same block (scale 1.002 on x, 1 mrad non-orthogonality between x and y),
        // remounted 6 mrad about x and -2 mrad about z; every K element known to 0.5e-3.
        let own = [[1.002, 0.001, 0.0], [0.001, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let s = split(own, rotated([6e-3, 0.0, -2e-3], own), 0.5e-3).expect("near the identity");
        // K_b K_a^-1 - I is [theta]x exactly: theta_x = (M21 - M12) / 2 = (6 + 6) / 2 mrad.
        assert!(
            (s.rotation_mrad[0].diff - 6.0).abs() < 1e-9,
            "{:?}",
            s.rotation_mrad
        );
        assert!(s.rotation_mrad[1].diff.abs() < 1e-9);
        assert!((s.rotation_mrad[2].diff + 2.0).abs() < 1e-9);
        // Its deviation: half the hypot of two 0.707e-3 differences, in mrad: 0.5.
        assert!((s.rotation_mrad[0].std.unwrap() - 0.5).abs() < 1e-9);
        assert!(s.rotation_significant && !s.own_significant);
        // The rotation leaves nothing in the block's own part.
        for d in s.k_own.iter().flatten() {
            assert!(d.diff.abs() < 1e-12, "{d:?}");
        }
        let words = s.words();
        assert!(words.contains("the axes are rotated by 6.32 mrad"), "{words}");
        assert!(words.contains("mostly about x"), "{words}");
        assert!(
            words.contains("own scale factors, non-orthogonality and delay agree"),
            "{words}"
        );
    }

    #[test]
    fn a_change_of_the_block_s_axes_is_not_taken_for_the_mount() {
        // A 4 mrad change of non-orthogonality between y and z (symmetric): the block's own.
        let mut b = I;
        b[1][2] = 4e-3;
        b[2][1] = 4e-3;
        let s = split(I, b, 0.5e-3).expect("near the identity");
        assert!(s.rotation_mrad.iter().all(|d| d.diff.abs() < 1e-12));
        assert!(!s.rotation_significant && s.own_significant);
        assert!((s.k_own[1][2].diff - 4e-3).abs() < 1e-12 && (s.k_own[2][1].diff - 4e-3).abs() < 1e-12);
        // A scale factor change is the block's own too.
        let mut c = I;
        c[2][2] = 1.01;
        let s = split(I, c, 0.5e-3).expect("near the identity");
        assert!(s.own_significant && !s.rotation_significant);
        let words = s.words();
        assert!(words.contains("the axes' rotation agrees"), "{words}");
        assert!(words.contains("differ beyond their deviations"), "{words}");
    }

    #[test]
    fn no_split_far_from_the_identity_or_unjudged_without_deviations() {
        let mut far = I;
        far[0][0] = 0.5;
        assert!(split(far, I, 1e-3).is_none());
        let mut b = I;
        b[1][2] = 4e-3;
        let s = split(I, b, f64::NAN).expect("near the identity");
        assert!(!s.own_significant && !s.rotation_significant);
        assert!(s.rotation_mrad[0].std.is_none());
        // Nothing judged is never said to agree.
        let words = s.words();
        assert!(!words.contains("agree"), "{words}");
        assert!(
            words.contains("is not judged") && words.contains("not all judged"),
            "{words}"
        );
    }
}
