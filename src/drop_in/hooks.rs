//! The physics hook that switches rapier's contact response off for handled pairs and
//! passes everything else to the user's hooks.

use super::*;

/// Wraps the user's hooks: handled pairs get no rapier contact response.
pub(super) struct Hooks<'a> {
    pub(super) handled: &'a HashMap<ColliderHandle, Handled>,
    pub(super) user: &'a dyn PhysicsHooks,
}

impl PhysicsHooks for Hooks<'_> {
    fn filter_contact_pair(&self, ctx: &PairFilterContext) -> Option<SolverFlags> {
        if self.handled.contains_key(&ctx.collider1) && self.handled.contains_key(&ctx.collider2) {
            None
        } else {
            self.user.filter_contact_pair(ctx)
        }
    }
    fn filter_intersection_pair(&self, ctx: &PairFilterContext) -> bool {
        self.user.filter_intersection_pair(ctx)
    }
    fn modify_solver_contacts(&self, ctx: &mut ContactModificationContext) {
        self.user.modify_solver_contacts(ctx)
    }
}
