//! Typed errors: every error names what was wrong and what would be right.

use crate::math::Real;
use std::ops::Bound::{Excluded, Unbounded};
use std::ops::RangeBounds;

/// Everything the library can refuse, with the reason.
///
/// The variants are listed in the crate's error catalogue (see the crate docs).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    /// A scalar parameter is outside its allowed range (or not finite).
    #[error("invalid parameter `{name}` = {value:e}: allowed range is {allowed}")]
    InvalidParameter {
        /// The parameter's name, as in the API.
        name: &'static str,
        /// The value that was given.
        value: Real,
        /// The allowed range, in words.
        allowed: &'static str,
    },
    /// An argument that is not a number and not what the call accepts: a handle of another
    /// world, a collider not attached to a dynamic body, a periodic box that does not match.
    #[error("invalid argument `{name}`: needs {allowed}")]
    InvalidArgument {
        /// The argument's name, as in the API.
        name: &'static str,
        /// What it must be, in words.
        allowed: &'static str,
    },
    /// A parry shape that has no convex signed distance function here.
    #[error("unsupported shape `{shape}`: {why}")]
    UnsupportedShape {
        /// The shape's type name.
        shape: String,
        /// Why it is refused and what to use instead.
        why: &'static str,
    },
    /// A position, orientation or velocity that is NaN or infinite.
    #[error("non-finite {what}: {detail}")]
    NonFinite {
        /// Which quantity (e.g. `pose of body A`).
        what: &'static str,
        /// The offending value, printed.
        detail: String,
    },
    /// The two bodies' bounds do not limit the overlap region (e.g. two half-spaces).
    #[error("unbounded overlap region between {a} and {b}: at least one body must be bounded")]
    UnboundedOverlap {
        /// First body's description.
        a: String,
        /// Second body's description.
        b: String,
    },
    /// The time step cannot resolve a contact and the policy forbids sub-stepping further.
    #[error("time step {dt:e} s is too large for the stiffest contact (contact time {contact_time:e} s between {pair}); use a step of at most {recommended:e} s or allow {substeps_needed} sub-steps")]
    TimeStepTooLarge {
        /// The step given (s).
        dt: Real,
        /// The largest safe (sub-)step (s).
        recommended: Real,
        /// The contact time that sets it (s): Hertz's, or the half-period of a live contact's
        /// own or its tangential spring's oscillation when that sets a shorter step.
        contact_time: Real,
        /// Sub-steps per step that would resolve it.
        substeps_needed: usize,
        /// Which pair, in words.
        pair: String,
    },
    /// An impact too energetic for the bodies' materials: Hertz theory puts the deepest
    /// indentation beyond what an overlap of these bodies can represent (they would pass
    /// through each other).
    #[error("contact between {pair} too soft for its impact speed {speed:e} m/s: expected indentation {indentation:e} m exceeds the limit for the smaller body ({limit:e} m); use a stiffer material or a lower speed, or raise the limit (DiscreteContacts::with_indentation_limit)")]
    ContactTooSoft {
        /// Which pair, in words.
        pair: String,
        /// Approach speed (m/s).
        speed: Real,
        /// Hertz maximum indentation (m).
        indentation: Real,
        /// The largest indentation accepted (m).
        limit: Real,
    },
    /// A contact whose approach the numbers that hold the bodies' coordinates cannot resolve:
    /// in one sub-step it indents by less than
    /// `PRECISION_SPACINGS` (the drop-in's constant) spacings of the
    /// coordinates (f32 for `rapier3d`: 1.2e-7 m at 1 m from the origin), so the body would
    /// stall or move in quanta.
    #[error("contact between {pair} cannot be resolved in {precision} at {distance:e} m from the origin: one sub-step of {substep:e} s indents it by {indentation:e} m, under {required} times the spacing of its coordinates ({spacing:e} m); move the scene nearer the origin, use a softer material, or use the f64 build (rapier3d-f64, module `rapier`)")]
    PrecisionTooLow {
        /// Which pair, in words.
        pair: String,
        /// The numbers rapier holds the coordinates in (`f32` or `f64`).
        precision: &'static str,
        /// The largest coordinate of the pair's moving bodies (m).
        distance: Real,
        /// The sub-step (s).
        substep: Real,
        /// The pair's approach in one sub-step (m).
        indentation: Real,
        /// The spacing of the coordinates there (m).
        spacing: Real,
        /// The least indentation accepted, in spacings.
        required: Real,
    },
    /// A step whose outcome cannot be trusted — a contact's overlap beyond what its bodies can
    /// hold, energy the step created, an implicit step that found no solution — and that
    /// could not be redone safely. The world is left as it was before the step.
    #[error("step {step} rejected: {problem}, between {pair}; the world is left as before the step: use a smaller step (integration_parameters.dt), a softer material or slower bodies")]
    StepRejected {
        /// The drop-in's step count when it happened (its first step is 0).
        step: u64,
        /// Which pair, in words.
        pair: String,
        /// What went wrong, with the numbers.
        problem: String,
    },
    /// A file could not be created, written, renamed or read.
    #[error("i/o error on `{path}`: {message}")]
    Io {
        /// The file's path.
        path: String,
        /// The operating system's message.
        message: String,
    },
    /// (feature `checkpoint`) A file that cannot be resumed: not a checkpoint, from another
    /// format or crate version, of another kind, damaged, or holding state that cannot be
    /// saved.
    #[cfg(feature = "checkpoint")]
    #[error("checkpoint `{path}`: {problem}")]
    Checkpoint {
        /// The file's path.
        path: String,
        /// What is wrong with it.
        problem: CheckpointProblem,
    },
    /// (feature `fluid`) The lattice refused a parameter, blew up (with the step and the node),
    /// or could not write a file.
    #[cfg(feature = "fluid")]
    #[error("fluid: {0}")]
    Fluid(#[from] hlbm::Error),
}

