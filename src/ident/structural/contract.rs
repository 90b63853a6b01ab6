//! The input contract of a structural fit: why a fit is refused ([`StructuralError`]), the checks
//! of the input that refuse it, and the validated, precomputed input they let through.

use std::sync::Arc;

use super::weights::RowWeight;
use super::{MAX_ORDER, OrderChoice, ResponseEstimate, StructuralSettings, model, order};

/// Why a structural fit was refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum StructuralError {
    /// No bins were given.
    #[error("the analysis band is empty: no frequency bins to fit")]
    EmptyBand,
    /// The three slices differ in length.
    #[error("length mismatch: {frequencies} frequencies, {responses} responses, {weights} weights")]
    LengthMismatch {
        /// Number of frequencies.
        frequencies: usize,
        /// Number of response matrices.
        responses: usize,
        /// Number of weight entries (variance matrices or row-weight triples).
        weights: usize,
    },
    /// The offsets (`ResponseEstimate::offset_hz`) are not one per bin.
    #[error("{offsets} offset matrices for {frequencies} frequencies")]
    OffsetMismatch {
        /// Number of offset matrices.
        offsets: usize,
        /// Number of frequencies.
        frequencies: usize,
    },
    /// An offset matrix holds a value that is not finite.
    #[error("the offset matrix at bin {bin} is not finite")]
    NonFiniteOffset {
        /// The bin.
        bin: usize,
    },
    /// A frequency is not finite or not positive.
    #[error("frequency {value} Hz at bin {bin} is not finite and positive")]
    BadFrequency {
        /// The bin.
        bin: usize,
        /// Its frequency, Hz.
        value: f64,
    },
    /// A response element is NaN or infinite.
    #[error("response element ({row}, {col}) at bin {bin} is not finite")]
    NonFiniteResponse {
        /// The bin.
        bin: usize,
        /// Output channel.
        row: usize,
        /// Input axis.
        col: usize,
    },
    /// A variance element is NaN or infinite.
    #[error("variance element ({row}, {col}) at bin {bin} is not finite")]
    NonFiniteVariance {
        /// The bin.
        bin: usize,
        /// Output channel.
        row: usize,
        /// Input axis.
        col: usize,
    },
    /// A variance element is zero, negative, or so small (subnormal) that its weight overflows.
    #[error("variance element ({row}, {col}) at bin {bin} is {value}, not a usable positive value")]
    NonPositiveVariance {
        /// The bin.
        bin: usize,
        /// Output channel.
        row: usize,
        /// Input axis.
        col: usize,
        /// The value.
        value: f64,
    },
    /// A row weight element is NaN or infinite.
    #[error("row weight of output {row} at bin {bin} is not finite")]
    NonFiniteWeight {
        /// The bin.
        bin: usize,
        /// Output channel.
        row: usize,
    },
    /// A row weight is not Hermitian within tolerance.
    #[error("row weight of output {row} at bin {bin} is not Hermitian")]
    NonHermitianWeight {
        /// The bin.
        bin: usize,
        /// Output channel.
        row: usize,
    },
    /// A row weight has an eigenvalue below `-1e-9` of its trace.
    #[error(
        "row weight of output {row} at bin {bin} is not positive semi-definite (eigenvalue \
         {eigenvalue})"
    )]
    IndefiniteWeight {
        /// The bin.
        bin: usize,
        /// Output channel.
        row: usize,
        /// Its most negative eigenvalue.
        eigenvalue: f64,
    },
    /// The requested order exceeds [`MAX_ORDER`].
    #[error("model order {order} is not supported: the highest is {max}")]
    OrderTooHigh {
        /// The requested order.
        order: usize,
        /// The highest supported order.
        max: usize,
    },
    /// The band has too few bins for the order's parameters.
    #[error(
        "order {order} has {parameters} parameters and needs at least {required} bins, the \
         band has {bins}"
    )]
    TooFewBins {
        /// The order.
        order: usize,
        /// Its number of real parameters.
        parameters: usize,
        /// Bins required.
        required: usize,
        /// Bins given.
        bins: usize,
    },
    /// The delay scan range is not finite or empty.
    #[error("delay scan range [{tau_min_s}, {tau_max_s}] s is not a finite, non-empty interval")]
    BadTauRange {
        /// Lower end, s.
        tau_min_s: f64,
        /// Upper end, s.
        tau_max_s: f64,
    },
    /// The numerical fit produced no finite model (degenerate data, e.g. an all-zero response
    /// at a rational order).
    #[error("the order-{order} fit did not produce a finite model")]
    NumericalFailure {
        /// The order.
        order: usize,
    },
}

