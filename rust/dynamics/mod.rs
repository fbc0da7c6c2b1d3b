//! What callers ask of a model's dynamics beyond one recursion: the explicit DeNOC matrices
//! (`denoc`), what a moving mechanism does to its supports (`reactions`; per sample along a
//! trajectory from the links' summed point masses, `link_shaking`), and a model many
//! threads call at once with its pool of per-call workspaces (`shared`).
pub mod at_state;
pub mod calls;
pub mod denoc;
pub mod kinematics_calls;
pub mod link_shaking;
pub mod reaction_args;
pub mod reactions;
pub mod shared;
pub mod stacked;