/// Why a checkpoint cannot be written or resumed (see [`Error::Checkpoint`]).
#[cfg(feature = "checkpoint")]
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CheckpointProblem {
    /// The file does not start with the checkpoint signature.
    #[error("not a discrete-contact checkpoint (wrong signature); check the path")]
    NotACheckpoint,
    /// Written in another checkpoint format.
    #[error("checkpoint format {found}, this build reads format {supported}; resume with the version that wrote it")]
    FormatVersion {
        /// The file's format.
        found: u32,
        /// The format this build reads.
        supported: u32,
    },
    /// Written by another version of the crate, whose state layout may differ.
    #[error("written by {found}, this is {this}; resume with the version that wrote it")]
    WrittenBy {
        /// The writer named in the file.
        found: String,
        /// This crate and version.
        this: String,
    },
    /// Holds another kind of state than the caller asked for.
    #[error("holds `{found}`, expected `{expected}`")]
    Kind {
        /// The kind named in the file.
        found: String,
        /// The kind asked for.
        expected: String,
    },
    /// Shorter or longer than its header says: an interrupted copy or a damaged disk.
    #[error("damaged: {found} payload bytes where the header says {expected}")]
    Length {
        /// Payload bytes the header announces.
        expected: u64,
        /// Payload bytes present.
        found: u64,
    },
    /// The payload's checksum does not match: the file was altered or damaged.
    #[error("damaged: checksum {computed:08x} where the header says {stored:08x}")]
    Checksum {
        /// The checksum in the header.
        stored: u32,
        /// The checksum of the payload read.
        computed: u32,
    },
    /// The payload does not decode into the requested state.
    #[error("payload does not decode as the requested state: {0}")]
    Decode(String),
    /// The state cannot be saved (e.g. a body with a custom SDF, a closure).
    #[error("state cannot be saved: {0}")]
    Encode(String),
}

/// `Result` with this crate's [`Error`].
pub type Result<T> = core::result::Result<T, Error>;

/// Checks that `value` is finite and inside `range` (bounds inclusive or exclusive as the range
/// says: `0.0..=0.5`, or `(Excluded(0.0), Included(1.0))`); else
/// [`Error::InvalidParameter`] with `name` and `allowed`.
pub(crate) fn check_range(
    name: &'static str,
    value: Real,
    range: impl RangeBounds<Real>,
    allowed: &'static str,
) -> Result<Real> {
    if value.is_finite() && range.contains(&value) {
        Ok(value)
    } else {
        Err(Error::InvalidParameter { name, value, allowed })
    }
}

/// Checks that `value` is finite and strictly positive.
pub(crate) fn check_positive(name: &'static str, value: Real) -> Result<Real> {
    check_range(name, value, (Excluded(0.0), Unbounded), "finite and > 0")
}

/// Checks that `value` is finite and not negative.
pub(crate) fn check_non_negative(name: &'static str, value: Real) -> Result<Real> {
    check_range(name, value, 0.0.., "finite and >= 0")
}

/// Checks that every component of a vector is finite.
pub(crate) fn check_finite_vec(what: &'static str, v: crate::math::Vector) -> Result<()> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(Error::NonFinite { what, detail: format!("{v:?}") })
    }
}
