//! The validation cases of `discrete-contact` — experiments with analytical or published
//! results, shared by its examples, tests and benches. Not part of the library's API: a
//! workspace crate (`publish = false`) the root package uses as a dev-dependency.

pub mod cylinder_impact;
pub mod drop_in;
pub mod hertz;
pub mod hindered_settling;
pub mod precision;
pub mod stability;
pub mod stacks;
pub mod wet_rebound;

/// Loads a validation run saved under `kind` and checks that it holds `case`: the one rule
/// behind every resumable run's `load`. Another case is refused with
/// [`InvalidParameter`](discrete_contact::Error::InvalidParameter) named `case`, `allowed` saying what must
/// match.
pub(crate) fn resume<R: serde::de::DeserializeOwned, C: PartialEq>(
    path: &std::path::Path,
    kind: &str,
    case: &C,
    case_of: impl Fn(&R) -> &C,
    allowed: &'static str,
) -> discrete_contact::Result<R> {
    let run: R = discrete_contact::checkpoint::load(path, kind)?;
    if case_of(&run) != case {
        return Err(discrete_contact::Error::InvalidArgument { name: "case", allowed });
    }
    Ok(run)
}
