//! How the drop-in sub-steps a rapier step: the policy when a step cannot resolve a contact,
//! the sub-step counts per contact time, and what a step did. Shared by the f64 and f32
//! drop-ins (modules `rapier` and `rapier_f32`), which re-export these items.

use crate::math::Real;

/// What to do when the user's step cannot resolve a contact.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "checkpoint", derive(serde::Serialize, serde::Deserialize))]
pub enum StepPolicy {
    /// Always this many sub-steps per step; refuse with [`Error::TimeStepTooLarge`](crate::Error::TimeStepTooLarge) when a
    /// contact needs more.
    Fixed {
        /// Sub-steps per step (>= 1).
        substeps: usize,
    },
    /// As many sub-steps as the stiffest contact needs (by default [`SUBSTEPS_PER_CONTACT`] per
    /// Hertz contact time), up to `max_substeps`; beyond that, refuse.
    AutoSubstep {
        /// Upper bound on sub-steps per step.
        max_substeps: usize,
    },
}

/// How the drop-in integrates its contacts over a step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "checkpoint", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub enum Integration {
    /// Impacts explicitly, in sub-steps of their Hertz contact time (their restitution and
    /// force history resolved); every other contact — bodies resting on each other, rolling,
    /// sliding, or touching at less than the rest speed (the larger of [`AT_REST_SPEED`] and
    /// what gravity gives in [`REST_STEPS`] steps) — implicitly, at whatever step the impacts
    /// leave: its force taken where the step ends, stable at any stiffness. A resting scene
    /// steps at rapier's step. An impact is a contact that began at the rest speed or faster,
    /// for [`IMPACT_WINDOW`] Hertz contact times and until its normal motion falls below the
    /// rest speed. Contacts with an enlargement or a liquid film (wet runs) are integrated
    /// explicitly. The default.
    #[default]
    Implicit,
    /// Every contact explicitly, in sub-steps of the stiffest contact's period — a resting
    /// face's, or the highest frequency of all resting contacts together: every force
    /// history resolved in time, at a cost that grows as the square root of the stiffness.
    Explicit,
}

/// The steps of gravity's pull that make the rest speed: a pair that meets slower than
/// gravity accelerates a body in this many of the user's steps is resting, not impacting (its
/// rebound, at most `e` times that speed, would rise less than `REST_STEPS² g dt² / 2`: 5 mm
/// at 60 Hz).
pub const REST_STEPS: Real = 2.0;

/// How long an impact counts as one after its first touch, in Hertz contact times at its
/// impact speed (the contact has rebounded or settled by then; a contact still moving along
/// its normal faster than the rest speed stays an impact).
pub const IMPACT_WINDOW: Real = 2.0;

/// Sub-steps a contact gets within its Hertz contact time by default: restitution within about
/// 1 % of `e`. `DiscreteContacts::with_substeps_per_contact` trades accuracy for speed.
pub const SUBSTEPS_PER_CONTACT: Real = 30.0;

/// The fewest sub-steps per Hertz contact time accepted: the explicit integration of the
/// stiffest contact stays stable with a margin.
pub const MIN_SUBSTEPS_PER_CONTACT: Real = 5.0;

/// The fewest sub-steps per half-period of a live contact's own oscillation (normal, or the
/// tangential spring's): `ω Δt <= π/2.5 ≈ 1.26`, a margin below the explicit integration's
/// limit `ω Δt < 2`.
pub const STABLE_SUBSTEPS_PER_HALF_PERIOD: Real = 2.5;

/// The least indentation a resolved pair's approach may make in one sub-step, in spacings of
/// the floating-point numbers that hold its bodies' coordinates. Below half a spacing the
/// body's position does not change at all (`x + v Δt` rounds back to `x`): it stalls. At two,
/// each sub-step's displacement is rounded by at most a quarter of itself (what the rounding
/// still costs a served impact is in the precision table of `docs/validation.md`). A step
/// that cannot give every moving pair this is refused with
/// [`Error::PrecisionTooLow`](crate::Error::PrecisionTooLow).
pub const PRECISION_SPACINGS: Real = 2.0;

/// The approach speed (m/s) below which the sub-step advice treats a pair as touching at rest
/// (its Hertz time is taken at this speed), and the precision guard does not ask the pair's
/// motion to be resolved: a body at rest may stand still in rounded coordinates.
pub const AT_REST_SPEED: Real = 1e-3;

/// The spacing (m) of floating-point numbers with relative spacing `epsilon` (the unit
/// round-off's double, e.g. `f32::EPSILON`) around coordinates up to `largest` in magnitude:
/// the distance from `largest` to the next number.
pub(crate) fn coordinate_spacing(largest: Real, epsilon: Real) -> Real {
    if largest > 0.0 && largest.is_finite() {
        epsilon * largest.log2().floor().exp2()
    } else {
        0.0
    }
}

/// What a step did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[non_exhaustive]
pub struct StepStats {
    /// Sub-steps taken.
    pub substeps: usize,
    /// Contacts alive at the end of the step.
    pub contacts: usize,
    /// Largest indentation seen during the step (m).
    pub max_indentation: Real,
    /// Contact evaluations during the step (one per live contact per sub-step).
    pub evaluations: usize,
    /// Of these, the ones integrated in full (the rest updated their last full geometry, see
    /// `DiscreteContacts::with_geometry_reuse`), counted by why each was full.
    pub refreshes: crate::contact::Refreshes,
    /// Times the bounding-sphere neighbour list was rebuilt during the step (usually 0: it
    /// lasts until some body may have moved half its skin, a tenth of the smallest bounding
    /// radius).
    pub neighbour_builds: usize,
    /// Contacts taken implicitly ([`Integration::Implicit`]), summed over the sub-steps.
    pub implicit_contacts: usize,
    /// Of these, pairs about to touch whose law came from a probe of their overlap.
    pub approaching_contacts: usize,
    /// Islands of bodies solved implicitly, summed over the sub-steps.
    pub islands: usize,
    /// Sub-steps of the impacts' own bodies ([`Integration::Implicit`]), summed over their
    /// groups and the step's sub-steps.
    pub impact_substeps: usize,
}

impl StepStats {
    /// The evaluations integrated in full, for whatever reason ([`refreshes`](Self::refreshes)).
    pub fn full_evaluations(&self) -> usize {
        self.refreshes.total()
    }
}
