//! A model extended by accepted effects (`identify --effects`, the app's Accept): the structural
//! model replaced by the paper's model with the effects, and the fit's figures and self-check
//! warnings judged again on what the model now is ([`BlockModel::set_effects`]); the band the
//! identified model's top misfit cut taken back where the joint fit explains it
//! ([`BlockModel::take_back_the_cut_band`]).

use super::{BlockModel, ModelEffects};
use crate::ident::left_out_noise::widened_by_shift;
use crate::ident::warnings::IdentWarning;
use crate::ident::witness_noise::widened_std;

impl BlockModel {
    /// Replaces the structural model by the paper's model extended with `effects`, of gain `k`
    /// (standard deviations `k_std`) and delay `tau_s` (`tau_std_s`): the static figures
    /// (scale factors, misalignments) follow, and so do the self-check's warnings on what the
    /// model now is (its gain, delay and fit; the gain's plausibility where `calibrated`, the
    /// identifier's setting). Before, a gyro on a resonant mount with the mode accepted (`K`
    /// within 0.05 % of the truth, the joint fit's chi2/dof 0.65) kept the identified model's
    /// "does not explain the data: chi2/dof 3922, uncertainties widened by 62.62x" and three
    /// "implausible" elements of a `K` (0.19, -0.10, 1.10) the file no longer held.
    pub fn set_effects(
        &mut self,
        effects: ModelEffects,
        k: [[f64; 3]; 3],
        k_std: [[Option<f64>; 3]; 3],
        tau_s: f64,
        tau_std_s: Option<f64>,
        calibrated: bool,
    ) {
        // The gyro's own noise in the angle-noise model biases the extended model's gains as it
        // did the structural fit's: its estimate stays in their deviations, as the warning says.
        let witness = self.fit.warnings.iter().find_map(|w| match w {
            IdentWarning::WitnessNoiseBias { estimates, .. } => Some(*estimates),
            _ => None,
        });
        let k_std = match witness {
            Some(e) => std::array::from_fn(|i| {
                std::array::from_fn(|j| k_std[i][j].map(|s| widened_std(s, e[j], k[i][j])))
            }),
            None => k_std,
        };
        // So does the angle noise the observer's model left out (`ident::left_out_noise`).
        let k_std = match self.fit.k_shift_left_out_angle_noise {
            Some(shift) => std::array::from_fn(|i| {
                std::array::from_fn(|j| k_std[i][j].map(|s| widened_by_shift(s, shift[i][j])))
            }),
            None => k_std,
        };
        // The joint fit is its own (the diagnosis's design and weights, its effects may take
        // part of a gain rise): its gain is given as fitted, without the delay-only model's even
        // gain, and the gain-rise warning says so.
        self.even_gain = None;
        // A structural fit's poles weighed against an even gain (`poles_or_even_gain`), its delay
        // split with its zeros (`zeros_lag`), and its own delay beside the delay-only model's
        // (`delay_outside_usual_range`), are not this model's: the joint fit is order 0 and says
        // its own. (`zeros_lead` stays, angles that lag being the data's, unless a causal band
        // limit accepted takes their lag: below.)
        // A gain that depends on the amplitude is no longer the model's problem once the
        // nonlinearity is fitted beside `K`.
        let odd_fitted = effects
            .accepted
            .iter()
            .any(|a| a.effect == crate::effect::Effect::ScaleNonlinearity);
        // An accepted band limit (one that holds something: `T > 0`) is the stand's low-pass
        // modelled: the gain's rise across the band is its own (no longer the model's misfit),
        // and a causal one takes the lag of the angles (their leading zeros) and its group delay.
        let band_limit = effects.reference_band_limit.filter(|b| b.t_s > 0.0);
        self.fit.warnings.retain(|w| match w {
            // The identified fit's own: its poles, its fixed order, its delay beside its poles;
            // and its suspected effects (the extended model is the diagnosis's, whose rounds
            // test every effect beside the accepted ones: `crate::diagnose::suspect` tests
            // beside the paper's model alone).
            IdentWarning::PolesOrEvenGain { .. }
            | IdentWarning::ZerosLag { .. }
            | IdentWarning::DelayAbsorbedByPoles { .. }
            | IdentWarning::InadmissibleOrder { .. }
            | IdentWarning::EffectSuspected(_) => false,
            IdentWarning::GainDependsOnAmplitude { .. } => !odd_fitted,
            w @ IdentWarning::GainChangesAcrossBand { rise, .. } => {
                !((band_limit.is_some() && *rise >= 0.0)
                    || effects.lag_explains(w)
                    || effects.resonances.iter().any(|r| r.explains(w)))
            }
            IdentWarning::ZerosLead { .. } => !band_limit.is_some_and(|b| b.shape.causal()),
            _ => true,
        });
        self.redo_negative_delay(tau_s, tau_std_s);
        for w in &mut self.fit.warnings {
            if let IdentWarning::DelayOutsideUsualRange { model_tau_s, .. } = w {
                *model_tau_s = None;
            }
            if let IdentWarning::GainChangesAcrossBand {
                k_at_low_frequency, ..
            } = w
            {
                *k_at_low_frequency = false;
            }
        }
        self.k = k;
        self.tau_s = tau_s;
        self.order = 0;
        self.denominator = Vec::new();
        self.numerator = vec![k];
        self.poles = effects.poles();
        let fit = &mut self.fit;
        fit.k_std = k_std;
        fit.tau_std_s = tau_std_s;
        for i in 0..3 {
            fit.scale_factor_error_ppm[i] = (k[i][i] - 1.0) * 1e6;
            fit.scale_factor_error_std_ppm[i] = k_std[i][i].map(|v| v * 1e6);
            for j in 0..3 {
                let off = i != j;
                fit.misalignment_mrad[i][j] = if off { k[i][j] * 1e3 } else { 0.0 };
                fit.misalignment_std_mrad[i][j] = if off {
                    k_std[i][j].map(|v| v * 1e3)
                } else {
                    Some(0.0)
                };
            }
        }
        self.redo_poor_fit(effects.chi2_per_dof);
        self.effects = Some(effects);
        self.redo_imprecise_gain(calibrated);
        self.redo_implausible_gain(calibrated);
    }

