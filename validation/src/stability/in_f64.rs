use discrete_contact::rapier as drop_in;
use discrete_contact::rapier3d_f64 as engine;
// One source for both rapier builds, compiled once per build on purpose.
#[allow(clippy::duplicate_mod)]
#[path = "run.rs"]
pub(super) mod run;
