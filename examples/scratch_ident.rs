//! Scratch: accuracy of the identifier chain on simulated runs (not committed).
use imu_attest::block::Block;
use imu_attest::ident::{factorisation::factorise, settings::LambdaSetting, signals::block_signals, spectra::block_spectra, wiener::*};
use imu_attest::sim::{SimConfig, regime::Regime, simulate};
use imu_attest::spectral::{WelchPlanner, WelchSettings, factor::WilsonSettings};
use imu_attest::stand::observer::{ObserverSettings, observe};
use nalgebra::Matrix3;
use num_complex::Complex64;

fn fit0(f: &[f64], w: &[Matrix3<Complex64>], sd: &[Matrix3<f64>], band: &[usize]) -> (Matrix3<f64>, f64) {
    let cost = |tau: f64| {
        let mut k = Matrix3::zeros();
        let mut j = 0.0;
        for i in 0..3 { for c in 0..3 {
            let (mut num, mut den) = (0.0, 0.0);
            for &b in band { let wt = 1.0 / sd[b][(i, c)].powi(2); let om = 2.0 * std::f64::consts::PI * f[b];
                num += wt * (w[b][(i, c)] * Complex64::from_polar(1.0, om * tau)).re; den += wt; }
            k[(i, c)] = num / den;
            for &b in band { let wt = 1.0 / sd[b][(i, c)].powi(2); let om = 2.0 * std::f64::consts::PI * f[b];
                j += wt * (w[b][(i, c)] - Complex64::from_polar(k[(i, c)], -om * tau)).norm_sqr(); }
        }}
        (j, k)
    };
    let mut best = (f64::INFINITY, 0.0);
    let mut tau = -0.02; while tau < 0.05 { let (j, _) = cost(tau); if j < best.0 { best = (j, tau); } tau += 2e-5; }
    let (mut lo, mut hi) = (best.1 - 2e-5, best.1 + 2e-5);
    for _ in 0..80 { let m1 = lo + (hi - lo) / 3.0; let m2 = hi - (hi - lo) / 3.0; if cost(m1).0 < cost(m2).0 { hi = m2 } else { lo = m1 } }
    let t = 0.5 * (lo + hi); (cost(t).1, t)
}

/// Order-0 GLS fit: per output row, weight matrix Omega_i(f) = S_uu(f) / S_psi,ii(f).
fn fit0_gls(f: &[f64], w: &[Matrix3<Complex64>], suu: &[Matrix3<Complex64>], spsi: &[Matrix3<Complex64>], band: &[usize]) -> (Matrix3<f64>, f64) {
    let solve = |tau: f64| {
        let mut k = Matrix3::zeros(); let mut j = 0.0;
        for i in 0..3 {
            let mut a = Matrix3::<f64>::zeros(); let mut bvec = nalgebra::RowVector3::<f64>::zeros();
            for &b in band { let om = 2.0 * std::f64::consts::PI * f[b]; let o = suu[b] / Complex64::from(spsi[b][(i, i)].re);
                let wt = w[b].row(i) * Complex64::from_polar(1.0, om * tau);
                a += o.map(|z| z.re); bvec += (wt * o).map(|z| z.re); }
            let ki = bvec * a.try_inverse().unwrap(); k.set_row(i, &ki);
            for &b in band { let om = 2.0 * std::f64::consts::PI * f[b]; let o = suu[b] / Complex64::from(spsi[b][(i, i)].re);
                let r = w[b].row(i) - ki.map(Complex64::from) * Complex64::from_polar(1.0, -om * tau);
                j += (r * o * r.adjoint())[(0, 0)].re; }
        }
        (j, k)
    };
    let mut best = (f64::INFINITY, 0.0);
    let mut tau = -0.02; while tau < 0.05 { let (j, _) = solve(tau); if j < best.0 { best = (j, tau); } tau += 2e-5; }
    let (mut lo, mut hi) = (best.1 - 2e-5, best.1 + 2e-5);
    for _ in 0..80 { let m1 = lo + (hi - lo) / 3.0; let m2 = hi - (hi - lo) / 3.0; if solve(m1).0 < solve(m2).0 { hi = m2 } else { lo = m1 } }
    let t = 0.5 * (lo + hi); (solve(t).1, t)
}