    /// The poor-fit check on the joint fit's own chi2/dof (`[without, with]` the effects): the
    /// identified model's poor fit (its chi2/dof, its worst octave, its widening) is not this
    /// model's, so it goes; [`IdentWarning::PoorFitWithEffects`] is said where the joint fit
    /// stays above [`crate::ident::selfcheck::POOR_FIT`] (or is NaN), whether or not the
    /// identified one was.
    fn redo_poor_fit(&mut self, [without_effects, chi2_per_dof]: [f64; 2]) {
        let at = self.fit.warnings.iter().position(|w| {
            matches!(
                w,
                IdentWarning::PoorFit { .. } | IdentWarning::PoorFitWithEffects { .. }
            )
        });
        let poor = chi2_per_dof.is_nan() || chi2_per_dof > crate::ident::selfcheck::POOR_FIT;
        let judged = poor.then_some(IdentWarning::PoorFitWithEffects {
            chi2_per_dof,
            without_effects,
        });
        self.replace_warning(at, judged);
    }

    /// The gain-plausibility check ([`crate::ident::selfcheck::gain_plausibility`]) on the
    /// extended model's own `K` where the block is `calibrated`: the identified model's elements
    /// and pattern go, the new `K`'s beyond the tolerance are said with what it reads as (in the
    /// place of the first identified one, else at the end).
    fn redo_implausible_gain(&mut self, calibrated: bool) {
        let gain_check = |w: &IdentWarning| {
            matches!(
                w,
                IdentWarning::ImplausibleGain { .. } | IdentWarning::GainPattern(_)
            )
        };
        let at = self
            .fit
            .warnings
            .iter()
            .position(gain_check)
            .unwrap_or(self.fit.warnings.len());
        self.fit.warnings.retain(|w| !gain_check(w));
        if !calibrated {
            return;
        }
        let inputs = self.inputs.each_ref().map(String::as_str);
        let outputs = self.outputs.each_ref().map(String::as_str);
        // The block whose channels these are (the identifier names them so).
        let block = [crate::block::Block::Gyro, crate::block::Block::Accel]
            .into_iter()
            .find(|b| crate::ident::signals::channel_names(*b).1 == outputs);
        let judged: Vec<IdentWarning> = match block {
            Some(block) => crate::ident::selfcheck::gain_plausibility(block, &self.k),
            None => crate::ident::selfcheck::implausible_gains(&self.k, inputs, outputs).collect(),
        };
        let at = at.min(self.fit.warnings.len());
        self.fit.warnings.splice(at..at, judged);
    }

