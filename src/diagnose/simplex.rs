//! Nelder-Mead minimisation of a few parameters (the diagnosis's nonlinear ones: at most a
//! handful), with the standard coefficients (reflection 1, expansion 2, contraction 1/2,
//! shrink 1/2). A non-finite objective value counts as `+inf`, so the search steps away from
//! degenerate points instead of failing.

/// Minimises `f` from `start` with initial steps `step` (one per coordinate); stops when the
/// simplex's values agree within `tol` (absolute) or after `max_evals` evaluations. Returns the
/// best point and its value. An empty `start` evaluates `f` once.
pub fn minimise(
    f: &mut dyn FnMut(&[f64]) -> f64,
    start: &[f64],
    step: &[f64],
    tol: f64,
    max_evals: usize,
) -> (Vec<f64>, f64) {
    let n = start.len();
    let mut eval = |x: &[f64]| {
        let v = f(x);
        if v.is_finite() { v } else { f64::INFINITY }
    };
    let mut pts: Vec<Vec<f64>> = vec![start.to_vec()];
    for k in 0..n {
        let mut p = start.to_vec();
        p[k] += step[k];
        pts.push(p);
    }
    let mut vals: Vec<f64> = pts.iter().map(|p| eval(p)).collect();
    let mut evals = n + 1;
    while evals < max_evals && n > 0 {
        let mut order: Vec<usize> = (0..=n).collect();
        order.sort_by(|&a, &b| vals[a].total_cmp(&vals[b]));
        pts = order.iter().map(|&i| pts[i].clone()).collect();
        vals = order.iter().map(|&i| vals[i]).collect();
        if (vals[n] - vals[0]).abs() <= tol {
            break;
        }
        let centroid: Vec<f64> = (0..n)
            .map(|k| pts[..n].iter().map(|p| p[k]).sum::<f64>() / n as f64)
            .collect();
        let along = |t: f64| -> Vec<f64> {
            (0..n)
                .map(|k| centroid[k] + t * (pts[n][k] - centroid[k]))
                .collect()
        };
        let reflected = along(-1.0);
        let fr = eval(&reflected);
        evals += 1;
        if fr < vals[0] {
            let expanded = along(-2.0);
            let fe = eval(&expanded);
            evals += 1;
            (pts[n], vals[n]) = if fe < fr { (expanded, fe) } else { (reflected, fr) };
        } else if fr < vals[n - 1] {
            (pts[n], vals[n]) = (reflected, fr);
        } else {
            let contracted = if fr < vals[n] { along(-0.5) } else { along(0.5) };
            let fc = eval(&contracted);
            evals += 1;
            if fc < vals[n].min(fr) {
                (pts[n], vals[n]) = (contracted, fc);
            } else {
                for i in 1..=n {
                    let shrunk: Vec<f64> = (0..n)
                        .map(|k| pts[0][k] + 0.5 * (pts[i][k] - pts[0][k]))
                        .collect();
                    vals[i] = eval(&shrunk);
                    pts[i] = shrunk;
                }
                evals += n;
            }
        }
    }
    let best = (0..=n).min_by(|&a, &b| vals[a].total_cmp(&vals[b])).unwrap_or(0);
    (pts[best].clone(), vals[best])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_the_minimum_of_a_rotated_quadratic_and_of_rosenbrock() {
        let mut quad = |x: &[f64]| {
            let (a, b) = (x[0] - 1.5, x[1] + 0.25);
            (a + 0.5 * b).powi(2) + 3.0 * b * b
        };
        let (x, v) = minimise(&mut quad, &[0.0, 0.0], &[0.5, 0.5], 1e-14, 2000);
        assert!((x[0] - 1.5).abs() < 1e-5 && (x[1] + 0.25).abs() < 1e-5, "{x:?}");
        assert!(v < 1e-10);
        let mut rosen = |x: &[f64]| (1.0 - x[0]).powi(2) + 100.0 * (x[1] - x[0] * x[0]).powi(2);
        let (x, _) = minimise(&mut rosen, &[-1.2, 1.0], &[0.3, 0.3], 1e-16, 5000);
        assert!((x[0] - 1.0).abs() < 1e-3 && (x[1] - 1.0).abs() < 2e-3, "{x:?}");
    }

    #[test]
    fn non_finite_values_are_avoided_and_empty_start_is_one_evaluation() {
        let mut f = |x: &[f64]| {
            if x[0] < 0.0 {
                f64::NAN
            } else {
                (x[0] - 2.0).powi(2)
            }
        };
        let (x, _) = minimise(&mut f, &[0.5], &[1.0], 1e-14, 500);
        assert!((x[0] - 2.0).abs() < 1e-5, "{x:?}");
        let mut calls = 0;
        let (x, v) = minimise(
            &mut |_| {
                calls += 1;
                7.0
            },
            &[],
            &[],
            0.0,
            10,
        );
        assert!(x.is_empty() && (v - 7.0).abs() < 1e-15 && calls == 1);
    }
}
