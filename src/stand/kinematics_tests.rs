use super::*;

const G: f64 = 9.806_65;

/// An analytic trajectory with closed-form derivatives: each angle a sum of two sinusoids.
fn trajectory(t: f64) -> EulerState {
    let spec = [
        (0.3, 1.3, 0.2, 0.05, 4.1, 1.0),
        (0.5, 0.7, 0.9, 0.08, 6.3, 0.3),
        (0.25, 0.9, 1.7, 0.06, 5.2, 2.0),
    ];
    let mut e = EulerState::default();
    for (k, &(a1, w1, p1, a2, w2, p2)) in spec.iter().enumerate() {
        e.angle[k] = a1 * (w1 * t + p1).sin() + a2 * (w2 * t + p2).sin();
        e.rate[k] = a1 * w1 * (w1 * t + p1).cos() + a2 * w2 * (w2 * t + p2).cos();
        e.accel[k] = -a1 * w1 * w1 * (w1 * t + p1).sin() - a2 * w2 * w2 * (w2 * t + p2).sin();
    }
    e
}

fn skew_inv(m: &Matrix3<f64>) -> Vector3<f64> {
    Vector3::new(
        m[(2, 1)] - m[(1, 2)],
        m[(0, 2)] - m[(2, 0)],
        m[(1, 0)] - m[(0, 1)],
    ) * 0.5
}

#[test]
fn body_rate_matches_rotation_matrix_derivative() {
    let h = 1e-5;
    for i in 0..50 {
        let t = 0.37 * f64::from(i);
        let e = trajectory(t);
        let c = platform_to_level(e.angle);
        let dc = (platform_to_level(trajectory(t + h).angle) - platform_to_level(trajectory(t - h).angle))
            / (2.0 * h);
        // C' = C [w]x  =>  [w]x = C^T C'
        let w_ref = skew_inv(&(c.transpose() * dc));
        let w = body_rate(&e);
        assert!(
            (w - w_ref).norm() < 1e-8 * (1.0 + w.norm()),
            "t={t}: {w} vs {w_ref}"
        );
    }
}

#[test]
fn angular_accel_matches_finite_difference_of_rate() {
    let h = 1e-5;
    for i in 0..50 {
        let t = 0.41 * f64::from(i);
        let dw = body_angular_accel(&trajectory(t));
        let dw_ref = (body_rate(&trajectory(t + h)) - body_rate(&trajectory(t - h))) / (2.0 * h);
        assert!(
            (dw - dw_ref).norm() < 1e-7 * (1.0 + dw.norm()),
            "t={t}: {dw} vs {dw_ref}"
        );
    }
}

#[test]
fn specific_force_matches_second_derivative_of_position() {
    // Level-frame position of the point: p = C r. Its acceleration, taken to platform axes, plus
    // the reaction to gravity (0, g, 0)_level taken to platform axes, minus g on y.
    let r = Vector3::new(0.30, 0.12, -0.07);
    let h = 1e-4;
    for i in 0..40 {
        let t = 0.53 * f64::from(i);
        let p = |t: f64| platform_to_level(trajectory(t).angle) * r;
        let a_level = (p(t + h) - 2.0 * p(t) + p(t - h)) / (h * h);
        let c = platform_to_level(trajectory(t).angle);
        let mut f_ref = c.transpose() * (a_level + Vector3::new(0.0, G, 0.0));
        f_ref.y -= G;
        let f = specific_force(&trajectory(t), &r, G);
        assert!((f - f_ref).norm() < 2e-5, "t={t}: {f} vs {f_ref}");
    }
}

#[test]
fn at_rest_cases_of_the_reading() {
    let r = Vector3::new(0.3, 0.12, 0.0);
    let pitch = EulerState {
        angle: [0.0, 0.0, 0.1],
        ..Default::default()
    };
    let f = specific_force(&pitch, &r, G);
    assert!(
        (f - Vector3::new(0.979, -0.049, 0.0)).norm() < 1e-3,
        "pitch +0.1: {f}"
    );
    assert!((f.x - G * 0.1f64.sin()).abs() < 1e-12);
    assert!((f.y - G * (0.1f64.cos() - 1.0)).abs() < 1e-12);
    let roll = EulerState {
        angle: [0.1, 0.0, 0.0],
        ..Default::default()
    };
    let f = specific_force(&roll, &r, G);
    assert!(
        (f - Vector3::new(0.0, -0.049, -0.979)).norm() < 1e-3,
        "roll +0.1: {f}"
    );
    // Yaw alone changes nothing at rest.
    let yaw = EulerState {
        angle: [0.0, 0.7, 0.0],
        ..Default::default()
    };
    assert!(specific_force(&yaw, &r, G).norm() < 1e-12);
}