/// The validated, precomputed input with `rows` for its weights (validated: the input's own
/// from [`super::weights::row_weights`], or narrowed from them).
pub(super) fn prepare(
    input: &ResponseEstimate,
    rows: Arc<[[RowWeight; 3]]>,
    settings: &StructuralSettings,
) -> Result<model::Prepared, StructuralError> {
    validate(input)?;
    // A delay range that is not finite and ordered is refused.
    if !(settings.tau_min_s.is_finite()
        && settings.tau_max_s.is_finite()
        && settings.tau_min_s < settings.tau_max_s)
    {
        return Err(StructuralError::BadTauRange {
            tau_min_s: settings.tau_min_s,
            tau_max_s: settings.tau_max_s,
        });
    }
    Ok(model::Prepared::new(input, rows))
}

/// The highest order to fit for `order` on `n_bins` bins.
pub(super) fn highest_order(order: OrderChoice, n_bins: usize) -> Result<usize, StructuralError> {
    match order {
        OrderChoice::Fixed(n) if n > MAX_ORDER => Err(StructuralError::OrderTooHigh {
            order: n,
            max: MAX_ORDER,
        }),
        OrderChoice::Fixed(n) => {
            let required = order::required_bins(n);
            if n_bins < required {
                return Err(StructuralError::TooFewBins {
                    order: n,
                    parameters: model::parameter_count(n),
                    required,
                    bins: n_bins,
                });
            }
            Ok(n)
        }
        OrderChoice::Auto => {
            let supported = (0..=MAX_ORDER).rev().find(|&n| order::required_bins(n) <= n_bins);
            supported.ok_or(StructuralError::TooFewBins {
                order: 0,
                parameters: model::parameter_count(0),
                required: order::required_bins(0),
                bins: n_bins,
            })
        }
    }
}

/// Checks lengths, finiteness, positivity and ordering of the input (the weights themselves in
/// [`super::weights::row_weights`]).
pub(super) fn validate(input: &ResponseEstimate) -> Result<(), StructuralError> {
    let (nf, nr, nv) = (
        input.frequency_hz.len(),
        input.response.len(),
        input.weights.len(),
    );
    if nf != nr || nf != nv {
        return Err(StructuralError::LengthMismatch {
            frequencies: nf,
            responses: nr,
            weights: nv,
        });
    }
    if nf == 0 {
        return Err(StructuralError::EmptyBand);
    }
    if let Some(offsets) = input.offset_hz {
        if offsets.len() != nf {
            return Err(StructuralError::OffsetMismatch {
                offsets: offsets.len(),
                frequencies: nf,
            });
        }
        if let Some(bin) = offsets.iter().position(|g| !g.iter().all(|z| z.is_finite())) {
            return Err(StructuralError::NonFiniteOffset { bin });
        }
    }
    // Not necessarily ascending: the model is compared with each bin at its inputs' power
    // centroid (`spectral::centroid`), and two bins beside one line share the line's frequency.
    for (bin, &f) in input.frequency_hz.iter().enumerate() {
        if !(f.is_finite() && f > 0.0) {
            return Err(StructuralError::BadFrequency { bin, value: f });
        }
    }
    for (bin, w) in input.response.iter().enumerate() {
        for row in 0..3 {
            for col in 0..3 {
                let z = w[(row, col)];
                if !(z.re.is_finite() && z.im.is_finite()) {
                    return Err(StructuralError::NonFiniteResponse { bin, row, col });
                }
            }
        }
    }
    Ok(())
}
