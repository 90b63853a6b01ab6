//! imu-attest: dynamic certification of strapdown-IMU sensor blocks on three-axis motion-simulator
//! stands.
//!
//! The core modules (`run`, `stand`, `sim`, `spectral`, `ident`, ...) are plain data in,
//! `Result<T, Error>` out, and never depend on the GUI. Units are SI throughout (s, rad, rad/s,
//! m/s^2, m); axes and angle conventions follow `../shared/contract.md` section 1.

pub mod batch;
pub mod bench;
pub mod block;
pub mod cli;
pub mod compare;
pub mod diagnose;
pub mod effect;
pub mod faults;
pub mod fourier;
#[cfg(feature = "gui")]
pub mod gui;
pub mod ident;
pub mod interp;
pub mod model;
pub mod noise;
pub mod output;
mod procfs;
pub mod report;
pub mod rng;
pub mod run;
pub mod sim;
pub mod spectral;
pub mod stand;
