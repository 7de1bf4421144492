//! Typed errors of the lattice crate.

/// What the lattice refuses or reports.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    /// A parameter outside its range.
    #[error("invalid parameter `{name}` = {value:e}: allowed range is {allowed}")]
    InvalidParameter {
        /// Parameter name.
        name: &'static str,
        /// Given value.
        value: f64,
        /// Allowed range in words.
        allowed: &'static str,
    },
    /// A fluid node on the face of a non-periodic axis.
    #[error("fluid node ({x}, {y}, {z}) lies on a non-periodic face: close it with walls (Lattice::close_faces)")]
    OpenBoundary {
        /// Node x.
        x: usize,
        /// Node y.
        y: usize,
        /// Node z.
        z: usize,
    },
    /// NaN or runaway velocity.
    #[error("unstable at step {step}, node ({x}, {y}, {z}): |u| = {velocity} (lattice units); reduce the time step or the velocity, or raise tau")]
    Unstable {
        /// Step at which it happened.
        step: u64,
        /// Node x.
        x: usize,
        /// Node y.
        y: usize,
        /// Node z.
        z: usize,
        /// The offending speed (NaN for NaN).
        velocity: f64,
    },
}

/// `Result` with the lattice crate's [`Error`].
pub type Result<T> = core::result::Result<T, Error>;
