//! Fitting one model structure: a Nelder-Mead search over the nonlinear parameters, each
//! evaluation solving the linear ones ([`project`]). Parameters are searched in scaled units
//! (delays, the lag and the band limit's time constant in ms, resonance frequency in Hz, log
//! damping) and kept inside their physical range (lag and band limit's time constant >= 0,
//! a resonance's damping in [0.005, 1] and a second-order lag's in `LAG_DAMPING`, resonance
//! inside the band).

use nalgebra::DMatrix;
use num_complex::Complex64;

use super::design::{Design, WINDOW_ENBW};
use super::profile::{Profile, project};
use super::simplex::minimise;
use super::structure::{LAG_DAMPING, LagShape, Layout, Structure, Theta};

/// A fitted structure.
#[derive(Clone, Debug)]
pub struct Fitted {
    /// What the model holds.
    pub structure: Structure,
    /// Its parameter layout.
    pub layout: Layout,
    /// Nonlinear parameters.
    pub theta: Theta,
    /// Linear parameters and cost.
    pub profile: Profile,
}

impl Fitted {
    /// `chi2 = 2 cost / ENBW` (degrees of freedom of the tapered bins).
    #[must_use]
    pub fn chi2(&self) -> f64 {
        2.0 * self.profile.cost / WINDOW_ENBW
    }

    /// Number of free real parameters (linear + nonlinear, `tau` included).
    #[must_use]
    pub fn n_params(&self) -> usize {
        self.layout.n_params + 1 + self.structure.n_nonlinear_extra()
    }
}

/// The nonlinear parameters in the search's scaled units (delays and the lag in ms, resonance
/// frequency in Hz, log damping), and the search's first steps.
pub(super) fn pack(structure: &Structure, theta: &Theta) -> (Vec<f64>, Vec<f64>) {
    let mut x = vec![theta.tau_s * 1e3];
    let mut step = vec![0.2];
    if structure.skew {
        x.extend(theta.skew_s.map(|v| v * 1e3));
        step.extend([0.2, 0.2]);
    }
    if let Some(shape) = structure.lag {
        x.push(theta.lag_s * 1e3);
        step.push(0.3 * (theta.lag_s * 1e3).max(0.5));
        if shape == LagShape::SecondOrder {
            x.push(theta.lag_damping.ln());
            step.push(0.3);
        }
    }
    if structure.band_limit.is_some() {
        x.push(theta.band_limit_t_s * 1e3);
        step.push(0.3 * (theta.band_limit_t_s * 1e3).max(0.5));
    }
    for &(f, z) in &theta.resonances {
        x.extend([f, z.ln()]);
        step.extend([0.3 * z.max(0.02) * f, 0.3]);
    }
    (x, step)
}

/// [`pack`]'s inverse; `None` outside the physical range.
pub(super) fn unpack(structure: &Structure, x: &[f64], band_hz: [f64; 2]) -> Option<Theta> {
    let mut it = x.iter().copied();
    let mut next = || it.next().unwrap_or(0.0);
    let tau_s = next() * 1e-3;
    let skew_s = if structure.skew {
        [next() * 1e-3, next() * 1e-3]
    } else {
        [0.0; 2]
    };
    let lag_s = if structure.lag.is_some() {
        next() * 1e-3
    } else {
        0.0
    };
    if lag_s < 0.0 {
        return None;
    }
    let lag_damping = if structure.lag == Some(LagShape::SecondOrder) {
        next().exp()
    } else {
        0.0
    };
    if structure.lag == Some(LagShape::SecondOrder)
        && !(LAG_DAMPING[0]..=LAG_DAMPING[1]).contains(&lag_damping)
    {
        return None;
    }
    let band_limit_t_s = if structure.band_limit.is_some() {
        next() * 1e-3
    } else {
        0.0
    };
    if band_limit_t_s < 0.0 {
        return None;
    }
    let mut resonances = Vec::new();
    for _ in &structure.resonance_axes {
        let (f, zeta) = (next(), next().exp());
        if !(band_hz[0]..=band_hz[1]).contains(&f) || !(0.005..=1.0).contains(&zeta) {
            return None;
        }
        resonances.push((f, zeta));
    }
    Some(Theta {
        tau_s,
        skew_s,
        lag_s,
        lag_damping,
        band_limit_t_s,
        resonances,
    })
}

/// Fits `structure` from `start`. `None` when no point of the search gives solvable normal
/// equations.
#[must_use]
pub fn fit(
    design: &Design,
    grams: &[DMatrix<Complex64>],
    structure: &Structure,
    start: &Theta,
    band_hz: [f64; 2],
) -> Option<Fitted> {
    let layout = structure.layout();
    let (x0, step) = pack(structure, start);
    let mut objective = |x: &[f64]| {
        unpack(structure, x, band_hz)
            .and_then(|t| project(design, grams, structure, &layout, &t))
            .map_or(f64::INFINITY, |p| p.cost)
    };
    let max_evals = 120 + 80 * x0.len();
    let (x, _) = minimise(&mut objective, &x0, &step, 1e-6, max_evals);
    // One restart from the best point refreshes a simplex that may have collapsed early.
    let (x, _) = minimise(
        &mut objective,
        &x,
        &step.iter().map(|s| s * 0.3).collect::<Vec<_>>(),
        1e-7,
        max_evals,
    );
    let theta = unpack(structure, &x, band_hz)?;
    let profile = project(design, grams, structure, &layout, &theta)?;
    Some(Fitted {
        structure: structure.clone(),
        layout,
        theta,
        profile,
    })
}

/// The cost of `structure` at `theta` without searching (grid initialisation).
#[must_use]
pub fn cost_at(design: &Design, grams: &[DMatrix<Complex64>], structure: &Structure, theta: &Theta) -> f64 {
    project(design, grams, structure, &structure.layout(), theta).map_or(f64::INFINITY, |p| p.cost)
}

/// The point of `points` with the least [`cost_at`] (the first of equals; points whose cost is not
/// finite are passed over): a search's start from a grid. `None` when no cost is finite (the
/// shape then gives no candidate; before this helper a resonance's or band limit's search could
/// start from a point whose cost was not finite).
#[must_use]
pub fn cheapest(
    design: &Design,
    grams: &[DMatrix<Complex64>],
    structure: &Structure,
    points: impl IntoIterator<Item = Theta>,
) -> Option<Theta> {
    points
        .into_iter()
        .map(|theta| (cost_at(design, grams, structure, &theta), theta))
        .filter(|(c, _)| c.is_finite())
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, theta)| theta)
}