    /// The delay-sign check ([`crate::ident::selfcheck::negative_delay`]) on the extended model's
    /// own delay `tau_s` and its deviation: said where that delay is three deviations below 0,
    /// whether or not the identified one was (the check holds for any model), with its figures,
    /// and dropped where it is not (a causal band limit accepted takes the angles' group delay:
    /// the delay is then against the motion; before, an extended model whose delay was 60 ms
    /// kept the identified model's "negative delay"). Where the deviation is unknown the
    /// identified warning stays, with its figures, only while the extended delay is negative.
    fn redo_negative_delay(&mut self, tau_s: f64, tau_std_s: Option<f64>) {
        let identified = self
            .fit
            .warnings
            .iter()
            .position(|w| matches!(w, IdentWarning::NegativeDelay { .. }));
        let judged = match tau_std_s {
            Some(sd) => crate::ident::selfcheck::negative_delay(tau_s, sd),
            None => identified
                .filter(|_| tau_s < 0.0)
                .map(|at| self.fit.warnings[at].clone()),
        };
        self.replace_warning(identified, judged);
    }

    /// The identified model's warning at `at` (if any) replaced by the extended model's own
    /// judgement `judged` in its place, removed where there is none; a new one at the end.
    fn replace_warning(&mut self, at: Option<usize>, judged: Option<IdentWarning>) {
        match (at, judged) {
            (Some(at), Some(w)) => self.fit.warnings[at] = w,
            (Some(at), None) => {
                self.fit.warnings.remove(at);
            }
            (None, Some(w)) => self.fit.warnings.push(w),
            (None, None) => {}
        }
    }

    /// The imprecise-gain check on the extended model's own `K` and deviations where the block is
    /// `calibrated` (the identifier's setting): the identified warning kept with the new figures
    /// where the least determined element is still beyond
    /// [`crate::ident::selfcheck::IMPRECISE_GAIN`], dropped where it is not (an accepted band
    /// limit can determine the gain far better than the delay-only fit it was said of: a 100 Hz
    /// reference's gyro, `K[gy][wy]` 1.0052 +- 0.0130 identified, 1.0006 +- 0.0005 extended, the
    /// warning's old figures still shown), said where the identified model's was not (the joint
    /// fit's deviations widened by its chi2 or the witness's noise), and left as it was where that
    /// deviation is unknown.
    fn redo_imprecise_gain(&mut self, calibrated: bool) {
        let at = self
            .fit
            .warnings
            .iter()
            .position(|w| matches!(w, IdentWarning::ImpreciseGain { .. }));
        let known = self.fit.k_std.map(|row| row.map(|v| v.unwrap_or(f64::NAN)));
        let ((i, j), imprecise) = crate::ident::selfcheck::least_determined_gain(&known);
        let judged = match self.fit.k_std[i][j] {
            Some(std) if imprecise && calibrated => Some(IdentWarning::ImpreciseGain {
                output: self.outputs[i].clone(),
                input: self.inputs[j].clone(),
                value: self.k[i][j],
                std,
            }),
            Some(_) => None,
            // Unknown: as it was.
            None => at.map(|at| self.fit.warnings[at].clone()),
        };
        self.replace_warning(at, judged);
    }

    /// The model fitted, with its accepted effects, through `band_hz`, wider than the band the
    /// identified model's misfit at its top cut (`crate::diagnose::extend::apply_effects`, where
    /// the joint fit explains that stretch): the model's band is the wider one, and the
    /// identified model's `band_top_misfit` goes with the cut.
    pub fn take_back_the_cut_band(&mut self, band_hz: [f64; 2]) {
        self.band_hz = band_hz;
        self.fit
            .warnings
            .retain(|w| !matches!(w, IdentWarning::BandTopMisfit { .. }));
    }
}
