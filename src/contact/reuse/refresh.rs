//! Why an evaluation was full ([`Refresh`]), the count of them ([`Refreshes`]), and the check
//! of the reuse fraction.

use crate::error::Result;
use crate::math::Real;

/// Checks a geometry reuse fraction (see [`ContactModel::with_geometry_reuse`](crate::ContactModel::with_geometry_reuse)): the
/// fraction itself, or [`Error::InvalidParameter`](crate::Error::InvalidParameter) naming
/// `geometry_reuse` outside `0 <= fraction <= 100`.
pub fn check_reuse(fraction: Real) -> Result<Real> {
    crate::error::check_range("geometry_reuse", fraction, 0.0..=100.0, "0 <= fraction <= 100")
}

/// Why an evaluation integrated the overlap in full rather than updating the last full
/// geometry (see [`ContactModel::with_geometry_reuse`](crate::ContactModel::with_geometry_reuse)).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Refresh {
    /// Geometry reuse is off, or the pair has an exact form, which costs less than an update.
    Off,
    /// A new contact: there is no full geometry to update.
    FirstTouch,
    /// The approach at the contact point exceeded its allowance.
    Approach,
    /// The approach was within its allowance, the approach plus the tilt across the overlap
    /// was not.
    Tilt,
    /// The contact travelled across the grid by more than its allowance.
    Travel,
    /// The update lost the overlap: the bodies would part, or a surface gradient vanished.
    Lost,
}

/// Full evaluations counted by why each was full ([`Refresh`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Refreshes {
    /// [`Refresh::Off`].
    pub off: usize,
    /// [`Refresh::FirstTouch`].
    pub first_touch: usize,
    /// [`Refresh::Approach`].
    pub approach: usize,
    /// [`Refresh::Tilt`].
    pub tilt: usize,
    /// [`Refresh::Travel`].
    pub travel: usize,
    /// [`Refresh::Lost`].
    pub lost: usize,
}

impl Refreshes {
    /// Counts one full evaluation, full for `why`.
    pub fn count(&mut self, why: Refresh) {
        *match why {
            Refresh::Off => &mut self.off,
            Refresh::FirstTouch => &mut self.first_touch,
            Refresh::Approach => &mut self.approach,
            Refresh::Tilt => &mut self.tilt,
            Refresh::Travel => &mut self.travel,
            Refresh::Lost => &mut self.lost,
        } += 1;
    }

    /// All full evaluations counted.
    pub fn total(&self) -> usize {
        self.off + self.first_touch + self.approach + self.tilt + self.travel + self.lost
    }
}

impl core::ops::AddAssign for Refreshes {
    fn add_assign(&mut self, o: Self) {
        self.off += o.off;
        self.first_touch += o.first_touch;
        self.approach += o.approach;
        self.tilt += o.tilt;
        self.travel += o.travel;
        self.lost += o.lost;
    }
}

impl core::fmt::Display for Refreshes {
    /// `first touch N, approach N, tilt N, travel N, lost N, reuse off N`.
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "first touch {}, approach {}, tilt {}, travel {}, lost {}, reuse off {}",
            self.first_touch, self.approach, self.tilt, self.travel, self.lost, self.off
        )
    }
}