fn main() {
    for (regime, seed) in [(Regime::Cruise, 1u64), (Regime::TurbulentCruise, 2), (Regime::Approach, 3)] {
        let mut c = SimConfig::new(regime); c.seed = seed;
        let sim = simulate(&c).unwrap();
        let dir = tempfile::tempdir().unwrap(); let p = dir.path().join("r.csv");
        imu_attest::sim::write::write_run(&sim, &p).unwrap();
        let run = imu_attest::run::load(&p, &Default::default()).unwrap();
        let t0 = std::time::Instant::now();
        let est = observe(run.angles.each_ref().map(Vec::as_slice), run.sample_rate_hz, &ObserverSettings { angle_noise_rad: run.sidecar.angle_noise_rad, ..Default::default() }).unwrap();
        let t_obs = t0.elapsed();
        let mut planner = WelchPlanner::new();
        for block in Block::BOTH {
            let sig = block_signals(&run, &est.euler, block).unwrap();
            let t1 = std::time::Instant::now();
            let sp = block_spectra(&mut planner, &sig, run.sample_rate_hz, &WelchSettings::default()).unwrap();
            let t_sp = t1.elapsed();
            let t2 = std::time::Instant::now();
            if std::env::var("CLEAN").is_ok() {
                let truth = if block == Block::Gyro { sim.sidecar.truth.gyro.clone().unwrap() } else { sim.sidecar.truth.accel.clone().unwrap() };
                let mut sp2 = sp.clone();
                for b in 0..sp2.frequency_hz.len() {
                    let wt = Matrix3::from_fn(|i, j| Complex64::from_polar(truth.k[i][j], -2.0 * std::f64::consts::PI * sp2.frequency_hz[b] * truth.tau_s));
                    sp2.s_xu[b] = wt * sp2.s_uu[b];
                    sp2.s_xx[b] = wt * sp2.s_uu[b] * wt.adjoint() + Matrix3::identity() * Complex64::from(1e-12);
                }
                let fa2 = factorise(&sp2, &WilsonSettings { eigen_floor: 1e-13, ..Default::default() }).unwrap();
                let w2 = regularised_wiener(&sp2, &fa2, &Matrix3::identity(), LambdaSetting::Values([0.0; 3]), [0.1, 40.0]).unwrap();
                let band = band_bins(&sp2.frequency_hz, [0.1, 40.0]);
                let kt = Matrix3::from_fn(|i, j| truth.k[i][j]);
                let (k2, t2) = fit0_gls(&sp2.frequency_hz, &w2.w_u, &sp2.s_uu, &factorise(&sp, &WilsonSettings::default()).unwrap().noise_psd, &band);
                for (lo, hi) in [(0.1, 0.2), (0.2, 0.5), (0.5, 2.0), (2.0, 10.0), (10.0, 40.0)] {
                    let bins: Vec<usize> = band.iter().copied().filter(|&b| sp2.frequency_hz[b] >= lo && sp2.frequency_hz[b] < hi).collect();
                    let mut e: f64 = 0.0; let mut ew: f64 = 0.0; let mut wsum = 0.0;
                    for &b in &bins { let wt = Matrix3::from_fn(|i, j| Complex64::from_polar(truth.k[i][j], -2.0 * std::f64::consts::PI * sp2.frequency_hz[b] * truth.tau_s));
                        let d = w2.w_u[b] - wt; e = e.max(d.norm()); ew += (d.adjoint() * d * sp2.s_uu[b]).trace().re.abs(); wsum += sp2.s_uu[b].trace().re; }
                    println!("   clean {lo}-{hi}: max |dW| {e:.2e}, S_uu-weighted {:.2e}, weight share {:.2e}", (ew / wsum).sqrt(), wsum);
                }
                println!("CLEAN {regime} {block:?}: W_u K err {:.5}% tau err {:.5} ms (tau {:.3} ms) neg-lag check", (k2 - kt).norm() / kt.norm() * 100.0, (t2 - truth.tau_s) * 1e3, truth.tau_s * 1e3);
            }
            let floor: f64 = std::env::var("FLOOR").ok().and_then(|v| v.parse().ok()).unwrap_or(1e-9);
            let fa = factorise(&sp, &WilsonSettings { eigen_floor: floor, ..Default::default() }).unwrap();
            let t_fa = t2.elapsed();
            let truth = if block == Block::Gyro { sim.sidecar.truth.gyro.clone().unwrap() } else { sim.sidecar.truth.accel.clone().unwrap() };
            let kt = Matrix3::from_fn(|i, j| truth.k[i][j]);
            let band = band_bins(&sp.frequency_hz, [0.1, 40.0]);
            {
                let w = regularised_wiener(&sp, &fa, &Matrix3::identity(), LambdaSetting::Values([0.0; 3]), [0.1, 40.0]).unwrap();
                let (k, tau) = fit0_gls(&sp.frequency_hz, &w.w_u, &sp.s_uu, &fa.noise_psd, &band);
                let (kh, tauh) = fit0_gls(&sp.frequency_hz, &fa.h1, &sp.s_uu, &fa.noise_psd, &band);
                if block == Block::Accel { println!("dK W_u (x1e3) {:.3}  dK H1 {:.3}", (k - kt) * 1e3, (kh - kt) * 1e3); }
                println!("{regime} {block:?} GLS: W_u K err {:.4}% tau err {:.4} ms | H1 K err {:.4}% tau err {:.4} ms", (k - kt).norm() / kt.norm() * 100.0, (tau - truth.tau_s) * 1e3, (kh - kt).norm() / kt.norm() * 100.0, (tauh - truth.tau_s) * 1e3);
            }
            for lam in [LambdaSetting::Values([0.0; 3])] {
                let w = regularised_wiener(&sp, &fa, &Matrix3::identity(), lam, [0.1, 40.0]).unwrap();
                let (k, tau) = fit0(&sp.frequency_hz, &w.w_u, &w.w_u_std, &band);
                let (kh, tauh) = fit0(&sp.frequency_hz, &fa.h1, &w.w_u_std, &band);
                println!("{regime} {block:?} {lam:?}: W_u K err {:.4}% tau err {:.4} ms | H1 K err {:.4}% tau err {:.4} ms | lambda {:?} resid {:.2e}/{:.2e} | fact err {:.1e} {:.1e} floored {} conv {}",
                    (k - kt).norm() / kt.norm() * 100.0, (tau - truth.tau_s) * 1e3, (kh - kt).norm() / kt.norm() * 100.0, (tauh - truth.tau_s) * 1e3,
                    w.lambda, w.constraint_residual, w.constraint_residual_unregularised, fa.input_factor_error, fa.noise_factor_error, fa.floored_input_bins, fa.converged);
            }
            if std::env::var("BANDS").is_ok() {
                let w = regularised_wiener(&sp, &fa, &Matrix3::identity(), LambdaSetting::Values([0.0; 3]), [0.1, 40.0]).unwrap();
                for (lo, hi) in [(0.1, 0.3), (0.3, 1.0), (1.0, 3.0), (3.0, 10.0), (10.0, 40.0)] {
                    let bins: Vec<usize> = band.iter().copied().filter(|&b| sp.frequency_hz[b] >= lo && sp.frequency_hz[b] < hi).collect();
                    let err = |m: &[Matrix3<Complex64>]| { let mut e = Matrix3::<f64>::zeros(); for &b in &bins { let wt = Matrix3::from_fn(|i, j| Complex64::from_polar(truth.k[i][j], -2.0 * std::f64::consts::PI * sp.frequency_hz[b] * truth.tau_s)); e += (m[b] - wt).map(|z| z.norm()); } e / bins.len() as f64 };
                    let ew = err(&w.w_u); let eh = err(&fa.h1);
                    println!("   {lo}-{hi} Hz: W_u err rows {:.1e} {:.1e} {:.1e} / cols {:.1e} {:.1e} {:.1e} | H1 max {:.1e}", ew.row(0).sum(), ew.row(1).sum(), ew.row(2).sum(), ew.column(0).sum(), ew.column(1).sum(), ew.column(2).sum(), eh.max());
                }
            }
            println!("   times: observer {t_obs:?} spectra {t_sp:?} factorisation {t_fa:?}");
        }
    }
}
