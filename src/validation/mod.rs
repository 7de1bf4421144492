//! Validation cases with analytical solutions, shared by the examples and the tests.

pub mod hertz;
#[cfg(feature = "rapier")]
pub mod cylinder_impact;
#[cfg(feature = "rapier")]
pub mod stability;
#[cfg(feature = "rapier")]
pub mod drop_in;
#[cfg(feature = "fluid")]
pub mod wet_rebound;
#[cfg(feature = "fluid")]
pub mod hindered_settling;
