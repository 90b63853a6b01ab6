//! What can go wrong when estimating spectra.

/// Why a spectral estimate was refused. Every variant carries the numbers that explain it.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SpectralError {
    /// A split of the segments into groups that is empty or finer than the segments.
    #[error("cannot split {n_segments} Welch segments into {parts} groups")]
    BadParts {
        /// Groups asked for.
        parts: usize,
        /// Segments there are.
        n_segments: usize,
    },
    /// No channels were given.
    #[error("no channels given: a spectral matrix needs at least one signal")]
    NoChannels,
    /// The segment length is odd or below the minimum of 8 samples.
    #[error("Welch segment length {segment_len} is not allowed: it must be even and at least 8")]
    BadSegmentLen {
        /// The rejected segment length, samples.
        segment_len: usize,
    },
    /// The overlap fraction is not in `[0, 1)`, or it rounds to a whole segment.
    #[error(
        "Welch overlap {overlap} is not allowed: it must be a fraction in [0, 1) that leaves a \
         step of at least one sample between {segment_len}-sample segments"
    )]
    BadOverlap {
        /// The rejected overlap fraction.
        overlap: f64,
        /// The segment length it was applied to, samples.
        segment_len: usize,
    },
    /// The FFT length is odd or shorter than the segment.
    #[error(
        "Welch fft_len {fft_len} is not allowed: it must be even and at least the segment length {segment_len}"
    )]
    BadFftLen {
        /// The rejected FFT length.
        fft_len: usize,
        /// The segment length.
        segment_len: usize,
    },
    /// The run is shorter than one segment.
    #[error(
        "too few samples for the chosen spectral segment: {n_samples} samples, but one Welch \
         segment needs {segment_len}"
    )]
    TooFewSamples {
        /// Samples available per channel.
        n_samples: usize,
        /// Samples needed for one segment.
        segment_len: usize,
    },
    /// Channels differ in length.
    #[error("channel {channel} has {len} samples, but channel 0 has {expected}")]
    ChannelLengthMismatch {
        /// Index of the offending channel.
        channel: usize,
        /// Its length.
        len: usize,
        /// The length of channel 0.
        expected: usize,
    },
    /// A sample is NaN or infinite.
    #[error("channel {channel}, sample {index} is not a finite number")]
    NonFinite {
        /// Index of the channel.
        channel: usize,
        /// Index of the first non-finite sample in it.
        index: usize,
    },
    /// The sample rate is not a finite positive number.
    #[error("sample rate {sample_rate_hz} Hz is not a finite positive number")]
    BadSampleRate {
        /// The rejected rate, Hz.
        sample_rate_hz: f64,
    },
    /// Parts given to build a spectral matrix do not fit together.
    #[error(
        "spectral matrix parts do not fit: {n_bins} frequencies x {n_channels}^2 channels needs \
         {expected} values, got {len}"
    )]
    ShapeMismatch {
        /// Number of frequencies given.
        n_bins: usize,
        /// Number of channels given.
        n_channels: usize,
        /// Values the shape needs.
        expected: usize,
        /// Values given.
        len: usize,
    },
    /// The FFT library refused its buffers. Unreachable unless this module has a bug.
    #[error("internal error in the FFT: {0}")]
    Fft(String),
}