#[test]
fn small_angle_limit_agrees_to_second_order() {
    let r = Vector3::new(0.3, 0.12, 0.05);
    for &eps in &[1e-2, 1e-3, 1e-4] {
        let base = trajectory(1.234);
        let e = EulerState {
            angle: base.angle.map(|a| a * eps),
            rate: base.rate.map(|a| a * eps),
            accel: base.accel.map(|a| a * eps),
        };
        let w = body_rate(&e);
        assert!(
            (w - Vector3::from(e.rate)).norm() < 5.0 * eps * eps,
            "rate, eps={eps}"
        );
        let f = specific_force(&e, &r, G);
        let f_small = specific_force_small_angle(&e, &r, G);
        let scale = f.norm().max(eps);
        assert!(
            (f - f_small).norm() < 40.0 * eps * eps,
            "force, eps={eps}: {f} vs {f_small} (|f|={scale})"
        );
    }
}

#[test]
#[expect(
    clippy::float_cmp,
    reason = "the series must give the pointwise values bit for bit"
)]
fn series_evaluation_matches_pointwise() {
    let n = 17;
    let mut s = EulerSeries::default();
    for i in 0..n {
        let e = trajectory(0.1 * i as f64);
        for k in 0..3 {
            s.angle[k].push(e.angle[k]);
            s.rate[k].push(e.rate[k]);
            s.accel[k].push(e.accel[k]);
        }
    }
    let w = s.body_rates();
    let f = s.specific_forces([0.1, 0.2, 0.3], G);
    for i in 0..n {
        let e = trajectory(0.1 * i as f64);
        let wi = body_rate(&e);
        let fi = specific_force(&e, &Vector3::new(0.1, 0.2, 0.3), G);
        for k in 0..3 {
            assert_eq!(w[k][i], wi[k]);
            assert_eq!(f[k][i], fi[k]);
        }
    }
}

#[test]
fn euler_rate_inverts_body_rate() {
    let e = EulerState {
        angle: [0.3, -1.1, -0.4],
        rate: [0.2, -0.7, 1.3],
        accel: [0.0; 3],
    };
    let w = body_rate(&e);
    let back = euler_rate(e.angle, [w[0], w[1], w[2]]);
    for (b, r) in back.iter().zip(e.rate) {
        assert!((b - r).abs() < 1e-14, "{back:?} vs {:?}", e.rate);
    }
}

#[test]
fn lever_arm_jacobian_is_the_difference_of_forces_at_shifted_arms() {
    // The force is affine in the lever arm: the Jacobian must equal the force at an arm shifted
    // by a unit along l minus the force at the arm, sample by sample (a brute-force reference).
    let mut series = EulerSeries::default();
    for n in 0..400 {
        let e = trajectory(0.013 * f64::from(n));
        for k in 0..3 {
            series.angle[k].push(e.angle[k]);
            series.rate[k].push(e.rate[k]);
            series.accel[k].push(e.accel[k]);
        }
    }
    let r = [0.3, -0.12, 0.05];
    let at = series.specific_forces(r, G);
    let jacobian = series.lever_arm_jacobian();
    let mut largest = 0.0_f64;
    for l in 0..3 {
        let mut shifted_arm = r;
        shifted_arm[l] += 1.0;
        let shifted = series.specific_forces(shifted_arm, G);
        for i in 0..3 {
            for n in 0..series.len() {
                let reference = shifted[i][n] - at[i][n];
                let got = jacobian[3 * i + l][n];
                assert!(
                    (got - reference).abs() <= 1e-12 + 1e-10 * reference.abs(),
                    "d f_{i} / d r_{l} at sample {n}: {got} against {reference}"
                );
                largest = largest.max(reference.abs());
            }
        }
    }
    // Not a vacuous comparison: the trajectory's rates make the terms material.
    assert!(largest > 0.5, "largest term {largest}");
}
