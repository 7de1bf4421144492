//! Validation cases with analytical solutions, shared by the examples and the tests.

#[cfg(feature = "rapier")]
pub mod cylinder_impact;
#[cfg(feature = "rapier")]
pub mod drop_in;
pub mod hertz;
#[cfg(feature = "fluid")]
pub mod hindered_settling;
#[cfg(feature = "rapier")]
pub mod precision;
#[cfg(feature = "rapier")]
pub mod stability;
#[cfg(feature = "fluid")]
pub mod wet_rebound;

/// Loads a validation run saved under `kind` and checks that it holds `case`: the one rule
/// behind every resumable run's `load`. Another case is refused with
/// [`InvalidParameter`](crate::Error::InvalidParameter) named `case`, `allowed` saying what must
/// match.
#[cfg(all(feature = "checkpoint", feature = "fluid"))]
pub(crate) fn resume<R: serde::de::DeserializeOwned, C: PartialEq>(
    path: &std::path::Path,
    kind: &str,
    case: &C,
    case_of: impl Fn(&R) -> &C,
    allowed: &'static str,
) -> crate::Result<R> {
    let run: R = crate::checkpoint::load(path, kind)?;
    if case_of(&run) != case {
        return Err(crate::Error::InvalidParameter {
            name: "case",
            value: crate::math::Real::NAN,
            allowed,
        });
    }
    Ok(run)
}
