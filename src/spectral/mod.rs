//! Spectral estimation and factorisation on FFT grids (see each submodule for its conventions).
pub mod factor;
pub mod causal;
pub mod grid;
pub mod cepstral;
