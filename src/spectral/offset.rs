//! The offset matrix of one Welch bin (`spectral::centroid`, "Offset matrix"): where each input
//! direction's power lies about the bin's centroid, formed direction by direction of the inputs'
//! bin power `S`, a direction left out where `S^-1` is rounding or its own power is leakage from
//! afar.
//!
//! Units: Hz (the bin spacing `df`, the centroid `f_c` and the bin centre `f_k`). Non-finite input
//! gives a zero matrix (every column compared at `f_c`).

use nalgebra::Matrix3;
use num_complex::Complex64;

use super::centroid::MAIN_LOBE_BINS;

/// The largest ratio of the inputs' bin power's largest eigenvalue to another for which that
/// direction gets an offset: beyond, the inputs are collinear there and `S^-1` amplifies rounding.
const MAX_CONDITION: f64 = 1e10;

/// `E S^-1 / 2 pi - (f_c - f_k) I` of one bin, direction by direction of `S`'s eigenvectors `v`:
/// each column `(E v / 2 pi lambda - (f_c - f_k) v)` (`lambda = v^H S v`) is kept where `lambda` is
/// at least `1 / MAX_CONDITION` of the largest (else `S^-1` there is rounding) and the direction's
/// own power lies inside the main lobe: its centroid (`f_c + Re v^H G v`) within
/// [`MAIN_LOBE_BINS`] bins of `f_k` (else that power is leakage from afar, which no first-order
/// shift describes); a direction left out is compared at `f_c` (`G v = 0`). The column's other
/// components are the strong directions' offsets correlated with this one and divided by its
/// power: large where the direction is weak, but no larger relative to its noise, which scales
/// alike, and not a far frequency. Judging the
/// column by its norm left the weak direction of an accelerometer's specific forces out on most
/// bins of an independent simulator's 1 kHz runs with sines (columns of 16 to over 64 bins, own
/// offsets within the main lobe): chi2/dof 1.05 with the true 2 ms delay and 1.18 with 4.25 ms,
/// and a sensor filter's order-2 fit left misfits of 5-15 times the noise at 1-8 Hz that a pole
/// pair at 3 Hz took up (`K` 1.5 % off); judged by its own offset, 0.99 and 0.92. With every
/// direction kept this is the formula itself; which directions of a repeated eigenvalue are kept
/// depends on the basis the decomposition picks. An accelerometer's
/// specific forces at high frequency lie near the plane normal to the lever arm, so its `S` has
/// one weak direction: where its own power is leakage, it alone is left out, the other two still
/// moved (zeroing the whole matrix there left chi2 per bin of 5-30 times its expectation on delays
/// of 5-10 ms, growing as `tau^2`). A bin whose centroid was held gets none
/// ([`super::centroid::InputMoments::centroid_at`]).
pub(super) fn offset(
    power: &Matrix3<Complex64>,
    shifted: &Matrix3<Complex64>,
    fc: f64,
    fk: f64,
    df: f64,
) -> Matrix3<Complex64> {
    let mut g = Matrix3::zeros();
    if !power.iter().all(|z| z.is_finite()) {
        return g;
    }
    // Every direction kept (the common case): the formula itself, without the eigenvectors. The
    // Frobenius condition bounds the eigenvalues' ratio and `||G||_F` every column's norm.
    if let Some(inverse) = power.try_inverse()
        && power.norm() * inverse.norm() < MAX_CONDITION
    {
        let full = shifted * inverse / Complex64::from(2.0 * std::f64::consts::PI)
            - Matrix3::identity() * Complex64::from(fc - fk);
        if full.iter().all(|z| z.is_finite()) && full.norm() <= MAIN_LOBE_BINS * df {
            return full;
        }
    }
    let eigen = nalgebra::SymmetricEigen::new(*power);
    let largest = eigen.eigenvalues.iter().copied().fold(0.0, f64::max);
    for m in 0..3 {
        let v = eigen.eigenvectors.column(m).into_owned();
        // The direction's own power (its Rayleigh quotient), not the eigenvalue as paired.
        let lambda = (v.adjoint() * power * v)[(0, 0)].re;
        if !(lambda > 0.0 && lambda * MAX_CONDITION >= largest) {
            continue;
        }
        let column =
            shifted * v / Complex64::from(2.0 * std::f64::consts::PI * lambda) - v * Complex64::from(fc - fk);
        // Where the direction's own power lies: `v^H G v` is its centroid less `f_c`, so its
        // distance from the bin's centre is that plus `f_c - f_k`.
        let own = (v.adjoint() * column)[(0, 0)].re + (fc - fk);
        if column.iter().all(|z| z.is_finite()) && own.abs() <= MAIN_LOBE_BINS * df {
            g += column * v.adjoint();
        }
    }
    g
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A weak direction is judged by where its own power lies, not by its column's norm: the
    /// column's other components are the strong directions' offsets correlated with it and divided
    /// by its small power (exact algebra). `S = diag(1, 1, 1e-6)` with the third direction's own
    /// offset at 1 bin and its correlation with the first giving a column of 10 bins: kept, `G` is
    /// the formula. With its own offset at 6 bins (past the main lobe) it is left out and the other
    /// two columns kept. The column's norm is asserted past the main lobe: the former rule, which
    /// judged the column by it, left the direction out in both cases.
    #[test]
    fn a_weak_direction_is_judged_by_its_own_power() {
        let (df, fk) = (0.25, 10.0);
        let two_pi = Complex64::from(2.0 * std::f64::consts::PI);
        let weak = 1e-6;
        let s = Matrix3::from_diagonal(&nalgebra::Vector3::new(1.0, 1.0, weak).map(Complex64::from));
        let formula = |e: &Matrix3<Complex64>, fc: f64| {
            e * s.try_inverse().unwrap() / two_pi - Matrix3::identity() * Complex64::from(fc - fk)
        };
        for (own_bins, kept) in [(1.0, true), (6.0, false)] {
            // E / 2 pi = S diag(0.5, -0.5, own) df, plus the weak direction's correlation with the
            // first: (E / 2 pi)_13 = 10 df weak.
            let g = Matrix3::from_diagonal(
                &nalgebra::Vector3::new(0.5, -0.5, own_bins).map(|v| Complex64::from(v * df)),
            );
            let mut e = s * g * two_pi;
            e[(0, 2)] = Complex64::new(0.0, 10.0 * df * weak) * two_pi;
            let fc = fk + e.trace().re / s.trace().re / (2.0 * std::f64::consts::PI);
            let want = formula(&e, fc);
            let third = want.column(2).into_owned();
            assert!(third.norm() > MAIN_LOBE_BINS * df, "{}", third.norm());
            let got = offset(&s, &e, fc, fk, df);
            if kept {
                assert!((got - want).norm() < 1e-9 * want.norm(), "{got} against {want}");
            } else {
                assert!(got.column(2).norm() < 1e-12, "{got}");
                for c in 0..2 {
                    assert!(
                        (got.column(c) - want.column(c)).norm() < 1e-9 * want.norm(),
                        "{got}"
                    );
                }
            }
        }
    }

    /// Every direction kept gives the formula itself, on the shortcut (a well-conditioned bin) and
    /// through the eigenvectors (a `G` whose norm exceeds the main lobe though no column does).
    #[test]
    fn every_direction_kept_is_the_formula() {
        let df = 0.5;
        let two_pi = Complex64::from(2.0 * std::f64::consts::PI);
        let formula = |s: &Matrix3<Complex64>, e: &Matrix3<Complex64>, fc: f64, fk: f64| {
            e * s.try_inverse().unwrap() / two_pi - Matrix3::identity() * Complex64::from(fc - fk)
        };
        let centroid = |s: &Matrix3<Complex64>, e: &Matrix3<Complex64>, fk: f64| {
            fk + e.trace().re / s.trace().re / (2.0 * std::f64::consts::PI)
        };
        let mut rng = crate::rng::Rng::new(3);
        let b = Matrix3::from_fn(|_, _| Complex64::new(rng.normal(), rng.normal()));
        let s = b * b.adjoint() + Matrix3::identity();
        let e = Matrix3::from_fn(|_, _| Complex64::new(rng.normal(), rng.normal()) * 0.1) * s;
        let fk = 10.0;
        let fc = centroid(&s, &e, fk);
        let want = formula(&s, &e, fc, fk);
        assert!(want.norm() <= MAIN_LOBE_BINS * df, "{}", want.norm());
        assert!((offset(&s, &e, fc, fk, df) - want).norm() < 1e-12 * want.norm());
        // S = diag(1, 2, 3), E S^-1 / 2 pi = diag(3, -3, 3) df: G = diag(2, -4, 2) df, of norm
        // 4.9 df, its columns 2, 4 and 2 df.
        let s = Matrix3::from_diagonal(&nalgebra::Vector3::new(1.0, 2.0, 3.0).map(Complex64::from));
        let d =
            Matrix3::from_diagonal(&nalgebra::Vector3::new(3.0, -3.0, 3.0).map(|v| Complex64::from(v * df)));
        let e = s * d * two_pi;
        let fc = centroid(&s, &e, fk);
        let want = formula(&s, &e, fc, fk);
        assert!(want.norm() > MAIN_LOBE_BINS * df);
        assert!(
            (offset(&s, &e, fc, fk, df) - want).norm() < 1e-9 * want.norm(),
            "{}",
            offset(&s, &e, fc, fk, df)
        );
    }
}
