use discrete_contact::rapier3d as engine;
use discrete_contact::rapier_f32 as drop_in;
// One source for both rapier builds, compiled once per build on purpose.
#[allow(clippy::duplicate_mod)]
#[path = "run.rs"]
pub(super) mod run;
