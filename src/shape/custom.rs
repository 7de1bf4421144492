//! A user's convex body: a distance closure and its bounds.

use std::fmt;
use std::sync::Arc;

use parry3d_f64::bounding_volume::Aabb;

use super::Sdf;
use crate::math::{Real, Vector};

/// A user-supplied SDF: a closure plus the body's bounds.
#[derive(Clone)]
pub struct CustomSdf {
    pub(super) f: Arc<dyn Fn(Vector) -> Real + Send + Sync>,
    pub(super) bounds: Aabb,
}

impl fmt::Debug for CustomSdf {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("CustomSdf").field("bounds", &self.bounds).finish_non_exhaustive()
    }
}

impl Sdf for CustomSdf {
    fn distance(&self, p: Vector) -> Real {
        (self.f)(p)
    }
    fn local_bounds(&self) -> Aabb {
        self.bounds
    }
}
