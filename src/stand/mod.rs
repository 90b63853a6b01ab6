//! The stand: exact rigid-body kinematics of the three-axis platform, the optimal observer that
//! estimates its motion from the angle sensors, and the block inputs derived from that estimate.
//!
//! Axes (contract section 1): platform `Oxyz`, x forward, y up, z right. Angles are stored in axis
//! order `[roll, yaw, pitch]` = rotations about `[x, y, z]`; the rotation sequence is
//! yaw -> pitch -> roll, so the platform-to-level rotation is `C = R_y(yaw) R_z(pitch) R_x(roll)`.
//! Units: rad, rad/s, rad/s^2, m, m/s^2.

pub mod colour;
mod colour_split;
mod colour_window;
pub mod inputs;
pub mod kinematics;
pub mod mount;
pub mod observer;
mod witness_delay;
mod witness_floor;
