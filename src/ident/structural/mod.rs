//! Structural identification: fitting `K e^(-tau s)` and richer rational models to a frequency
//! response estimate.
